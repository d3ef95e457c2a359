//! The kernel's f32 Cook–Torrance arithmetic on the bench's Mitsuba paths (GGX D and Smith
//! G in root form on the local f32 frame; Beckmann D through `exp_acc` and Smith-fast G on the float64
//! local frame; the conductor's metal form, the modern K and the product: glsl/terms.glsl,
//! glsl/math.glsl, glsl/models.glsl) under the precisions the Vulkan specification allows,
//! not those lavapipe happens to have: `+ − ×` correctly rounded (u = 2⁻²⁴), `x/y` within
//! 2.5 ULP (5u), `inversesqrt` 2 ULP (4u), `sqrt` inherited from `1/inversesqrt` (2 + 2.5
//! ULP: 9u). Each GLSL step is replayed in f64 with the material as the host writes it
//! (rounded to f32); the f32 frame's values exact (their errors are that frame's bound,
//! docs/VULKAN.md "The local frames"), the float64 frame's each rounded once to f32, an
//! operation of the replay. To first order the error of an execution is the sum of each
//! operation's own effect, so the worst execution the precisions allow is the sum of their
//! magnitudes: each is measured by moving that one operation by its whole allowance. The
//! replay is the GLSL rewritten by hand: a change to one is made in the other. No device.

use glam::DVec3;
use std::cell::Cell;
use vkbrdf::terms::d::{beckmann, ggx};
use vkbrdf::terms::f::conductor;
use vkbrdf::terms::f::conductor::poly::{Polynomial, CENTRE, DEGREE};
use vkbrdf::terms::g::{smith, smith_fast};

const U: f64 = f32::EPSILON as f64 / 2.0;

/// One execution: operation `moved` (in the order they run) off by its whole allowance,
/// the others exact.
struct Execution {
    moved: Option<u32>,
    next: Cell<u32>,
}

impl Execution {
    fn new(moved: Option<u32>) -> Execution {
        Execution {
            moved,
            next: Cell::new(0),
        }
    }

    /// The operations this execution ran.
    fn count(&self) -> u32 {
        self.next.get()
    }

    fn op(&self, x: f64, allowance: f64) -> f64 {
        let i = self.next.get();
        self.next.set(i + 1);
        if self.moved == Some(i) {
            x * (1.0 + allowance * U)
        } else {
            x
        }
    }
    fn add(&self, a: f64, b: f64) -> f64 {
        self.op(a + b, 1.0)
    }
    fn sub(&self, a: f64, b: f64) -> f64 {
        self.op(a - b, 1.0)
    }
    fn mul(&self, a: f64, b: f64) -> f64 {
        self.op(a * b, 1.0)
    }
    fn div(&self, a: f64, b: f64) -> f64 {
        self.op(a / b, 5.0)
    }
    fn sqrt(&self, a: f64) -> f64 {
        self.op(a.sqrt(), 9.0)
    }
    fn inversesqrt(&self, a: f64) -> f64 {
        self.op(1.0 / a.sqrt(), 4.0)
    }
    /// An f64 value of the float64 frame rounded once to f32.
    fn round(&self, a: f64) -> f64 {
        self.op(a, 1.0)
    }
}

/// The first-order worst execution of `replay` against `want` (absolute): the unmoved
/// execution's error plus, for each operation it ran, the magnitude of that operation's
/// own effect.
fn worst_execution(replay: impl Fn(&Execution) -> f64, want: f64) -> f64 {
    let unmoved = Execution::new(None);
    let base = replay(&unmoved);
    let moves = (0..unmoved.count()).map(|i| (replay(&Execution::new(Some(i))) - base).abs());
    (base - want).abs() + moves.sum::<f64>()
}

/// The value as the host rounds it into the material table.
fn f32_of(x: f64) -> f64 {
    f64::from(x as f32)
}

/// A Cook–Torrance conductor of the bench's kind (GGX or Beckmann by the path; modern K,
/// `specular` 1, no diffuse).
struct Material {
    m: f64,
    n: [f64; 3],
    k: [f64; 3],
}

