//! The judge judged: the f64 CPU reference (`src/reference/`) against an arbitrary-precision
//! evaluation of the contract (FORMULAS.md §1–§6) in 1024 bits (≈ 308 decimal digits).
//!
//! The exact side is written from the contract's formulas as printed, with none of the
//! reference's rearrangements: at 1024 bits a literal `1 − c²` or `μ² + c² − 1` loses at
//! most ~300 bits to cancellation (cosines down to the smallest f32 denormal, 1.4e-45), which
//! leaves far more than the 50 digits a 1e-12 check needs; an exact 0 (F of an index-matched
//! interface) then comes out below 1e-400 even after K ~ 1e89 multiplies it, under the 1e-250
//! floor below. Its inputs are the exact values
//! of the f32 numbers the reference receives, so nothing is excused by "the input was
//! rounded": the reference is judged against the exact value of the rounded input.
//!
//! Sample: every material of the stress corpus (`src/stress/corpus.rs`) in every case, four
//! times over (the corpus's own rows, deterministic), plus extreme grazing geometries below
//! the corpus's 1e-8 — exact mirror and off-mirror configurations with cosines 1e-4 … 1e-45
//! (f32 inputs whose cosine is exactly the small number: N = +z and a z-component that is
//! that number), for every corpus material.
//!
//! The bound. For every output (f per channel, D, G, F per channel, K) of every valid tuple:
//!
//! `|ref − exact| ≤ 1e-12·|exact| + 16·spread`,
//!
//! where `spread` is how far the exact value moves when every input component is perturbed
//! by a relative 2^-50 (≈ 8 ulps of f64; two deterministic sign patterns). The first term is
//! the formulas' own rounding (a few dozen operations, each ≤ 2^-53, far inside 1e-12). The
//! second is the input's conditioning at f64 resolution: the reference computes in f64, so
//! where the contract itself turns an 8-ulp change of the input into a large change of the
//! value — the critical angle of total internal reflection (`g² → 0`), the rim of a sharp lobe
//! where D = exp(−tan²δ/m²) with m = 1e-4, the exact directions of a cusp (`min` in the V-
//! cavity G, `max(0, r·v)` in Phong, the `a < 1.6` switch of smith-fast) — no f64 program can
//! do better than that spread, and the f32 engines do worse. Where the spread is below
//! 1e-14 relative (the value is well-conditioned) the check is therefore plain 1e-12
//! relative. Values below 1e-250 (1/sr or dimensionless) are compared at that absolute scale:
//! they are far below what the f32 outputs can carry and are where f64 `exp` goes subnormal.
//!
//! `cargo test --release --test judge -- --nocapture` prints the maximum relative error per
//! regime, separately for well-conditioned and conditioned tuples.

use astro_float::{BigFloat, Consts, RoundingMode};
use std::cell::RefCell;
use std::collections::BTreeMap;
use vkbrdf::material::{Convention, Distribution, Fresnel, Geometry, Material, Model, Roughness};
use vkbrdf::reference::{evaluate_tuple, Evaluation, Status};
use vkbrdf::stress::corpus;

/// FORMULAS.md §8 (HTSG) as printed, in the same arithmetic.
#[path = "judge/htsg.rs"]
mod htsg;

/// Working precision in bits.
const P: usize = 1024;
const RM: RoundingMode = RoundingMode::ToEven;

thread_local! {
    static CC: RefCell<Consts> = RefCell::new(Consts::new().expect("astro-float constants"));
}

// ---------------------------------------------------------------------------------------
// A thin wrapper for readable formulas.

#[derive(Clone, Debug)]
struct X(BigFloat);

fn x(v: f64) -> X {
    X(BigFloat::from_f64(v, P))
}

