//! The factored spectral path (FORMULAS.md §9). For every model whose wavelength dependence
//! is its colours and its Fresnel term — all but HTSG (whose lobe depends on λ) and measured
//! data — `f(λ) = c_diff(λ)·X + c_spec(λ)·Y·F(λ, c)`. The engine evaluates X and Y once per
//! tuple, as the RGB evaluation of a *basis* material (`c_diff = (1, 0, 0)`,
//! `c_spec = (0, 1, 0)`, F = 1: channel 0 is X, channel 1 is Y, so D, G and K are computed
//! once), and the host forms F at each wavelength with the terms' own lane forms, looping
//! over λ so that the loop vectorises, at `c = v·h = |l + v|/2` from the tuple's directions
//! in f64.

use crate::material::{CookTorrance, Fresnel, Material, Model};
use crate::spectral::cie::Matrix3;

/// A colour reduction: the quadrature weights by wavelength and the XYZ → output matrix.
pub(super) type ColourWeights<'a> = (&'a [[f64; 3]], Matrix3);
use crate::terms::f;

/// The factor of the basis material's third channel (`Y · 2⁻⁶⁴`, exact in f32): it
/// overflows only beyond 6e57 and keeps full precision above 2⁻⁶² (2e-19), far below the
/// contract's floor of 1e-6.
const BASIS_SCALE: f64 = 1.0 / 18_446_744_073_709_551_616.0;

/// F's parameters at each wavelength, by wavelength (structure of arrays).
#[derive(Debug, Clone)]
enum Lambda {
    /// F = 1 (no Fresnel term, or a model without one).
    One,
    /// Schlick's F0(λ).
    Schlick(Vec<f32>),
    /// The exact dielectric: μ(λ) and μ² − 1.
    Dielectric(Vec<f64>, Vec<f64>),
    /// The exact conductor's lane constants `[n, k, e2rm1, e2r]` and `[c_a, c_eb, c_iq,
    /// c_bq]` (see [`f::conductor::LaneConstants`]), one array each.
    Conductor([Vec<f32>; 4], [Vec<f32>; 4]),
}

/// One material at every wavelength.
#[derive(Debug, Clone)]
struct PerLambda {
    diffuse: Vec<f32>,
    specular: Vec<f32>,
    fresnel: Lambda,
}

/// The basis materials and every material's parameters by wavelength.
#[derive(Debug, Clone)]
pub(super) struct Factored {
    /// What the engine evaluates: each material with unit colours in two channels and F = 1.
    pub basis: Vec<Material>,
    materials: Vec<PerLambda>,
    wavelengths: usize,
}

/// Whether `m`'s model is one the factored path serves.
fn factors(m: &Material) -> bool {
    !matches!(m.model, Model::Htsg(_) | Model::Measured(_))
}

