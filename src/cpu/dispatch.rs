//! Which lanes run a run of blocks: the exhaustive dispatch from a material group's
//! [`Plan`] (its terms' enums) to the lanes' const-generic variants — the f32-frame groups
//! compiled per form, the f64-frame groups in two passes, and the groups no lanes are
//! compiled for sent to the reference. Each variant is a function of its own ([`apart`]).

use super::kernel::two_pass::{f_block, Stage};
use super::kernel::{self, Inputs, Outputs, LANES};
use super::plan::Plan;
use super::{aniso, lobes};
use crate::terms::math::MulAdd;
use crate::terms::FresnelKind;

/// A run of blocks of `plan`'s lanes, each `inp[b]` into `out[b]`, forming `a·b + c` as `A`
/// says (fused where `simd` has FMA); `z`: every lane's N is
/// (0, 0, 1) (the local form), which the groups with an f32 frame run without N's
/// arithmetic, to the same bits. The groups whose frame is always the f64 one (which
/// serves both forms: the local form's lanes carry N) are compiled once, not once per form.
#[inline(always)]
pub(crate) fn block<S: pulp::Simd, A: MulAdd>(
    simd: S,
    plan: &Plan,
    inp: &[Inputs],
    out: &mut [Outputs],
    z: bool,
) {
    match plan {
        Plan::Lambert(_) => {}
        Plan::Microfacet { d, aniso, g, f, .. } if kernel::fused(*d, *aniso, *g, *f) => {}
        _ => return f64_frame_block::<S, A>(simd, plan, inp, out),
    }
    if z {
        f32_frame_block::<S, A, true>(simd, plan, inp, out)
    } else {
        f32_frame_block::<S, A, false>(simd, plan, inp, out)
    }
}

/// Runs `lanes`, one group's lanes over a run of blocks, as a function of its own compiled
/// for `simd`'s instruction set (pulp's `vectorize`; the `inline(never)` keeps it apart
/// from the chunk loop, and LLVM does not inline the instruction set's function into this
/// one, which is compiled for the baseline). Inlined, every group's lanes made the chunk
/// loop one function per instruction set several times the size of the rest of the
/// engine, which LLVM optimises in time that grows faster than the size: it was most of
/// the crate's build (docs/CPU_ENGINE.md, round 8). Apart, each group is a function of a
/// few thousand instructions, and the codegen units share them.
#[inline(never)]
pub(crate) fn apart<S: pulp::Simd, R>(simd: S, lanes: impl FnOnce() -> R) -> R {
    simd.vectorize(lanes)
}

/// `body` for each block `i` of a run and its outputs `o`, as one function apart
/// ([`apart`]): the call is paid once a run.
///
/// The closure is `inline(always)`: left out of line, it is compiled outside the
/// instruction set's features, and every FMA in it becomes a `fmaf` call (a change that
/// grew `microfacet_block` once made Beckmann's rows 15× slower so).
macro_rules! each_block {
    ($simd:expr, $inp:expr, $out:expr, |$i:ident, $o:ident| $body:expr) => {
        apart($simd, #[inline(always)] || {
            for ($i, $o) in $inp.iter().zip($out.iter_mut()) {
                $body;
            }
        })
    };
}

/// Every lane of the run to the reference: the groups no lanes are compiled for, which
/// the parser refuses (`terms::legality`), so a material never plans them.
fn reference_block(out: &mut [Outputs]) {
    for o in out {
        o.rescue = [true; LANES];
    }
}