impl X {
    fn add(&self, o: &X) -> X {
        X(self.0.add(&o.0, P, RM))
    }
    fn sub(&self, o: &X) -> X {
        X(self.0.sub(&o.0, P, RM))
    }
    fn mul(&self, o: &X) -> X {
        X(self.0.mul(&o.0, P, RM))
    }
    fn div(&self, o: &X) -> X {
        X(self.0.div(&o.0, P, RM))
    }
    fn sq(&self) -> X {
        self.mul(self)
    }
    fn neg(&self) -> X {
        X(self.0.neg())
    }
    fn sqrt(&self) -> X {
        if self.is_zero() {
            return x(0.0);
        }
        X(self.0.sqrt(P, RM))
    }
    fn exp(&self) -> X {
        // Below e^-1e7 the value is far below any f64 and astro-float's exponent range is
        // not needed: 0 is exact enough.
        if self.lt(&x(-1e7)) {
            return x(0.0);
        }
        CC.with(|cc| X(self.0.exp(P, RM, &mut cc.borrow_mut())))
    }
    fn ln(&self) -> X {
        CC.with(|cc| X(self.0.ln(P, RM, &mut cc.borrow_mut())))
    }
    fn atan(&self) -> X {
        CC.with(|cc| X(self.0.atan(P, RM, &mut cc.borrow_mut())))
    }
    /// `self^e` for `self > 0`.
    fn powf(&self, e: f64) -> X {
        if e == 0.0 {
            return x(1.0);
        }
        self.ln().mul(&x(e)).exp()
    }
    fn is_zero(&self) -> bool {
        self.0.is_zero()
    }
    fn cmp(&self, o: &X) -> i64 {
        self.0.cmp(&o.0).expect("no NaN in the judge") as i64
    }
    fn lt(&self, o: &X) -> bool {
        self.cmp(o) < 0
    }
    fn le(&self, o: &X) -> bool {
        self.cmp(o) <= 0
    }
    fn pos(&self) -> bool {
        self.0.is_positive() && !self.is_zero()
    }
    fn abs(&self) -> X {
        X(self.0.abs())
    }
    fn min(&self, o: &X) -> X {
        if self.le(o) {
            self.clone()
        } else {
            o.clone()
        }
    }
    /// The nearest f64 (to within an ulp; enough for error figures).
    fn to_f64(&self) -> f64 {
        if self.is_zero() {
            return 0.0;
        }
        let (m, _, sign, e, _) = self.0.as_raw_parts().expect("finite");
        let top = *m.last().expect("mantissa") as f64 / 2f64.powi(64);
        let v = top * 2f64.powi(e.clamp(-1100, 1100));
        if sign == astro_float::Sign::Neg {
            -v
        } else {
            v
        }
    }
}

fn pi() -> X {
    CC.with(|cc| X(cc.borrow_mut().pi(P, RM)))
}

type V3 = [X; 3];

fn v3(a: [f64; 3]) -> V3 {
    a.map(x)
}
fn dot(a: &V3, b: &V3) -> X {
    a[0].mul(&b[0]).add(&a[1].mul(&b[1])).add(&a[2].mul(&b[2]))
}
fn cross(a: &V3, b: &V3) -> V3 {
    [
        a[1].mul(&b[2]).sub(&a[2].mul(&b[1])),
        a[2].mul(&b[0]).sub(&a[0].mul(&b[2])),
        a[0].mul(&b[1]).sub(&a[1].mul(&b[0])),
    ]
}
fn scale(a: &V3, s: &X) -> V3 {
    [a[0].mul(s), a[1].mul(s), a[2].mul(s)]
}
fn addv(a: &V3, b: &V3) -> V3 {
    [a[0].add(&b[0]), a[1].add(&b[1]), a[2].add(&b[2])]
}
fn subv(a: &V3, b: &V3) -> V3 {
    [a[0].sub(&b[0]), a[1].sub(&b[1]), a[2].sub(&b[2])]
}
fn norm(a: &V3) -> X {
    dot(a, a).sqrt()
}
fn unit(a: &V3) -> V3 {
    scale(a, &x(1.0).div(&norm(a)))
}

/// Complex numbers for the conductor.
#[derive(Clone)]
struct C(X, X);