/// The frame's values of one tuple with N = +z (exact).
struct Geometry {
    cos_i: f64,
    cos_o: f64,
    cos_h: f64,
    c: f64,
    sin2_h: f64,
    sin2_i: f64,
    sin2_o: f64,
}

/// `conductor_f_metal` (glsl/terms.glsl) at the frame's `c` for `η = n + ik`, from the
/// material as the host gives it (`n`, `k`, `n² − k² − 1` rounded to f32).
fn conductor_f_metal(x: &Execution, c: f64, n64: f64, k64: f64) -> f64 {
    let (n, k) = (f32_of(n64), f32_of(k64));
    let e2rm1 = f32_of(n64 * n64 - k64 * k64 - 1.0);
    let c2 = x.mul(c, c);
    let omc = if c >= 0.5 { 1.0 - c } else { x.sub(1.0, c) };
    let s2 = x.mul(omc, x.add(1.0, c));
    let e2ih = x.mul(n, k);
    let re = x.sub(x.add(e2rm1, 1.0), s2);
    let mag = x.sqrt(x.add(x.mul(re, re), 4.0 * x.mul(e2ih, e2ih)));
    let t = x.sqrt(0.5 * x.add(mag, re.abs()));
    let a = if re >= 0.0 { t } else { x.div(e2ih, t) };
    let ca2 = x.mul(2.0 * c, a);
    let bs = x.add(mag, c2);
    let bp = x.add(x.mul(mag, c2), x.mul(s2, s2));
    let num = x.mul(x.sub(bs, ca2), bp);
    let den = x.mul(x.add(bs, ca2), x.add(bp, x.mul(ca2, s2)));
    x.div(num, den)
}

/// The worst execution's relative error of `conductor_f_metal`, in u, at 4,001 c in
/// [1e-4, 1] (denser towards normal incidence, where its one difference cancels most).
fn conductor_worst_execution(n: f64, k: f64) -> f64 {
    let mut worst = 0f64;
    for j in 0..=4000 {
        let y = f64::from(j) / 4000.0;
        let c = f64::from((1e-4 + (1.0 - 1e-4) * y.sqrt()) as f32);
        let want = conductor::f(c, n, k);
        let err = worst_execution(|x| conductor_f_metal(x, c, n, k), want);
        worst = worst.max(err / (U * want));
    }
    worst
}

/// `model_cook_torrance`'s f for one channel, step by step as the GLSL takes it, with F's
/// metal form.
fn kernel_f(x: &Execution, g: &Geometry, mat: &Material, ch: usize) -> f64 {
    kernel_f_with(x, g, mat, |x| {
        conductor_f_metal(x, g.c, mat.n[ch], mat.k[ch])
    })
}

/// [`kernel_f`] with F's replay `f`.
fn kernel_f_with(
    x: &Execution,
    g: &Geometry,
    mat: &Material,
    f: impl Fn(&Execution) -> f64,
) -> f64 {
    let (inv_m2, m2) = (f32_of(1.0 / (mat.m * mat.m)), f32_of(mat.m * mat.m));
    let norm = f32_of(1.0 / (std::f64::consts::PI * mat.m * mat.m));
    // ggx_d(slope2_h, cos_h, norm)
    let slope2 = x.mul(g.sin2_h, inv_m2);
    let d = x.add(slope2, x.mul(g.cos_h, g.cos_h));
    let dd = x.div(norm, x.mul(d, d));
    // smith_g_ggx(cos_o, ggx_lambda_root(cos_o, m2_sin2(v)), cos_i, ggx_lambda_root(…))
    let root = |sin2: f64, cos: f64| x.sqrt(x.add(x.mul(cos, cos), x.mul(m2, sin2)));
    let (ro, ri) = (root(g.sin2_o, g.cos_o), root(g.sin2_i, g.cos_i));
    let num = x.mul(4.0 * g.cos_o, g.cos_i);
    let gg = x.div(num, x.mul(x.add(g.cos_o, ro), x.add(g.cos_i, ri)));
    product(x, dd, gg, f(x), g.cos_i, g.cos_o)
}

