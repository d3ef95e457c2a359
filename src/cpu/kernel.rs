//! The specialised lanes: one block of [`LANES`] tuples of one material group, the frame in
//! f64 lanes, the terms in f32 lanes (FORMULAS.md §1–§6), compiled once per material group
//! (distribution × geometry × Fresnel, as const generics) and per instruction set (the
//! caller dispatches with `pulp`). Every loop runs over the lanes with no data-dependent
//! branch and no call, so it vectorises to the widest registers the dispatch enabled.
//!
//! A lane whose tuple the f32 arithmetic cannot be trusted with is flagged for *rescue* —
//! the caller re-evaluates it with the f64 reference, which also decides its status:
//! invalid and below-horizon tuples, cosines below [`GRAZING`], and any output that came
//! out non-finite or above [`OUTPUT_LIMIT`] (the saturation and overflow cases).

// The lane loops index several arrays with the same lane (or column) number; iterator
// forms would hide that the loops are the vectorised dimension.
#![allow(clippy::needless_range_loop)]

use crate::backend::TERM_COLUMNS;
use crate::terms::d::{beckmann, blinn, charlie, gaussian, ggx};
use crate::terms::f::{conductor, dielectric, schlick};
use crate::terms::g::{cook_torrance, neubelt, schlick_smith, smith, smith_correlated, smith_fast};
use crate::terms::k::LaneK;
use crate::terms::{DistributionKind, FresnelKind, Geometry};

/// Tuples per block: 16 f32 lanes fill one AVX-512 register (two AVX2 registers).
pub const LANES: usize = 16;

/// Cosines (`cos_i`, `cos_o`, `cos_h`, `c`) below this go to the reference: there K and
/// the 1/cos factors of D and Λ leave the range where a few f32 roundings stay far inside
/// the tolerance, and the reference's log-domain and scaled forms take over (FORMULAS.md
/// §1, "Overflow": cosines down to the smallest subnormal must still come out exact).
pub const GRAZING: f64 = 1e-4;

/// Outputs above this go to the reference, which decides saturation (FORMULAS.md §1): an
/// f32 result this large may be a rounded value of an exact one above `f32::MAX`.
pub const OUTPUT_LIMIT: f32 = 1e37;

// The lanes' const parameters: each family's codes, from its list (`crate::terms`).
/// Distribution: GGX.
pub const D_GGX: u8 = DistributionKind::Ggx.code();
/// Distribution: Beckmann.
pub const D_BECKMANN: u8 = DistributionKind::Beckmann.code();
/// Distribution: Torrance–Sparrow Gaussian.
pub const D_GAUSSIAN: u8 = DistributionKind::Gaussian.code();
/// Distribution: normalised Blinn–Phong NDF.
pub const D_BLINN: u8 = DistributionKind::Blinn.code();
/// Distribution: Estevez–Kulla "Charlie" sheen.
pub const D_CHARLIE: u8 = DistributionKind::Charlie.code();
/// Geometry: none.
pub const G_NONE: u8 = Geometry::None.code();
/// Geometry: Cook–Torrance V-cavity.
pub const G_CT: u8 = Geometry::CookTorrance.code();
/// Geometry: separable Smith.
pub const G_SMITH: u8 = Geometry::Smith.code();
/// Geometry: height-correlated Smith.
pub const G_SMITH_CORRELATED: u8 = Geometry::SmithCorrelated.code();
/// Geometry: Walter's rational Smith–Beckmann fit.
pub const G_SMITH_FAST: u8 = Geometry::SmithFast.code();
/// Geometry: Schlick–Smith with Karis's k.
pub const G_SCHLICK_SMITH: u8 = Geometry::SchlickSmith.code();
/// Geometry: Neubelt–Pettineo cloth.
pub const G_NEUBELT: u8 = Geometry::Neubelt.code();
/// Fresnel: none.
pub const F_NONE: u8 = FresnelKind::None.code();
/// Fresnel: Schlick.
pub const F_SCHLICK: u8 = FresnelKind::Schlick.code();
/// Fresnel: exact dielectric.
pub const F_DIELECTRIC: u8 = FresnelKind::Dielectric.code();
/// Fresnel: exact conductor.
pub const F_CONDUCTOR: u8 = FresnelKind::Conductor.code();

/// The constants of one material, prepared once per batch (in f64 where the lanes use
/// f64, then rounded once).
#[derive(Debug, Clone, Copy, Default)]
pub struct Params {
    /// `d · c_diff / π` (Lambert: `c_diff / π`).
    pub diffuse: [f32; 3],
    /// `s · c_spec`.
    pub spec: [f32; 3],
    /// `m²`.
    pub m2: f64,
    /// `1/m²`.
    pub inv_m2: f64,
    /// The D normalisation: `1/(k m²)` for Beckmann, `m²/π` for GGX.
    pub d_norm: f64,
    /// `m²`, `1/m²` and the D normalisation rounded to f32, for the f32 frame's D.
    pub m2_f: f32,
    /// See `m2_f`.
    pub inv_m2_f: f32,
    /// See `m2_f`.
    pub d_norm_f: f32,
    /// K (the convention's lane form).
    pub k: LaneK,
    /// Schlick's F0.
    pub f0: [f32; 3],
    /// Dielectric μ.
    pub ior: [f64; 3],
    /// Dielectric `μ² − 1`, as `(μ − 1)(μ + 1)`.
    pub mu2m1: [f64; 3],
    /// The conductor's constants.
    pub conductor: conductor::LaneConstants,
    /// Whether the material may take the f32 frame (see [`microfacet_block`]): m ≥
    /// [`FAST_MIN_ROUGHNESS`] and a Fresnel term other than the dielectric (whose f64
    /// evaluation near total internal reflection wants the f64 `c`).
    pub fast_frame: bool,
    /// The exponent of a `cos^e` lobe: Blinn's and the empirical models' `e`, Charlie's
    /// `1/m`.
    pub exponent: f32,
    /// Schlick–Smith's k (Karis 2013: `m/2` GGX, `m √(2/π)` Beckmann).
    pub schlick_k: f32,
    /// Anisotropic roughness `[1/mx², 1/my², mx², my²]`.
    pub aniso: [f64; 4],
}

/// One block's inputs as structure of arrays (f32, as read from the rows).
#[derive(Clone, Copy)]
pub struct Inputs {
    /// L, V, N and T components: `v[j][k]` is component `j` of lane `k` (0–8: L, V, N;
    /// 9–11: T, filled only for the groups that read it).
    pub v: [[f32; LANES]; 12],
}

impl Default for Inputs {
    fn default() -> Self {
        Inputs {
            v: [[0.0; LANES]; 12],
        }
    }
}

