//! FORMULAS.md §1: inputs of one evaluation, the validity rule and the derived quantities.

// The vector helpers live in `crate::vector`; re-exported for callers that name them here.
use crate::vector::Dd;
pub use crate::vector::{cross, cross_accurate, dot, dot_accurate, length_squared, normalize};

/// Everything the terms read, derived once per tuple (the table of FORMULAS.md §1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Unit direction toward the light.
    pub l: [f64; 3],
    /// Unit direction toward the viewer.
    pub v: [f64; 3],
    /// Unit normal.
    pub n: [f64; 3],
    /// Unit half vector `normalize(l + v)` (meaningful when both cosines are > 0).
    pub h: [f64; 3],
    /// `cos_i = n·l`.
    pub cos_i: f64,
    /// `cos_o = n·v`.
    pub cos_o: f64,
    /// `cos_h = n·h` (cos δ).
    pub cos_h: f64,
    /// `c = v·h`, the Fresnel angle cosine.
    pub c: f64,
    /// `sin²δ = |n × h|²`: exact near the peak, where `1 − cos_h²` cancels to 0.
    pub sin2_h: f64,
    /// Unit tangent `t` and bitangent `b = n × t` (anisotropic materials only).
    pub tb: Option<([f64; 3], [f64; 3])>,
    /// `n × (l + v)` from the raw inputs in double-double (anisotropic frames; else zero):
    /// [`Frame::h_local`] reads the tangent-frame half vector from it.
    pub n_cross_s: [f64; 3],
    /// `l·v` from the raw inputs (accurate dot product), for Phong's `r·v = 2 cos_i cos_o −
    /// l·v`: with both cosines tiny, `dot(l, v)` of unit vectors (absolute error ~1e-16)
    /// has no correct digit of an `r·v` of 1e-40.
    pub l_dot_v: f64,
    /// `1 − c² = sin²θ_d = (1 − l·v)/2`, from the inputs: near `c = 1` (normal incidence,
    /// l ≈ v) `1 − c` of the rounded `c` has an absolute error ~u that a dielectric with
    /// μ ≪ 1 (g² = μ² − (1 − c²)) turns into a relative error of F of ~u/μ².
    pub sin2_d: f64,
}

/// `a` scaled by a power of two so that its largest |component| is in [0.5, 1): exact (no
/// rounding), and it keeps `|a|²` clear of under- and overflow for components from the
/// smallest f64 denormal to the largest finite value. `None` for a zero or non-finite `a`.
fn scaled(a: [f64; 3]) -> Option<[f64; 3]> {
    if !a.iter().all(|x| x.is_finite()) {
        return None;
    }
    let max = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if max == 0.0 {
        return None;
    }
    let e = libm::ilogb(max) + 1;
    Some(a.map(|x| libm::scalbn(x, -e)))
}

