//! FORMULAS.md §1's conformance rule applied to a whole output against the reference's.

use vkbrdf::backend::Output;
use vkbrdf::batch::Batch;
use vkbrdf::check;
use vkbrdf::material::Material;

/// Asserts every BRDF and term value of `out` within the rule of `reference`'s (both with
/// terms), naming `what`, the row and the column on failure; returns the largest relative
/// error `|x − r| / max(|r|, 1e-6)` over all values.
pub fn assert_within_rule(
    what: &str,
    batch: &Batch,
    mats: &[Material],
    out: &Output,
    reference: &Output,
) -> f64 {
    let (terms, ref_terms) = (
        out.terms.as_ref().expect("terms"),
        reference.terms.as_ref().expect("terms"),
    );
    let mut worst = 0f64;
    for i in 0..batch.len() {
        let t = batch.tuple(i);
        let s = check::f32_sensitivity(&t, &mats[t.material]);
        let got = (0..3)
            .map(|c| out.brdf[i * 3 + c])
            .chain((0..6).map(|c| terms[i * 6 + c]));
        let want = (0..3)
            .map(|c| reference.brdf[i * 3 + c])
            .chain((0..6).map(|c| ref_terms[i * 6 + c]));
        for (c, (x, r)) in got.zip(want).enumerate() {
            let (x, r) = (f64::from(x), f64::from(r));
            let allowed = check::allowed_error(r, s[c]);
            assert!(
                (x - r).abs() <= allowed,
                "{what}: row {i} column {c}: {x} vs {r} (allowed {allowed:e}, S_in {:e})",
                s[c]
            );
            worst = worst.max((x - r).abs() / r.abs().max(1e-6));
        }
    }
    worst
}