/// One block's outputs.
#[derive(Clone, Copy)]
pub struct Outputs {
    /// RGB per lane.
    pub brdf: [[f32; LANES]; 3],
    /// D, G, F_r, F_g, F_b, K per lane.
    pub terms: [[f32; LANES]; TERM_COLUMNS],
    /// Lanes to re-evaluate with the reference.
    pub rescue: [bool; LANES],
}

impl Outputs {
    /// Whether any lane is flagged for rescue: one 16-byte test instead of a branch a lane
    /// (the per-lane loop cost about 5 % of a microfacet block).
    #[inline(always)]
    pub fn any_rescue(&self) -> bool {
        u128::from_ne_bytes(self.rescue.map(u8::from)) != 0
    }
}

impl Default for Outputs {
    fn default() -> Self {
        Outputs {
            brdf: [[0.0; LANES]; 3],
            terms: [[0.0; LANES]; TERM_COLUMNS],
            rescue: [false; LANES],
        }
    }
}

/// The frame of one lane (FORMULAS.md §1) and whether the lanes may take it.
#[derive(Clone, Copy, Default)]
struct Frame {
    cos_i: f32,
    cos_o: f32,
    cos_h: f32,
    c: f32,
    /// `1 − c²`.
    s2: f32,
    sin2_h: f32,
    sin2_i: f32,
    sin2_o: f32,
    ok: bool,
}

/// Squared lengths in this range leave the lanes' f32 arithmetic a factor 1e19 either
/// side before anything over- or underflows; directions outside it (finite, but longer
/// than 1e15 or shorter than 1e-15) go to the reference, which normalises any f32.
const LENGTH2_MIN: f32 = 1e-30;
const LENGTH2_MAX: f32 = 1e30;

/// Whether a squared length is in [`LENGTH2_MIN`, `LENGTH2_MAX`] (false for NaN).
#[inline(always)]
fn length2_ok(q: f32) -> bool {
    (LENGTH2_MIN..=LENGTH2_MAX).contains(&q)
}

/// [`length2_ok`] of a squared length formed in f64 (false for NaN).
#[inline(always)]
fn length2_ok64(q: f64) -> bool {
    (f64::from(LENGTH2_MIN)..=f64::from(LENGTH2_MAX)).contains(&q)
}

/// `1/√x`, correctly rounded square root then division: within 1 ulp, and exactly 1 for
/// x = 1 (the local form's N must come out exactly (0, 0, 1), see [`frame`]).
#[inline(always)]
fn rsqrt(x: f32) -> f32 {
    1.0 / x.sqrt()
}

/// The frame of one lane in f32; `Z`: N is (0, 0, 1) (the local form), whose dot and
/// cross products with N reduce to single components — the same operations on the same
/// values as the general frame with that N, so both give the same bits.
///
/// Why f32 suffices (the bound and its margin: docs/CPU_ENGINE.md, "The f32 frame's error
/// bound"): l and v are the inputs times `1/|x|` formed in f64 and rounded once to f32, so
/// each component is within u = 2⁻²⁴ (relative) of the exact unit vector's. Their lengths
/// must agree to far better than f32's 1 ± 2u: h = normalize(l + v) turns by
/// `(ε_l − ε_v) tan θ_d` when l and v are scaled by 1 + ε_l and 1 + ε_v, and near the peak of
/// a lobe of roughness m that rotation δ moves D by ~2δ/m — with f32 lengths (ε up to
/// 2.5u each) 2e-5 of D at m = 0.05, four times the inputs' own rounding. In the local form
/// each cosine is one component of a unit vector (no cancellation at any angle), in the
/// general form a dot product of the raw inputs in f64, then scaled. The half vector's
/// components cancel near grazing mirror geometry (`l ≈ −v`), but only by as much as the
/// inputs' own rounding turns h there, and those lanes (`c` < [`FAST_MIN_C`]) take the f64
/// frame; `c` is taken as `|l + v|/2` rather than `v · h`, which would cancel a second time
/// (`v·l + 1`). The sines are sums of squares (cross products with the raw N in f64, from
/// the unrounded l, v and l + v), never `1 − cos²`.
#[inline(always)]
fn frame<const Z: bool>(x: &[f32; 9]) -> Frame {
    // l, v and h in f64, each rounded once to f32 (see the bound above): |L|² and |V|²
    // are exact in f64 (squares of f32 values), 1/|x| by `rsqrt64_fast` (~1e-14 relative).
    let w = |i: usize| f64::from(x[i]);
    let sq3 = |a: [f64; 3]| a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    let (l64, v64) = ([w(0), w(1), w(2)], [w(3), w(4), w(5)]);
    let (ll, vv) = (sq3(l64), sq3(v64));
    let (il, iv) = (rsqrt64_fast(ll), rsqrt64_fast(vv));
    let (l64, v64) = (l64.map(|q| q * il), v64.map(|q| q * iv));
    let h64: [f64; 3] = std::array::from_fn(|j| l64[j] + v64[j]);
    let hh = sq3(h64);
    let ih = rsqrt64_fast(hh);
    let c = (0.5 * (hh * ih)) as f32;
    let [lx, ly, lz] = l64.map(|q| q as f32);
    let [vx, vy, vz] = v64.map(|q| q as f32);
    // sin² of c from |l − v|/2 = sin θ_d: `1 − c²` of a c near 1 keeps only the bits c
    // lost, and F near the horizon of η² = sin² is steep in sin². (In f32: its relative
    // error, a few u, enters F no more than c's.)
    let (dx, dy, dz) = (lx - vx, ly - vy, lz - vz);
    let s2 = 0.25 * (dx * dx + dy * dy + dz * dz);
    let hz = (h64[2] * ih) as f32;
    let (cos_i, cos_o, cos_h, sin2_h, sin2_i, sin2_o, n_ok);
    if Z {
        // N = (0, 0, 1): |N|² = 1, `rsqrt(1)` = 1, each `n · w` is `0·wx + 0·wy + 1·wz =
        // wz` (a zero's sign aside, and a zero cosine is rescued either way) and each
        // `|n × w|²` is `(−wy)² + wx² + 0 = wy·wy + wx·wx`.
        (cos_i, cos_o, cos_h) = (lz, vz, hz);
        let side2 = |a: [f64; 3]| a[1] * a[1] + a[0] * a[0];
        sin2_h = (side2(h64) * (ih * ih)) as f32;
        sin2_i = side2(l64) as f32;
        sin2_o = side2(v64) as f32;
        n_ok = true;
    } else {
        let (nx, ny, nz) = (x[6], x[7], x[8]);
        let nn = nx * nx + ny * ny + nz * nz;
        let inn = rsqrt(nn);
        // n · l and n · v from the raw inputs in f64 (the products are exact there): an
        // f32 dot product of unit vectors has an absolute error of ~2 ulp, which a grazing
        // cosine turns into a relative error of K of 1e-3; this one is a few ulp relative
        // at any angle. (N · L)/|L| is rounded once, then scaled by 1/|N|: with N = (0, 0, 1)
        // the dot product is Lz exactly and `inn` is 1, so these are the local form's `lz`
        // and `vz`.
        let raw_dot = |a: usize| w(6) * w(a) + w(7) * w(a + 1) + w(8) * w(a + 2);
        let (nl, nv) = (raw_dot(0) * il, raw_dot(3) * iv);
        cos_i = nl as f32 * inn;
        cos_o = nv as f32 * inn;
        // n · h = (n · l + n · v)/|l + v|: a sum of two cosines, which above the horizon
        // does not cancel; with N = (0, 0, 1) it is the local form's `hz`.
        cos_h = ((nl + nv) * ih) as f32 * inn;
        // |N × w|² in f64 from the raw N and the f64 w (before w's rounding), scaled by
        // 1/|N|² as the cosines are: near n (h at the peak, l or v near the normal) an f32
        // cross product of unit vectors keeps only an absolute error of ~u, a relative
        // error of u/sin θ that G's and D's 1/sin-like factors pass on whole. With
        // N = (0, 0, 1) these are the local form's sums (the third term is +0 and `inn`
        // is 1).
        let n64 = [w(6), w(7), w(8)];
        let cross2 = |a: [f64; 3]| {
            let c = [
                n64[1] * a[2] - n64[2] * a[1],
                n64[2] * a[0] - n64[0] * a[2],
                n64[0] * a[1] - n64[1] * a[0],
            ];
            c[0] * c[0] + c[1] * c[1] + c[2] * c[2]
        };
        let i2 = inn * inn;
        sin2_h = (cross2(h64) * (ih * ih)) as f32 * i2;
        sin2_i = cross2(l64) as f32 * i2;
        sin2_o = cross2(v64) as f32 * i2;
        n_ok = length2_ok(nn);
    }
    let g = GRAZING as f32;
    // `>=` is false for NaN: lanes that went non-finite above are rescued too.
    let ok = length2_ok64(ll)
        && length2_ok64(vv)
        && n_ok
        && cos_i >= g
        && cos_o >= g
        && cos_h >= g
        && c >= g;
    Frame {
        cos_i,
        cos_o,
        cos_h,
        c,
        s2,
        sin2_h,
        sin2_i,
        sin2_o,
        ok,
    }
}

