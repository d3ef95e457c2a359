//! He, Torrance, Sillion & Greenberg 1991, "A comprehensive physical model for light
//! reflection" (SIGGRAPH '91), in Westin's formulation (Cornell's `heBRDF`): the
//! wave-optical model of FORMULAS.md §8, whole — its name, parameters and ranges, its f64
//! form (the reference's, the judge) and the spike weight `ρ_s`. The kernel's form is the
//! block `model/htsg` in `glsl/htsg.glsl`; the CPU engine evaluates it with this f64 form.
//!
//! Units: `σ0`, `τ` and `λ` in µm inside the formulas (materials give wavelengths in nm).

use super::f::conductor;
use super::term::Rgb;
use std::f64::consts::PI;

/// The spelling in a materials file (`model = "htsg"`).
pub const NAME: &str = "htsg";
/// The work the formula comes from.
pub const CITATION: &str = "He, Torrance, Sillion & Greenberg 1991";

/// The wavelengths of the R, G and B channels when a material names none, in nm
/// (Westin's and bbm's defaults).
pub const DEFAULT_WAVELENGTHS_NM: Rgb = [645.0, 526.0, 444.0];

/// D's switch from the series to Beckmann's rough-surface form (FORMULAS.md §8): the
/// series is used for `g ≤ 18.5`, as in the references.
pub const G_SWITCH: f64 = 18.5;

/// The accepted range of `sigma0` (µm).
pub const SIGMA0_RANGE: (f64, f64) = (1e-4, 10.0);
/// The accepted range of `tau` (µm).
pub const TAU_RANGE: (f64, f64) = (1e-3, 100.0);
/// The accepted range of `sigma0 / tau`.
pub const RATIO_RANGE: (f64, f64) = (1e-3, 10.0);
/// The accepted range of the wavelengths (nm).
pub const WAVELENGTH_RANGE_NM: (f64, f64) = (200.0, 5000.0);

/// An HTSG material's parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Htsg {
    /// `σ0`: the surface's rms height, µm.
    pub sigma0: f64,
    /// `τ`: its autocorrelation length, µm.
    pub tau: f64,
    /// `n` of `η = n + ik`, per channel.
    pub ior: Rgb,
    /// `k ≥ 0` of `η = n + ik`, per channel (0: a dielectric).
    pub extinction: Rgb,
    /// The channels' wavelengths, µm.
    pub wavelengths: Rgb,
}

/// What the parser asks of a material's parameters: `None`, or the key to blame and why.
pub fn legality(sigma0: f64, tau: f64) -> Option<(&'static str, String)> {
    let ratio = sigma0 / tau;
    (!(RATIO_RANGE.0..=RATIO_RANGE.1).contains(&ratio)).then(|| {
        (
            "sigma0",
            format!(
                "sigma0 / tau must be in [{:e}, {}] (got {ratio:e}): beyond it the model's \
                 lobe leaves the range f32 directions resolve (smooth) or the model's validity \
                 (rough)",
                RATIO_RANGE.0, RATIO_RANGE.1
            ),
        )
    })
}

/// HTSG's `sigma0` (µm), [`SIGMA0_RANGE`]: from a polished surface's
/// 0.1 nm to 10 µm.
pub fn sigma0_range(x: f64) -> Option<&'static str> {
    let (lo, hi) = SIGMA0_RANGE;
    (!(x.is_finite() && (lo..=hi).contains(&x)))
        .then_some("must be a finite number in [1e-4, 10] (µm)")
}
/// HTSG's `tau` (µm), [`TAU_RANGE`]: with λ ≥ 200 nm, `T = 2πτ/λ` and
/// the lobe's exponent `v_xy² T²/4` stay within float32's exp range where the lobe is
/// above the conformance floor.
pub fn tau_range(x: f64) -> Option<&'static str> {
    let (lo, hi) = TAU_RANGE;
    (!(x.is_finite() && (lo..=hi).contains(&x)))
        .then_some("must be a finite number in [1e-3, 100] (µm)")
}
/// HTSG's wavelengths (nm), [`WAVELENGTH_RANGE_NM`]: the near UV to the
/// mid infrared.
pub fn wavelength_range(x: f64) -> Option<&'static str> {
    let (lo, hi) = WAVELENGTH_RANGE_NM;
    (!(x.is_finite() && (lo..=hi).contains(&x)))
        .then_some("must be a finite number in [200, 5000] (nm)")
}

