//! Vector math on `[f64; 3]`: the one home of the dot and cross products and the
//! normalisations that the reference, the tables, the check, the stress corpus and the tests
//! use. It sits at the bottom layer and imports nothing from the crate.
//!
//! Plain arrays at the interface: the batch rows, the reference and the kernel's host side
//! all hold `[f64; 3]`. The dot and cross products are glam's (`DVec3`, scalar f64, a fixed
//! operation order), and every function here fixes its operation order, so a caller's
//! results are bit-for-bit the same wherever it runs.
//!
//! Three normalisations, each kept because callers depend on its exact rounding:
//! [`normalize`] (guarded and rescaled: for inputs, where a vector may be zero, non-finite,
//! tiny or huge), [`normalize_direct`] (`a / |a|`) and [`normalize_reciprocal`]
//! (`a · (1/|a|)`), the last two for vectors the caller knows to be finite, nonzero and of
//! moderate length.

use glam::DVec3;

/// `a · b`, summed left to right.
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    // glam's DVec3::dot: (x·x′ + y·y′) + z·z′, the products and sums in this order.
    DVec3::from_array(a).dot(DVec3::from_array(b))
}

/// `a × b`.
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    // glam's DVec3::cross: (a₁b₂ − a₂b₁, a₂b₀ − a₀b₂, a₀b₁ − a₁b₀), each a plain difference
    // of products (cross_accurate is the cancellation-free one).
    DVec3::from_array(a).cross(DVec3::from_array(b)).to_array()
}

/// `|a|²`.
pub fn length_squared(a: [f64; 3]) -> f64 {
    dot(a, a)
}

/// `s a`.
pub fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    a.map(|x| x * s)
}

/// `s x + y`.
pub fn axpy(s: f64, x: [f64; 3], y: [f64; 3]) -> [f64; 3] {
    [s * x[0] + y[0], s * x[1] + y[1], s * x[2] + y[2]]
}

/// `a / |a|`, or `None` for a zero-length or non-finite vector (an invalid input).
///
/// Scales by the largest |component| first: without it `|a|²` underflows to 0 for inputs
/// of length ~1e-170 and overflows for ~1e170 (f32 inputs never get there, but f64 callers can).
pub fn normalize(a: [f64; 3]) -> Option<[f64; 3]> {
    if !a.iter().all(|x| x.is_finite()) {
        return None;
    }
    let scale = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if scale == 0.0 {
        return None;
    }
    let s = a.map(|x| x / scale);
    let len = length_squared(s).sqrt();
    Some(s.map(|x| x / len))
}

/// `a / |a|` with `|a| = √(a·a)`, unguarded: for a vector the caller knows to be finite and
/// nonzero with `|a|²` in the normal range (a zero vector gives NaN components).
pub fn normalize_direct(a: [f64; 3]) -> [f64; 3] {
    let len = dot(a, a).sqrt();
    a.map(|x| x / len)
}

/// `a · (1/|a|)` with `|a| = √(a·a)`, unguarded like [`normalize_direct`] (one division
/// instead of three; its rounding differs from that of `a / |a|`).
pub fn normalize_reciprocal(a: [f64; 3]) -> [f64; 3] {
    let inv = 1.0 / dot(a, a).sqrt();
    a.map(|x| x * inv)
}

/// `a·b − c·d` to within ~1.5 ulp (Kahan's algorithm with a fused multiply-add): the plain
/// difference of two rounded products loses every digit when they nearly cancel, as the
/// components of `n × w` do for `w` near `n` and those of `l × v` for `l` near `−v`.
fn diff_of_products(a: f64, b: f64, c: f64, d: f64) -> f64 {
    let cd = c * d;
    let err = (-c).mul_add(d, cd); // cd − c·d exactly
    a.mul_add(b, -cd) + err
}

/// `a × b` with each component accurate to a few ulps of itself (Kahan's fused multiply-add difference of products).
pub fn cross_accurate(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        diff_of_products(a[1], b[2], a[2], b[1]),
        diff_of_products(a[2], b[0], a[0], b[2]),
        diff_of_products(a[0], b[1], a[1], b[0]),
    ]
}