impl Factored {
    /// The factored form of the triplet materials (`triplets[t][i]`: material `i` at the
    /// wavelengths `3t, 3t+1, 3t+2`), or `None` when some material's model does not factor.
    pub fn new(triplets: &[Vec<Material>], wavelengths: usize) -> Option<Factored> {
        let first = triplets.first()?;
        if !first.iter().all(factors) {
            return None;
        }
        let at = |i: usize, l: usize| (&triplets[l / 3][i], l % 3);
        let materials = (0..first.len())
            .map(|i| {
                let per = |g: &dyn Fn(&Material, usize) -> f32| {
                    (0..wavelengths)
                        .map(|l| {
                            let (m, j) = at(i, l);
                            g(m, j)
                        })
                        .collect::<Vec<f32>>()
                };
                let fresnel = match first[i].cook_torrance().map(|ct| ct.fresnel) {
                    None | Some(Fresnel::None) => Lambda::One,
                    Some(Fresnel::Schlick { .. }) => {
                        Lambda::Schlick(per(&|m, j| match m.cook_torrance().map(|c| c.fresnel) {
                            Some(Fresnel::Schlick { f0 }) => f0[j] as f32,
                            _ => unreachable!("one Fresnel kind at every wavelength"),
                        }))
                    }
                    Some(Fresnel::Dielectric { .. }) => {
                        let mu: Vec<f64> = (0..wavelengths)
                            .map(|l| {
                                let (m, j) = at(i, l);
                                match m.cook_torrance().map(|c| c.fresnel) {
                                    Some(Fresnel::Dielectric { ior }) => ior[j],
                                    _ => unreachable!("one Fresnel kind at every wavelength"),
                                }
                            })
                            .collect();
                        let m2 = mu.iter().map(|&m| f::dielectric::mu2m1(m)).collect();
                        Lambda::Dielectric(mu, m2)
                    }
                    Some(Fresnel::Conductor { .. }) => {
                        let lc = |l: usize| {
                            let (m, j) = at(i, l);
                            match m.cook_torrance().map(|c| c.fresnel) {
                                Some(Fresnel::Conductor { ior, extinction }) => {
                                    (f::conductor::LaneConstants::new(ior, extinction), j)
                                }
                                _ => unreachable!("one Fresnel kind at every wavelength"),
                            }
                        };
                        let all: Vec<_> = (0..wavelengths).map(lc).collect();
                        let col = |g: fn(&f::conductor::LaneConstants) -> [f32; 3]| {
                            all.iter().map(|(p, j)| g(p)[*j]).collect::<Vec<f32>>()
                        };
                        Lambda::Conductor(
                            [col(|p| p.n), col(|p| p.k), col(|p| p.e2rm1), col(|p| p.e2r)],
                            [
                                col(|p| p.c_a),
                                col(|p| p.c_eb),
                                col(|p| p.c_iq),
                                col(|p| p.c_bq),
                            ],
                        )
                    }
                };
                PerLambda {
                    diffuse: per(&|m, j| m.diffuse[j] as f32),
                    specular: per(&|m, j| m.specular[j] as f32),
                    fresnel,
                }
            })
            .collect();
        let basis = first
            .iter()
            .map(|m| {
                let mut b = m.clone();
                b.diffuse = [1.0, 0.0, 0.0];
                // Channel 2 holds Y scaled by 2⁻⁶⁴: where D·G·K alone exceeds f32::MAX
                // (K at grazing) the engine saturates channel 1, though F may bring f
                // back into range (water at cos 1e-45: 3 % of the true f was returned).
                b.specular = [0.0, 1.0, BASIS_SCALE];
                if let Model::CookTorrance(ct) = &m.model {
                    b.model = Model::CookTorrance(CookTorrance {
                        fresnel: Fresnel::None,
                        ..ct.clone()
                    });
                }
                b
            })
            .collect();
        Some(Factored {
            basis,
            materials,
            wavelengths,
        })
    }

    /// `f(λ)` of rows `[0, n)` into `out` (`n × W`), or their colour (`n × 3`, the
    /// quadrature weights `weights` and the XYZ → output matrix `to_output`), from the
    /// basis evaluation `xy` (`n × 3`); `row(r)` gives row r's L, V and material.
    pub fn combine(
        &self,
        xy: &[f32],
        row: &(dyn Fn(usize) -> ([f32; 3], [f32; 3], usize) + Sync),
        colour: Option<ColourWeights<'_>>,
        out: &mut [f32],
    ) {
        let cols = if colour.is_some() {
            3
        } else {
            self.wavelengths
        };
        let n = xy.len() / 3;
        let threads = std::thread::available_parallelism()
            .map_or(1, |p| p.get())
            .min(n.div_ceil(4096))
            .max(1);
        let per = n.div_ceil(threads);
        let arch = pulp::Arch::new();
        std::thread::scope(|s| {
            for (part, chunk) in out.chunks_mut(per * cols).enumerate() {
                let op = RowsOp {
                    this: self,
                    start: part * per,
                    xy,
                    row,
                    colour,
                    out: chunk,
                };
                // The loops over λ compiled for the widest vectors the CPU has (pulp).
                s.spawn(move || arch.dispatch(op));
            }
        });
    }