/// The f64 frame of one lane (FORMULAS.md §1) and whether the lanes may take it.
#[derive(Clone, Copy, Default)]
pub(crate) struct Frame64 {
    pub(super) cos_i: f64,
    pub(super) cos_o: f64,
    pub(super) cos_h: f64,
    pub(super) c: f64,
    pub(super) sin2_h: f64,
    pub(super) sin2_i: f64,
    pub(super) sin2_o: f64,
    /// `r · v` with `r = 2 cos_i n − l` (Phong), and `sin²` of the angle between r and v:
    /// near the peak `1 − |r − v|²/2` and `|r − v|²/2 (2 − |r − v|²/2)`, which keep the
    /// relative precision that `cos^e` needs (the reference's `phong_lobe`); elsewhere
    /// `2 cos_i cos_o − l · v` and 1 (`log_cos` then takes the cosine itself). Only
    /// Phong's lanes read them; the others' variants do not compute them.
    pub(super) rv: f64,
    pub(super) sin2_rv: f64,
    /// The unit vectors, for the tangent frame (`src/cpu/aniso.rs`).
    pub(super) n: [f64; 3],
    pub(super) l: [f64; 3],
    pub(super) v: [f64; 3],
    pub(super) h: [f64; 3],
    pub(super) ok: bool,
}

/// `1/√x` to f64 rounding for x in f32's range: the f32 estimate (cheap in wide lanes)
/// refined by two Newton steps in f64, each of which squares the relative error (6e-8,
/// 5e-15, then rounding). One step was not enough: a unit vector's length off by 5e-15
/// turns h by as much, which near the peak of a lobe cos^e with e = 1e18 (sin_h ~ 1e-9)
/// is 5e-6 of sin²_h and put the stress corpus's RTR 2e-4 off. Outside f32's range the
/// estimate is 0 or ∞ and the result 0 or NaN: the frame then fails its tests and the lane
/// is rescued.
#[inline(always)]
pub(super) fn rsqrt64(x: f64) -> f64 {
    let y0 = f64::from(1.0 / (x as f32).sqrt());
    let y1 = y0 * (1.5 - 0.5 * x * y0 * y0);
    y1 * (1.5 - 0.5 * x * y1 * y1)
}

/// `1/√x` in f64 with one Newton step from f32's estimate: relative error below 1e-14
/// (1.5 e² for the estimate's e ≤ 6e-8), for the f32 frame, which rounds every result to
/// f32 and needs only that l and v be scaled alike to far better than u = 6e-8 (see
/// [`frame`]). Outside f32's range the result is 0, ∞ or NaN and the frame's tests fail.
#[inline(always)]
fn rsqrt64_fast(x: f64) -> f64 {
    let y0 = f64::from(1.0 / (x as f32).sqrt());
    y0 * (1.5 - 0.5 * x * y0 * y0)
}

/// One lane's L, V, N in f64 with their squared lengths, and whether all three are lengths
/// the f64 frame can normalise (see `in_range`).
struct Raw {
    l: [f64; 3],
    v: [f64; 3],
    n: [f64; 3],
    ll: f64,
    vv: f64,
    nn: f64,
    in_range: bool,
}

#[inline(always)]
fn raw(x: &[f32; 9]) -> Raw {
    let w = |i: usize| f64::from(x[i]);
    let (l, v, n) = ([w(0), w(1), w(2)], [w(3), w(4), w(5)], [w(6), w(7), w(8)]);
    // Products of f32 values are exact in f64, and squares of f32 magnitudes stay inside
    // f64's normal range, so these lengths neither overflow nor underflow.
    let sq = |a: [f64; 3]| a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    let (ll, vv, nn) = (sq(l), sq(v), sq(n));
    // Squared lengths inside f32's normal range, where `rsqrt64`'s estimate is finite and
    // non-zero: outside it the Newton steps turn an estimate of ∞ into ±∞ (not NaN), which
    // made every cosine of an N with components of 1e-43 come out +∞ and pass the
    // frame's tests. The lanes outside it (zero, non-finite, or merely very short or long
    // inputs) go to the reference, which decides whether they are invalid. NaN fails the
    // range test.
    let ok = |q: f64| (1e-37..=1e37).contains(&q);
    Raw {
        l,
        v,
        n,
        ll,
        vv,
        nn,
        in_range: ok(ll) && ok(vv) && ok(nn),
    }
}