/// Lambert and the fused microfacet groups ([`kernel::fused`]): the groups with an f32
/// frame, compiled per form (`Z`: N = +z). The others go on to [`f64_frame_block`].
#[inline(always)]
fn f32_frame_block<S: pulp::Simd, A: MulAdd, const Z: bool>(
    simd: S,
    plan: &Plan,
    inp: &[Inputs],
    out: &mut [Outputs],
) {
    use crate::terms::{DistributionKind as D, FresnelKind as F, Geometry as G};
    use kernel::*;
    let Plan::Microfacet { d, g, f, p, .. } = plan else {
        if let Plan::Lambert(p) = plan {
            for (i, o) in inp.iter().zip(out.iter_mut()) {
                lambert_block::<Z>(p, i, o);
            }
        }
        return;
    };
    macro_rules! by_f {
        ($d:expr, $g:expr) => {
            match f {
                F::None => each_block!(simd, inp, out, |i, o| microfacet_block::<
                    A,
                    $d,
                    $g,
                    F_NONE,
                    Z,
                >(p, i, o)),
                F::Schlick => each_block!(simd, inp, out, |i, o| microfacet_block::<
                    A,
                    $d,
                    $g,
                    F_SCHLICK,
                    Z,
                >(p, i, o)),
                F::Conductor => each_block!(simd, inp, out, |i, o| microfacet_block::<
                    A,
                    $d,
                    $g,
                    F_CONDUCTOR,
                    Z,
                >(p, i, o)),
                F::Dielectric => f64_frame_block::<S, A>(simd, plan, inp, out),
            }
        };
    }
    match (d, g) {
        (D::Ggx, G::None) => by_f!(D_GGX, G_NONE),
        (D::Ggx, G::CookTorrance) => by_f!(D_GGX, G_CT),
        (D::Ggx, G::Smith) => by_f!(D_GGX, G_SMITH),
        (D::Ggx, G::SmithCorrelated) => by_f!(D_GGX, G_SMITH_CORRELATED),
        (D::Beckmann, G::None) => by_f!(D_BECKMANN, G_NONE),
        (D::Beckmann, G::CookTorrance) => by_f!(D_BECKMANN, G_CT),
        (D::Beckmann, G::Smith) => by_f!(D_BECKMANN, G_SMITH),
        (D::Beckmann, G::SmithCorrelated) => by_f!(D_BECKMANN, G_SMITH_CORRELATED),
        (D::Beckmann, G::SmithFast) => by_f!(D_BECKMANN, G_SMITH_FAST),
        // Smith-fast is Beckmann's fit: no GGX variant is compiled.
        (D::Ggx, G::SmithFast) => reference_block(out),
        // Not fused (`kernel::fused`).
        (D::Ggx | D::Beckmann, G::SchlickSmith | G::Neubelt)
        | (D::Gaussian | D::Blinn | D::Charlie, _) => f64_frame_block::<S, A>(simd, plan, inp, out),
    }
}

