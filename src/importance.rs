//! The host's importance sampler for the albedo and DFG tables' integrals (the method is
//! stated in [`crate::table::albedo`]): Hammersley points, mapped to microfacet normals
//! (GGX through its visible normals, Heitz 2018; Beckmann through `D cos_h`), and each
//! sample's `l` and weight `cos_i / pdf(l)` computed in f64 from the f32 directions a
//! backend reads. The tables use it to build tuples; the CPU engine makes the same samples
//! inside its workers ([`crate::backend::GeneratedDirections::importance_sums`]), so both
//! paths weight every sample alike.

use crate::error::{Error, Result};
use crate::material::DistributionKind;
use crate::terms::d::{beckmann, ggx};
use crate::vector::{cross, dot, normalize_reciprocal};
use std::f64::consts::{PI, TAU};

/// The microfacet distribution of an integrated table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Lobe {
    /// GGX / Trowbridge–Reitz, sampled by its visible normals.
    Ggx,
    /// Beckmann (modern convention, `k = π`), sampled by `D cos_h`.
    Beckmann,
}

impl Lobe {
    /// The sampler of distribution `d`, or why the integrators cannot take it: each needs
    /// an importance sampler of its own, and only GGX and Beckmann have one.
    pub fn of(d: DistributionKind) -> Result<Lobe> {
        match d {
            DistributionKind::Ggx => Ok(Lobe::Ggx),
            DistributionKind::Beckmann => Ok(Lobe::Beckmann),
            other => Err(Error::Table(format!(
                "--distribution {}: the albedo and DFG integrators importance-sample the \
                 distribution, and only ggx and beckmann have a sampler; use one of those \
                 (or evaluate `{}` through `vkbrdf eval` / `table slice`)",
                other.toml_name(),
                other.toml_name()
            ))),
        }
    }

    /// The materials-file name (`ggx`, `beckmann`).
    pub fn name(self) -> &'static str {
        match self {
            Lobe::Ggx => "ggx",
            Lobe::Beckmann => "beckmann",
        }
    }
}

/// How an integrated table draws its microfacet normals.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Sampler {
    /// The project's integrator: GGX by its visible normals (Heitz 2018), Beckmann by
    /// `D cos_h`, from the Hammersley points of [`hammersley`] (converged to the accuracy
    /// [`crate::table::albedo::DEFAULT_SAMPLES`] states).
    Visible,
    /// The engines' integrator (GGX only): `h` drawn by `D cos_h` from the point
    /// `(k/N, radical inverse₂(k))` with `φ = 2π k/N` and
    /// `cos²θ = (1 − u₂)/(1 + (α² − 1) u₂)` — what UE4's `IntegrateBRDF` (Karis 2013) and
    /// Filament's DFG generator do. With their sample count a table reproduces their LUT
    /// texel for texel, their quasi-Monte Carlo error included (up to ~6e-3 at 1024
    /// points near grazing view against a converged integral).
    Engine,
}

/// Point `k` of the `n`-point Hammersley set, `((k + ½)/n, radical inverse₂(k))`.
pub fn hammersley(k: u32, n: u32) -> (f64, f64) {
    (
        (f64::from(k) + 0.5) / f64::from(n),
        f64::from(k.reverse_bits()) * (1.0 / 4_294_967_296.0),
    )
}

/// A Hammersley point `(u1, u2)` in the forms the two mappings read: computed once per
/// sample index and shared by every `(μ, α)` point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnitSample {
    /// `(√u1 cos 2πu2, √u1 sin 2πu2)`: the point on the unit disk (GGX).
    disk: [f64; 2],
    /// `√(1 − disk₀²)`: half the disk's chord at `disk₀` (GGX).
    chord: f64,
    /// `−ln(1 − u1)`: Beckmann's `tan²θ / α²`.
    neg_log: f64,
    /// `(cos 2πu2, sin 2πu2)` (Beckmann).
    phi: [f64; 2],
    /// `(cos 2πk/N, sin 2πk/N, radical inverse₂(k))` ([`Sampler::Engine`]).
    engine: [f64; 3],
}