/// The f64 frame of one lane, for the lanes [`frame`] cannot serve (see
/// [`microfacet_block`]); the local form's lanes carry N = (0, 0, 1).
#[inline(always)]
pub(super) fn frame64(x: &[f32; 9]) -> Frame64 {
    let Raw {
        l: [lx, ly, lz],
        v: [vx, vy, vz],
        n: [nx, ny, nz],
        ll,
        vv,
        nn,
        in_range,
    } = raw(x);
    let (il, iv, inn) = (rsqrt64(ll), rsqrt64(vv), rsqrt64(nn));
    let (lx, ly, lz) = (lx * il, ly * il, lz * il);
    let (vx, vy, vz) = (vx * iv, vy * iv, vz * iv);
    let (nx, ny, nz) = (nx * inn, ny * inn, nz * inn);
    let cos_i = nx * lx + ny * ly + nz * lz;
    let cos_o = nx * vx + ny * vy + nz * vz;
    let (hx, hy, hz) = (lx + vx, ly + vy, lz + vz);
    let ih = rsqrt64(hx * hx + hy * hy + hz * hz);
    let (hx, hy, hz) = (hx * ih, hy * ih, hz * ih);
    let cos_h = nx * hx + ny * hy + nz * hz;
    let c = vx * hx + vy * hy + vz * hz;
    let cross2 = |ax: f64, ay: f64, az: f64| {
        let (cx, cy, cz) = (ny * az - nz * ay, nz * ax - nx * az, nx * ay - ny * ax);
        cx * cx + cy * cy + cz * cz
    };
    let (rx, ry, rz) = (
        2.0 * cos_i * nx - lx,
        2.0 * cos_i * ny - ly,
        2.0 * cos_i * nz - lz,
    );
    let (dx, dy, dz) = (rx - vx, ry - vy, rz - vz);
    let half_d2 = 0.5 * (dx * dx + dy * dy + dz * dz);
    let near = half_d2 < 0.5;
    let rv = if near {
        1.0 - half_d2
    } else {
        2.0 * cos_i * cos_o - (lx * vx + ly * vy + lz * vz)
    };
    let sin2_rv = if near { half_d2 * (2.0 - half_d2) } else { 1.0 };
    // `>=` is false for NaN: lanes that went non-finite above are rescued too.
    let ok = in_range && cos_i >= GRAZING && cos_o >= GRAZING && cos_h >= GRAZING && c >= GRAZING;
    Frame64 {
        rv,
        sin2_rv,
        n: [nx, ny, nz],
        l: [lx, ly, lz],
        v: [vx, vy, vz],
        h: [hx, hy, hz],
        cos_i,
        cos_o,
        cos_h,
        c,
        sin2_h: cross2(hx, hy, hz),
        sin2_i: cross2(lx, ly, lz),
        sin2_o: cross2(vx, vy, vz),
        ok,
    }
}

#[inline(always)]
pub(super) fn lane_inputs(inp: &Inputs, k: usize) -> [f32; 9] {
    std::array::from_fn(|j| inp.v[j][k])
}

/// Smith's Λ (FORMULAS.md §3) given `q2 = m² tan²θ`: the distribution `D`'s own.
#[inline(always)]
fn lambda<const D: u8>(q2: f32) -> f32 {
    match const { DistributionKind::from_code(D) } {
        DistributionKind::Ggx => ggx::lambda_lane(q2),
        DistributionKind::Beckmann => beckmann::lambda_lane(q2),
        // The Smith terms are not defined without a Λ (`Geometry::legality`), and the
        // dispatch (`cpu::block`) compiles none of these groups with one.
        DistributionKind::Gaussian | DistributionKind::Blinn | DistributionKind::Charlie => {
            unreachable!("no Smith Λ for this distribution")
        }
    }
}

/// Lambert on one block (`Z`: N = (0, 0, 1), the local form): only the validity and the
/// horizon matter, so only the two cosines are formed, as `frame` forms them (a cosine
/// below [`GRAZING`] still goes to the reference, which decides the horizon case).
#[inline(always)]
pub fn lambert_block<const Z: bool>(p: &Params, inp: &Inputs, out: &mut Outputs) {
    for k in 0..LANES {
        let x = lane_inputs(inp, k);
        let (lx, ly, lz) = (x[0], x[1], x[2]);
        let (vx, vy, vz) = (x[3], x[4], x[5]);
        let (ll, vv) = (lx * lx + ly * ly + lz * lz, vx * vx + vy * vy + vz * vz);
        let (il, iv) = (rsqrt(ll), rsqrt(vv));
        let (cos_i, cos_o, n_ok) = if Z {
            // N = (0, 0, 1): the general form's bits (see `frame`).
            (lz * il, vz * iv, true)
        } else {
            let (nx, ny, nz) = (x[6], x[7], x[8]);
            let nn = nx * nx + ny * ny + nz * nz;
            let inn = rsqrt(nn);
            let (nx, ny, nz) = (nx * inn, ny * inn, nz * inn);
            (
                nx * (lx * il) + ny * (ly * il) + nz * (lz * il),
                nx * (vx * iv) + ny * (vy * iv) + nz * (vz * iv),
                length2_ok(nn),
            )
        };
        let g = GRAZING as f32;
        out.rescue[k] = !(length2_ok(ll) && length2_ok(vv) && n_ok && cos_i >= g && cos_o >= g);
        for ch in 0..3 {
            out.brdf[ch][k] = p.diffuse[ch];
        }
    }
}

/// Lambert's terms, the same in every lane: D = 0, G = F = K = 1 (FORMULAS.md §6). Set once
/// a chunk, not by [`lambert_block`] (whose per-lane stores of these constants took 15 %
/// of its time).
pub fn lambert_terms(out: &mut Outputs) {
    out.terms[0] = [0.0; LANES];
    for t in 1..TERM_COLUMNS {
        out.terms[t] = [1.0; LANES];
    }
}

/// A lane's frame as the terms read it: f32 values, and f64 ones where D and the
/// dielectric Fresnel take f64 — from [`frame`], or [`frame64`] rounded.
#[derive(Clone, Copy)]
pub(crate) struct Lane {
    cos_i: f32,
    cos_o: f32,
    cos_h: f32,
    c: f32,
    sin2_i: f32,
    sin2_o: f32,
    /// `1 − c` and `sin²` of `c`, for Schlick and the conductor.
    one_minus_c: f32,
    s2: f32,
    sin2_h32: f32,
    cos_h2: f64,
    sin2_h: f64,
    c64: f64,
    s2_64: f64,
    pub(super) ok: bool,
}