/// The geometry one evaluation reads (FORMULAS.md §1 and §8), all from the frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Angles {
    /// `cos θ_i = n·l > 0`.
    pub cos_i: f64,
    /// `cos θ_r = n·v > 0`.
    pub cos_o: f64,
    /// `sin θ_i = |n × l|`.
    pub sin_i: f64,
    /// `sin θ_r = |n × v|`.
    pub sin_o: f64,
    /// `c = |l + v|/2`.
    pub c: f64,
    /// `sin²δ = |n × h|²`.
    pub sin2_h: f64,
}

/// One evaluation's outputs (FORMULAS.md §8, "Outputs").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Terms {
    /// `ρ_dd` per channel (without the uniform diffuse `a/π`), 1/sr.
    pub rho_dd: Rgb,
    /// D of the green channel.
    pub d: f64,
    /// G.
    pub g: f64,
    /// F per channel.
    pub f: Rgb,
    /// `K = S/(π cos_i cos_r)`.
    pub k: f64,
}

/// `x = τ cot θ/(2σ0)`, the argument of S1 and of K(θ); +∞ at normal incidence.
pub fn slope_x(p: &Htsg, cos: f64, sin: f64) -> f64 {
    if sin == 0.0 {
        return f64::INFINITY;
    }
    p.tau / (2.0 * p.sigma0) * (cos / sin)
}

/// `S1 = (1 − erfc(x)/2)/(Λ(x) + 1)` (Eq. 24–25 with the erratum), evaluated as
/// `A/(e^{−x²} + A)` with `A = x√π (1 + erf x)`: the same value multiplied through by
/// `2x√π`, which removes `Λ`'s `1/x` (it overflows as x → 0, at grazing) and the
/// cancellation of `e^{−x²}/(x√π) − erfc(x)` for large x (where S1 → 1).
pub fn shadow(x: f64) -> f64 {
    // Beyond 27, e^{−x²} < 1e-316 and S1 = 1 in f64 (also x = +∞, normal incidence).
    if x > 27.0 {
        return 1.0;
    }
    let a = x * PI.sqrt() * (2.0 - libm::erfc(x));
    a / ((-x * x).exp() + a)
}

/// `K(θ) = tan θ · erfc(x)` (Eq. 82), 0 at normal incidence.
fn k_of(cos: f64, sin: f64, x: f64) -> f64 {
    if sin == 0.0 {
        return 0.0;
    }
    sin / cos * libm::erfc(x)
}

/// The effective roughness `σ = σ0/√(1 + z²)` (Eqs. 80–83), `z ≥ 0` solving
/// `z e^{z²/2} = (K_i + K_r)/√(8π)`. Solved as `ln z + z²/2 = ln R` by Newton (from `z = R`
/// for R ≤ 1, else `√(2 ln(1 + R))`) until a step is below 2⁻⁵² of z: in the logarithm R
/// never overflows (K ~ 1/cos reaches 1e45 at f32's smallest cosines).
pub fn effective_sigma(p: &Htsg, k_sum: f64) -> f64 {
    let r = k_sum / (8.0 * PI).sqrt();
    if r <= 0.0 {
        return p.sigma0;
    }
    let ln_r = r.ln();
    // The start: z = R for R ≤ 1, √(2 ln(1 + R)) above (Westin's √(2 ln R) lies near 0
    // just above R = 1, far from the root z ≈ 0.75; FORMULAS.md §8).
    let mut z = if r <= 1.0 {
        r
    } else {
        (2.0 * r.ln_1p()).sqrt()
    };
    for _ in 0..100 {
        let h = z.ln() + 0.5 * z * z - ln_r;
        let step = z * h / (1.0 + z * z);
        z -= step;
        if step.abs() <= z * f64::EPSILON * 0.5 {
            break;
        }
    }
    p.sigma0 / (1.0 + z * z).sqrt()
}

/// D of Eq. 78 per unit `(πτ/(2λ))²` (Westin's formulation): for `g ≤ 18.5` the series
/// `Σ_{m≥1} e^{−g} g^m/(m!·m) · e^{−a/m}`, `a = v_xy² T²/4`; above, `e^{−a/g}/g`.
///
/// The weights `e^{−g} g^m/m!` grow by `g/m` (relative rounding ~m·2⁻⁵³, under 1e-14 at the
/// m ≈ 60 the sum needs at g = 18.5), one exp a term. A weight that underflows makes a term
/// below 1e-308, beneath every output's floor even after G and K (≤ 1e91) multiply it. The
/// sum stops once the tail's bound — the current weight over m (e^{−a/m} ≤ 1) times the
/// geometric series of `g/(m+1)` — is below 2⁻⁵³ of the sum, or is 0.
pub fn series(g: f64, a: f64) -> f64 {
    if g > G_SWITCH {
        return (-a / g).exp() / g;
    }
    if g <= 0.0 {
        return 0.0;
    }
    let mut weight = (-g).exp(); // e^{−g} g^m / m! at m = 0
    let mut sum = 0.0f64;
    for m in 1..=2000u32 {
        let mf = f64::from(m);
        weight *= g / mf;
        let t = weight / mf;
        sum += t * (-a / mf).exp();
        if mf > g {
            let tail = t / (1.0 - g / (mf + 1.0));
            if tail <= sum * f64::EPSILON * 0.5 || tail == 0.0 {
                break;
            }
        }
    }
    sum
}