impl C {
    fn real(r: X) -> C {
        C(r, x(0.0))
    }
    fn add(&self, o: &C) -> C {
        C(self.0.add(&o.0), self.1.add(&o.1))
    }
    fn sub(&self, o: &C) -> C {
        C(self.0.sub(&o.0), self.1.sub(&o.1))
    }
    fn mul(&self, o: &C) -> C {
        C(
            self.0.mul(&o.0).sub(&self.1.mul(&o.1)),
            self.0.mul(&o.1).add(&self.1.mul(&o.0)),
        )
    }
    fn norm_sqr(&self) -> X {
        self.0.sq().add(&self.1.sq())
    }
    fn div(&self, o: &C) -> C {
        let d = o.norm_sqr();
        C(
            self.0.mul(&o.0).add(&self.1.mul(&o.1)).div(&d),
            self.1.mul(&o.0).sub(&self.0.mul(&o.1)).div(&d),
        )
    }
    /// Principal square root: Re ≥ 0, Im with the sign of the input's Im (+ for Im = 0).
    fn sqrt(&self) -> C {
        let r = self.norm_sqr().sqrt();
        let re = r.add(&self.0).div(&x(2.0)).sqrt();
        let im = r.sub(&self.0).div(&x(2.0)).sqrt();
        if self.1.lt(&x(0.0)) {
            C(re, im.neg())
        } else {
            C(re, im)
        }
    }
}

// ---------------------------------------------------------------------------------------
// The contract, literally.

/// The exact outputs of one tuple.
struct Exact {
    status: Status,
    brdf: [X; 3],
    d: X,
    g: X,
    f: [X; 3],
    k: X,
}

struct Fr {
    l: V3,
    v: V3,
    n: V3,
    h: V3,
    cos_i: X,
    cos_o: X,
    cos_h: X,
    c: X,
    sin2_h: X,
    tb: Option<(V3, V3)>,
}

fn zero_out(status: Status) -> Exact {
    Exact {
        status,
        brdf: [x(0.0), x(0.0), x(0.0)],
        d: x(0.0),
        g: x(0.0),
        f: [x(0.0), x(0.0), x(0.0)],
        k: x(0.0),
    }
}

/// FORMULAS.md §1.
fn frame(raw: &[[f64; 4]; 3], t: Option<[f64; 3]>, aniso: bool) -> Result<Fr, Status> {
    let bad = |a: &[f64]| a.iter().any(|c| !c.is_finite()) || a.iter().all(|&c| c == 0.0);
    if raw.iter().any(|a| bad(&a[..3])) {
        return Err(Status::Invalid);
    }
    let [l, v, n] = raw.map(|a| unit(&v3([a[0], a[1], a[2]])));
    let tb = if aniso {
        let Some(t) = t else {
            return Err(Status::Invalid);
        };
        if bad(&t) {
            return Err(Status::Invalid);
        }
        let tv = v3(t);
        let perp = subv(&tv, &scale(&n, &dot(&n, &tv)));
        // |T − n(n·T)| ≤ 1e-12 |T|
        if norm(&perp).le(&x(1e-12).mul(&norm(&tv))) {
            return Err(Status::Invalid);
        }
        let t = unit(&perp);
        let b = cross(&n, &t);
        Some((t, b))
    } else {
        None
    };
    let cos_i = dot(&n, &l);
    let cos_o = dot(&n, &v);
    if !cos_i.pos() || !cos_o.pos() {
        return Err(Status::BelowHorizon);
    }
    let h = unit(&addv(&l, &v));
    let nxh = cross(&n, &h);
    Ok(Fr {
        cos_h: dot(&n, &h),
        c: dot(&v, &h),
        sin2_h: dot(&nxh, &nxh),
        l,
        v,
        n,
        h,
        cos_i,
        cos_o,
        tb,
    })
}

/// erfc(a) for a > 0: the Taylor series of erf with enough guard bits for its cancellation
/// (terms grow to ~e^{a²}) up to a = 12; beyond, the asymptotic series, whose smallest term
/// (~e^{-a²} < 2^-207 relative) bounds its error.
fn erfc(a: &X) -> X {
    let a2 = a.sq();
    if a.le(&x(12.0)) {
        let mut sum = x(0.0);
        let mut term = a.clone(); // (-1)^n a^(2n+1) / n!
        let mut n = 0u32;
        loop {
            let t = term.div(&x(2.0 * n as f64 + 1.0));
            sum = sum.add(&t);
            if n > 10 && t.abs().lt(&x(2f64.powi(-1000))) {
                break;
            }
            n += 1;
            term = term.mul(&a2).div(&x(n as f64)).neg();
        }
        x(1.0).sub(&sum.mul(&x(2.0)).div(&pi().sqrt()))
    } else {
        let lead = a2.neg().exp().div(&a.mul(&pi().sqrt()));
        let mut sum = x(1.0);
        let mut term = x(1.0);
        let mut n = 1u32;
        loop {
            let next = term.mul(&x(-(2.0 * n as f64 - 1.0))).div(&a2.mul(&x(2.0)));
            if next.abs().le(&x(2f64.powi(-(P as i32)))) || term.abs().le(&next.abs()) {
                break;
            }
            sum = sum.add(&next);
            term = next;
            n += 1;
        }
        lead.mul(&sum)
    }
}

