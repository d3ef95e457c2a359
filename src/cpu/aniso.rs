//! Anisotropic roughness in the lanes (FORMULAS.md §1–§3): the tangent frame `t`, `b`, and
//! the anisotropic GGX and Beckmann D and Smith `q2`, all in f64 (roughness ratios up to
//! 1e4 multiply the frame's error, as the kernel's `make_frame` found), then G, F, K and
//! the outputs by the isotropic groups' code (`kernel::geometry`, `kernel::two_pass::f_block`).

// The lane loops index several arrays with the same lane number (see `kernel`).
#![allow(clippy::needless_range_loop)]

use super::frame::{frame64, rsqrt64, Frame64};
use super::kernel::two_pass::Stage;
use super::kernel::{geometry, lane_inputs, Inputs, Lane, Params, LANES};
use crate::terms::d::{beckmann, ggx};
use crate::terms::DistributionKind;

/// `[1/mx², 1/my², mx², my²]`, the constants the lanes read ([`Params::aniso`]).
pub fn roughness(mx: f64, my: f64) -> [f64; 4] {
    [1.0 / (mx * mx), 1.0 / (my * my), mx * mx, my * my]
}

/// One lane's tangent frame: h, l and v in (t, b), and whether the lanes may use it.
pub(super) struct Tangent {
    /// `h · t`, `h · b`.
    pub(super) hx: f64,
    pub(super) hy: f64,
    /// `l · t`, `l · b`, `v · t`, `v · b`.
    lt: f64,
    lb: f64,
    vt: f64,
    vb: f64,
    pub(super) ok: bool,
}

/// The tangent frame of a lane from its f64 frame and raw tangent T (FORMULAS.md §1:
/// `t = normalize(T − n (n·T))`, `b = n × t`).
#[inline(always)]
pub(super) fn tangent(f: &Frame64, t: [f32; 3]) -> Tangent {
    let t = t.map(f64::from);
    let tt = t[0] * t[0] + t[1] * t[1] + t[2] * t[2];
    // T normalised first, so that T − n(n·T) of a T nearly parallel to N stays inside
    // the range `rsqrt64` serves (its square is at least 1e-12 below).
    let it = rsqrt64(tt);
    let t = t.map(|x| x * it);
    let n = f.n;
    let tn = n[0] * t[0] + n[1] * t[1] + n[2] * t[2];
    let tp = [t[0] - n[0] * tn, t[1] - n[1] * tn, t[2] - n[2] * tn];
    let tp2 = tp[0] * tp[0] + tp[1] * tp[1] + tp[2] * tp[2];
    // T within 1e-6 of N's direction (the reference's invalid test is 1e-12, FORMULAS.md
    // §1) or of a length outside f32's normal range: the reference decides. NaN fails.
    let ok = (1e-37..=1e37).contains(&tt) && tp2 > 1e-12;
    let ip = rsqrt64(tp2);
    let t = tp.map(|x| x * ip);
    let b = [
        n[1] * t[2] - n[2] * t[1],
        n[2] * t[0] - n[0] * t[2],
        n[0] * t[1] - n[1] * t[0],
    ];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    Tangent {
        hx: dot(f.h, t),
        hy: dot(f.h, b),
        lt: dot(f.l, t),
        lb: dot(f.l, b),
        vt: dot(f.v, t),
        vb: dot(f.v, b),
        ok,
    }
}

/// Lane `k`'s tangent T (components 9–11 of the block).
#[inline(always)]
pub(super) fn lane_tangent(inp: &Inputs, k: usize) -> [f32; 3] {
    [inp.v[9][k], inp.v[10][k], inp.v[11][k]]
}

/// `(hx/mx)² + (hy/my)²`: `tan²θ_h · cos²θ_h` of the anisotropic lobes.
#[inline(always)]
pub(super) fn slope2(p: &Params, t: &Tangent) -> f64 {
    t.hx * t.hx * p.aniso[0] + t.hy * t.hy * p.aniso[1]
}

/// The first pass of an anisotropic GGX or Beckmann group (`D`): D (modern
/// convention, FORMULAS.md §2) and G into `st`, for `kernel::two_pass::f_block`.
#[inline(always)]
pub fn dg_block64_aniso<const D: u8, const G: u8>(p: &Params, inp: &Inputs, st: &mut Stage) {
    for k in 0..LANES {
        let f = frame64(&lane_inputs(inp, k));
        let t = tangent(&f, lane_tangent(inp, k));
        let mut fr = Lane::from64(&f);
        fr.ok = fr.ok && t.ok;
        let s2 = slope2(p, &t);
        let ch2 = f.cos_h * f.cos_h;
        let d = match const { DistributionKind::from_code(D) } {
            DistributionKind::Ggx => ggx::d_aniso_lane(s2, ch2, p.d_norm),
            DistributionKind::Beckmann => beckmann::d_aniso_lane(s2, ch2, p.d_norm),
            // Anisotropic roughness exists for GGX and Beckmann only (their `anisotropic`
            // rules), and the dispatch compiles no other group here.
            DistributionKind::Gaussian | DistributionKind::Blinn | DistributionKind::Charlie => {
                unreachable!("no anisotropic form of this distribution")
            }
        };
        // q2 = (mx² (w·t)² + my² (w·b)²)/cos²θ for Smith's Λ.
        let [_, _, mx2, my2] = p.aniso;
        let q2 = |a: f64, b: f64, c: f64| ((mx2 * a * a + my2 * b * b) / (c * c)) as f32;
        let g = geometry::<D, G>(p, &fr, q2(t.lt, t.lb, f.cos_i), q2(t.vt, t.vb, f.cos_o));
        st.put(k, &fr, d, g);
    }
}
