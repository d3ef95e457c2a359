//! The conductor's F on the f32 frames' lanes as a polynomial in `c`, fitted per material
//! (Trefethen 2013, "Approximation Theory and Approximation Practice", ch. 3–4 and 8: the
//! Chebyshev interpolant of an analytic function and the decay of its coefficients).
//!
//! On the lanes of the f32 frames `c` lies in [`FAST_MIN_C`, 1] (smaller `c` takes the
//! f64 frame), where a conductor's F is analytic and smooth: η² − sin²θ stays away from 0
//! for every material the metal form takes, so F's nearest singularity is a fixed distance
//! off the interval and its Chebyshev coefficients fall geometrically. Degree [`DEGREE`]
//! then gives F to a fraction of the metal form's budget, in [`DEGREE`] fused multiply-adds
//! a channel instead of two square roots and a division (the divider is what the lanes
//! wait on). A material whose fit cannot be shown inside the budget keeps the metal form.
//!
//! [`FAST_MIN_C`]: crate::cpu::kernel::FAST_MIN_C

use super::{f, LaneConstants, METAL_FORM_BUDGET};
use crate::terms::math::MulAdd;
use crate::terms::real::Real;
use std::collections::BTreeMap;
use std::sync::Mutex;

/// The polynomial's degree (15 coefficients a channel).
pub const DEGREE: usize = 14;

/// The centre of the fitted interval: the lanes take `t = c − CENTRE`, which is exact for
/// `c` in [CENTRE/2, 2·CENTRE] (Sterbenz) and otherwise rounded once, relative to `t`.
/// 35/64, exactly an f32.
pub const CENTRE: f32 = 0.546875;

/// The fitted interval's half-width in `c`: [0.091875, 1.001875] holds every `c` of the f32
/// frames' lanes (≥ `FAST_MIN_C` = 0.1, ≤ 1 plus the frame's few ulp).
const HALF_WIDTH: f64 = 0.455;

/// A conductor's F per channel as `Σ bᵢ tⁱ` in `t = c − CENTRE` (coefficients `b[ch][i]`,
/// rounded once to f32), and the bound it was admitted under.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Polynomial {
    /// The coefficients of each channel, constant term first.
    pub b: [[f32; DEGREE + 1]; 3],
    /// The worst channel's error bound in units of u = 2⁻²⁴ relative to F (see
    /// [`Polynomial::fit`]).
    pub bound_u: f64,
}

/// Chebyshev points of the interpolant whose upper coefficients measure the truncation.
const NODES: usize = 33;

/// One channel's fit of F for `η = n + ik` on `[centre − half_width, centre + half_width]`
/// (F at `nodes` Chebyshev points, the interpolant truncated to degree `N − 1`): the f64
/// coefficients of the powers of `t = c − centre` and the truncation's bound (absolute), or
/// `None` when the Chebyshev coefficients do not fall far enough by the interpolant's last
/// ones to trust the bound (Trefethen 2013, ch. 4 and 8).
pub(super) fn fit_channel<const N: usize>(
    centre: f64,
    half_width: f64,
    nodes: usize,
    n: f64,
    k: f64,
) -> Option<([f64; N], f64)> {
    // F at the Chebyshev points of the first kind on the interval.
    let x: Vec<f64> = (0..nodes)
        .map(|j| (std::f64::consts::PI * (j as f64 + 0.5) / nodes as f64).cos())
        .collect();
    let fx: Vec<f64> = x.iter().map(|&x| f(centre + half_width * x, n, k)).collect();
    if fx.iter().any(|v| !v.is_finite()) {
        return None;
    }
    // Chebyshev coefficients of the interpolant (a discrete cosine transform).
    let mut a = vec![0.0; nodes];
    for (m, am) in a.iter_mut().enumerate() {
        let angle = |j: usize| std::f64::consts::PI * m as f64 * (j as f64 + 0.5) / nodes as f64;
        let s: f64 = (0..nodes).map(|j| fx[j] * angle(j).cos()).sum();
        *am = s * 2.0 / nodes as f64 * if m == 0 { 0.5 } else { 1.0 };
    }
    // The coefficients beyond the interpolant's (and their aliases in it) are bounded by
    // its last ones where these have fallen far below u (6e-8): a function analytic in a
    // Bernstein ellipse has |aₘ| ≤ 2Mρ⁻ᵐ, so the tail past the interpolant is below the
    // last few. Where they have not, F is near a singularity and the bound is not trusted.
    let last: f64 = a[nodes - 4..].iter().map(|c| c.abs()).sum();
    if last > 1e-10 {
        return None;
    }
    // Truncation to degree N − 1: the dropped coefficients, the aliasing of the computed
    // ones and the tail, each at most the sum of the dropped magnitudes plus the last ones.
    let truncation = 2.0 * a[N..].iter().map(|c| c.abs()).sum::<f64>() + 3.0 * last;
    // Σ aₘ Tₘ(x) to powers of x (Tₘ₊₁ = 2x Tₘ − Tₘ₋₁), then x = t/h to powers of t.
    let mut pow = [0.0; N];
    let (mut tm1, mut tm) = ([0.0; N], [0.0; N]);
    tm1[0] = 1.0; // T₀
    tm[1] = 1.0; // T₁
    pow[0] += a[0];
    for i in 0..N {
        pow[i] += a[1] * tm[i];
    }
    for am in &a[2..N] {
        let mut next = [0.0; N];
        for i in 0..N {
            next[i] = if i > 0 { 2.0 * tm[i - 1] } else { 0.0 } - tm1[i];
        }
        for i in 0..N {
            pow[i] += am * next[i];
        }
        (tm1, tm) = (tm, next);
    }
    let mut scale = 1.0;
    for p in &mut pow {
        *p /= scale;
        scale *= half_width;
    }
    Some((pow, truncation))
}