/// [`kernel_f`] in a folded kernel of a conductor with a fitted polynomial
/// (`conductor_f_poly`, glsl/terms.glsl): F by Horner's rule in `t = c − CENTRE` from the
/// coefficients as the host rounds them, each step a product and a sum (Vulkan lets an
/// `fma` round twice), where c ≥ `CONDUCTOR_POLY_MIN_C` (0.1); below, the metal form.
fn kernel_f_poly(x: &Execution, g: &Geometry, mat: &Material, ch: usize) -> f64 {
    let poly = Polynomial::fitted(mat.n, mat.k).expect("the metals here have a fit");
    let f_poly = |x: &Execution| {
        let b = poly.b[ch].map(f64::from);
        let t = x.sub(g.c, f64::from(CENTRE));
        let mut r = b[DEGREE];
        for i in (0..DEGREE).rev() {
            r = x.add(x.mul(r, t), b[i]);
        }
        r
    };
    let f = |x: &Execution| {
        if g.c >= f64::from(0.1f32) {
            f_poly(x)
        } else {
            conductor_f_metal(x, g.c, mat.n[ch], mat.k[ch])
        }
    };
    kernel_f_with(x, g, mat, f)
}

/// `modern_k`, then `model_cook_torrance`'s (D G) F K and the colour (diffuse 0 plus
/// specular 1 times it: two more roundings).
fn product(x: &Execution, dd: f64, gg: f64, f: f64, cos_i: f64, cos_o: f64) -> f64 {
    let kk = x.div(0.25, x.mul(cos_i, cos_o));
    let dgf = x.mul(x.mul(dd, gg), f);
    x.add(0.0, x.mul(1.0, x.mul(dgf, kk)))
}

/// The exact f of the same tuple (the reference's terms in f64).
fn exact_f(g: &Geometry, mat: &Material, ch: usize) -> f64 {
    let m2 = mat.m * mat.m;
    let dd = ggx::d(g.cos_h, g.sin2_h, mat.m);
    let lambda = |sin2: f64, cos: f64| ggx::lambda(m2 * sin2 / (cos * cos));
    let gg = smith::g(lambda(g.sin2_o, g.cos_o), lambda(g.sin2_i, g.cos_i));
    let f = conductor::f(g.c, mat.n[ch], mat.k[ch]);
    dd * gg * f / (4.0 * g.cos_i * g.cos_o)
}

/// The frame's values (FORMULAS.md §1) of unit l, v, n, exactly.
fn frame(l: DVec3, v: DVec3, n: DVec3) -> Geometry {
    let len = (l + v).length();
    let h = (l + v) / len;
    let sin2 = |w: DVec3| n.cross(w).length_squared();
    Geometry {
        cos_i: n.dot(l),
        cos_o: n.dot(v),
        cos_h: n.dot(h),
        c: len / 2.0,
        sin2_h: sin2(h),
        sin2_i: sin2(l),
        sin2_o: sin2(v),
    }
}

/// `w` turned by the angle u about the unit axis `a` ⊥ `w`.
fn turned(w: DVec3, a: DVec3) -> DVec3 {
    let (s, c) = U.sin_cos();
    w * c + a.cross(w) * s
}

/// FORMULAS.md §1's S_in of channel `ch`: the sum over the rotation modes of L, V and N
/// (each turned by u about two axes perpendicular to it) of |f(turned) − f|.
fn s_in(path: &Path, l: DVec3, v: DVec3, n: DVec3, mat: &Material, ch: usize) -> f64 {
    let exact_f = path.exact;
    let f0 = exact_f(&frame(l, v, n), mat, ch);
    let axes = |w: DVec3| {
        let a = w.any_orthonormal_vector();
        [a, w.cross(a)]
    };
    let mut sum = 0.0;
    for which in 0..3 {
        let w = [l, v, n][which];
        for a in axes(w) {
            let mut dirs = [l, v, n];
            dirs[which] = turned(w, a);
            sum += (exact_f(&frame(dirs[0], dirs[1], dirs[2]), mat, ch) - f0).abs();
        }
    }
    sum
}