/// `tan²θ(w)` scaled by the roughness (§3): `m² |n×w|²/(n·w)²`, or anisotropic
/// `(mx² (w·t)² + my² (w·b)²)/(n·w)²`.
fn rough_tan2(fr: &Fr, w: &V3, cos_w: &X, r: Roughness) -> X {
    match (r, &fr.tb) {
        (Roughness::Anisotropic(mx, my), Some((t, b))) => x(mx)
            .sq()
            .mul(&dot(w, t).sq())
            .add(&x(my).sq().mul(&dot(w, b).sq()))
            .div(&cos_w.sq()),
        _ => {
            let nxw = cross(&fr.n, w);
            x(r.xy().0).sq().mul(&dot(&nxw, &nxw)).div(&cos_w.sq())
        }
    }
}

fn lambda(dist: Distribution, q2: &X) -> X {
    match dist {
        Distribution::Beckmann(_) => {
            if q2.is_zero() {
                return x(0.0);
            }
            let a = x(1.0).div(&q2.sqrt());
            if x(1e4).lt(&a) {
                // Λ < e^{-1e8}: zero to far more than any precision G = 1/(1 + Λ) can show.
                return x(0.0);
            }
            // (erf(a) − 1)/2 + exp(−a²)/(2a√π)
            erfc(&a)
                .neg()
                .div(&x(2.0))
                .add(&a.sq().neg().exp().div(&x(2.0).mul(&a).mul(&pi().sqrt())))
        }
        _ => x(-1.0).add(&x(1.0).add(q2).sqrt()).div(&x(2.0)),
    }
}

fn smith_fast_g1(q2: &X) -> X {
    if q2.is_zero() {
        return x(1.0);
    }
    let a = x(1.0).div(&q2.sqrt());
    if a.lt(&x(1.6)) {
        x(3.535)
            .mul(&a)
            .add(&x(2.181).mul(&a.sq()))
            .div(&x(1.0).add(&x(2.276).mul(&a)).add(&x(2.577).mul(&a.sq())))
    } else {
        x(1.0)
    }
}

fn fresnel(c: &X, f: &Fresnel, ch: usize) -> X {
    match *f {
        Fresnel::None => x(1.0),
        Fresnel::Dielectric { ior } => {
            let mu = x(ior[ch]);
            let g2 = mu.sq().add(&c.sq()).sub(&x(1.0));
            if g2.lt(&x(0.0)) {
                return x(1.0);
            }
            let g = g2.sqrt();
            let a = g.sub(c).div(&g.add(c));
            let b = c
                .mul(&g.add(c))
                .sub(&x(1.0))
                .div(&c.mul(&g.sub(c)).add(&x(1.0)));
            x(0.5).mul(&a.sq()).mul(&x(1.0).add(&b.sq()))
        }
        Fresnel::Conductor { ior, extinction } => {
            let eta = C(x(ior[ch]), x(extinction[ch]));
            let cc = C::real(c.clone());
            let sin2_t = C::real(x(1.0).sub(&c.sq())).div(&eta.mul(&eta));
            let cos_t = C::real(x(1.0)).sub(&sin2_t).sqrt();
            let ec = eta.mul(&cc);
            let r_par = ec.sub(&cos_t).div(&ec.add(&cos_t));
            let ect = eta.mul(&cos_t);
            let r_perp = cc.sub(&ect).div(&cc.add(&ect));
            r_par.norm_sqr().add(&r_perp.norm_sqr()).div(&x(2.0))
        }
        Fresnel::Schlick { f0 } => {
            let f0 = x(f0[ch]);
            let om = x(1.0).sub(c);
            f0.add(&x(1.0).sub(&f0).mul(&om.sq().sq().mul(&om)))
        }
    }
}

