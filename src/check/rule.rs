//! FORMULAS.md §1's conformance rule as `check` applies it: the sensitivity `S_in` of
//! each output to one rounding of the given f32 inputs, and the error a value is allowed.

use crate::batch::Tuple;
use crate::material::Material;
use crate::reference;
use crate::vector::{cross, dot, normalize_direct};

/// Absolute floor of the relative error: below it an error counts as absolute. BRDF values
/// and D below 1e-6 sr⁻¹ (G, F, K below 1e-6) are far beneath anything visible, and a
/// value there can only be reached in an exponential tail whose relative error grows with
/// the exponent (see [`tolerance`](super::tolerance)).
pub const FLOOR: f64 = 1e-6;

/// The relative part of the tolerance (see [`tolerance`](super::tolerance)).
pub const RELATIVE_TOLERANCE: f64 = 1e-5;

/// Multiple of [`f32_sensitivity`] allowed on top of the relative part (see [`tolerance`](super::tolerance)).
pub const CONDITIONING_FACTOR: f64 = 4.0;

/// The f32 rounding unit u = 2⁻²⁴.
const U: f64 = 1.0 / (1u64 << 24) as f64;

/// `S_in` of FORMULAS.md §1's rule, per column: how much each output moves when the given
/// float32 inputs change by one rounding — `Σ_modes |f(perturbed) − f|` with the f64
/// reference, over each input direction (L, V, N, and T when present) rotated by an angle
/// u = 2⁻²⁴ about two axes perpendicular to it. There are no modes for the quantities an
/// evaluator derives (the unit vectors' lengths, the half vector): their rounding is the
/// evaluator's own error, which the f64 frames show is avoidable.
///
/// Large where the problem is ill-conditioned for f32 inputs (sharp lobes, grazing mirror
/// configurations), tiny elsewhere; the tolerance scales with it
/// ([`CONDITIONING_FACTOR`]).
pub fn f32_sensitivity(t: &Tuple, m: &Material) -> [f64; 9] {
    let w = |a: [f32; 3]| a.map(f64::from);
    let (l, v, n, tan) = (w(t.l), w(t.v), w(t.n), t.t.map(w));
    let values = |e: &reference::Evaluation| {
        let terms = e.terms();
        [
            e.brdf[0], e.brdf[1], e.brdf[2], terms[0], terms[1], terms[2], terms[3], terms[4],
            terms[5],
        ]
    };
    let base = values(&reference::evaluate(l, v, n, tan, m));
    let mut s = [0f64; 9];
    let mut add = |l: [f64; 3], v: [f64; 3], n: [f64; 3], tan: Option<[f64; 3]>| {
        for (acc, (a, b)) in s.iter_mut().zip(
            values(&reference::evaluate(l, v, n, tan, m))
                .iter()
                .zip(base),
        ) {
            *acc += (a - b).abs();
        }
    };
    // Rotations of each direction by u about two axes perpendicular to it.
    let rotations = |x: [f64; 3]| -> [[f64; 3]; 2] {
        let len = dot(x, x).sqrt();
        let xn = x.map(|c| c / len);
        let p1 = normalize_direct(cross(
            xn,
            if xn[0].abs() < 0.9 {
                [1.0, 0.0, 0.0]
            } else {
                [0.0, 1.0, 0.0]
            },
        ));
        let p2 = cross(xn, p1);
        [p1, p2].map(|p| std::array::from_fn(|k| x[k] + U * len * p[k]))
    };
    for r in rotations(l) {
        add(r, v, n, tan);
    }
    for r in rotations(v) {
        add(l, r, n, tan);
    }
    for r in rotations(n) {
        add(l, v, r, tan);
    }
    if let Some(tv) = tan {
        for r in rotations(tv) {
            add(l, v, n, Some(r));
        }
    }
    s
}

/// The values of one tuple in [`COLUMNS`](super::COLUMNS) order.
pub(super) fn columns_of(e: &reference::Evaluation) -> [f64; 9] {
    let t = e.terms();
    [
        e.brdf[0], e.brdf[1], e.brdf[2], t[0], t[1], t[2], t[3], t[4], t[5],
    ]
}

/// The error a value may have: `RELATIVE_TOLERANCE · max(|ref|, FLOOR) +
/// CONDITIONING_FACTOR · sensitivity` (see [`tolerance`](super::tolerance)).
pub fn allowed_error(reference: f64, sensitivity: f64) -> f64 {
    RELATIVE_TOLERANCE * reference.abs().max(FLOOR) + CONDITIONING_FACTOR * sensitivity
}