/// The local f32 frame's own bound on a lane (docs/VULKAN.md, "The local frames"): D moves
/// by its log-slope times h's turn δ = u (2/c + 1), at most B = 4e-6 on the lanes the
/// certificate passes (the others take the accurate frame), and ~45u from the frame's
/// other values.
fn frame_bound(g: &Geometry, m: f64) -> f64 {
    let m2 = m * m;
    let (cos2, sin2) = (g.cos_h * g.cos_h, g.sin2_h);
    let slope = 4.0 * (1.0 - m2).abs() * sin2.sqrt() * g.cos_h / (m2 * cos2 + sin2);
    (slope * U * (2.0 / g.c + 1.0)).min(4e-6) + 45.0 * U
}

/// One kernel path: its replay, the exact f it computes, the bound of the frame it runs on
/// (relative, on a lane) and the least c at which it runs.
struct Path {
    kernel: fn(&Execution, &Geometry, &Material, usize) -> f64,
    exact: fn(&Geometry, &Material, usize) -> f64,
    frame: fn(&Geometry, f64) -> f64,
    min_c: f64,
}

/// GGX's lanes on the local f32 frame (below c = 1/16, `LOCAL32_MIN_C`, the accurate frame
/// takes the lane).
const GGX_LOCAL32: Path = Path {
    kernel: kernel_f,
    exact: exact_f,
    frame: frame_bound,
    min_c: 1.0 / 16.0,
};

/// [`GGX_LOCAL32`] in a folded kernel whose conductor has a fitted polynomial.
const GGX_LOCAL32_POLY: Path = Path {
    kernel: kernel_f_poly,
    ..GGX_LOCAL32
};

/// Beckmann's lanes on the float64 local frame, whose values' roundings the replay holds.
const BECKMANN_F64: Path = Path {
    kernel: kernel_f_beckmann,
    exact: exact_f_beckmann,
    frame: |_, _| 0.0,
    min_c: 0.0,
};

/// The smallest margin, in u, between what the rule leaves the terms' arithmetic on the
/// local f32 frame's lanes — FORMULAS.md §1's `1e-5 |f| + 4 S_in` less the frame's own
/// bound (docs/VULKAN.md "The local frames": D's certificate B = 4e-6 and ~45u) — and the
/// worst execution of that arithmetic, over a grid of directions (cosines from 1e-4, the
/// frame's least, to 1; mirror, retro and side azimuths; the specular peak), every
/// channel. Also the worst execution itself, in u of f.
fn margin(path: &Path, mat: &Material) -> (f64, f64) {
    let (kernel_f, exact_f, frame_bound) = (path.kernel, path.exact, path.frame);
    let (mut least, mut worst) = (f64::INFINITY, 0f64);
    let angles: Vec<f64> = (0..=24)
        .map(|i| 1e-4f64.powf(f64::from(i) / 24.0).acos())
        .collect();
    let n = DVec3::Z;
    for &ti in &angles {
        for &to in &angles {
            for phi in [0.0, 0.3, 1.0, 2.0, 3.0, std::f64::consts::PI] {
                let l = DVec3::new(ti.sin(), 0.0, ti.cos());
                let v = DVec3::new(to.sin() * phi.cos(), to.sin() * phi.sin(), to.cos());
                let g = frame(l, v, n);
                if g.c < path.min_c {
                    continue;
                }
                for ch in 0..3 {
                    let want = exact_f(&g, mat, ch);
                    let err = worst_execution(|x| kernel_f(x, &g, mat, ch), want);
                    // FORMULAS.md §1's floor: 1e-5 of at least 1e-6.
                    let scale = want.max(1e-6);
                    let allowed = 1e-5 * scale + 4.0 * s_in(path, l, v, n, mat, ch)
                        - frame_bound(&g, mat.m) * want;
                    least = least.min((allowed - err) / (U * scale));
                    worst = worst.max(err / (U * scale));
                }
            }
        }
    }
    (least, worst)
}