/// FORMULAS.md §6 for one tuple, from the raw (f32-valued) inputs.
fn exact(raw: &[[f64; 4]; 3], t: Option<[f64; 3]>, m: &Material) -> Exact {
    let fr = match frame(raw, t, m.is_anisotropic()) {
        Ok(fr) => fr,
        Err(s) => return zero_out(s),
    };
    let diffuse = m.diffuse.map(|c| x(c).div(&pi()));
    let lobe_model = |lobe: X| Exact {
        status: Status::Valid,
        brdf: std::array::from_fn(|c| diffuse[c].add(&x(m.specular[c]).mul(&lobe))),
        d: lobe,
        g: x(1.0),
        f: [x(1.0), x(1.0), x(1.0)],
        k: x(1.0),
    };
    let tan2_h = fr.sin2_h.div(&fr.cos_h.sq());
    let hloc = fr
        .tb
        .as_ref()
        .map(|(t, b)| (dot(&fr.h, t), dot(&fr.h, b), fr.cos_h.clone()));
    let aniso_slope = |mx: f64, my: f64| {
        let (hx, hy, hz) = hloc.clone().expect("anisotropic frame");
        hx.div(&x(mx)).sq().add(&hy.div(&x(my)).sq()).div(&hz.sq())
    };
    match &m.model {
        Model::Lambert => lobe_model(x(0.0)),
        Model::Phong { exponent } => {
            let r = subv(&scale(&fr.n, &x(2.0).mul(&fr.cos_i)), &fr.l);
            let rv = dot(&r, &fr.v);
            let p = if *exponent == 0.0 {
                x(1.0)
            } else if rv.pos() {
                rv.powf(*exponent)
            } else {
                x(0.0)
            };
            lobe_model(x(exponent + 2.0).div(&x(2.0).mul(&pi())).mul(&p))
        }
        Model::BlinnPhong { exponent } => {
            lobe_model(fr.cos_h.powf(*exponent).div(&pi().mul(&fr.cos_i)))
        }
        Model::Rtr { exponent } => lobe_model(
            x(exponent + 8.0)
                .div(&x(8.0).mul(&pi()))
                .mul(&fr.cos_h.powf(*exponent)),
        ),
        Model::Ward { roughness } => {
            let (mx, my) = roughness.xy();
            let arg = match roughness {
                Roughness::Anisotropic(..) => aniso_slope(mx, my).neg(),
                Roughness::Isotropic(m) => tan2_h.div(&x(*m).sq()).neg(),
            };
            lobe_model(
                arg.exp().div(
                    &x(4.0)
                        .mul(&pi())
                        .mul(&x(mx))
                        .mul(&x(my))
                        .mul(&fr.cos_i.mul(&fr.cos_o).sqrt()),
                ),
            )
        }
        Model::CookTorrance(ct) => {
            let cos4 = fr.cos_h.sq().sq();
            let d = match ct.distribution {
                Distribution::Gaussian { m } => {
                    let delta = fr.sin2_h.sqrt().div(&fr.cos_h).atan();
                    delta.div(&x(m)).sq().neg().exp()
                }
                Distribution::Beckmann(Roughness::Isotropic(m)) => {
                    let k = match ct.convention {
                        Convention::Seed => x(4.0),
                        Convention::CookTorrance1982 => x(1.0),
                        Convention::Modern => pi(),
                    };
                    tan2_h
                        .div(&x(m).sq())
                        .neg()
                        .exp()
                        .div(&k.mul(&x(m).sq()).mul(&cos4))
                }
                Distribution::Beckmann(Roughness::Anisotropic(mx, my)) => aniso_slope(mx, my)
                    .neg()
                    .exp()
                    .div(&pi().mul(&x(mx)).mul(&x(my)).mul(&cos4)),
                Distribution::Ggx(Roughness::Isotropic(m)) => {
                    let m2 = x(m).sq();
                    m2.div(&pi().mul(&cos4).mul(&m2.add(&tan2_h).sq()))
                }
                Distribution::Ggx(Roughness::Anisotropic(mx, my)) => {
                    let (hx, hy, hz) = hloc.clone().expect("anisotropic frame");
                    let s = hx.div(&x(mx)).sq().add(&hy.div(&x(my)).sq()).add(&hz.sq());
                    x(1.0).div(&pi().mul(&x(mx)).mul(&x(my)).mul(&s.sq()))
                }
                Distribution::Blinn { exponent } => x(exponent + 2.0)
                    .div(&x(2.0).mul(&pi()))
                    .mul(&fr.cos_h.powf(exponent)),
                Distribution::Charlie { m } => {
                    let inv_m = x(1.0).div(&x(m));
                    // sin_h^(1/m) = exp(ln(sin2_h) / (2m)), the exponent exact.
                    let p = if fr.sin2_h.is_zero() {
                        x(0.0)
                    } else {
                        fr.sin2_h.ln().mul(&inv_m).div(&x(2.0)).exp()
                    };
                    x(2.0).add(&inv_m).div(&x(2.0).mul(&pi())).mul(&p)
                }
            };
            let rough = match ct.distribution {
                Distribution::Beckmann(r) | Distribution::Ggx(r) => Some(r),
                _ => None,
            };
            let q2 = |w: &V3, cw: &X| rough_tan2(&fr, w, cw, rough.expect("validated"));
            let g = match ct.geometry {
                Geometry::None => x(1.0),
                Geometry::CookTorrance => {
                    let k = x(2.0).mul(&fr.cos_h).div(&fr.c);
                    x(1.0).min(&k.mul(&fr.cos_o)).min(&k.mul(&fr.cos_i))
                }
                Geometry::Smith => {
                    let lo = lambda(ct.distribution, &q2(&fr.v, &fr.cos_o));
                    let li = lambda(ct.distribution, &q2(&fr.l, &fr.cos_i));
                    x(1.0)
                        .div(&x(1.0).add(&lo))
                        .mul(&x(1.0).div(&x(1.0).add(&li)))
                }
                Geometry::SmithCorrelated => {
                    let lo = lambda(ct.distribution, &q2(&fr.v, &fr.cos_o));
                    let li = lambda(ct.distribution, &q2(&fr.l, &fr.cos_i));
                    x(1.0).div(&x(1.0).add(&lo).add(&li))
                }
                Geometry::SmithFast => {
                    smith_fast_g1(&q2(&fr.v, &fr.cos_o)).mul(&smith_fast_g1(&q2(&fr.l, &fr.cos_i)))
                }
                Geometry::SchlickSmith => {
                    // k = m √(2/π) (Beckmann) or m/2 (GGX), exact.
                    let m = x(rough.expect("validated").xy().0);
                    let k = match ct.distribution {
                        Distribution::Ggx(_) => m.div(&x(2.0)),
                        _ => m.mul(&x(2.0).div(&pi()).sqrt()),
                    };
                    let g1 = |c: &X| c.div(&c.add(&k.mul(&x(1.0).sub(c))));
                    g1(&fr.cos_o).mul(&g1(&fr.cos_i))
                }
                Geometry::Neubelt => {
                    let p = fr.cos_i.mul(&fr.cos_o);
                    p.div(&fr.cos_i.add(&fr.cos_o).sub(&p))
                }
            };
            let f: [X; 3] = std::array::from_fn(|ch| fresnel(&fr.c, &ct.fresnel, ch));
            let k = match ct.convention {
                Convention::Seed => x(1.0).div(&fr.cos_o),
                Convention::CookTorrance1982 => x(1.0).div(&pi().mul(&fr.cos_i).mul(&fr.cos_o)),
                Convention::Modern => x(1.0).div(&x(4.0).mul(&fr.cos_i).mul(&fr.cos_o)),
            };
            let brdf = std::array::from_fn(|ch| {
                x(ct.diffuse_weight).mul(&diffuse[ch]).add(
                    &x(ct.specular_weight)
                        .mul(&x(m.specular[ch]))
                        .mul(&d)
                        .mul(&g)
                        .mul(&f[ch])
                        .mul(&k),
                )
            });
            Exact {
                status: Status::Valid,
                brdf,
                d,
                g,
                f,
                k,
            }
        }
        Model::Measured(_) => unreachable!("the corpus has no measured material"),
        Model::Htsg(p) => htsg::exact(&fr, p, &diffuse),
    }
}