/// The relative error bound, in u, of Horner's rule in f32 for one channel with
/// coefficients `b` (as rounded to f32) of the powers of `t`, `|t| ≤ half_width`, whose f64
/// polynomial is within `truncation` of F there:
///
/// `(truncation/u + max_t Σ (2i + 3)|bᵢ||t|ⁱ) / F_min`.
///
/// - Horner's running error (Higham 2002, §5.1): a step `rᵢ = rᵢ₊₁ t + bᵢ` rounds once
///   with FMA and twice without, each rounding relative to a value at most
///   `Σⱼ≥ᵢ |bⱼ||t|ʲ⁻ⁱ`, carried to the result by `|t|ⁱ`: in all ≤ `2u Σ (i + 1)|bᵢ||t|ⁱ`
///   without FMA, half that with it.
/// - The coefficients' rounding to f32: `u Σ |bᵢ||t|ⁱ`.
/// - `t` rounded (where `c − centre` is not exact): `t(1 + δ)`, `|δ| ≤ u`, moves the value
///   by ≤ `u Σ i|bᵢ||t|ⁱ` — inside the sum with FMA (`(i + 1) + 1 + i`), which is how
///   [`f_lanes_poly`] runs; where `t` is exact (the segments' lanes), with or without.
///
/// The maximum is taken on a grid of `grid + 1` points in t (the sum grows with |t|, so its
/// maximum is at an end) and F_min is the least f64 polynomial value on the same grid
/// less the truncation and the largest change between neighbouring points.
pub(super) fn bound<const N: usize>(
    b: &[f64; N],
    truncation: f64,
    half_width: f64,
    grid: usize,
) -> f64 {
    let u = f64::from(f32::EPSILON) / 2.0;
    let h = half_width;
    let at = |t: f64| b.iter().rev().fold(0.0, |acc, &bi| acc * t + bi);
    let slope: f64 = (1..N)
        .map(|i| i as f64 * b[i].abs() * h.powi(i as i32 - 1))
        .sum();
    let step = 2.0 * h / grid as f64;
    let fmin = (0..=grid)
        .map(|j| at(-h + step * j as f64))
        .fold(f64::INFINITY, f64::min)
        - truncation
        - slope * step;
    if fmin.is_nan() || fmin <= 0.0 {
        return f64::INFINITY;
    }
    let rounding: f64 = (0..N)
        .map(|i| (2 * i + 3) as f64 * b[i].abs() * h.powi(i as i32))
        .sum();
    (truncation / u + rounding) / fmin
}

/// A process's fits by `η` (both the polynomial's and the segments'): a fit takes ~0.1 ms
/// (the polynomial) to ~0.2 (the segments), the CPU engine makes its plans on every call (every chunk of a
/// stream), a fitting run evaluates the same η many times, and the Vulkan kernel folds the
/// polynomial into each pipeline of a conductor material. Cleared when it holds 65,536 fits.
pub(super) struct FitCache<V>(Mutex<BTreeMap<[u64; 6], Option<V>>>);