    #[inline(always)]
    fn row(
        &self,
        r: usize,
        xy: &[f32],
        row: &(dyn Fn(usize) -> ([f32; 3], [f32; 3], usize) + Sync),
        colour: Option<ColourWeights<'_>>,
        fl: &mut [f32],
        o: &mut [f32],
    ) {
        let (x, y) = (xy[3 * r], xy[3 * r + 1]);
        // Y itself, from the scaled channel where the unscaled one saturated (in f64, as is
        // the combination below: c_spec·Y·F may exceed f32 before F brings it down).
        let y64 = if y == f32::MAX {
            f64::from(xy[3 * r + 2]) / BASIS_SCALE
        } else {
            f64::from(y)
        };
        if x == 0.0 && y == 0.0 {
            o.fill(0.0); // invalid or below the horizon (or black): every λ is 0
            return;
        }
        let (l, v, mi) = row(r);
        let m = &self.materials[mi];
        // c = v·h = |l + v|/2 for unit l, v (h = (l + v)/|l + v|), in f64.
        let unit = |a: [f32; 3]| {
            let a = a.map(f64::from);
            let len = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
            a.map(|c| c / len)
        };
        let (l, v) = (unit(l), unit(v));
        let s = [l[0] + v[0], l[1] + v[1], l[2] + v[2]];
        let c = ((s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt() / 2.0).min(1.0);
        let s2 = (1.0 - c) * (1.0 + c);
        let w = self.wavelengths;
        // Every slice cut to w, so that the loops below carry no bounds checks and vectorise.
        let (d, sp, fl) = (&m.diffuse[..w], &m.specular[..w], &mut fl[..w]);
        match &m.fresnel {
            Lambda::One => fl.fill(1.0),
            Lambda::Schlick(f0) => {
                let omc = (s2 / (1.0 + c)) as f32;
                for (o, &f0) in fl.iter_mut().zip(&f0[..w]) {
                    *o = f::schlick::f_lane(omc, f0);
                }
            }
            Lambda::Dielectric(mu, m2) => {
                for ((o, &mu), &m2) in fl.iter_mut().zip(&mu[..w]).zip(&m2[..w]) {
                    *o = f::dielectric::f_lane(c, s2, mu, m2);
                }
            }
            Lambda::Conductor(nk, q) => {
                let (cf, s2f) = (c as f32, s2 as f32);
                let [n, k, a, b] = nk.each_ref().map(|v| &v[..w]);
                let [qa, qb, qc, qd] = q.each_ref().map(|v| &v[..w]);
                for j in 0..w {
                    fl[j] = f::conductor::f_lane_with(
                        cf,
                        s2f,
                        [n[j], k[j], a[j], b[j]],
                        [qa[j], qb[j], qc[j], qd[j]],
                    );
                }
            }
        }
        match colour {
            None => {
                let (o, x) = (&mut o[..w], f64::from(x));
                for j in 0..w {
                    let f = f64::from(d[j]) * x + f64::from(sp[j]) * y64 * f64::from(fl[j]);
                    // Beyond f32::MAX: f32::MAX (FORMULAS.md §1).
                    o[j] = f.min(f64::from(f32::MAX)) as f32;
                }
            }
            Some((weights, to_output)) => {
                let (weights, x) = (&weights[..w], f64::from(x));
                let mut xyz = [0f64; 3];
                for j in 0..w {
                    let f = f64::from(d[j]) * x + f64::from(sp[j]) * y64 * f64::from(fl[j]);
                    let wt = weights[j];
                    xyz[0] += f * wt[0];
                    xyz[1] += f * wt[1];
                    xyz[2] += f * wt[2];
                }
                for (c, row) in o.iter_mut().zip(to_output) {
                    let v = row[0] * xyz[0] + row[1] * xyz[1] + row[2] * xyz[2];
                    *c = v.clamp(-f64::from(f32::MAX), f64::from(f32::MAX)) as f32;
                }
            }
        }
    }
}

/// One thread's rows, as a `pulp` operation so that the loops over λ vectorise.
struct RowsOp<'a> {
    this: &'a Factored,
    start: usize,
    xy: &'a [f32],
    row: &'a (dyn Fn(usize) -> ([f32; 3], [f32; 3], usize) + Sync),
    colour: Option<ColourWeights<'a>>,
    out: &'a mut [f32],
}

impl pulp::WithSimd for RowsOp<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        let cols = if self.colour.is_some() {
            3
        } else {
            self.this.wavelengths
        };
        let mut fl = vec![0f32; self.this.wavelengths];
        for (k, o) in self.out.chunks_mut(cols).enumerate() {
            self.this
                .row(self.start + k, self.xy, self.row, self.colour, &mut fl, o);
        }
    }
}