const NAMES: [&str; 9] = ["f_r", "f_g", "f_b", "D", "G", "F_r", "F_g", "F_b", "K"];

fn all_outputs(e: &Exact) -> Vec<X> {
    let mut v: Vec<X> = e.brdf.to_vec();
    v.push(e.d.clone());
    v.push(e.g.clone());
    v.extend(e.f.iter().cloned());
    v.push(e.k.clone());
    v
}

fn ref_outputs(e: &Evaluation) -> [f64; 9] {
    [
        e.brdf[0], e.brdf[1], e.brdf[2], e.d, e.g, e.f[0], e.f[1], e.f[2], e.k,
    ]
}

/// Scale below which values are compared absolutely (see the module docs).
const TINY: f64 = 1e-250;
/// The formula-rounding part of the bound.
const TOL: f64 = 1e-12;
/// Relative input perturbation of the spread.
const PERTURB: f64 = 1.0 / (1u64 << 50) as f64;

fn perturbed(
    raw: &[[f64; 4]; 3],
    t: Option<[f64; 3]>,
    pattern: u32,
) -> ([[f64; 4]; 3], Option<[f64; 3]>) {
    // Deterministic signs from the bits of a small hash of (pattern, component).
    let sign = |k: u32| {
        let h = (k.wrapping_mul(0x9E37_79B9) ^ pattern.wrapping_mul(0x85EB_CA6B)).rotate_left(13);
        if h & 0x100 != 0 {
            1.0
        } else {
            -1.0
        }
    };
    let mut r = *raw;
    for (i, a) in r.iter_mut().enumerate() {
        for (j, c) in a.iter_mut().take(3).enumerate() {
            *c *= 1.0 + sign((3 * i + j) as u32) * PERTURB;
        }
    }
    let t = t.map(|t| {
        let mut t = t;
        for (j, c) in t.iter_mut().enumerate() {
            *c *= 1.0 + sign(9 + j as u32) * PERTURB;
        }
        t
    });
    (r, t)
}