/// The groups whose frame is always the f64 one: the empirical lobes, and the microfacet
/// groups [`kernel::fused`] leaves out, in two passes ([`kernel::two_pass::dg_block64`]). Each
/// distribution compiles the geometry terms its rules allow (`terms::legality`); the
/// others take [`reference_block`].
#[inline(always)]
fn f64_frame_block<S: pulp::Simd, A: MulAdd>(
    simd: S,
    plan: &Plan,
    inp: &[Inputs],
    out: &mut [Outputs],
) {
    use crate::terms::{DistributionKind as D, Geometry as G};
    use kernel::two_pass::dg_block64;
    use kernel::*;
    use lobes::{lobe_block, Lobe, L_BLINN_PHONG, L_PHONG, L_RTR, L_WARD, L_WARD_ANISO};
    let (d, aniso, g, f, p) = match plan {
        Plan::Microfacet { d, aniso, g, f, p } => (*d, *aniso, *g, *f, p),
        Plan::Lobe { model, p } => {
            match *model {
                Lobe::Phong => each_block!(simd, inp, out, |i, o| lobe_block::<L_PHONG>(p, i, o)),
                Lobe::BlinnPhong => {
                    each_block!(simd, inp, out, |i, o| lobe_block::<L_BLINN_PHONG>(p, i, o))
                }
                Lobe::Rtr => each_block!(simd, inp, out, |i, o| lobe_block::<L_RTR>(p, i, o)),
                Lobe::Ward => each_block!(simd, inp, out, |i, o| lobe_block::<L_WARD>(p, i, o)),
                Lobe::WardAniso => {
                    each_block!(simd, inp, out, |i, o| lobe_block::<L_WARD_ANISO>(p, i, o))
                }
            }
            return;
        }
        Plan::Htsg { p, h } => {
            return each_block!(simd, inp, out, |i, o| super::htsg::htsg_block(p, h, i, o))
        }
        Plan::Lambert(_) | Plan::Measured | Plan::Reference => return,
    };
    // Both passes in one function apart per (D, G); F is matched in it, a block at a time.
    macro_rules! dg {
        ($d:expr, $g:expr) => {
            each_block!(simd, inp, out, |i, o| {
                let mut st = Stage::default();
                dg_block64::<A, $d, $g>(p, i, &mut st);
                f_pass::<A>(f, p, &st, o)
            })
        };
    }
    macro_rules! aniso {
        ($d:expr, $g:expr) => {
            each_block!(simd, inp, out, |i, o| {
                let mut st = Stage::default();
                aniso::dg_block64_aniso::<$d, $g>(p, i, &mut st);
                f_pass::<A>(f, p, &st, o)
            })
        };
    }
    // Gaussian, Blinn and Charlie: no Smith Λ (so no Smith or Schlick–Smith geometry) and
    // no anisotropic roughness.
    macro_rules! no_lambda {
        ($d:expr) => {
            match g {
                G::None => dg!($d, G_NONE),
                G::CookTorrance => dg!($d, G_CT),
                G::Neubelt => dg!($d, G_NEUBELT),
                G::Smith | G::SmithCorrelated | G::SmithFast | G::SchlickSmith => {
                    reference_block(out)
                }
            }
        };
    }
    match (d, aniso, g) {
        (D::Ggx, false, G::None) => dg!(D_GGX, G_NONE),
        (D::Ggx, false, G::CookTorrance) => dg!(D_GGX, G_CT),
        (D::Ggx, false, G::Smith) => dg!(D_GGX, G_SMITH),
        (D::Ggx, false, G::SmithCorrelated) => dg!(D_GGX, G_SMITH_CORRELATED),
        (D::Ggx, false, G::SchlickSmith) => dg!(D_GGX, G_SCHLICK_SMITH),
        (D::Ggx, false, G::Neubelt) => dg!(D_GGX, G_NEUBELT),
        (D::Beckmann, false, G::None) => dg!(D_BECKMANN, G_NONE),
        (D::Beckmann, false, G::CookTorrance) => dg!(D_BECKMANN, G_CT),
        (D::Beckmann, false, G::Smith) => dg!(D_BECKMANN, G_SMITH),
        (D::Beckmann, false, G::SmithCorrelated) => dg!(D_BECKMANN, G_SMITH_CORRELATED),
        (D::Beckmann, false, G::SmithFast) => dg!(D_BECKMANN, G_SMITH_FAST),
        (D::Beckmann, false, G::SchlickSmith) => dg!(D_BECKMANN, G_SCHLICK_SMITH),
        (D::Beckmann, false, G::Neubelt) => dg!(D_BECKMANN, G_NEUBELT),
        // Anisotropic roughness: no schlick-smith (FORMULAS.md §3), smith-fast with
        // Beckmann only.
        (D::Ggx, true, G::None) => aniso!(D_GGX, G_NONE),
        (D::Ggx, true, G::CookTorrance) => aniso!(D_GGX, G_CT),
        (D::Ggx, true, G::Smith) => aniso!(D_GGX, G_SMITH),
        (D::Ggx, true, G::SmithCorrelated) => aniso!(D_GGX, G_SMITH_CORRELATED),
        (D::Ggx, true, G::Neubelt) => aniso!(D_GGX, G_NEUBELT),
        (D::Beckmann, true, G::None) => aniso!(D_BECKMANN, G_NONE),
        (D::Beckmann, true, G::CookTorrance) => aniso!(D_BECKMANN, G_CT),
        (D::Beckmann, true, G::Smith) => aniso!(D_BECKMANN, G_SMITH),
        (D::Beckmann, true, G::SmithCorrelated) => aniso!(D_BECKMANN, G_SMITH_CORRELATED),
        (D::Beckmann, true, G::SmithFast) => aniso!(D_BECKMANN, G_SMITH_FAST),
        (D::Beckmann, true, G::Neubelt) => aniso!(D_BECKMANN, G_NEUBELT),
        (D::Ggx, false, G::SmithFast)
        | (D::Ggx, true, G::SmithFast | G::SchlickSmith)
        | (D::Beckmann, true, G::SchlickSmith)
        | (D::Gaussian | D::Blinn | D::Charlie, true, _) => reference_block(out),
        (D::Gaussian, false, _) => no_lambda!(D_GAUSSIAN),
        (D::Blinn, false, _) => no_lambda!(D_BLINN),
        (D::Charlie, false, _) => no_lambda!(D_CHARLIE),
    }
}

/// The second pass of the f64-frame groups: F, K and the outputs ([`kernel::two_pass::f_block`]).
#[inline(always)]
fn f_pass<A: MulAdd>(f: FresnelKind, p: &kernel::Params, st: &Stage, out: &mut Outputs) {
    use kernel::*;
    match f {
        FresnelKind::None => f_block::<A, F_NONE>(p, st, out),
        FresnelKind::Schlick => f_block::<A, F_SCHLICK>(p, st, out),
        FresnelKind::Dielectric => f_block::<A, F_DIELECTRIC>(p, st, out),
        FresnelKind::Conductor => f_block::<A, F_CONDUCTOR>(p, st, out),
    }
}
