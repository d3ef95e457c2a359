//! A spectral material's form at three wavelengths (FORMULAS.md §9), which is what every
//! engine evaluates: a channel per wavelength, the RGB-valued parameters up-sampled (Jakob &
//! Hanika 2019) and the spectral index read at each. (The `ior` keys themselves are read by
//! `crate::spectral::keys`, the RGB form by `crate::spectral::colour::rgb_fresnel`.)

use super::{CookTorrance, Fresnel, Material, Model};
pub use crate::spectral::colour::rgb_fresnel;
use crate::spectral::upsample::Reflectance;
use crate::spectral::IndexSpectrum;
pub use crate::spectral::SpectralIndex;

/// A material ready to be evaluated at wavelengths: its RGB parameters up-sampled once.
#[derive(Debug, Clone)]
pub struct SpectralForm {
    material: Material,
    diffuse: Reflectance,
    specular: Reflectance,
    f0: Option<Reflectance>,
}

/// Why `material` has no spectral form, or its form.
pub fn spectral_form(material: &Material) -> Result<SpectralForm, String> {
    let who = format!("material `{}`", material.name);
    let f0 = match &material.model {
        Model::Measured(_) => {
            return Err(format!("{who} is measured (MERL) data, which is RGB: it has no spectral form"))
        }
        Model::CookTorrance(ct) if material.spectral.is_none() => match ct.fresnel {
            Fresnel::Schlick { f0 } => Some(Reflectance::fit(f0)),
            Fresnel::Dielectric { ior } | Fresnel::Conductor { ior, .. } if !is_grey(ior) => {
                return Err(format!(
                    "{who} has an RGB ior {ior:?}; an index of refraction is not a colour to up-sample: give `ior` as a spectrum (a data set such as `au-johnson-christy`, [[λ_nm, n, k], …] rows, or {{ file = \"x.yml\" }}), or use a preset's spectral form (`gold-spectral`, …)"
                ))
            }
            Fresnel::Conductor { extinction, .. } if !is_grey(extinction) => {
                return Err(format!("{who} has an RGB extinction {extinction:?}; give `ior` as a spectrum (see `vkbrdf materials --help`)"))
            }
            _ => None,
        },
        Model::Htsg(h) if material.spectral.is_none() && !(is_grey(h.ior) && is_grey(h.extinction)) => {
            return Err(format!("{who} has an RGB ior; give `ior` as a spectrum to evaluate it at wavelengths"))
        }
        _ => None,
    };
    Ok(SpectralForm {
        material: material.clone(),
        diffuse: Reflectance::fit(material.diffuse),
        specular: Reflectance::fit(material.specular),
        f0,
    })
}

fn is_grey(v: [f64; 3]) -> bool {
    v[0] == v[1] && v[1] == v[2]
}

impl SpectralForm {
    /// The material whose channels are the wavelengths `nm` (FORMULAS.md §9): what every
    /// engine evaluates, so the spectral values come from the same code as the RGB ones.
    pub fn at(&self, nm: [f64; 3]) -> Result<Material, String> {
        let m = &self.material;
        let up = |r: &Reflectance| nm.map(|l| r.at(l));
        let index = |f: fn(&IndexSpectrum, f64) -> Result<f64, String>| -> Result<Option<[f64; 3]>, String> {
            let Some(s) = &m.spectral else {
                return Ok(None);
            };
            let at = |l: f64| f(&s.index, l).map_err(|e| format!("material `{}`: {e}", m.name));
            Ok(Some([at(nm[0])?, at(nm[1])?, at(nm[2])?]))
        };
        if let Model::Htsg(_) = m.model {
            if let Some(l) = nm
                .iter()
                .find(|l| crate::terms::htsg::wavelength_range(**l).is_some())
            {
                return Err(format!(
                    "material `{}`: {l} nm is outside htsg's wavelength range [200, 5000] nm",
                    m.name
                ));
            }
        }
        let n = index(|i, l| i.at(l).map(|p| p.0.max(1e-6)))?;
        let k = index(|i, l| i.at(l).map(|p| p.1))?;
        let f0 = index(|i, l| i.f0(l))?;
        let mut out = m.clone();
        out.diffuse = up(&self.diffuse);
        out.specular = up(&self.specular);
        out.spectral = None;
        out.model = match &m.model {
            Model::CookTorrance(ct) => Model::CookTorrance(CookTorrance {
                fresnel: match (&m.spectral, n, k, f0) {
                    (Some(s), Some(n), Some(k), Some(f0)) => {
                        use crate::terms::FresnelKind as K;
                        // `precision = "fast"` made the exact terms Schlick (as in RGB).
                        let fast = matches!(ct.fresnel, Fresnel::Schlick { .. });
                        match s.fresnel {
                            K::None => Fresnel::None,
                            K::Schlick => Fresnel::Schlick { f0 },
                            _ if fast => Fresnel::Schlick { f0 },
                            K::Dielectric => Fresnel::Dielectric { ior: n },
                            K::Conductor => Fresnel::Conductor {
                                ior: n,
                                extinction: k,
                            },
                        }
                    }
                    _ => match ct.fresnel {
                        Fresnel::Schlick { .. } => Fresnel::Schlick {
                            f0: up(self
                                .f0
                                .as_ref()
                                .expect("an RGB Schlick material's f0 was up-sampled")),
                        },
                        other => other, // none, or a grey RGB index: the same at every λ
                    },
                },
                ..ct.clone()
            }),
            Model::Htsg(h) => {
                let mut h = *h;
                h.wavelengths = nm.map(|l| l / 1000.0);
                if let (Some(n), Some(k)) = (n, k) {
                    h.ior = n;
                    h.extinction = k;
                }
                Model::Htsg(h)
            }
            other => other.clone(),
        };
        Ok(out)
    }
}
