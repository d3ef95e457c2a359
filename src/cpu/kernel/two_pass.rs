//! The groups that always take the f64 frame (every dielectric group, the Gaussian, Blinn
//! and Charlie distributions, the schlick-smith and neubelt geometries) in two passes: the
//! frame, D and G of a block ([`dg_block64`]) into a [`Stage`], then F, K and the outputs
//! ([`f_block`]), so that D × G + F variants are compiled where one pass would compile
//! D × G × F.

use super::{
    finish_lane, frame64, lane_inputs, microfacet_dg, Inputs, Lane, Outputs, Params, LANES,
};
use crate::terms::f::conductor;
use crate::terms::math::MulAdd;

/// The f64-frame groups' lanes between their two passes (see [`dg_block64`]).
pub struct Stage {
    cos_i: [f32; LANES],
    cos_o: [f32; LANES],
    c: [f32; LANES],
    s2: [f32; LANES],
    one_minus_c: [f32; LANES],
    c64: [f64; LANES],
    s2_64: [f64; LANES],
    d: [f32; LANES],
    g: [f32; LANES],
    ok: [bool; LANES],
}

impl Default for Stage {
    fn default() -> Self {
        Stage {
            cos_i: [0.0; LANES],
            cos_o: [0.0; LANES],
            c: [0.0; LANES],
            s2: [0.0; LANES],
            one_minus_c: [0.0; LANES],
            c64: [0.0; LANES],
            s2_64: [0.0; LANES],
            d: [0.0; LANES],
            g: [0.0; LANES],
            ok: [false; LANES],
        }
    }
}

/// The first pass of the groups that always take the f64 frame (every dielectric group,
/// the Gaussian, Blinn and Charlie distributions, and the schlick-smith and neubelt
/// geometries): the frame, D and G of a block into `st`; [`f_block`] then adds F, K and
/// the outputs. Two passes compile D × G + F variants where one would compile D × G × F
/// (the fused form took the clean build from 113 to 255 s); these groups pay for it with
/// a store and a load of ten values a lane.
#[inline(always)]
pub fn dg_block64<A: MulAdd, const D: u8, const G: u8>(p: &Params, inp: &Inputs, st: &mut Stage) {
    for k in 0..LANES {
        let fr = Lane::from64(&frame64(&lane_inputs(inp, k)));
        let (d, g) = microfacet_dg::<A, D, G, false>(p, &fr);
        st.put(k, &fr, d.0 / d.1, g.0 / g.1);
    }
}

impl Stage {
    /// Stores lane `k`'s frame values that F and K read, its D and G.
    #[inline(always)]
    pub(crate) fn put(&mut self, k: usize, fr: &Lane, d: f32, g: f32) {
        let st = self;
        st.cos_i[k] = fr.cos_i;
        st.cos_o[k] = fr.cos_o;
        st.c[k] = fr.c;
        st.s2[k] = fr.s2;
        st.one_minus_c[k] = fr.one_minus_c;
        st.c64[k] = fr.c64;
        st.s2_64[k] = fr.s2_64;
        st.d[k] = d;
        st.g[k] = g;
        st.ok[k] = fr.ok;
    }
}

/// The second pass of [`dg_block64`]: F, K and the outputs.
#[inline(always)]
pub fn f_block<A: MulAdd, const F: u8>(p: &Params, st: &Stage, out: &mut Outputs) {
    for k in 0..LANES {
        // The fields `finish_lane` reads; the others are not needed after D and G.
        let fr = Lane {
            cos_i: st.cos_i[k],
            cos_o: st.cos_o[k],
            cos_h: 0.0,
            c: st.c[k],
            sin2_i: 0.0,
            sin2_o: 0.0,
            one_minus_c: st.one_minus_c[k],
            s2: st.s2[k],
            sin2_h32: 0.0,
            tan2_h32: 0.0,
            cos_h2: 0.0,
            sin2_h: 0.0,
            c64: st.c64[k],
            s2_64: st.s2_64[k],
            ok: st.ok[k],
        };
        finish_lane::<A, F, true, { conductor::FORM_SCALED }>(
            p,
            &fr,
            (st.d[k], 1.0),
            (st.g[k], 1.0),
            [1.0; 3],
            out,
            k,
        );
    }
}