/// `path` on the bench's metal (the Mitsuba scenarios' η) and on copper and gold at low,
/// middle and high roughness: the worst execution the specification allows keeps within
/// what the frame leaves of the rule (FORMULAS.md §1) on every lane of the grid, and the
/// replay is not idle (each operation moved does move f).
fn fits_the_rule(path: &Path) {
    let metals = [
        ([0.2, 0.92, 1.1], [3.9, 2.45, 2.14]), // the bench's Mitsuba scenarios
        ([0.27, 0.68, 1.2], [3.61, 2.63, 2.3]), // copper
        ([0.18, 0.42, 1.37], [3.42, 2.35, 1.77]), // gold
    ];
    for (n, k) in metals {
        for m in [0.08, 0.3, 1.0] {
            let (least, worst) = margin(path, &Material { m, n, k });
            eprintln!("m = {m}, η = {n:?} + {k:?}i: worst {worst:.1}u, least margin {least:.1}u");
            assert!(
                least >= 0.0,
                "m = {m}, η = {n:?} + {k:?}i: {least:.1}u short"
            );
            assert!(worst > 40.0, "the replay moved f by only {worst:.1}u");
        }
    }
}

/// The mitsuba-ggx scenario's path (GGX D, Smith G, the metal form, modern K) on the
/// local f32 frame.
#[test]
fn the_kernels_cook_torrance_arithmetic_fits_the_rule_under_vulkans_precisions() {
    fits_the_rule(&GGX_LOCAL32);
}

/// The same path in a folded kernel, F from the conductor's fitted polynomial
/// (`conductor_f_poly`, glsl/terms.glsl) on the lanes with c ≥ 0.1 and the metal form below.
#[test]
fn the_kernels_cook_torrance_arithmetic_with_fs_polynomial_fits_the_rule() {
    fits_the_rule(&GGX_LOCAL32_POLY);
}

/// `exp_acc` (glsl/math.glsl) of an f32 `x` in its normal range: Cody–Waite reduction with
/// the exact `k · LN2_HI`, then the degree-7 polynomial (its truncation included) and the
/// exact scaling. `k` is taken from the unmoved x (a moved one changes k only where both
/// reductions are equally valid).
fn exp_acc(x: &Execution, v: f64) -> f64 {
    const LN2_HI: f64 = 0.693145751953125;
    let ln2_lo = f64::from(1.428_606_8e-6_f32);
    if v < -87.3 {
        return 0.0; // below FLT_MIN: the GLSL's early 0
    }
    let k = (v * std::f64::consts::LOG2_E + 0.5).floor();
    let r = x.sub(v - k * LN2_HI, k * ln2_lo);
    let mut p = 1.0 / 5040.0;
    for c in [720.0, 120.0, 24.0, 6.0, 2.0, 1.0, 1.0] {
        p = x.add(1.0 / c, x.mul(r, p));
    }
    p * 2f64.powf(k)
}