/// Raw f32 inputs of one tuple: L, V, N and the tangent.
type Raw32 = ([f32; 3], [f32; 3], [f32; 3], Option<[f32; 3]>);

/// One judged tuple: (worst relative error over the outputs, worst spread, which output).
struct Verdict {
    err: f64,
    spread: f64,
    worst: usize,
    ok: bool,
    status_ok: bool,
}

fn judge_one(raw32: Raw32, m: &Material) -> Verdict {
    let (l, v, n, t) = raw32;
    let w = |a: [f32; 3]| [a[0] as f64, a[1] as f64, a[2] as f64, 0.0];
    let raw = [w(l), w(v), w(n)];
    let t64 = t.map(|t| t.map(f64::from));
    let tuple = vkbrdf::batch::Tuple {
        l,
        v,
        n,
        material: 0,
        t,
    };
    let got = evaluate_tuple(&tuple, m);
    let want = exact(&raw, t64, m);
    if got.status != want.status {
        return Verdict {
            err: f64::INFINITY,
            spread: 0.0,
            worst: 0,
            ok: false,
            status_ok: false,
        };
    }
    if want.status != Status::Valid {
        let zero = ref_outputs(&got).iter().all(|&o| o == 0.0);
        return Verdict {
            err: if zero { 0.0 } else { f64::INFINITY },
            spread: 0.0,
            worst: 0,
            ok: zero,
            status_ok: true,
        };
    }
    let exact_out = all_outputs(&want);
    let mut spread = [0f64; 9];
    for pattern in 0..2 {
        let (pr, pt) = perturbed(&raw, t64, pattern);
        let p = exact(&pr, pt, m);
        if p.status != Status::Valid {
            spread = [f64::INFINITY; 9];
            break;
        }
        for (k, (a, b)) in all_outputs(&p).iter().zip(&exact_out).enumerate() {
            let s = a.sub(b).abs().div(&b.abs().max_with(TINY)).to_f64();
            spread[k] = spread[k].max(s);
        }
    }
    let mut verdict = Verdict {
        err: 0.0,
        spread: 0.0,
        worst: 0,
        ok: true,
        status_ok: true,
    };
    for (k, (g, e)) in ref_outputs(&got).iter().zip(&exact_out).enumerate() {
        let err = if g.is_finite() {
            x(*g).sub(e).abs().div(&e.abs().max_with(TINY)).to_f64()
        } else {
            f64::INFINITY
        };
        if err > TOL + 16.0 * spread[k] {
            verdict.ok = false;
        }
        if err > verdict.err {
            verdict.err = err;
            verdict.worst = k;
        }
        verdict.spread = verdict.spread.max(spread[k]);
    }
    verdict
}

