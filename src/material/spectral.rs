//! Spectral materials (FORMULAS.md §9): an `ior` given as a spectrum — a shipped data set's
//! name, inline `[λ_nm, n, k]` rows, or `{ file = "x.yml" }` in refractiveindex.info's
//! format — and a material's form at three wavelengths, which is what every engine
//! evaluates: a channel per wavelength, the RGB-valued parameters up-sampled (Jakob &
//! Hanika 2019) and the spectral index read at each.

use super::{CookTorrance, Fresnel, Material, Model};
use crate::spectral::upsample::Reflectance;
use crate::spectral::{datasets, rii, Curve, IndexSpectrum, RgbReduction};
use std::path::Path;
use toml::Value;

/// A material's spectral index and the reduction that gave its RGB form.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralIndex {
    /// `η(λ) = n(λ) + i k(λ)`.
    pub index: IndexSpectrum,
    /// How the material's RGB `ior`/`extinction` (or Schlick `f0`) were derived from it.
    pub reduction: RgbReduction,
    /// The Fresnel term the file named (HTSG's is the conductor's): what a spectral
    /// evaluation uses, whatever term the RGB reduction chose.
    pub fresnel: crate::terms::FresnelKind,
}

/// Whether a TOML `ior` value is a spectrum (a name, rows or a file), not a number or RGB.
pub(super) fn is_spectrum(v: &Value) -> bool {
    match v {
        Value::String(_) | Value::Table(_) => true,
        Value::Array(items) => items.iter().any(|i| matches!(i, Value::Array(_))),
        _ => false,
    }
}

/// The spectrum of `ior` (and of `extinction`, when given: a number or `[λ_nm, k]` rows
/// replace the ior source's k). Errors are `(key, message)`.
pub(super) fn index_from(
    ior: &Value,
    extinction: Option<&Value>,
    base: &Path,
) -> Result<IndexSpectrum, (&'static str, String)> {
    let mut index = match ior {
        Value::String(name) => datasets::dataset(name).ok_or_else(|| {
            (
                "ior",
                format!("unknown data set `{name}`; the shipped ones are: {} (or give [[λ_nm, n, k], …] rows, or {{ file = \"x.yml\" }})", datasets::names()),
            )
        })?,
        Value::Table(t) => {
            let file = match (t.get("file"), t.len()) {
                (Some(Value::String(f)), 1) => f,
                _ => return Err(("ior", "a table here is `{ file = \"x.yml\" }` (a refractiveindex.info file)".into())),
            };
            let path = base.join(file);
            let text = std::fs::read_to_string(&path)
                .map_err(|e| ("ior", format!("cannot read `{}`: {e}", path.display())))?;
            rii::parse(&text, &path.display().to_string()).map_err(|m| ("ior", m))?
        }
        Value::Array(items) => {
            let rows = rows(items, &[2, 3]).map_err(|m| ("ior", m))?;
            let col = |c: usize| Curve::table(rows.iter().map(|r| (r[0], r[c])).collect());
            IndexSpectrum {
                source: "inline rows".into(),
                n: col(1).map_err(|m| ("ior", m))?,
                k: if rows[0].len() == 3 {
                    col(2).map_err(|m| ("ior", m))?
                } else {
                    Curve::Constant(0.0)
                },
            }
        }
        _ => return Err(("ior", "not a spectrum".into())),
    };
    match extinction {
        None => {}
        Some(Value::Float(_) | Value::Integer(_)) => {
            let k = extinction
                .and_then(Value::as_float)
                .or(extinction.and_then(Value::as_integer).map(|i| i as f64));
            match k {
                Some(k) if k.is_finite() && k >= 0.0 => index.k = Curve::Constant(k),
                _ => return Err(("extinction", "must be a finite number ≥ 0".into())),
            }
        }
        Some(Value::Array(items)) if items.iter().all(|i| matches!(i, Value::Array(_))) => {
            let rows = rows(items, &[2]).map_err(|m| ("extinction", m))?;
            index.k = Curve::table(rows.iter().map(|r| (r[0], r[1])).collect())
                .map_err(|m| ("extinction", m))?;
        }
        Some(_) => {
            return Err((
                "extinction",
                "with a spectral `ior`, `extinction` is a number or [[λ_nm, k], …] rows (not RGB)"
                    .into(),
            ))
        }
    }
    check_values(&index)?;
    Ok(index)
}

