//! Measured (MERL) materials in the lanes (FORMULAS.md §7, "MERL lookup"): the
//! half/difference angles of a block's tuples in f64 lanes — the frame as
//! [`crate::material::merl::half_diff`] builds it, the three angles by a branch-free f64
//! atan2 ([`atan2_upper64`]) — then each lane's lookup in the table, which is a gather.
//!
//! Why f64: the bin is chosen by truncation, so the angles must be the reference's to far
//! better than a bin's width; the kernel found that an f32 frame and atan2 put 1 tuple in
//! 10^4 in the neighbouring bin (`glsl/measured.glsl`). In f64 the lanes' angles differ
//! from the reference's by rounding only (~1e-15), so a bin differs only for a tuple
//! within that distance of a bin edge, and [`crate::material::merl::BIN_TOLERANCE`] keeps
//! the bins' own sample points a thousandth of a bin away from their edges.
//!
//! The reference takes the lanes it classifies itself (invalid vectors, the horizon) and
//! those where an angle is ill-conditioned: `h` within 1e-4 of `n` (the axis `n × h`, and
//! with it φ_d, is then a quotient of tiny differences; the reference picks a fixed axis
//! at `h = n`), and `l` within 1e-4 of `h` (φ_d of a nearly vertical `d`).

use super::kernel::{Inputs, Outputs, LANES};
use crate::material::merl::{Lookup, MeasuredMerl};
use crate::reference::to_output_f32;
use crate::terms::math::atan2_upper64;
use std::f64::consts::PI;

/// Squared raw lengths the lanes take (the other engines' range, 1e-37 to 1e37 as a
/// length): beyond it the squares leave f64's comfortable range for the plain formulas.
const LEN2_RANGE: (f64, f64) = (1e-74, 1e74);

/// Smallest cosine the lanes take: below it the reference decides the horizon.
const MIN_COS: f64 = 1e-6;

/// Smallest `|n × h|²` and `sin²θ_d` the lanes take (the angles 1e-4 from their poles).
const MIN_SIN2: f64 = 1e-8;

/// f of one block of a measured material; `rescue` marks the lanes the reference takes.
#[inline(always)]
pub fn measured_block(data: &MeasuredMerl, lookup: Lookup, inp: &Inputs, out: &mut Outputs) {
    let mut angles = [[0f64; LANES]; 3];
    let mut ok = [false; LANES];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    for k in 0..LANES {
        let vec = |j: usize| {
            [
                f64::from(inp.v[j][k]),
                f64::from(inp.v[j + 1][k]),
                f64::from(inp.v[j + 2][k]),
            ]
        };
        let (l, v, n) = (vec(0), vec(3), vec(6));
        let (ll, vv, nn) = (dot(l, l), dot(v, v), dot(n, n));
        // A NaN length fails every comparison, so NaN components land here too.
        let in_range = |x: f64| x >= LEN2_RANGE.0 && x <= LEN2_RANGE.1;
        let mut good = in_range(ll) && in_range(vv) && in_range(nn);
        let unit = |a: [f64; 3], len2: f64| {
            let inv = 1.0 / len2.sqrt();
            a.map(|x| x * inv)
        };
        let (l, v, n) = (unit(l, ll), unit(v, vv), unit(n, nn));
        good &= dot(n, l) > MIN_COS && dot(n, v) > MIN_COS;
        let lv = [l[0] + v[0], l[1] + v[1], l[2] + v[2]];
        let h = unit(lv, dot(lv, lv));
        let nxh = cross(n, h);
        let s2 = dot(nxh, nxh);
        good &= s2 > MIN_SIN2;
        // b: the axis θ_h rotates about; t = b × h; d = l in (t, b, h).
        let b = unit(nxh, s2);
        let t = cross(b, h);
        let d = [dot(l, t), dot(l, b), dot(l, h)];
        let r2 = d[0] * d[0] + d[1] * d[1];
        good &= r2 > MIN_SIN2;
        angles[0][k] = atan2_upper64(s2.sqrt(), dot(n, h));
        angles[1][k] = atan2_upper64(r2.sqrt(), d[2]);
        // φ_d folded into [0, π) by reciprocity: (d₀, d₁) and (−d₀, −d₁) are one bin.
        let phi = atan2_upper64(d[1].abs(), d[0]);
        let phi = if d[1] < 0.0 { PI - phi } else { phi };
        angles[2][k] = if phi >= PI { 0.0 } else { phi };
        ok[k] = good;
    }
    for k in 0..LANES {
        out.rescue[k] = !ok[k];
        if ok[k] {
            let rgb = data.lookup_half_diff_with(lookup, angles[0][k], angles[1][k], angles[2][k]);
            for (c, x) in rgb.into_iter().enumerate() {
                out.brdf[c][k] = to_output_f32(x);
            }
        }
    }
}