/// FORMULAS.md §8 on a valid, above-horizon geometry: `ρ_dd` per channel and the terms.
pub fn evaluate(p: &Htsg, w: &Angles) -> Terms {
    let x_i = slope_x(p, w.cos_i, w.sin_i);
    let x_o = slope_x(p, w.cos_o, w.sin_o);
    // S/(π cos_i cos_r) as (S1_i/cos_i)(S1_r/cos_r)/π: each quotient is finite in f64
    // down to f32's smallest cosine (S1 ~ 2x√π ∝ cos there).
    let k = shadow(x_i) / w.cos_i * (shadow(x_o) / w.cos_o) / PI;
    let sigma = effective_sigma(p, k_of(w.cos_i, w.sin_i, x_i) + k_of(w.cos_o, w.sin_o, x_o));
    // |l + v|² = 4c², n·(l + v) = cos_i + cos_r, v_xy² = |l + v|² sin²δ.
    let s2 = 4.0 * w.c * w.c;
    let ns = w.cos_i + w.cos_o;
    let g = (s2 / ns) * (s2 / ns);
    let vxy2 = s2 * w.sin2_h;
    let mut d = [0.0; 3];
    let mut f = [0.0; 3];
    let mut rho_dd = [0.0; 3];
    for ch in 0..3 {
        let lambda = p.wavelengths[ch];
        let gg = (2.0 * PI * sigma * ns / lambda).powi(2);
        let t = 2.0 * PI * p.tau / lambda;
        let norm = (PI * p.tau / (2.0 * lambda)).powi(2);
        d[ch] = norm * series(gg, vxy2 * t * t / 4.0);
        f[ch] = conductor::f(w.c, p.ior[ch], p.extinction[ch]);
        rho_dd[ch] = f[ch] * g * d[ch] * k;
    }
    Terms {
        rho_dd,
        d: d[1],
        g,
        f,
        k,
    }
}

/// The mirror spike's weight `ρ_s = F(cos_i) e^{−g_s} S1(θ_i)²` per channel, `g_s =
/// (4π σ_s cos_i/λ)²`, `σ_s` the effective roughness with `θ_r = θ_i` (FORMULAS.md §8).
pub fn spike(p: &Htsg, cos_i: f64, sin_i: f64) -> Rgb {
    let x = slope_x(p, cos_i, sin_i);
    let s1 = shadow(x);
    let sigma = effective_sigma(p, 2.0 * k_of(cos_i, sin_i, x));
    std::array::from_fn(|ch| {
        let gs = (4.0 * PI * sigma * cos_i / p.wavelengths[ch]).powi(2);
        conductor::f(cos_i, p.ior[ch], p.extinction[ch]) * (-gs).exp() * s1 * s1
    })
}

/// An HTSG material's constants for the CPU engine's lanes, formed in f64 and rounded once
/// (the kernel's packing, `gpu::layout`, holds the same numbers).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LaneConstants {
    /// `τ/(2σ0)`: `x = half_cot · cot θ`.
    pub half_cot: f32,
    /// `σ0/τ`: `w = 2πσ/λ = T · (σ/τ)`.
    pub ratio: f32,
    /// `T = 2πτ/λ` per channel.
    pub t: [f32; 3],
}

impl LaneConstants {
    /// The constants of `p`.
    pub fn new(p: &Htsg) -> LaneConstants {
        LaneConstants {
            half_cot: (p.tau / (2.0 * p.sigma0)) as f32,
            ratio: (p.sigma0 / p.tau) as f32,
            t: p.wavelengths.map(|l| (2.0 * PI * p.tau / l) as f32),
        }
    }
}

/// A block of lanes' HTSG terms but F (the conductor's lane form gives F per channel).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LaneTerms<const N: usize> {
    /// `K = S/(π cos_i cos_r)`.
    pub k: [f32; N],
    /// G.
    pub g: [f32; N],
    /// D of the green channel.
    pub d: [f32; N],
    /// `G·D` per channel (formed together: see [`lanes`]).
    pub gd: [[f32; N]; 3],
}