/// Rows of numbers, each of one of the lengths `widths` (all rows the same).
fn rows(items: &[Value], widths: &[usize]) -> Result<Vec<Vec<f64>>, String> {
    let out: Vec<Vec<f64>> = items
        .iter()
        .enumerate()
        .map(|(i, r)| match r {
            Value::Array(xs) => xs
                .iter()
                .map(|x| match x {
                    Value::Float(f) => Ok(*f),
                    Value::Integer(v) => Ok(*v as f64),
                    _ => Err(format!("row {}: not a number", i + 1)),
                })
                .collect::<Result<Vec<f64>, String>>(),
            _ => Err(format!("row {}: expected [λ_nm, value, …]", i + 1)),
        })
        .collect::<Result<_, _>>()?;
    let w = out.first().map_or(0, Vec::len);
    if !widths.contains(&w) || out.iter().any(|r| r.len() != w) {
        let want: Vec<String> = widths.iter().map(usize::to_string).collect();
        return Err(format!(
            "rows of {} numbers each ([λ_nm, n, k] or [λ_nm, n])",
            want.join(" or ")
        ));
    }
    Ok(out)
}

/// n > 0 and k ≥ 0 at every row of a table (the formulas are checked where evaluated).
fn check_values(index: &IndexSpectrum) -> Result<(), (&'static str, String)> {
    for (key, curve, min) in [("ior", &index.n, 1e-6), ("extinction", &index.k, 0.0)] {
        if let Curve::Table(rows) = curve {
            if let Some(r) = rows.iter().find(|r| !(r.1 >= min && r.1 <= 1e18)) {
                return Err((
                    key,
                    format!("{} at {} nm is out of range [{min}, 1e18]", r.1, r.0),
                ));
            }
        }
    }
    Ok(())
}

/// The RGB Fresnel term a spectral index gives `kind` under `reduction` (FORMULAS.md §9):
/// Mitsuba's reduced (n, k) with the exact term, or Filament's D65 F0 with Schlick
/// (clamped to [0, 1]: a Schlick F0 is a reflectance).
pub fn rgb_fresnel(
    kind: crate::terms::FresnelKind,
    index: &IndexSpectrum,
    reduction: RgbReduction,
) -> Result<Fresnel, String> {
    use crate::terms::FresnelKind as K;
    let positive = |v: [f64; 3]| v.map(|x| x.max(1e-6));
    Ok(match (reduction, kind) {
        (_, K::None) => Fresnel::None,
        (RgbReduction::Mitsuba, K::Dielectric) => Fresnel::Dielectric {
            ior: positive(crate::spectral::colour::mitsuba(index)?.0),
        },
        (RgbReduction::Mitsuba, K::Conductor) => {
            let (n, k) = crate::spectral::colour::mitsuba(index)?;
            Fresnel::Conductor {
                ior: positive(n),
                extinction: k,
            }
        }
        (RgbReduction::Mitsuba, K::Schlick) => {
            let (n, k) = crate::spectral::colour::mitsuba(index)?;
            Fresnel::Schlick {
                f0: super::f0_from_ior(positive(n), k),
            }
        }
        (RgbReduction::Filament, _) => {
            // A dielectric reads n only (FORMULAS.md §9).
            let mut i = index.clone();
            if kind == K::Dielectric {
                i.k = Curve::Constant(0.0);
            }
            Fresnel::Schlick {
                f0: crate::spectral::colour::filament_f0(&i)?.map(|x| x.clamp(0.0, 1.0)),
            }
        }
    })
}

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