impl Lane {
    #[inline(always)]
    fn from32(f: &Frame) -> Lane {
        // 1 − c = sin²/(1 + c), which does not cancel.
        let one_minus_c = f.s2 / (1.0 + f.c);
        let c64 = f64::from(f.c);
        Lane {
            cos_i: f.cos_i,
            cos_o: f.cos_o,
            cos_h: f.cos_h,
            c: f.c,
            sin2_i: f.sin2_i,
            sin2_o: f.sin2_o,
            one_minus_c,
            s2: f.s2,
            sin2_h32: f.sin2_h,
            cos_h2: f64::from(f.cos_h) * f64::from(f.cos_h),
            sin2_h: f64::from(f.sin2_h),
            c64,
            s2_64: f64::from(f.s2),
            ok: f.ok,
        }
    }

    #[inline(always)]
    pub(super) fn from64(f: &Frame64) -> Lane {
        // 1 − c in f64: of a c rounded to f32 it would cancel.
        let s2_64 = (1.0 - f.c) * (1.0 + f.c);
        Lane {
            cos_i: f.cos_i as f32,
            cos_o: f.cos_o as f32,
            cos_h: f.cos_h as f32,
            c: f.c as f32,
            sin2_i: f.sin2_i as f32,
            sin2_o: f.sin2_o as f32,
            one_minus_c: (1.0 - f.c) as f32,
            s2: s2_64 as f32,
            sin2_h32: f.sin2_h as f32,
            cos_h2: f.cos_h * f.cos_h,
            sin2_h: f.sin2_h,
            c64: f.c,
            s2_64,
            ok: f.ok,
        }
    }
}

/// Smallest `c = v · h` for which a lane may take the f32 frame: below it (l and v more
/// than 168° apart, grazing mirror geometry) the half vector's components cancel, which
/// the rule allows for but the f64 frame does not need to (docs/CPU_ENGINE.md has the
/// tolerance each threshold used). Uniform directions fall below it in 0.09 % of lanes.
pub const FAST_MIN_C: f32 = 0.1;

/// Smallest roughness m for which a material may take the f32 frame. With h formed in
/// f64 and its cross product with N too, the frame no longer turns h (its D error is
/// ~10u, u = 2⁻²⁴), and the f32 terms add ≤ 25u; the threshold was set from the earlier
/// bound `10u/m + 25u ≤ 1e-5` (m ≥ 0.0687) and keeps D's f32 quantities far inside f32's
/// normal range. Lowering it is a measured change still to make (docs/CPU_ENGINE.md, "The
/// f32 frame's error bound"). Below it the f64 frame takes the material.
pub const FAST_MIN_ROUGHNESS: f64 = 0.075;

/// Isotropic Cook–Torrance on one block, specialised to one distribution, geometry and
/// Fresnel term, and (`Z`) to N = (0, 0, 1) for the local form.
///
/// The frame is f32 (`frame`) when the material allows it ([`Params::fast_frame`]) and
/// the lane does (`c` ≥ [`FAST_MIN_C`]); the other lanes take the f64 frame
/// (`frame64`), which a block computes only when it has such a lane. The choice depends
/// only on the lane's own f32 frame, whose bits the local form and the rows with
/// N = (0, 0, 1) share, so a lane's result depends on its tuple alone and both forms give
/// the same bits.
#[inline(always)]
pub fn microfacet_block<const D: u8, const G: u8, const F: u8, const Z: bool>(
    p: &Params,
    inp: &Inputs,
    out: &mut Outputs,
) {
    // Lanes for the f64 frame: every lane unless the material may take the f32 frame
    // (`Params::fast_frame`). Only the fused groups (`fused`) are compiled here: the
    // dielectric and the other distributions take `dg_block64`.
    let mut slow = [true; LANES];
    if p.fast_frame {
        // The block's f32 frames as structure of arrays (an array of `Frame`s kept LLVM
        // from vectorising either loop: 4× slower).
        let mut fs = [[0.0f32; LANES]; 8];
        let mut ok = [false; LANES];
        for k in 0..LANES {
            let fr = frame::<Z>(&lane_inputs(inp, k));
            slow[k] = fr.ok && fr.c < FAST_MIN_C;
            let v = [
                fr.cos_i, fr.cos_o, fr.cos_h, fr.c, fr.sin2_h, fr.sin2_i, fr.sin2_o, fr.s2,
            ];
            for j in 0..8 {
                fs[j][k] = v[j];
            }
            ok[k] = fr.ok;
        }
        for k in 0..LANES {
            let fr = Frame {
                cos_i: fs[0][k],
                cos_o: fs[1][k],
                cos_h: fs[2][k],
                c: fs[3][k],
                sin2_h: fs[4][k],
                sin2_i: fs[5][k],
                sin2_o: fs[6][k],
                s2: fs[7][k],
                ok: ok[k],
            };
            microfacet_lane::<D, G, F, true>(p, &Lane::from32(&fr), out, k);
        }
    }
    if u128::from_ne_bytes(slow.map(u8::from)) != 0 {
        // The lanes the f32 frame cannot serve take the f64 frame's results, lane by lane:
        // what a lane gets must not depend on its neighbours in the block, or the output
        // would change with the chunking (the stream's, the shards').
        let mut o64 = Outputs::default();
        microfacet_block64::<D, G, F>(p, inp, &mut o64);
        for k in 0..LANES {
            if slow[k] {
                for ch in 0..3 {
                    out.brdf[ch][k] = o64.brdf[ch][k];
                }
                for t in 0..TERM_COLUMNS {
                    out.terms[t][k] = o64.terms[t][k];
                }
                out.rescue[k] = o64.rescue[k];
            }
        }
    }
}

/// [`microfacet_block`] with the f64 frame in every lane. The local form's blocks carry
/// N = (0, 0, 1) in their lanes, so one variant serves both forms (an N = +z variant
/// doubled the slow path's code and put the binary past its 48 MiB budget).
#[inline(always)]
fn microfacet_block64<const D: u8, const G: u8, const F: u8>(
    p: &Params,
    inp: &Inputs,
    out: &mut Outputs,
) {
    for k in 0..LANES {
        let fr = frame64(&lane_inputs(inp, k));
        microfacet_lane::<D, G, F, false>(p, &Lane::from64(&fr), out, k);
    }
}

