//! The CI stress pass: 200,000 adversarial tuples per backend (cosines down to the smallest
//! positive float32, every parameter at the parser's bounds); any non-finite output, count
//! disagreement (saturated included) or non-zero reject fails. (`vkbrdf stress --tuples 10000000` is the full run.)

mod common;

use vkbrdf::stress;

const TUPLES: usize = 200_000;

#[test]
fn stress_policy_holds_on_every_backend() {
    for mut backend in common::backends() {
        let report =
            stress::run(backend.as_mut(), TUPLES, 7, 1 << 16, &mut |_| {}).expect("stress run");
        assert_eq!(report.tuples, TUPLES as u64);
        // FORMULAS.md §1: no output is ever inf or NaN, down to subnormal cosines and at
        // every parameter's bound, and the saturated count equals the reference's.
        assert_eq!(report.non_finite, 0, "{}", report.to_markdown(1e-5));
        assert_eq!(
            report.saturated.0, report.saturated.1,
            "saturated count on {}",
            report.backend
        );
        assert_eq!(report.invalid.0, report.invalid.1);
        assert!(
            report.policy_holds(),
            "stress policy fails on {}:\n{}",
            report.backend,
            report.to_markdown(1e-5)
        );
        // The corpus really is adversarial: it holds invalid and below-horizon tuples.
        assert!(
            report.invalid.1 > TUPLES as u64 / 20 && report.below_horizon.1 > TUPLES as u64 / 20
        );
        // ... and it reaches the overflow rule: saturated tuples exist.
        assert!(
            report.saturated.1 > TUPLES as u64 / 100,
            "{:?}",
            report.saturated
        );
    }
}

#[test]
fn corpus_is_deterministic_and_chunkable() {
    let (_, whole, cases) = stress::corpus::corpus(3000, 11);
    let (_, part, part_cases) = stress::corpus::corpus_rows(1000..3000, 11);
    let first_diff = whole.as_slice()[1000 * 13..]
        .iter()
        .zip(part.as_slice())
        .position(|(a, b)| a.to_bits() != b.to_bits());
    assert_eq!(
        first_diff, None,
        "chunked corpus differs from the whole (index into the chunk)"
    );
    assert_eq!(&cases[1000..], &part_cases[..]);
    for case in stress::corpus::CASES {
        assert!(cases.contains(&case), "{case:?} missing from the corpus");
    }
}

#[test]
fn the_fast_precision_variant_keeps_the_policy() {
    use vkbrdf::precision::Precision;
    for mut backend in common::backends() {
        let report = stress::run_with(
            backend.as_mut(),
            Precision::Fast,
            50_000,
            9,
            1 << 15,
            &mut |_| {},
        )
        .expect("stress run");
        assert!(
            report.policy_holds(),
            "fast variant fails the policy on {}:\n{}",
            report.backend,
            report.to_markdown(1e-5)
        );
        // It is judged against the exact reference, so Schlick's error must show up in F.
        let f_err = report
            .errors
            .iter()
            .filter(|((q, _), _)| q == "F")
            .map(|(_, s)| s.max)
            .fold(0.0, f64::max);
        assert!(
            f_err > 1e-3,
            "fast F error {f_err} should be Schlick's, not zero: was the variant evaluated?"
        );
    }
}