trait MaxWith {
    fn max_with(&self, floor: f64) -> X;
}
impl MaxWith for X {
    fn max_with(&self, floor: f64) -> X {
        let f = x(floor);
        if self.lt(&f) {
            f
        } else {
            self.clone()
        }
    }
}

/// The extreme-grazing tuples: N = +z (times 2), and f32 directions whose z-component is
/// exactly the cosine, so the f32 input's cosine is that small number.
fn extreme_grazing(materials: usize) -> Vec<(String, usize, Raw32)> {
    let mut out = Vec::new();
    let cosines: [f32; 8] = [1e-4, 1e-8, 1e-12, 1e-20, 1e-30, 1e-38, 1e-41, 1e-45];
    for mi in 0..materials {
        for (ci, &c) in cosines.iter().enumerate() {
            let phi = 0.37 + 0.91 * (mi * 8 + ci) as f64;
            let (s, co) = (phi.sin() as f32, phi.cos() as f32);
            let n = [0.0, 0.0, 2.0];
            let t = Some([0.6, -0.2, 0.4]);
            // exact mirror: h = n exactly, c = cos_i = cos_o
            out.push((
                format!("mirror cos {c:e}"),
                mi,
                ([co, s, c], [-co, -s, c], n, t),
            ));
            // both grazing, 3° off the mirror azimuth
            let p2 = phi + std::f64::consts::PI + 0.05;
            out.push((
                format!("off-mirror cos {c:e}"),
                mi,
                (
                    [co, s, c],
                    [p2.cos() as f32, p2.sin() as f32, c * 3.0],
                    n,
                    t,
                ),
            ));
            // one grazing, the other at 45°
            out.push((
                format!("one grazing cos {c:e}"),
                mi,
                ([co, s, c], [-0.5, 0.2, 0.6], n, t),
            ));
        }
    }
    out
}

#[test]
fn reference_matches_the_arbitrary_precision_contract() {
    let materials = corpus::materials();
    let m = materials.len();
    // Every material in every case, four times over: rows 0 .. 40 m of seed 7.
    let (_, batch, cases) = corpus::corpus_rows(0..40 * m, 7);
    type Key = (String, bool);
    let mut stats: BTreeMap<Key, (usize, f64, String)> = BTreeMap::new();
    let mut failures = Vec::new();
    let mut record = |regime: String, mat: &Material, v: Verdict, what: String| {
        let conditioned = v.spread > 1e-14;
        let e = stats
            .entry((regime.clone(), conditioned))
            .or_insert((0, 0.0, String::new()));
        e.0 += 1;
        if v.err > e.1 || (v.err.is_nan()) {
            e.1 = v.err;
            e.2 = format!("{} {} ({what})", mat.name, NAMES[v.worst]);
        }
        if !v.ok && failures.len() < 40 {
            failures.push(format!(
                "{regime}: {} {}: rel err {:.3e}, spread {:.3e}, status ok {} ({what})",
                mat.name, NAMES[v.worst], v.err, v.spread, v.status_ok
            ));
        }
    };
    for (i, case) in cases.iter().enumerate() {
        let t = batch.tuple(i);
        let mat = &materials[t.material];
        let v = judge_one((t.l, t.v, t.n, t.t), mat);
        record(format!("{case:?}"), mat, v, format!("corpus row {i}"));
    }
    for (label, mi, tuple) in extreme_grazing(m) {
        let v = judge_one(tuple, &materials[mi]);
        let regime = format!(
            "extreme grazing {}",
            label.split(" cos ").next().unwrap_or("")
        );
        record(regime, &materials[mi], v, label);
    }
    println!("| regime | conditioned | tuples | max rel err | worst |");
    println!("|---|---|---|---|---|");
    for ((regime, cond), (count, err, worst)) in &stats {
        println!(
            "| {regime} | {} | {count} | {err:.3e} | {worst} |",
            if *cond { "yes" } else { "no" }
        );
    }
    assert!(
        failures.is_empty(),
        "{} outputs outside |err| <= 1e-12 + 16 spread:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