/// `a · b` as if computed in twice the working precision and rounded once (Ogita, Rump &
/// Oishi 2005, "Accurate sum and dot product", Dot2: error-free products by fused
/// multiply-add, error-free sums, the errors added back). Its relative error is ~u +
/// u²·cond, where the plain dot product's is u·cond: at a grazing cosine of 1e-30 between
/// f32 inputs, cond is ~1e30 and the plain dot product of normalised vectors has no correct
/// digit (its absolute error, ~1e-16, dwarfs the cosine), while this one is exact to an ulp.
pub fn dot_accurate(a: [f64; 3], b: [f64; 3]) -> f64 {
    let (mut s, mut err) = (0.0f64, 0.0f64);
    for k in 0..3 {
        let p = a[k] * b[k];
        let pe = a[k].mul_add(b[k], -p); // a·b − p exactly
        let t = s + p;
        let z = t - s;
        let se = (s - (t - z)) + (p - z); // s + p − t exactly (TwoSum)
        s = t;
        err += pe + se;
    }
    s + err
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn double_double_is_exact_where_it_must_be() {
        // (1 + 2^-30)^2 = 1 + 2^-29 + 2^-60: the 2^-60 is below f64's precision at 1.
        let a = 1.0 + 2f64.powi(-30);
        let p = Dd::two_prod(a, a);
        assert_eq!((p.hi, p.lo), (1.0 + 2f64.powi(-29), 2f64.powi(-60)));
        let s = Dd::two_sum(1.0, 2f64.powi(-80));
        assert_eq!((s.hi, s.lo), (1.0, 2f64.powi(-80)));
        // 1/3 · 3 = 1 to double-double precision; √2 · √2 = 2 likewise.
        let third = Dd::from(1.0) / Dd::from(3.0);
        let one = third * Dd::from(3.0) - Dd::from(1.0);
        assert!(one.value().abs() < 1e-31, "{one:?}");
        let r = Dd::from(2.0).sqrt();
        assert!((r * r - Dd::from(2.0)).value().abs() < 1e-31);
    }

    #[test]
    fn products_of_the_axes() {
        let (x, y, z) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
        assert_eq!(cross(x, y), z);
        assert_eq!(cross(y, z), x);
        assert_eq!(cross(z, x), y);
        assert_eq!(dot([1.0, 2.0, 3.0], [4.0, -5.0, 6.0]), 12.0);
        assert_eq!(length_squared([2.0, 3.0, 6.0]), 49.0);
        assert_eq!(axpy(2.0, [1.0, 2.0, 3.0], [1.0, 1.0, 1.0]), [3.0, 5.0, 7.0]);
        assert_eq!(scale([1.0, -2.0, 0.5], 4.0), [4.0, -8.0, 2.0]);
    }

    #[test]
    fn the_normalisations_agree_where_exact_and_guard_where_asked() {
        // |(2, 3, 6)| = 7: 2/7, 3/7, 6/7 correctly rounded by the direct form.
        assert_eq!(
            normalize_direct([2.0, 3.0, 6.0]),
            [2.0 / 7.0, 3.0 / 7.0, 6.0 / 7.0]
        );
        assert_eq!(normalize_reciprocal([0.0, 0.0, 4.0]), [0.0, 0.0, 1.0]);
        assert_eq!(normalize([0.0, 0.0, 0.0]), None);
        assert_eq!(normalize([f64::NAN, 0.0, 1.0]), None);
        // Beyond the direct form's range (|a|² underflows to 0 there).
        let tiny = 2f64.powi(-600);
        assert_eq!(
            normalize([3.0 * tiny, 0.0, 4.0 * tiny]),
            Some([0.6, 0.0, 0.8])
        );
        assert!(!normalize_direct([3.0 * tiny, 0.0, 4.0 * tiny])[0].is_finite());
    }

    #[test]
    fn accurate_products_keep_digits_the_plain_ones_lose() {
        // (1 + 2⁻³⁰)·(1 − 2⁻³⁰) − 1·1 = −2⁻⁶⁰ exactly; the plain form rounds it to 0.
        let e = 2f64.powi(-30);
        let (a, b) = ([0.0, 1.0 + e, 1.0], [0.0, 1.0, 1.0 - e]);
        assert_eq!(cross_accurate(a, b)[0], -(e * e));
        assert_eq!(cross(a, b)[0], 0.0);
        // 1 + 2⁻⁶⁰ − 1 = 2⁻⁶⁰, lost by the plain left-to-right sum.
        let (u, v) = ([1.0, e * e, -1.0], [1.0, 1.0, 1.0]);
        assert_eq!(dot_accurate(u, v), e * e);
        assert_eq!(dot(u, v), 0.0);
    }
}

/// A double-double number `hi + lo` (about 106 bits): the reference's half vector in the
/// tangent frame needs more than f64 near the peak (see `reference::frame`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dd {
    /// The leading part.
    pub hi: f64,
    /// The remainder, `|lo| <= ulp(hi)/2`.
    pub lo: f64,
}

impl Dd {
    /// `x` exactly.
    pub fn from(x: f64) -> Dd {
        Dd { hi: x, lo: 0.0 }
    }

    /// The sum, rounded once to f64.
    pub fn value(self) -> f64 {
        self.hi + self.lo
    }

    /// `a + b` exactly as a pair (Knuth's two-sum).
    pub fn two_sum(a: f64, b: f64) -> Dd {
        let s = a + b;
        let bb = s - a;
        Dd {
            hi: s,
            lo: (a - (s - bb)) + (b - bb),
        }
    }

    /// `a · b` exactly as a pair (FMA two-product).
    pub fn two_prod(a: f64, b: f64) -> Dd {
        let p = a * b;
        Dd {
            hi: p,
            lo: a.mul_add(b, -p),
        }
    }

    fn renorm(hi: f64, lo: f64) -> Dd {
        let s = hi + lo;
        Dd {
            hi: s,
            lo: lo - (s - hi),
        }
    }

    /// `√self` for `self > 0` (one Newton correction of the f64 root).
    pub fn sqrt(self) -> Dd {
        let s = self.hi.sqrt();
        let r = self - Dd::two_prod(s, s);
        Dd::renorm(s, r.hi / (2.0 * s))
    }
}

impl std::ops::Add for Dd {
    type Output = Dd;
    fn add(self, o: Dd) -> Dd {
        let s = Dd::two_sum(self.hi, o.hi);
        Dd::renorm(s.hi, s.lo + self.lo + o.lo)
    }
}

impl std::ops::Sub for Dd {
    type Output = Dd;
    fn sub(self, o: Dd) -> Dd {
        self + Dd {
            hi: -o.hi,
            lo: -o.lo,
        }
    }
}

impl std::ops::Mul for Dd {
    type Output = Dd;
    fn mul(self, o: Dd) -> Dd {
        let p = Dd::two_prod(self.hi, o.hi);
        Dd::renorm(p.hi, p.lo + self.hi * o.lo + self.lo * o.hi)
    }
}

impl std::ops::Div for Dd {
    type Output = Dd;
    /// One Newton correction of the f64 quotient.
    fn div(self, o: Dd) -> Dd {
        let q = self.hi / o.hi;
        let r = self - o * Dd::from(q);
        Dd::renorm(q, r.hi / o.hi)
    }
}