/// The geometry of a block of lanes, from the CPU engine's f64 frame rounded once.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LaneAngles<const N: usize> {
    /// `cos θ_i`, at least 1e-4 (the frame sends smaller cosines to the reference).
    pub cos_i: [f32; N],
    /// `cos θ_r`, at least 1e-4.
    pub cos_o: [f32; N],
    /// `|n × l|²`.
    pub sin2_i: [f32; N],
    /// `|n × v|²`.
    pub sin2_o: [f32; N],
    /// `c = |l + v|/2`, at least 1e-4.
    pub c: [f32; N],
    /// `|n × h|²`.
    pub sin2_h: [f32; N],
}

/// `S1/cos θ` and `ln K(θ)` of one direction in f32 (`glsl/htsg.glsl`'s `htsg_direction`),
/// branch-free: past `x = 4.5`, S1 = 1 to f32's resolution and K < 2.2e-8 is dropped (the
/// kernel's comment gives the bound; `ln K` = −1e30 then), and the other branch's values
/// (NaN at normal incidence, where x = ∞) are selected away.
#[inline(always)]
fn lane_direction(cos: f32, sin2: f32, half_cot: f32) -> (f32, f32) {
    use super::math::{erfc, exp_neg, log_acc};
    let sin = sin2.sqrt();
    let x = half_cot * cos / sin;
    let e = erfc(x);
    let one_plus_erf = 2.0 - e;
    let sqrt_pi = PI.sqrt() as f32;
    let den = exp_neg(-x * x) + x * sqrt_pi * one_plus_erf;
    let q = sqrt_pi * one_plus_erf * half_cot / (sin * den);
    let ln_k = log_acc(sin * e) - log_acc(cos);
    let flat = half_cot * cos > 4.5 * sin;
    (
        if flat { 1.0 / cos } else { q },
        if flat { -1e30 } else { ln_k },
    )
}

/// FORMULAS.md §8 but F, in f32, for a block of lanes whose cosines are at least 1e-4 (the
/// CPU engine's f64 frame sends the others to the reference): the kernel's form
/// (`glsl/htsg.glsl`) without its extended-range paths, written lane-parallel so that it
/// vectorises — Newton five steps from `z = R` or `√(2 ln(1 + R))` (1.1e-7 of σ over ln R
/// ∈ [−9.3, 104]), and the series run for every lane until each has its tail bound below
/// 2⁻²⁵ of its sum (a lane that is done earlier only adds terms smaller still); lanes past
/// D's switch take Beckmann's form by a select. `G·D` is formed together in the series'
/// range (there `g = (w (cos_i + cos_r))²` divides out of G).
#[inline(always)]
pub fn lanes<const N: usize>(k: &LaneConstants, w: &LaneAngles<N>) -> LaneTerms<N> {
    use super::math::{exp_neg, log1p_acc, log_acc};
    let mut out = LaneTerms {
        k: [0.0; N],
        g: [0.0; N],
        d: [0.0; N],
        gd: [[0.0; N]; 3],
    };
    let mut ratio = [0.0f32; N];
    let mut ns = [0.0f32; N];
    let mut s2 = [0.0f32; N];
    let ln_sqrt_8pi = (0.5 * (8.0 * PI).ln()) as f32;
    for j in 0..N {
        let (q_i, ln_k_i) = lane_direction(w.cos_i[j], w.sin2_i[j], k.half_cot);
        let (q_o, ln_k_o) = lane_direction(w.cos_o[j], w.sin2_o[j], k.half_cot);
        let (hi, lo) = (ln_k_i.max(ln_k_o), ln_k_i.min(ln_k_o));
        // ln R = ln(K_i + K_r) − ln √(8π); −1e30 when both K are 0.
        let ln_r = hi + log1p_acc(exp_neg(lo - hi)) - ln_sqrt_8pi;
        // Below ln R = −9.3, z < 1e-4 and σ = σ0 to f32 precision (also the K = 0 lanes).
        let small = ln_r < -9.3;
        let lr = if small { 0.0 } else { ln_r };
        let mut z = if lr <= 0.0 {
            exp_neg(lr)
        } else {
            (2.0 * (lr + log1p_acc(exp_neg(-lr)))).sqrt()
        };
        for _ in 0..5 {
            let h = log_acc(z) + 0.5 * z * z - lr;
            z -= z * h / (1.0 + z * z);
        }
        ratio[j] = if small {
            k.ratio
        } else {
            k.ratio / (1.0 + z * z).sqrt()
        };
        ns[j] = w.cos_i[j] + w.cos_o[j];
        s2[j] = 4.0 * w.c[j] * w.c[j];
        out.g[j] = (s2[j] / ns[j]) * (s2[j] / ns[j]);
        out.k[j] = q_i * q_o / PI as f32;
    }
    for ch in 0..3 {
        let t = k.t[ch];
        let norm = 0.0625 * t * t;
        let mut gg = [0.0f32; N];
        let mut a = [0.0f32; N];
        let mut q = [0.0f32; N];
        let mut sum = [0.0f32; N];
        for j in 0..N {
            let wv = t * ratio[j];
            gg[j] = wv * ns[j] * wv * ns[j];
            a[j] = 0.25 * s2[j] * w.sin2_h[j] * t * t;
            // Lanes past the switch run the series on 0 weights (their result is replaced).
            q[j] = if gg[j] > G_SWITCH as f32 {
                0.0
            } else {
                exp_neg(-gg[j])
            };
        }
        for m in 1..=80u32 {
            let mf = m as f32;
            let mut done = true;
            for j in 0..N {
                q[j] /= mf;
                let wt = q[j] / mf;
                sum[j] += wt * exp_neg(-a[j] / mf);
                q[j] *= gg[j];
                done &= mf > gg[j] && wt * gg[j] / (1.0 - gg[j] / (mf + 1.0)) <= sum[j] * 3e-8
                    || q[j] == 0.0;
            }
            if done {
                break;
            }
        }
        for j in 0..N {
            let rough = gg[j] > G_SWITCH as f32;
            let s = norm * sum[j];
            let d_rough = norm * exp_neg(-a[j] / gg[j]) / gg[j];
            let wv = t * ratio[j];
            let d = if rough { d_rough } else { gg[j] * s };
            out.gd[ch][j] = if rough {
                out.g[j] * d_rough
            } else {
                s2[j] * s2[j] * wv * wv * s
            };
            if ch == 1 {
                out.d[j] = d;
            }
        }
    }
    out
}