impl UnitSample {
    /// The columns [`View::lane_samples`] reads for `lobe`: GGX `(√u1 cos 2πu2,
    /// √u1 sin 2πu2, chord)`, Beckmann `(−ln(1 − u1), cos 2πu2, sin 2πu2)`.
    pub fn columns(&self, lobe: Lobe) -> [f64; 3] {
        match lobe {
            Lobe::Ggx => [self.disk[0], self.disk[1], self.chord],
            Lobe::Beckmann => [self.neg_log, self.phi[0], self.phi[1]],
        }
    }

    /// Point `k` of `n` ([`hammersley`]).
    pub fn new(k: u32, n: u32) -> UnitSample {
        let (u1, u2) = hammersley(k, n);
        let (sin, cos) = (TAU * u2).sin_cos();
        let r = u1.sqrt();
        UnitSample {
            disk: [r * cos, r * sin],
            chord: (1.0 - r * r * cos * cos).max(0.0).sqrt(),
            neg_log: -(-u1).ln_1p(),
            phi: [cos, sin],
            engine: {
                let (s, c) = (TAU * f64::from(k) / f64::from(n)).sin_cos();
                [c, s, u2]
            },
        }
    }
}

/// The sampling constants of one `(μ, α)` point, computed once for all its samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    lobe: Lobe,
    sampler: Sampler,
    alpha: f64,
    /// `v = (√(1−μ²), 0, μ)`.
    pub(crate) v: [f64; 3],
    /// `v` as the backend reads it: rounded to f32, normalised.
    vf: [f64; 3],
    /// `G1(v)` of GGX (Smith, uncorrelated: the visible-normal density's own G1).
    pub(crate) g1: f64,
    /// The hemisphere frame of the stretched view (GGX): `t1`, `t2`, `v_h`, and
    /// `s = (1 + v_h·z)/2`.
    pub(crate) frame: [[f64; 3]; 3],
    pub(crate) s: f64,
}

impl View {
    /// The constants for view cosine `mu` and roughness `alpha` ([`Sampler::Visible`]).
    pub fn new(lobe: Lobe, mu: f64, alpha: f64) -> View {
        View::sampled(lobe, Sampler::Visible, mu, alpha)
    }

