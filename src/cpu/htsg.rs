//! HTSG (FORMULAS.md §8) in the lanes: the f64 frame (`frame::frame64`, whose `ok` sends
//! every lane with a cosine below 1e-4 to the reference), the model's f32 lane form
//! (`terms::htsg::lanes`, the kernel's `glsl/htsg.glsl` function for function) and the
//! conductor's F (`terms::f::conductor::f_lane`).

// The lane loops index several arrays with the same lane number (see `kernel`).
#![allow(clippy::needless_range_loop)]

use super::frame::frame64;
use super::kernel::{lane_inputs, Inputs, Outputs, Params, LANES, OUTPUT_LIMIT};
use crate::terms::f::conductor;
use crate::terms::htsg;

/// One block of an HTSG material: BRDF `F·(G·D)·K + a/π` per channel and every term.
#[inline(always)]
pub fn htsg_block(p: &Params, h: &htsg::LaneConstants, inp: &Inputs, out: &mut Outputs) {
    let mut w = htsg::LaneAngles {
        cos_i: [0.0; LANES],
        cos_o: [0.0; LANES],
        sin2_i: [0.0; LANES],
        sin2_o: [0.0; LANES],
        c: [0.0; LANES],
        sin2_h: [0.0; LANES],
    };
    let mut ok = [false; LANES];
    // sin²θ_d = 1 − c² from the f64 c: in f32 it cancels near c = 1.
    let mut sin2_d = [0.0f32; LANES];
    for k in 0..LANES {
        let f = frame64(&lane_inputs(inp, k));
        // Lanes the frame rejects are rescued; their angles are set to a harmless
        // geometry (normal incidence) so that no NaN runs through the series.
        ok[k] = f.ok;
        let pick = |x: f64, safe: f64| if f.ok { x as f32 } else { safe as f32 };
        w.cos_i[k] = pick(f.cos_i, 1.0);
        w.cos_o[k] = pick(f.cos_o, 1.0);
        w.sin2_i[k] = pick(f.sin2_i, 0.0);
        w.sin2_o[k] = pick(f.sin2_o, 0.0);
        w.c[k] = pick(f.c, 1.0);
        w.sin2_h[k] = pick(f.sin2_h, 0.0);
        sin2_d[k] = pick((1.0 - f.c) * (1.0 + f.c), 0.0);
    }
    let t = htsg::lanes(h, &w);
    for k in 0..LANES {
        let mut size = t.d[k].abs() + t.g[k].abs() + t.k[k].abs();
        for ch in 0..3 {
            let fr = conductor::f_lane(w.c[k], sin2_d[k], &p.conductor, ch);
            out.terms[2 + ch][k] = fr;
            let b = fr * t.gd[ch][k] * t.k[k] + p.diffuse[ch];
            out.brdf[ch][k] = b;
            size += b.abs();
        }
        out.terms[0][k] = t.d[k];
        out.terms[1][k] = t.g[k];
        out.terms[5][k] = t.k[k];
        // `<=` is false for NaN: one comparison catches both (see `microfacet_lane`).
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        let bad = !ok[k] || !(size <= OUTPUT_LIMIT);
        out.rescue[k] = bad;
    }
}