impl<V: Copy> FitCache<V> {
    /// An empty cache.
    pub(super) const fn new() -> FitCache<V> {
        FitCache(Mutex::new(BTreeMap::new()))
    }

    /// The fit of `η = ior + i·extinction`, from the cache or made by `fit` once.
    pub(super) fn get(
        &self,
        ior: [f64; 3],
        extinction: [f64; 3],
        fit: impl FnOnce() -> Option<V>,
    ) -> Option<V> {
        let key = [ior, extinction].concat();
        let key: [u64; 6] = std::array::from_fn(|i| key[i].to_bits());
        // A poisoned lock only means another thread panicked while inserting: the map
        // holds whole entries either way.
        if let Some(v) = self.0.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
            return *v;
        }
        let v = fit();
        let mut fits = self.0.lock().unwrap_or_else(|e| e.into_inner());
        if fits.len() >= 1 << 16 {
            fits.clear();
        }
        fits.insert(key, v);
        v
    }
}

impl Polynomial {
    /// No polynomial: zero coefficients, an infinite bound.
    pub const NONE: Polynomial = Polynomial {
        b: [[0.0; DEGREE + 1]; 3],
        bound_u: f64::INFINITY,
    };

    /// The fit of `η = ior + i·extinction` per channel, when every channel's bound
    /// (`(truncation/u + max_t Σ (2i + 3)|bᵢ||t|ⁱ)/F_min`: Horner's running error with or
    /// without FMA, the coefficients' and `t`'s rounding and the fit's truncation,
    /// docs/CPU_ENGINE.md) is within [`METAL_FORM_BUDGET`] and the material may take the
    /// metal form (`constants.metal`); else `None` (the lanes keep the metal form).
    pub fn fit(
        constants: &LaneConstants,
        ior: [f64; 3],
        extinction: [f64; 3],
    ) -> Option<Polynomial> {
        if !constants.metal {
            return None;
        }
        let mut out = Polynomial {
            b: [[0.0; DEGREE + 1]; 3],
            bound_u: 0.0,
        };
        for ch in 0..3 {
            let (pow, truncation) = fit_channel::<{ DEGREE + 1 }>(
                f64::from(CENTRE),
                HALF_WIDTH,
                NODES,
                ior[ch],
                extinction[ch],
            )?;
            let rounded = pow.map(|x| x as f32);
            let bound_u = bound(&rounded.map(f64::from), truncation, HALF_WIDTH, 4096);
            if bound_u > METAL_FORM_BUDGET {
                return None;
            }
            out.b[ch] = rounded;
            out.bound_u = out.bound_u.max(bound_u);
        }
        Some(out)
    }

    /// [`Polynomial::fit`] of `η = ior + i·extinction` (with its [`LaneConstants`]), once a
    /// process per η (a per-process cache shared with the segment tables' fits).
    pub fn fitted(ior: [f64; 3], extinction: [f64; 3]) -> Option<Polynomial> {
        static FITS: FitCache<Polynomial> = FitCache::new();
        FITS.get(ior, extinction, || {
            Polynomial::fit(&LaneConstants::new(ior, extinction), ior, extinction)
        })
    }
}