    /// The constants for view cosine `mu` and roughness `alpha`, drawing with `sampler`
    /// ([`Sampler::Engine`] draws GGX whatever `lobe` says: [`crate::table::albedo::integrate_with`] refuses
    /// Beckmann with it).
    pub fn sampled(lobe: Lobe, sampler: Sampler, mu: f64, alpha: f64) -> View {
        let v = [(1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu];
        let vf = normalize_reciprocal(as_f32(v));
        let tan2_o = (vf[0] * vf[0] + vf[1] * vf[1]) / (vf[2] * vf[2]);
        // Heitz 2018 listing 1: the view stretched to the hemisphere configuration and an
        // orthonormal basis around it.
        let vh = normalize_reciprocal([alpha * v[0], alpha * v[1], v[2]]);
        let len2 = vh[0] * vh[0] + vh[1] * vh[1];
        let t1 = if len2 > 0.0 {
            let inv = 1.0 / len2.sqrt();
            [-vh[1] * inv, vh[0] * inv, 0.0]
        } else {
            [1.0, 0.0, 0.0]
        };
        View {
            lobe,
            sampler,
            alpha,
            v,
            vf,
            g1: 1.0 / (1.0 + ggx::lambda(alpha * alpha * tan2_o)),
            frame: [t1, cross(vh, t1), vh],
            s: 0.5 * (1.0 + vh[2]),
        }
    }

    /// Whether [`View::lane_samples`] makes this view's samples (the project's sampler,
    /// [`Sampler::Visible`], of either lobe).
    pub fn has_lanes(&self) -> bool {
        self.sampler == Sampler::Visible
    }

    /// The lobe it samples.
    pub fn lobe(&self) -> Lobe {
        self.lobe
    }

    /// The microfacet normal of unit sample `u`: GGX by Heitz 2018, "Sampling the GGX
    /// Distribution of Visible Normals" (JCGT 7(4)), density `G1(v) max(0, v·h) D(h)/cos_o`;
    /// Beckmann by `D(h) cos_h`, `tan²θ = −α² ln(1 − u1)`, `φ = 2π u2`.
    pub fn normal(&self, u: &UnitSample) -> [f64; 3] {
        let a = self.alpha;
        if self.sampler == Sampler::Engine {
            let [cos_phi, sin_phi, u2] = u.engine;
            // (α² − 1) as (α − 1)(α + 1): no cancellation for α near 1.
            let cos2 = ((1.0 - u2) / (1.0 + (a - 1.0) * (a + 1.0) * u2)).clamp(0.0, 1.0);
            let sin = (1.0 - cos2).sqrt();
            return [sin * cos_phi, sin * sin_phi, cos2.sqrt()];
        }
        let [c0, c1, c2] = u.columns(self.lobe);
        self.lane_normal(c0, c1, c2)
    }

    /// The normal of one unit sample given as its columns ([`UnitSample::columns`]): the
    /// one formula behind [`View::normal`] and [`View::lane_samples`].
    #[inline(always)]
    fn lane_normal(&self, c0: f64, c1: f64, c2: f64) -> [f64; 3] {
        let (m, inv_mm) = self.lane_normal_unnormalised(c0, c1, c2);
        m.map(|x| x * inv_mm.sqrt())
    }

    /// The microfacet normal of one unit sample's columns before its normalisation, and
    /// one over its squared length: GGX's point on the stretched hemisphere, unstretched
    /// (Heitz 2018, listing 3); Beckmann's `(tan θ cos φ, tan θ sin φ, 1)`, whose squared
    /// length is `1 + tan²θ`.
    #[inline(always)]
    fn lane_normal_unnormalised(&self, c0: f64, c1: f64, c2: f64) -> ([f64; 3], f64) {
        let a = self.alpha;
        match self.lobe {
            Lobe::Ggx => {
                let [t1, t2, vh] = self.frame;
                let (p1, disk1, chord) = (c0, c1, c2);
                let p2 = (1.0 - self.s) * chord + self.s * disk1;
                let p3 = (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
                let n: [f64; 3] = std::array::from_fn(|i| p1 * t1[i] + p2 * t2[i] + p3 * vh[i]);
                let m = [a * n[0], a * n[1], n[2].max(0.0)];
                (m, 1.0 / dot(m, m))
            }
            Lobe::Beckmann => {
                let (neg_log, cos_phi, sin_phi) = (c0, c1, c2);
                let tan2 = a * a * neg_log;
                let tan = tan2.sqrt();
                ([tan * cos_phi, tan * sin_phi, 1.0], 1.0 / (1.0 + tan2))
            }
        }
    }

    /// The sample of `u`, or `None` when `l` falls below the horizon (f = 0 there). The
    /// weight is computed from the f32-rounded directions the backend evaluates, so
    /// `f(l) · weight` is consistent: GGX `cos_i / (G1(v) D(h) / (4 cos_o))`, Beckmann
    /// `cos_i / (D(h) cos_h / (4 c))`.
    pub fn sample(&self, u: &UnitSample) -> Option<Sample> {
        if self.has_lanes() {
            let mut s = Samples::<1>::default();
            let [a, b, c] = u.columns(self.lobe);
            self.lane_samples(&[a], &[b], &[c], &mut s);
            if !s.redo[0] {
                return s.ok[0].then_some(Sample {
                    l: [s.l[0][0], s.l[1][0], s.l[2][0]],
                    weight: s.weight[0],
                    c: s.c[0],
                });
            }
        }
        self.sample_one(u)
    }

    /// [`View::sample`] lane by lane with libm's `exp` and the reference's guarded D:
    /// the engines' LUT sampler, and the Beckmann lanes whose D leaves the range of
    /// [`View::lane_samples`]' direct form (`redo`).
    pub fn sample_one(&self, u: &UnitSample) -> Option<Sample> {
        let (v, vf) = (self.v, self.vf);
        let h = self.normal(u);
        let vh = dot(v, h);
        let l: [f64; 3] = std::array::from_fn(|i| 2.0 * vh * h[i] - v[i]);
        let lf = normalize_reciprocal(as_f32(l));
        let (cos_i, cos_o) = (lf[2], vf[2]);
        if cos_i.is_nan() || cos_i <= 0.0 {
            return None; // below the horizon (or a degenerate l)
        }
        let hf = normalize_reciprocal(std::array::from_fn(|i| lf[i] + vf[i]));
        let (cos_h, sin2_h, c) = (hf[2], hf[0] * hf[0] + hf[1] * hf[1], dot(vf, hf));
        let pdf = match (self.sampler, self.lobe) {
            (Sampler::Engine, _) => ggx::d(cos_h, sin2_h, self.alpha) * cos_h / (4.0 * c),
            (Sampler::Visible, Lobe::Ggx) => {
                self.g1 * ggx::d(cos_h, sin2_h, self.alpha) / (4.0 * cos_o)
            }
            (Sampler::Visible, Lobe::Beckmann) => {
                beckmann::d(cos_h, sin2_h, self.alpha, PI) * cos_h / (4.0 * c)
            }
        };
        let weight = cos_i / pdf;
        weight.is_finite().then_some(Sample { l, weight, c })
    }
}

impl View {
    /// [`View::sample`] of `L` unit samples at once ([`Sampler::Visible`]): the unit
    /// samples as columns ([`UnitSample::columns`] of this view's lobe), the samples into
    /// `out`. Each lane runs `sample`'s operations in its order, written as loops over the
    /// lanes that the compiler vectorises where the caller enables wide registers (the CPU
    /// engine): `sample` is this function with one lane, so both give the same bits. A
    /// lane marked `redo` (Beckmann's D outside its direct form's range) is
    /// [`View::sample_one`]'s.
    #[inline(always)]
    pub fn lane_samples<const L: usize>(
        &self,
        c0: &[f64; L],
        c1: &[f64; L],
        c2: &[f64; L],
        out: &mut Samples<L>,
    ) {
        let a = self.alpha;
        // The divider is what a lane waits on (an f64 square root or division is a chain of
        // tens of cycles): the microfacet normal and the half vector are left unnormalised
        // where only their direction or a ratio of their components is read — the
        // reflection takes `1/|h|²`, D and the pdf ratios of squares — so that a lane takes
        // three square roots and three (GGX) or five (Beckmann) divisions, where
        // normalising took four and six or eight.
        // The constant parts of the weights `cos_i/pdf`, once per view: GGX
        // `4π/(G1 α²)`, Beckmann `4π α²` (see below).
        let (ggx_weight, beckmann_weight) = (4.0 * PI / (self.g1 * (a * a)), 4.0 * PI * (a * a));
        // One loop a lobe: a loop over both computed both in every lane and selected.
        match self.lobe {
            Lobe::Ggx => self.lanes::<L, true>(c0, c1, c2, ggx_weight, out),
            Lobe::Beckmann => self.lanes::<L, false>(c0, c1, c2, beckmann_weight, out),
        }
    }

    /// [`View::lane_samples`]' loop for one lobe (`GGX`, else Beckmann), with the constant
    /// part of its weight.
    #[inline(always)]
    fn lanes<const L: usize, const GGX: bool>(
        &self,
        c0: &[f64; L],
        c1: &[f64; L],
        c2: &[f64; L],
        weight_constant: f64,
        out: &mut Samples<L>,
    ) {
        let (a, v, vf) = (self.alpha, self.v, self.vf);
        let dot3 = |x: [f64; 3], y: [f64; 3]| (x[0] * y[0] + x[1] * y[1]) + x[2] * y[2];
        let unit = |x: [f64; 3]| {
            let inv = 1.0 / dot3(x, x).sqrt();
            x.map(|c| c * inv)
        };
        for k in 0..L {
            // The microfacet normal m (unnormalised), `1/|m|²`, and the sample
            // `l = 2 (v·m) m/|m|² − v`.
            let (m, inv_mm) = self.lane_normal_unnormalised(c0[k], c1[k], c2[k]);
            let s = 2.0 * dot3(v, m) * inv_mm;
            let l: [f64; 3] = std::array::from_fn(|i| s * m[i] - v[i]);
            // l as the backend reads it, normalised, and the half vector `h = lf + vf`
            // (unnormalised): `cos_h² = h_z²/|h|²`, `c = (vf·h)/|h|`.
            let lf = unit(as_f32(l));
            let (cos_i, cos_o) = (lf[2], vf[2]);
            let h: [f64; 3] = std::array::from_fn(|i| lf[i] + vf[i]);
            let inv_hh = 1.0 / dot3(h, h);
            let (side2, vh) = (h[0] * h[0] + h[1] * h[1], dot3(vf, h));
            let (weight, redo) = if GGX {
                // pdf = G1 D/(4 cos_o), `D = α²/(π q²)`, `q = (α² h_z² + h_x² + h_y²)/|h|²`:
                // `cos_i/pdf = (4π/(G1 α²)) cos_o cos_i q²`.
                let q = ((a * a) * (h[2] * h[2]) + side2) * inv_hh;
                (weight_constant * (cos_o * cos_i) * (q * q), false)
            } else {
                // pdf = D cos_h/(4c), `D = e^−x/(π α² cos_h⁴)`, `x = tan²θ_h/α²`:
                // `cos_i/pdf = 4π α² cos_i c cos_h³ e^x = 4π α² cos_i h_z³ (vf·h)/(|h|⁴ e^−x)`,
                // in this direct form; where it under- or overflows the lane is redone with
                // the reference's guarded one (`sample_one`).
                let arg = -side2 / ((a * a) * (h[2] * h[2]));
                let cos_h2 = (h[2] * h[2]) * inv_hh;
                let num = weight_constant * cos_i * (h[2] * h[2] * h[2]) * vh;
                let weight = num * (inv_hh * inv_hh) / exp_neg(arg);
                let ok = arg >= EXP_NEG_MIN && (cos_h2 * cos_h2).is_normal();
                (weight, !ok)
            };
            for (o, x) in out.l.iter_mut().zip(l) {
                o[k] = x;
            }
            out.weight[k] = weight;
            out.c[k] = vh * inv_hh.sqrt();
            // Below the horizon (or a degenerate l: NaN), or a pdf that underflowed.
            out.ok[k] = cos_i > 0.0 && weight.is_finite();
            out.redo[k] = redo && cos_i > 0.0;
        }
    }
}

/// Smallest argument of [`exp_neg`]: e^−700 ≈ 1e-304 is still normal.
const EXP_NEG_MIN: f64 = -700.0;

/// e^x for `EXP_NEG_MIN ≤ x ≤ 0` within 2 ulp, branch free (so that lanes of it
/// vectorise, where libm's `exp` is a call a lane): x = k ln 2 + r with |r| ≤ ln 2/2
/// (Cody–Waite, ln 2 split so that k·LN2_HI is exact), the Taylor polynomial of e^r to r¹³
/// (the first term left out is below 4e-18), times 2^k from the exponent bits. Outside the
/// range the caller does not use the value.
#[inline(always)]
fn exp_neg(x: f64) -> f64 {
    const LN2_HI: f64 = 6.931_471_803_691_238e-1;
    const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
    // 1.5 · 2^52: adding and subtracting it rounds to an integer without `round` (a libm
    // call below SSE4.1).
    const ROUND: f64 = 6_755_399_441_055_744.0;
    let x = x.clamp(EXP_NEG_MIN, 0.0);
    let sum = x * std::f64::consts::LOG2_E + ROUND;
    let k = sum - ROUND;
    let r = (x - k * LN2_HI) - k * LN2_LO;
    let mut p = 1.0 / 6_227_020_800.0; // 1/13!
    let mut f = 6_227_020_800.0;
    for n in (1..13).rev() {
        f /= f64::from(n + 1);
        p = p * r + 1.0 / f;
    }
    let p = p * r + 1.0;
    // 2^k from the integer in the sum's low bits (`k as i64` is a saturating cast, which
    // LLVM does not vectorise: it made every lane of Beckmann's samples scalar code).
    let k_int = sum.to_bits().wrapping_sub(ROUND.to_bits());
    p * f64::from_bits(k_int.wrapping_add(1023) << 52)
}

/// `L` samples of [`View::lane_samples`], lane by lane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Samples<const L: usize> {
    /// `l` (unit; the backend reads it rounded to f32): `l[i][k]` is component `i` of lane `k`.
    pub l: [[f64; L]; 3],
    /// `cos_i / pdf(l)`.
    pub weight: [f64; L],
    /// `c = v·h`.
    pub c: [f64; L],
    /// Whether the lane is a sample (`false`: below the horizon, where [`View::sample`]
    /// gives `None`).
    pub ok: [bool; L],
    /// Whether the lane must be made again by [`View::sample_one`] (its other fields are
    /// then not the sample).
    pub redo: [bool; L],
}

impl<const L: usize> Default for Samples<L> {
    fn default() -> Self {
        Samples {
            l: [[0.0; L]; 3],
            weight: [0.0; L],
            c: [0.0; L],
            ok: [false; L],
            redo: [false; L],
        }
    }
}

/// One importance sample: the light direction, `cos_i / pdf(l)`, and `c = v·h`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Direction toward the light (unit; the backend reads it rounded to f32).
    pub l: [f64; 3],
    /// `cos_i / pdf(l)`, from the f32-rounded directions.
    pub weight: f64,
    /// `c = v·h`, from the f32-rounded directions.
    pub c: f64,
}