/// Whether a microfacet group runs fused, with the f32 frame where it suffices
/// ([`microfacet_block`]): GGX and Beckmann with the V-cavity, a Smith geometry or none,
/// and any Fresnel term but the dielectric (whose f64 evaluation wants the f64 frame) —
/// the common groups. The others take the two-pass f64 path ([`dg_block64`]).
pub fn fused(d: DistributionKind, aniso: bool, g: Geometry, f: FresnelKind) -> bool {
    let d = !aniso && matches!(d, DistributionKind::Ggx | DistributionKind::Beckmann);
    let g = match g {
        Geometry::None
        | Geometry::CookTorrance
        | Geometry::Smith
        | Geometry::SmithCorrelated
        | Geometry::SmithFast => true,
        Geometry::SchlickSmith | Geometry::Neubelt => false,
    };
    d && g && f != FresnelKind::Dielectric
}

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
pub fn dg_block64<const D: u8, const G: u8>(p: &Params, inp: &Inputs, st: &mut Stage) {
    for k in 0..LANES {
        let fr = Lane::from64(&frame64(&lane_inputs(inp, k)));
        let (d, g) = microfacet_dg::<D, G, false>(p, &fr);
        st.put(k, &fr, d, g);
    }
}

impl Stage {
    /// Stores lane `k`'s frame values that F and K read, its D and G.
    #[inline(always)]
    pub(super) fn put(&mut self, k: usize, fr: &Lane, d: f32, g: f32) {
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
pub fn f_block<const F: u8>(p: &Params, st: &Stage, out: &mut Outputs) {
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
            cos_h2: 0.0,
            sin2_h: 0.0,
            c64: st.c64[k],
            s2_64: st.s2_64[k],
            ok: st.ok[k],
        };
        finish_lane::<F>(p, &fr, st.d[k], st.g[k], out, k);
    }
}

/// The terms and the BRDF of lane `k` from its frame (`FAST`: the f32 frame's, see D).
#[inline(always)]
fn microfacet_lane<const D: u8, const G: u8, const F: u8, const FAST: bool>(
    p: &Params,
    fr: &Lane,
    out: &mut Outputs,
    k: usize,
) {
    let (d, g) = microfacet_dg::<D, G, FAST>(p, fr);
    finish_lane::<F>(p, fr, d, g, out, k);
}

/// D and G of one lane (FORMULAS.md §2–§3) from its frame (`FAST`: the f32 frame's).
#[inline(always)]
fn microfacet_dg<const D: u8, const G: u8, const FAST: bool>(p: &Params, fr: &Lane) -> (f32, f32) {
    let (cos_i, cos_o, cos_h) = (fr.cos_i, fr.cos_o, fr.cos_h);
    // D (FORMULAS.md §2): the f32 frame's lanes (`FAST`) take GGX's and Beckmann's f32
    // forms, the f64 frame's their f64 ones.
    let d = match const { DistributionKind::from_code(D) } {
        DistributionKind::Gaussian => gaussian::d_lane(cos_h, fr.sin2_h32, p.inv_m2_f),
        DistributionKind::Blinn => blinn::d_lane(cos_h, fr.sin2_h32, p.exponent, p.d_norm_f),
        DistributionKind::Charlie => {
            charlie::d_lane(fr.cos_h2 as f32, fr.sin2_h32, p.exponent, p.d_norm_f)
        }
        DistributionKind::Ggx if FAST => ggx::d_lane32(cos_h, fr.sin2_h32, p.m2_f, p.d_norm_f),
        DistributionKind::Ggx => ggx::d_lane64(fr.cos_h2, fr.sin2_h, p.m2, p.d_norm),
        DistributionKind::Beckmann if FAST => {
            beckmann::d_lane32(cos_h, fr.sin2_h32, p.inv_m2_f, p.d_norm_f)
        }
        DistributionKind::Beckmann => beckmann::d_lane64(fr.cos_h2, fr.sin2_h, p.inv_m2, p.d_norm),
    };
    // G (FORMULAS.md §3) from q2 = m² tan²θ = m² |n × w|² / cos²θ: products and
    // quotients of positive numbers, which f32 carries to a few ulp (the cancelling
    // parts, |n × w|² and the cosines, come from the frame).
    let m2 = p.m2 as f32;
    let q2_i = m2 * fr.sin2_i / (cos_i * cos_i);
    let q2_o = m2 * fr.sin2_o / (cos_o * cos_o);
    (d, geometry::<D, G>(p, fr, q2_i, q2_o))
}

/// G (FORMULAS.md §3) of one lane given `q2 = m² tan²θ` of each direction (for
/// anisotropic roughness `(mx² (w·t)² + my² (w·b)²)/cos²θ`); `D` picks Smith's Λ.
#[inline(always)]
pub(super) fn geometry<const D: u8, const G: u8>(
    p: &Params,
    fr: &Lane,
    q2_i: f32,
    q2_o: f32,
) -> f32 {
    let (cos_i, cos_o, cos_h, c) = (fr.cos_i, fr.cos_o, fr.cos_h, fr.c);
    match const { Geometry::from_code(G) } {
        Geometry::None => 1.0,
        Geometry::CookTorrance => cook_torrance::g_lane(cos_h, cos_i, cos_o, c),
        Geometry::Smith => smith::g_lane(lambda::<D>(q2_o), lambda::<D>(q2_i)),
        Geometry::SmithCorrelated => smith_correlated::g_lane(lambda::<D>(q2_o), lambda::<D>(q2_i)),
        Geometry::SmithFast => smith_fast::g1_lane(q2_o) * smith_fast::g1_lane(q2_i),
        Geometry::SchlickSmith => {
            schlick_smith::g_lane(cos_o, fr.sin2_o, cos_i, fr.sin2_i, p.schlick_k)
        }
        Geometry::Neubelt => neubelt::g_lane(cos_i, cos_o),
    }
}

