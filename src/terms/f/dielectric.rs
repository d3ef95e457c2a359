//! Cook & Torrance 1982, eq. 8: the exact unpolarised dielectric Fresnel term (with the
//! seed's typo in the last denominator corrected to `c(g − c) + 1`): `g² = μ² + c² − 1`;
//! `g² < 0` is total internal reflection (F = 1); else
//! `F = ½ ((g−c)/(g+c))² (1 + ((c(g+c) − 1)/(c(g−c) + 1))²)`.

/// The spelling in a materials file.
pub const NAME: &str = "dielectric";
/// The work the formula comes from.
pub const CITATION: &str = "Cook & Torrance 1982";

/// F in f64 at `c` for relative IOR `ior`.
pub fn f(c: f64, ior: f64) -> f64 {
    // 1 − c² as (1 − c)(1 + c): 1 − c is exact for c in [0.5, 1].
    f_with_sin2(c, (1.0 - c) * (1.0 + c), ior)
}

/// [`f`] given also `s2 = 1 − c²`, accurate near c = 1 where `1 − c` of a
/// rounded `c` is not (the frame forms it from the inputs: `reference::frame::Frame::sin2_d`).
pub fn f_with_sin2(c: f64, s2: f64, ior: f64) -> f64 {
    // μ² − 1 as (μ − 1)(μ + 1): `μ·μ − 1` rounds μ² first and, for μ = 1 + 1e-9, keeps
    // only ~7 of its digits (μ − 1 is exact by Sterbenz's lemma for μ in [0.5, 2]).
    let mu2m1 = (ior - 1.0) * (ior + 1.0);
    // g² = μ² + c² − 1 in whichever grouping rounds least (each form's error is ~u times the
    // sum of its terms' magnitudes): (μ² − 1) + c² near μ = 1, where μ² + c² − 1 rounds
    // c² ≤ 1e-16 away next to 1 (g² = 0 instead of c², F = 1 instead of 0 at grazing c);
    // μ² − (1 − c²) near c = 1 with μ ≪ 1, where (μ² − 1) + c² cancels −1 against 1 to
    // leave μ² (μ = 1e-6 at normal incidence: F off by 2e-10 relative).
    let g2 = if mu2m1.abs() + c * c <= ior * ior + s2 {
        mu2m1 + c * c
    } else {
        ior * ior - s2
    };
    if g2 < 0.0 {
        return 1.0;
    }
    let g = g2.sqrt();
    // g − c = (μ² − 1)/(g + c): the subtraction cancels for μ ≈ 1 (F ≈ 0 there, and its
    // relative error would be unbounded); the product form is exact to a few ulps.
    let g_minus_c = mu2m1 / (g + c);
    let r = g_minus_c / (g + c);
    // c(g + c) − 1 = c·g − (1 − c²) and c(g − c) + 1 = c·g + (1 − c²): near c = 1 with
    // g ≪ 1 (μ ≪ 1 at normal incidence) both printed forms cancel 1 against ~1 (the
    // denominator is ~μ there: F off by 3e-11 relative at μ = 1e-6).
    let q = (c * g - s2) / (c * g + s2);
    0.5 * r * r * (1.0 + q * q)
}

/// `μ² − 1` as `(μ − 1)(μ + 1)`, the per-material constant [`f_lane`] takes.
pub fn mu2m1(ior: f64) -> f64 {
    (ior - 1.0) * (ior + 1.0)
}

/// F in a lane, in f64 with [`f_with_sin2`]'s grouping (its evaluation near total internal
/// reflection wants the f64 `c`), rounded once; `mu2m1` from [`mu2m1`].
#[inline(always)]
pub fn f_lane(c: f64, s2: f64, mu: f64, mu2m1: f64) -> f32 {
    let g2 = if mu2m1.abs() + c * c <= mu * mu + s2 {
        mu2m1 + c * c
    } else {
        mu * mu - s2
    };
    let g = g2.max(0.0).sqrt();
    let r = mu2m1 / (g + c) / (g + c);
    let q = (c * g - s2) / (c * g + s2);
    let f = 0.5 * r * r * (1.0 + q * q);
    if g2 < 0.0 {
        1.0
    } else {
        f as f32
    }
}