/// A unit vector rounded to f32 and widened back: the direction a backend actually sees.
pub fn as_f32(a: [f64; 3]) -> [f64; 3] {
    a.map(|x| f64::from(x as f32))
}

/// `(1 − c)⁵`: Schlick's weight of `1 − F0` (Schlick 1994), the DFG table's second sum.
pub fn schlick_weight(c: f64) -> f64 {
    (1.0 - c).clamp(0.0, 1.0).powi(5)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_neg_is_within_two_ulp_of_libm() {
        let mut worst = 0f64;
        for i in 0..=700_000 {
            let x = -f64::from(i) / 1000.0 - f64::from(i % 7) * 1e-4;
            let x = x.max(EXP_NEG_MIN);
            let (got, want) = (exp_neg(x), x.exp());
            let ulps = (got - want).abs() / (want * f64::EPSILON);
            assert!(ulps <= 2.0, "exp({x}) = {got:e}, libm {want:e}: {ulps} ulp");
            worst = worst.max(ulps);
        }
        assert_eq!(exp_neg(0.0), 1.0);
        assert!(worst > 0.0, "compared something");
    }

    #[test]
    fn one_lane_and_sixteen_give_the_same_samples() {
        for lobe in [Lobe::Ggx, Lobe::Beckmann] {
            for (mu, alpha) in [(0.01, 0.001), (0.3, 0.2), (0.9, 1.0)] {
                let view = View::new(lobe, mu, alpha);
                let units: Vec<UnitSample> = (0..64).map(|k| UnitSample::new(k, 64)).collect();
                for block in units.chunks(16) {
                    let col = |c: usize| -> [f64; 16] {
                        std::array::from_fn(|k| block[k].columns(lobe)[c])
                    };
                    let mut out = Samples::<16>::default();
                    view.lane_samples(&col(0), &col(1), &col(2), &mut out);
                    for (k, u) in block.iter().enumerate() {
                        let one = view.sample(u);
                        assert!(!out.redo[k]);
                        assert_eq!(out.ok[k], one.is_some(), "{lobe:?} {mu} {alpha} lane {k}");
                        if let Some(s) = one {
                            assert_eq!(s.weight.to_bits(), out.weight[k].to_bits());
                            assert_eq!(s.c.to_bits(), out.c[k].to_bits());
                            assert_eq!(s.l, [out.l[0][k], out.l[1][k], out.l[2][k]]);
                        }
                    }
                }
            }
        }
    }
}