/// F, K and the outputs of lane `k` given its D and G (FORMULAS.md §4–§6).
#[inline(always)]
fn finish_lane<const F: u8>(p: &Params, fr: &Lane, d: f32, g: f32, out: &mut Outputs, k: usize) {
    let (cos_i, cos_o, c) = (fr.cos_i, fr.cos_o, fr.c);
    // F (FORMULAS.md §4) per channel.
    let (one_minus_c, s2_f) = (fr.one_minus_c, fr.s2);
    // A loop, not `array::from_fn`: LLVM declined to inline from_fn's closure around
    // the conductor, which made every lane a call and nothing vectorised.
    let mut f = [1.0f32; 3];
    for ch in 0..3 {
        f[ch] = match const { FresnelKind::from_code(F) } {
            FresnelKind::None => 1.0,
            FresnelKind::Schlick => schlick::f_lane(one_minus_c, p.f0[ch]),
            FresnelKind::Dielectric => dielectric::f_lane(fr.c64, fr.s2_64, p.ior[ch], p.mu2m1[ch]),
            FresnelKind::Conductor => conductor::f_lane(c, s2_f, &p.conductor, ch),
        };
    }
    // K (FORMULAS.md §5), one cosine at a time.
    let kk = p.k.k(cos_i, cos_o);
    // One test for every output: a sum of magnitudes is NaN if any is, and above
    // OUTPUT_LIMIT if any is (a sum that only rounds up past it sends a lane to the
    // reference needlessly, never the other way) — 18 operations where a test a value
    // took 45.
    let dgk = d * g * kk;
    let mut size = d.abs() + g.abs() + kk.abs();
    for ch in 0..3 {
        let b = p.diffuse[ch] + p.spec[ch] * (dgk * f[ch]);
        out.brdf[ch][k] = b;
        size += b.abs() + f[ch].abs();
    }
    let terms = [d, g, f[0], f[1], f[2], kk];
    for (t, x) in terms.into_iter().enumerate() {
        out.terms[t][k] = x;
    }
    // `<=` is false for NaN: one comparison catches both.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    let bad = !fr.ok || !(size <= OUTPUT_LIMIT);
    out.rescue[k] = bad;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cpu::plan::Plan;
    use crate::material::parse_materials;
    use crate::reference::{evaluate, Status};

    /// Every lanes-group on ordinary directions: no lane is rescued (so the lanes, not the
    /// reference, made the numbers) and every output is within 3e-6 relative of the
    /// reference (these tuples are well conditioned; the rule allows 1e-5 there).
    #[test]
    fn every_lanes_group_computes_without_rescue() {
        let dirs: [[f32; 9]; 4] = [
            [0.3, 0.2, 0.9, -0.2, 0.1, 0.8, 0.0, 0.0, 1.0],
            [0.7, -0.1, 0.3, -0.6, 0.2, 0.5, 0.0, 0.0, 2.0],
            [0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0],
            [0.5, 0.5, 0.2, 0.1, -0.6, 0.4, 0.1, 0.05, 1.0],
        ];
        let mut inp = Inputs::default();
        // A tangent for the anisotropic groups, across every lane's N.
        let tangent = [1.0f32, 0.2, 0.0];
        for k in 0..LANES {
            for j in 0..9 {
                inp.v[j][k] = dirs[k % 4][j];
            }
            for j in 0..3 {
                inp.v[9 + j][k] = tangent[j];
            }
        }
        // Every group the lanes take: each distribution with each geometry it is legal
        // with, each Fresnel term and convention, then the lobe models.
        let mut materials = Vec::new();
        for (d, param) in [
            ("ggx", "roughness = 0.3"),
            ("beckmann", "roughness = 0.3"),
            ("gaussian", "roughness = 0.3"),
            ("blinn", "exponent = 40"),
            ("charlie", "roughness = 0.4"),
        ] {
            let slope = d == "ggx" || d == "beckmann";
            for g in [
                "none",
                "cook-torrance",
                "smith",
                "smith-correlated",
                "smith-fast",
                "schlick-smith",
                "neubelt",
            ] {
                let smith = g.starts_with("smith") || g == "schlick-smith";
                if (smith && !slope) || (g == "smith-fast" && d != "beckmann") {
                    continue;
                }
                for f in [
                    "fresnel = \"none\"",
                    "fresnel = \"schlick\"\nf0 = [0.04, 0.5, 0.9]",
                    "fresnel = \"dielectric\"\nior = [1.5, 0.7, 2.4]",
                    "fresnel = \"conductor\"\nior = [0.2, 0.9, 1.1]\nextinction = [3.9, 2.4, 0.0]",
                ] {
                    for conv in ["modern", "seed", "cook-torrance-1982"] {
                        materials.push(format!(
                            "model = \"cook-torrance\"\ndistribution = \"{d}\"\n\
                             geometry = \"{g}\"\n{f}\n{param}\nconvention = \"{conv}\"\n\
                             diffuse_weight = 0.5\nspecular_weight = 0.7"
                        ));
                    }
                }
            }
        }
        // Anisotropic roughness: modern convention only, no schlick-smith.
        for (d, g) in [
            ("ggx", "none"),
            ("ggx", "smith"),
            ("ggx", "smith-correlated"),
            ("ggx", "neubelt"),
            ("beckmann", "cook-torrance"),
            ("beckmann", "smith"),
            ("beckmann", "smith-fast"),
        ] {
            materials.push(format!(
                "model = \"cook-torrance\"\ndistribution = \"{d}\"\ngeometry = \"{g}\"\n\
                 fresnel = \"conductor\"\nior = [0.2, 0.9, 1.1]\nextinction = [3.9, 2.4, 0.0]\n\
                 roughness = [0.2, 0.45]"
            ));
        }
        for model in [
            "model = \"ward\"\nroughness = [0.15, 0.4]",
            "model = \"phong\"\nexponent = 30",
            "model = \"phong\"\nexponent = 0",
            "model = \"blinn-phong\"\nexponent = 50",
            "model = \"rtr\"\nexponent = 20",
            "model = \"ward\"\nroughness = 0.3",
        ] {
            materials.push(model.to_string());
        }
        // 2 rms-slope distributions × (6 geometries for GGX, 7 for Beckmann), 3 others × 3
        // geometries, each × 4 Fresnel × 3 conventions; 7 anisotropic groups; 6 lobes.
        assert_eq!(materials.len(), (6 + 7 + 3 * 3) * 4 * 3 + 7 + 6);
        for body in &materials {
            let toml = format!(
                "[[material]]\nname = \"x\"\n{body}\ndiffuse = [0.2, 0.3, 0.4]\n\
                 specular = [0.9, 0.8, 0.7]\n"
            );
            let m = &parse_materials(&toml, "t").unwrap()[0];
            let plan = Plan::for_material(m);
            assert!(plan.is_simd(), "{body} is not in the lanes");
            let mut out = Outputs::default();
            lambert_terms(&mut out);
            crate::cpu::block(
                pulp::Scalar::new(),
                &plan,
                std::slice::from_ref(&inp),
                std::slice::from_mut(&mut out),
                false,
            );
            for k in 0..LANES {
                assert!(!out.rescue[k], "{body}: lane {k} rescued");
                let w = |a: usize| f64::from(dirs[k % 4][a]);
                let e = evaluate(
                    [w(0), w(1), w(2)],
                    [w(3), w(4), w(5)],
                    [w(6), w(7), w(8)],
                    Some(tangent.map(f64::from)),
                    m,
                );
                assert_eq!(e.status, Status::Valid);
                let want = [
                    e.brdf[0], e.brdf[1], e.brdf[2], e.d, e.g, e.f[0], e.f[1], e.f[2], e.k,
                ];
                let got = [
                    out.brdf[0][k],
                    out.brdf[1][k],
                    out.brdf[2][k],
                    out.terms[0][k],
                    out.terms[1][k],
                    out.terms[2][k],
                    out.terms[3][k],
                    out.terms[4][k],
                    out.terms[5][k],
                ];
                for (i, (x, r)) in got.iter().zip(want).enumerate() {
                    let err = (f64::from(*x) - r).abs() / r.abs().max(1e-6);
                    // Roughness 0.3: the f32 frame (FAST_MIN_ROUGHNESS), whose few ulp in
                    // the sines the Beckmann exponent multiplies by tan²/m²: 2.4e-6 at most
                    // here (the f64 frame made 1.5e-6), well inside the rule's 1e-5 for
                    // well-conditioned values.
                    assert!(err < 3e-6, "{body}\nlane {k} col {i}: {x} vs {r}");
                }
            }
        }
    }

    #[test]
    fn grazing_invalid_and_below_horizon_lanes_are_rescued() {
        let mut inp = Inputs::default();
        let rows: [[f32; 9]; 4] = [
            [1.0, 0.0, 1e-6, -0.2, 0.1, 0.8, 0.0, 0.0, 1.0], // cos_i ≈ 1e-6
            [0.3, 0.2, 0.9, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0],   // V = 0
            [0.3, 0.2, -0.9, -0.2, 0.1, 0.8, 0.0, 0.0, 1.0], // below the horizon
            [0.3, 0.2, 0.9, f32::INFINITY, 0.1, 0.8, 0.0, 0.0, 1.0],
        ];
        for k in 0..LANES {
            for j in 0..9 {
                inp.v[j][k] = rows[k % 4][j];
            }
        }
        let m = &parse_materials(
            "[[material]]\nname = \"x\"\nmodel = \"lambert\"\ndiffuse = [0.5, 0.5, 0.5]\n",
            "t",
        )
        .unwrap()[0];
        let mut out = Outputs::default();
        crate::cpu::block(
            pulp::Scalar::new(),
            &Plan::for_material(m),
            std::slice::from_ref(&inp),
            std::slice::from_mut(&mut out),
            false,
        );
        assert!(out.rescue.iter().all(|&r| r));
    }

    /// The N = +z lanes (the local form) give the general lanes' bits when N = (0, 0, 1):
    /// every group, on random, grazing, below-horizon and invalid directions.
    #[test]
    fn the_local_frame_lanes_give_the_general_bits() {
        let mut seed = 99u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
        };
        let mut blocks = Vec::new();
        for b in 0..64 {
            let mut inp = Inputs::default();
            for k in 0..LANES {
                for j in 0..6 {
                    inp.v[j][k] = rnd() * if b % 3 == 0 { 1e-3 } else { 1.0 };
                }
                match (b * LANES + k) % 13 {
                    0 => inp.v[2][k] = 1e-6,
                    1 => inp.v[5][k] = -inp.v[5][k].abs(),
                    2 => inp.v[0][k] = f32::NAN,
                    3 => inp.v[3..6].iter_mut().for_each(|c| c[k] = 0.0),
                    4 => inp.v[1][k] = f32::INFINITY,
                    5..=7 => {
                        // Near the specular peak, where |n × h|² is tiny.
                        let l = [inp.v[0][k], inp.v[1][k], inp.v[2][k].abs() + 0.1];
                        inp.v[0][k] = l[0];
                        inp.v[1][k] = l[1];
                        inp.v[2][k] = l[2];
                        inp.v[3][k] = -l[0] * (1.0 + 1e-3 * rnd());
                        inp.v[4][k] = -l[1] + 1e-4 * rnd();
                        inp.v[5][k] = l[2];
                    }
                    _ => {
                        inp.v[2][k] = inp.v[2][k].abs();
                        inp.v[5][k] = inp.v[5][k].abs();
                    }
                }
                inp.v[8][k] = 1.0;
            }
            blocks.push(inp);
        }
        let mut groups = 0;
        for model in [
            "model = \"lambert\"".to_string(),
            "model = \"cook-torrance\"\nroughness = 0.02".to_string(),
            // The f32 frame (roughness ≥ FAST_MIN_ROUGHNESS) as well as the f64 one.
            "model = \"cook-torrance\"\nroughness = 0.3".to_string(),
        ] {
            for d in ["ggx", "beckmann"] {
                for g in [
                    "none",
                    "cook-torrance",
                    "smith",
                    "smith-correlated",
                    "smith-fast",
                ] {
                    for f in [
                        "fresnel = \"none\"",
                        "fresnel = \"schlick\"\nf0 = [0.04, 0.5, 0.9]",
                        "fresnel = \"dielectric\"\nior = [1.5, 0.7, 2.4]",
                        "fresnel = \"conductor\"\nior = [0.2, 0.9, 1.1]\nextinction = [3.9, 2.4, 0.0]",
                    ] {
                        let extra = if model.contains("lambert") {
                            String::new()
                        } else {
                            format!("distribution = \"{d}\"\ngeometry = \"{g}\"\n{f}\n")
                        };
                        let toml = format!(
                            "[[material]]\nname = \"x\"\n{model}\n{extra}diffuse = [0.2, 0.3, 0.4]\n"
                        );
                        let Ok(ms) = parse_materials(&toml, "t") else {
                            continue; // smith-fast is Beckmann's only
                        };
                        let plan = Plan::for_material(&ms[0]);
                        assert!(plan.is_simd(), "{toml}");
                        for inp in &blocks {
                            let (mut a, mut b) = (Outputs::default(), Outputs::default());
                            crate::cpu::block(
                                pulp::Scalar::new(),
                                &plan,
                                std::slice::from_ref(inp),
                                std::slice::from_mut(&mut a),
                                false,
                            );
                            crate::cpu::block(
                                pulp::Scalar::new(),
                                &plan,
                                std::slice::from_ref(inp),
                                std::slice::from_mut(&mut b),
                                true,
                            );
                            assert_eq!(a.rescue, b.rescue, "{toml}");
                            for k in 0..LANES {
                                if a.rescue[k] {
                                    continue; // the reference writes these lanes
                                }
                                for ch in 0..3 {
                                    assert_eq!(a.brdf[ch][k].to_bits(), b.brdf[ch][k].to_bits(), "{toml}");
                                }
                                for t in 0..TERM_COLUMNS {
                                    assert_eq!(a.terms[t][k].to_bits(), b.terms[t][k].to_bits(), "{toml}");
                                }
                            }
                        }
                        groups += 1;
                    }
                }
            }
        }
        assert!(groups > 40, "{groups}");
    }
}