/// The mitsuba-beckmann scenario's f (Beckmann D, Smith-fast G, the metal form, modern K;
/// `model_cook_torrance`) for one channel on the float64 local frame: the frame's values
/// exact in f64, each rounded once to f32 (an operation of allowance u), then the GLSL's
/// f32 steps.
fn kernel_f_beckmann(x: &Execution, g: &Geometry, mat: &Material, ch: usize) -> f64 {
    let (cos_i, cos_o, cos_h, c) = (
        x.round(g.cos_i),
        x.round(g.cos_o),
        x.round(g.cos_h),
        x.round(g.c),
    );
    let (sin2_h, sin2_i, sin2_o) = (x.round(g.sin2_h), x.round(g.sin2_i), x.round(g.sin2_o));
    let (inv_m2, m2) = (f32_of(1.0 / (mat.m * mat.m)), f32_of(mat.m * mat.m));
    let norm = f32_of(1.0 / (std::f64::consts::PI * mat.m * mat.m));
    // beckmann_d(slope2_h, cos_h, sin2_h, norm)
    let slope2 = x.mul(sin2_h, inv_m2);
    let inv_c2 = x.div(1.0, x.mul(cos_h, cos_h));
    let half_lobe = x.mul(exp_acc(x, -0.5 * x.mul(slope2, inv_c2)), inv_c2);
    let dd = x.mul(norm, x.mul(half_lobe, half_lobe));
    // smith_fast_g1(m2_tan2(v)) * smith_fast_g1(m2_tan2(l))
    let g1 = |sin2: f64, cos: f64| {
        let q2 = x.div(x.mul(m2, sin2), x.mul(cos, cos));
        let a = x.inversesqrt(q2);
        if a < 1.6 {
            let aa = x.mul(a, a);
            let num = x.add(x.mul(3.535, a), x.mul(2.181, aa));
            let den = x.add(x.add(1.0, x.mul(2.276, a)), x.mul(2.577, aa));
            x.div(num, den)
        } else {
            1.0
        }
    };
    let gg = x.mul(g1(sin2_o, cos_o), g1(sin2_i, cos_i));
    let f = conductor_f_metal(x, c, mat.n[ch], mat.k[ch]);
    product(x, dd, gg, f, cos_i, cos_o)
}

/// The exact f of the mitsuba-beckmann scenario's material.
fn exact_f_beckmann(g: &Geometry, mat: &Material, ch: usize) -> f64 {
    let m2 = mat.m * mat.m;
    let dd = beckmann::d(g.cos_h, g.sin2_h, mat.m, std::f64::consts::PI);
    let g1 = |sin2: f64, cos: f64| smith_fast::g1(m2 * sin2 / (cos * cos));
    let f = conductor::f(g.c, mat.n[ch], mat.k[ch]);
    dd * g1(g.sin2_o, g.cos_o) * g1(g.sin2_i, g.cos_i) * f / (4.0 * g.cos_i * g.cos_o)
}

/// The mitsuba-beckmann scenario's path (Beckmann D with `exp_acc`, Smith-fast G, the
/// metal form, modern K) on the float64 local frame, whose one rounding a value the
/// replay holds.
#[test]
fn the_kernels_beckmann_arithmetic_fits_the_rule_under_vulkans_precisions() {
    fits_the_rule(&BECKMANN_F64);
}

/// The kernel's metal form keeps inside the bound written for Vulkan's precisions
/// (`conductor::metal_form_bound_vulkan`) in its worst execution, on copper's channels
/// and on the legal materials nearest the lanes' budget (small F0, Re η² near 0 and 1,
/// small |η|). docs/VULKAN.md ("The metal form under Vulkan's precisions") has the
/// figures: the written bound is 3–10× the worst execution.
#[test]
fn the_kernels_metal_form_keeps_its_bound_under_vulkans_precisions() {
    let cases = [
        (0.27, 3.61),
        (0.68, 2.63),
        (1.2, 2.3),
        (0.2, 3.9),
        (1.37, 1.77),
        (5.0, 0.0),
        (1.0, 1.3),
        (0.02, 0.7),
    ];
    for (n, k) in cases {
        let bound = conductor::metal_form_bound_vulkan(n, k);
        let worst = conductor_worst_execution(n, k);
        eprintln!("η = {n} + {k}i: worst {worst:.1}u, written bound {bound:.1}u");
        assert!(
            worst <= bound,
            "η = {n} + {k}i: {worst:.1}u against {bound:.1}u"
        );
        assert!(worst > 5.0, "the replay moved F by only {worst:.1}u");
    }
}