/// F of the three channels from the material's polynomial, by Horner's rule in
/// `t = c − CENTRE` (valid for `c` in [`FAST_MIN_C`, 1]: the f32 frames' lanes; elsewhere
/// finite and meaningless, and those lanes take another frame) — the channels' steps
/// interleaved, so that three independent multiply-adds are in flight where one channel's
/// chain of 14 would wait on each one's latency.
///
/// [`FAST_MIN_C`]: crate::cpu::kernel::FAST_MIN_C
#[inline(always)]
pub fn f_lanes_poly<A: MulAdd, T: Real>(c: T, p: &Polynomial) -> [T; 3] {
    let t = c - c.splat_as(CENTRE);
    let mut r = [c; 3];
    for (r, b) in r.iter_mut().zip(&p.b) {
        *r = c.splat_as(b[DEGREE]);
    }
    for i in (0..DEGREE).rev() {
        for (r, b) in r.iter_mut().zip(&p.b) {
            *r = A::mul_add(*r, t, c.splat_as(b[i]));
        }
    }
    r
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::terms::math::{Fused, Rounded};

    /// Metals of the bench and the tests: the Mitsuba scenarios' metal, copper, gold,
    /// silver-like and iron-like η (the segment tables' tests take them too).
    pub(in crate::terms::f::conductor) const METALS: [([f64; 3], [f64; 3]); 5] = [
        ([0.2, 0.92, 1.1], [3.9, 2.45, 2.14]),
        ([0.27, 0.68, 1.22], [3.61, 2.62, 2.24]),
        ([0.18, 0.42, 1.37], [3.42, 2.35, 1.77]),
        ([0.05, 0.06, 0.05], [4.2, 3.6, 2.5]),
        ([2.9, 2.9, 2.6], [3.1, 2.9, 2.8]),
    ];

    /// The polynomial's largest relative error in u against the f64 F over every `c` an
    /// f32 lane may bring (a dense sweep from `FAST_MIN_C` to 1 and the f32 numbers next
    /// to both ends), on both MulAdd kinds.
    fn measured(p: &Polynomial, ior: [f64; 3], ext: [f64; 3]) -> f64 {
        let mut cs = sweep();
        let mut c = 0.1f32;
        for _ in 0..64 {
            cs.push(c);
            c = f32::from_bits(c.to_bits() + 1);
        }
        cs.extend([1.0f32, f32::from_bits(1.0f32.to_bits() - 1), 1.0 + f32::EPSILON]);
        worst_u(&cs, ior, ext, |c| {
            [f_lanes_poly::<Fused, f32>(c, p), f_lanes_poly::<Rounded, f32>(c, p)]
        })
    }

    /// A dense sweep of c from `FAST_MIN_C` (0.1) to 1: 200,001 values.
    pub(in crate::terms::f::conductor) fn sweep() -> Vec<f32> {
        (0..=200_000)
            .map(|i| (0.1 + 0.9 * f64::from(i) / 200_000.0) as f32)
            .collect()
    }

    /// The largest relative error in u against the f64 F over `cs` of a lane form `eval`
    /// (its three channels with FMA and without) for `η = ior + i·ext`.
    pub(in crate::terms::f::conductor) fn worst_u(
        cs: &[f32],
        ior: [f64; 3],
        ext: [f64; 3],
        eval: impl Fn(f32) -> [[f32; 3]; 2],
    ) -> f64 {
        let u = f64::from(f32::EPSILON) / 2.0;
        let mut worst = 0f64;
        for &c in cs {
            let got = eval(c);
            for ch in 0..3 {
                let want = f(f64::from(c), ior[ch], ext[ch]);
                for got in got.map(|g| g[ch]) {
                    worst = worst.max((f64::from(got) - want).abs() / want / u);
                }
            }
        }
        worst
    }

    #[test]
    fn metals_fit_inside_their_bound_and_the_budget() {
        for (ior, ext) in METALS {
            let constants = LaneConstants::new(ior, ext);
            let p = Polynomial::fit(&constants, ior, ext)
                .unwrap_or_else(|| panic!("{ior:?} {ext:?} should fit"));
            let err = measured(&p, ior, ext);
            assert!(p.bound_u <= METAL_FORM_BUDGET, "{ior:?}: {}", p.bound_u);
            assert!(err <= p.bound_u, "{ior:?}: measured {err}u > bound {}u", p.bound_u);
        }
    }

    /// A material the metal form refuses gets no polynomial, and a material whose
    /// coefficients fall slowly (aluminium-like η, whose |η| is large; n ≫ k) is refused
    /// by the bound rather than admitted with a fit that misses; a fit admitted near the
    /// metal form's limits holds its bound.
    #[test]
    fn materials_without_a_trustworthy_fit_are_refused() {
        let dielectric = LaneConstants::new([1.5; 3], [0.0; 3]);
        assert!(Polynomial::fit(&dielectric, [1.5; 3], [0.0; 3]).is_none());
        let mut refused = 0;
        for (n, k) in [(0.02, 0.7), (0.2, 0.9), (1.0, 1.35), (1.3, 1.5), (5.0, 0.0), (1.35, 7.5)] {
            let constants = LaneConstants::new([n; 3], [k; 3]);
            match Polynomial::fit(&constants, [n; 3], [k; 3]) {
                None => refused += 1,
                Some(p) => {
                    let err = measured(&p, [n; 3], [k; 3]);
                    assert!(err <= p.bound_u, "η = {n} + {k}i: {err}u > {}u", p.bound_u);
                }
            }
        }
        assert!(refused >= 2, "aluminium-like η and n ≫ k should be refused ({refused})");
    }
}