/// The equivalent Beckmann roughness of the rough limit, `m = 2σ0/τ` (S1's `x = cot θ/m`).
pub fn beckmann_m(p: &Htsg) -> f64 {
    2.0 * p.sigma0 / p.tau
}

#[cfg(test)]
mod tests {
    use super::*;

    fn alu() -> Htsg {
        Htsg {
            sigma0: 0.0318,
            tau: 0.3,
            ior: [1.3211, 0.88045, 0.59765],
            extinction: [7.41785, 6.1455, 5.2337],
            wavelengths: [0.645, 0.526, 0.444],
        }
    }

    #[test]
    fn shadow_limits() {
        // x → ∞: 1; small x: S1 ≈ x√π (the numerator 1/2 over Λ ≈ 1/(2x√π)).
        assert_eq!(shadow(f64::INFINITY), 1.0);
        let x = 1e-30;
        assert!((shadow(x) / (x * PI.sqrt()) - 1.0).abs() < 1e-12);
        // The printed form where it does not cancel (x = 0.7).
        let x = 0.7f64;
        let lambda = ((-x * x).exp() / (x * PI.sqrt()) - libm::erfc(x)) / 2.0;
        let printed = (1.0 - libm::erfc(x) / 2.0) / (lambda + 1.0);
        assert!((shadow(x) - printed).abs() < 1e-15);
    }

    #[test]
    fn newton_solves_the_roughness_equation() {
        let p = alu();
        // z is read back from σ, which needs z² well above f64's rounding of (σ0/σ)²: R ≥
        // 2e-4 here, and just above R = 1 (where Westin's start lies near 0).
        let root_8pi = (8.0 * PI).sqrt();
        for k_sum in [1e-3, 0.5, root_8pi * 1.0001, 2.0, 37.0, 1e6, 1e45] {
            let sigma = effective_sigma(&p, k_sum);
            let z = ((p.sigma0 / sigma).powi(2) - 1.0).max(0.0).sqrt();
            let lhs = z * (0.5 * z * z).exp();
            let rhs = k_sum / (8.0 * PI).sqrt();
            assert!((lhs / rhs - 1.0).abs() < 1e-8, "{k_sum}: {lhs} vs {rhs}");
        }
    }

    #[test]
    fn series_is_continuous_in_g_and_sums_to_its_closed_form_at_a_zero() {
        // a = 0: Σ e^{−g} g^m/(m!·m) = e^{−g}(Ei(g) − γ − ln g); at g = 1, 1.3179021514544038 e^{−1}.
        let s = series(1.0, 0.0);
        assert!(
            (s - 1.317_902_151_454_403_8 * (-1.0f64).exp()).abs() < 1e-15,
            "{s}"
        );
    }
}