impl Frame {
    /// Builds the frame, or `None` when the tuple is invalid (FORMULAS.md §1): a zero or
    /// non-finite L, V or N, or for anisotropic materials a missing, zero, non-finite
    /// tangent or one parallel to N (`|T − n(n·T)| ≤ 1e-12 |T|`).
    ///
    /// The scalars are formed from the raw inputs, not from the normalised vectors, so that
    /// each keeps its relative precision where the textbook `dot(n, l)` of unit vectors
    /// (absolute error ~1e-16) has none:
    /// - `cos_i = N·L / (|N||L|)` with an accurate dot product: without it K = 1/(cos_i cos_o)
    ///   and the horizon test are wrong below cosines of ~1e-8 (f32 inputs reach 1e-45);
    /// - `1 + l·v` from Lagrange's identity `|L|²|V|² − (L·V)² = |L × V|²` when `L·V < 0`,
    ///   so `c = |l + v|/2 = √((1 + l·v)/2)` keeps its relative precision at grazing mirror
    ///   geometry (l ≈ −v), where `dot(v, h)` came out with a relative error of ~u/c²
    ///   (`c = v·h` of 1e-8 had no correct digit, and F, G and the Fresnel angle with it);
    /// - `cos_h = (cos_i + cos_o)/|l + v|`, exact as the quotient of accurate positives,
    ///   where `dot(n, h)` inherits the direction error of `h = (l + v)/|l + v|`, ~u/|l + v|;
    /// - `sin²δ = |n × h|²` near the peak (where `1 − cos_h²` cancels) but `(1 − cos_h)(1 +
    ///   cos_h)` once `cos²δ ≤ 1/2`, where it is exact and `h`'s direction error is not.
    pub fn new(
        l: [f64; 3],
        v: [f64; 3],
        n: [f64; 3],
        t: Option<[f64; 3]>,
        anisotropic: bool,
    ) -> Option<Frame> {
        let (ls, vs, ns) = (scaled(l)?, scaled(v)?, scaled(n)?);
        let len = |a: [f64; 3]| dot_accurate(a, a).sqrt();
        let (nl, nv, nn) = (len(ls), len(vs), len(ns));
        let (l, v, n) = (ls.map(|x| x / nl), vs.map(|x| x / nv), ns.map(|x| x / nn));
        let tb = if anisotropic {
            let ts = scaled(t?)?;
            let nt = len(ts);
            // |T − n(n·T)|/|T| = |n × t|, from the accurate cross product: Gram–Schmidt's
            // subtraction cancels when T is nearly parallel to N.
            let nxt = cross_accurate(ns, ts);
            let s = len(nxt) / (nn * nt);
            if s <= 1e-12 {
                return None;
            }
            // b = n × t/|n × t| and t = b × n: the same frame as t = normalize(T − n(n·T)),
            // b = n × t, but Gram–Schmidt leaves t tilted out of the tangent plane by
            // ~u/|n × t| when T is near N, which h (mostly along n) turns into an error of
            // h·t; b × n is perpendicular to n to within u.
            let lb = len(nxt);
            let b = nxt.map(|x| x / lb);
            Some((cross(b, n), b))
        } else {
            None
        };
        let cos_i = dot_accurate(ns, ls) / (nn * nl);
        let cos_o = dot_accurate(ns, vs) / (nn * nv);
        let p = dot_accurate(ls, vs);
        let q = nl * nv;
        // 1 + l·v = (q + p)/q; for p < 0 that sum cancels near l = −v, and Lagrange's
        // identity turns it into |L × V|²/(q (q − p)), a quotient of positives.
        let one_plus_lv = if p >= 0.0 {
            1.0 + p / q
        } else {
            let lxv = len(cross_accurate(ls, vs));
            (lxv / q) * (lxv / (q - p))
        };
        // 1 − l·v likewise: direct for p ≤ 0, |L × V|²/(q (q + p)) for p > 0 (near l = v).
        let one_minus_lv = if p <= 0.0 {
            1.0 - p / q
        } else {
            let lxv = len(cross_accurate(ls, vs));
            (lxv / q) * (lxv / (q + p))
        };
        let sin2_d = 0.5 * one_minus_lv;
        let lv_len = (2.0 * one_plus_lv).sqrt(); // |l + v|
                                                 // l = −v exactly gives |l + v| = 0 and no h, but that tuple is below the horizon
                                                 // (cos_i = −cos_o), and the caller returns before reading h.
        let h = if lv_len > 0.0 {
            [0, 1, 2].map(|k| (l[k] + v[k]) / lv_len)
        } else {
            n
        };
        let cos_h = ((cos_i + cos_o) / lv_len).min(1.0);
        let sin2_h = if cos_h * cos_h > 0.5 {
            length_squared(cross(n, h))
        } else {
            (1.0 - cos_h) * (1.0 + cos_h)
        };
        let n_cross_s = if tb.is_some() {
            n_cross_sum(ns, ls, vs)
        } else {
            [0.0; 3]
        };
        Some(Frame {
            n_cross_s,
            l,
            v,
            n,
            h,
            cos_i,
            cos_o,
            cos_h,
            c: 0.5 * lv_len,
            l_dot_v: p / q,
            sin2_d,
            sin2_h,
            tb,
        })
    }

    /// `tan²δ = sin²δ / cos²δ`.
    pub fn tan2_h(&self) -> f64 {
        self.sin2_h / (self.cos_h * self.cos_h)
    }

    /// `(h·t, h·b, h·n)`: the half vector in the tangent frame (anisotropic only).
    pub fn h_local(&self) -> Option<[f64; 3]> {
        self.tb.map(|(t, b)| {
            // h·t = b·(n × s)/|s| and h·b = −t·(n × s)/|s| with s = l + v (triple products,
            // t = b × n, b = n × t): near the peak h·t and h·b are tiny, and dot(h, t) of the
            // rounded h and t carried an absolute error of ~1e-16 (t is perpendicular to n
            // only to within u), which a roughness of 1e-7 turned into 3e-9 relative in
            // anisotropic D (tests/judge.rs). n × s in double-double from the raw inputs is
            // accurate to its own size.
            let w = self.n_cross_s;
            [
                dot(b, w) / (2.0 * self.c),
                -dot(t, w) / (2.0 * self.c),
                self.cos_h,
            ]
        })
    }
}

/// `n × (l + v)` for `n = N/|N|`, `l = L/|L|`, `v = V/|V|`, in double-double from the raw
/// (scaled, exact) vectors: each component carries a relative error of ~1e-32 of the
/// components summed, so the result keeps its own relative precision even where it is
/// ~1e-8 of them (near the specular peak, where l + v is nearly parallel to n).
fn n_cross_sum(n: [f64; 3], l: [f64; 3], v: [f64; 3]) -> [f64; 3] {
    let unit = |a: [f64; 3]| {
        let len2 = a
            .iter()
            .fold(Dd::from(0.0), |acc, &x| acc + Dd::two_prod(x, x));
        let len = len2.sqrt();
        a.map(|x| Dd::from(x) / len)
    };
    let (n, l, v) = (unit(n), unit(l), unit(v));
    let s: [Dd; 3] = std::array::from_fn(|k| l[k] + v[k]);
    let c = |i: usize, j: usize| (n[i] * s[j] - n[j] * s[i]).value();
    [c(1, 2), c(2, 0), c(0, 1)]
}
