//! The lanes' two frames (FORMULAS.md §1) of one tuple: the f32 frame ([`frame`]), which
//! the fused microfacet groups take where its error bound allows (docs/CPU_ENGINE.md, "The
//! f32 frame's error bound"), and the f64 frame ([`frame64`]) every other lane takes, with
//! the validity, horizon and grazing tests that send a lane to the reference.

/// Cosines (`cos_i`, `cos_o`, `cos_h`, `c`) below this go to the reference: there K and
/// the 1/cos factors of D and Λ leave the range where a few f32 roundings stay far inside
/// the tolerance, and the reference's log-domain and scaled forms take over (FORMULAS.md
/// §1, "Overflow": cosines down to the smallest subnormal must still come out exact).
pub const GRAZING: f64 = 1e-4;

/// GRAZING²: `cos_h ≥ GRAZING` is `hz² ≥ GRAZING²·|h|²` for hz > 0.
const GRAZING2: f32 = (GRAZING * GRAZING) as f32;

use crate::terms::math::MulAdd;
use crate::terms::real::{Real, Wide};

/// The frame of one lane (FORMULAS.md §1), or of a register of lanes
/// (`cpu::register`), and whether the lanes may take it.
#[derive(Clone, Copy)]
pub(super) struct Frame<T: Real = f32> {
    pub(super) cos_i: T,
    pub(super) cos_o: T,
    pub(super) cos_h: T,
    pub(super) c: T,
    /// `1 − c²`.
    pub(super) s2: T,
    pub(super) sin2_h: T,
    /// tan²θ_h (Beckmann's D reads it): from h's components where the frame has them
    /// ([`frame_local_h64`]), else `sin2_h/cos_h²` ([`tan2_of`]).
    pub(super) tan2_h: T,
    pub(super) sin2_i: T,
    pub(super) sin2_o: T,
    pub(super) ok: T::Mask,
}

/// tan²θ_h = `sin2_h · (1/cos_h²)` from a frame's f32 values: the ratio cancels the common
/// `1/|N|` (and h's) scale of both, so it is within ~2.5u of theirs.
#[inline(always)]
pub(super) fn tan2_of<T: Real>(cos_h: T, sin2_h: T) -> T {
    sin2_h * (cos_h.splat_as(1.0) / (cos_h * cos_h))
}

/// Squared lengths in this range leave the lanes' f32 arithmetic a factor 1e19 either
/// side before anything over- or underflows; directions outside it (finite, but longer
/// than 1e15 or shorter than 1e-15) go to the reference, which normalises any f32.
const LENGTH2_MIN: f32 = 1e-30;
const LENGTH2_MAX: f32 = 1e30;

/// Whether a squared length is in [`LENGTH2_MIN`, `LENGTH2_MAX`] (false for NaN).
#[inline(always)]
pub(super) fn length2_ok<T: Real>(q: T) -> T::Mask {
    q.ge_scalar(LENGTH2_MIN) & q.le_scalar(LENGTH2_MAX)
}

/// `1/√x`, correctly rounded square root then division: within 1 ulp, and exactly 1 for
/// x = 1 (the local form's N must come out exactly (0, 0, 1), see [`frame`]).
#[inline(always)]
pub(super) fn rsqrt<T: Real>(x: T) -> T {
    x.splat_as(1.0) / x.sqrt()
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
/// inputs' own rounding turns h there, and those lanes (`c` < `kernel::FAST_MIN_C`) take the f64
/// frame; `c` is taken as `|l + v|/2` rather than `v · h`, which would cancel a second time
/// (`v·l + 1`). The sines are sums of squares (cross products with the raw N in f64, from
/// the unrounded l, v and l + v), never `1 − cos²`.
#[inline(always)]
pub(super) fn frame<A: MulAdd, const Z: bool>(x: &[f32; 9]) -> Frame {
    if Z {
        return frame_local64::<A>([x[0], x[1], x[2]], [x[3], x[4], x[5]]);
    }
    // l, v and h in f64, each rounded once to f32 (see the bound above): |L|² and |V|²
    // are exact in f64 (squares of f32 values), 1/|x| by `rsqrt64_fast` (~1e-14 relative).
    let w = |i: usize| f64::from(x[i]);
    // `a·b + c` as the instruction set forms it (`A`); [`frame_local64`], the N = +z form,
    // keeps the general one's order, so that both give the same bits.
    let sq3 = |a: [f64; 3]| A::mul_add64(a[2], a[2], A::mul_add64(a[0], a[0], a[1] * a[1]));
    let (l64, v64) = ([w(0), w(1), w(2)], [w(3), w(4), w(5)]);
    let (ll, vv) = (sq3(l64), sq3(v64));
    let (il, iv) = (rsqrt64_fast::<A, f64>(ll), rsqrt64_fast::<A, f64>(vv));
    let (l64, v64) = (l64.map(|q| q * il), v64.map(|q| q * iv));
    let h64: [f64; 3] = std::array::from_fn(|j| l64[j] + v64[j]);
    let hh = sq3(h64);
    let ih = rsqrt64_fast::<A, f64>(hh);
    let c = (0.5 * (hh * ih)) as f32;
    let [lx, ly, lz] = l64.map(|q| q as f32);
    let [vx, vy, vz] = v64.map(|q| q as f32);
    // sin² of c from |l − v|/2 = sin θ_d: `1 − c²` of a c near 1 keeps only the bits c
    // lost, and F near the horizon of η² = sin² is steep in sin². (In f32: its relative
    // error, a few u, enters F no more than c's.)
    let (dx, dy, dz) = (lx - vx, ly - vy, lz - vz);
    let s2 = 0.25 * (dx * dx + dy * dy + dz * dz);
    let (nx, ny, nz) = (x[6], x[7], x[8]);
    let nn = nx * nx + ny * ny + nz * nz;
    let inn = rsqrt(nn);
    // n · l and n · v from the raw inputs in f64 (the products are exact there): an
    // f32 dot product of unit vectors has an absolute error of ~2 ulp, which a grazing
    // cosine turns into a relative error of K of 1e-3; this one is a few ulp relative
    // at any angle. (N · L)/|L| is rounded once, then scaled by 1/|N|: with N = (0, 0, 1)
    // the dot product is Lz exactly and `inn` is 1, so these are the local form's `lz`
    // and `vz`.
    let raw_dot =
        |a: usize| A::mul_add64(w(8), w(a + 2), A::mul_add64(w(6), w(a), w(7) * w(a + 1)));
    let (nl, nv) = (raw_dot(0) * il, raw_dot(3) * iv);
    let cos_i = nl as f32 * inn;
    let cos_o = nv as f32 * inn;
    // n · h = (n · l + n · v)/|l + v|: a sum of two cosines, which above the horizon
    // does not cancel; with N = (0, 0, 1) it is the local form's `hz`.
    let cos_h = ((nl + nv) * ih) as f32 * inn;
    // |N × w|² in f64 from the raw N and the f64 w (before w's rounding), scaled by
    // 1/|N|² as the cosines are: near n (h at the peak, l or v near the normal) an f32
    // cross product of unit vectors keeps only an absolute error of ~u, a relative
    // error of u/sin θ that G's and D's 1/sin-like factors pass on whole. With
    // N = (0, 0, 1) these are the local form's sums (the third term is +0 and `inn`
    // is 1).
    let n64 = [w(6), w(7), w(8)];
    let cross2 = |a: [f64; 3]| {
        let c = [
            A::mul_add64(n64[1], a[2], -(n64[2] * a[1])),
            A::mul_add64(n64[2], a[0], -(n64[0] * a[2])),
            A::mul_add64(n64[0], a[1], -(n64[1] * a[0])),
        ];
        sq3(c)
    };
    let i2 = inn * inn;
    let sin2_h = (cross2(h64) * (ih * ih)) as f32 * i2;
    let sin2_i = cross2(l64) as f32 * i2;
    let sin2_o = cross2(v64) as f32 * i2;
    let g = GRAZING as f32;
    // `>=` is false for NaN: lanes that went non-finite above are rescued too.
    // The squared lengths' test on their f32 roundings (which `rsqrt64_fast` forms): the
    // same as in f64 but for a length that rounds onto a limit, which either side serves.
    let ok = length2_ok(ll as f32)
        && length2_ok(vv as f32)
        && length2_ok(nn)
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
        tan2_h: tan2_of(cos_h, sin2_h),
        sin2_i,
        sin2_o,
        ok,
    }
}

/// [`frame`] with N = (0, 0, 1) (the rows whose N is +z in a block that has only such
/// rows): each `n · w` is `0·wx + 0·wy + 1·wz = wz` (a zero's sign aside, and a
/// zero cosine is rescued either way), each `|n × w|²` is `(−wy)² + wx² + 0 = wy·wy + wx·wx`,
/// `|N|² = 1` and its `rsqrt` 1 — the same operations on the same values as the general
/// frame with that N, so both give the same bits. Its bound is the general frame's: h
/// turns by its components' last rounding only.
#[inline(always)]
pub(super) fn frame_local64<A: MulAdd>(l: [f32; 3], v: [f32; 3]) -> Frame {
    local_frame_of(wide_parts::<A>(l.map(f64::from), v.map(f64::from)))
}

/// A local form's frame (N = +z) from the values it is made of: `1 − c²` from |l − v|/2
/// = sin θ_d, as in [`frame`], and the horizon and grazing tests on the cosines.
#[inline(always)]
fn local_frame_of<T: Real>(w: LocalParts<T>) -> Frame<T> {
    let ([lx, ly, lz], [vx, vy, vz]) = (w.l, w.v);
    let (dx, dy, dz) = (lx - vx, ly - vy, lz - vz);
    let s2 = (dx * dx + dy * dy + dz * dz) * 0.25;
    let g = GRAZING as f32;
    // `≥` is false for NaN: lanes that went non-finite above are rescued too.
    let ok = w.lengths_ok & lz.ge_scalar(g) & vz.ge_scalar(g) & w.h_up & w.c.ge_scalar(g);
    Frame {
        cos_i: lz,
        cos_o: vz,
        cos_h: w.cos_h,
        c: w.c,
        s2,
        sin2_h: w.sin2_h,
        tan2_h: w.tan2_h,
        sin2_i: w.sin2_i,
        sin2_o: w.sin2_o,
        ok,
    }
}

/// The values a local form's frame is made of ([`local_frame_of`]): what [`frame_local64`]
/// forms in f64 ([`wide_parts`]), each rounded once to f32, or [`frame_local_h64`] its way.
#[derive(Clone, Copy)]
struct LocalParts<T: Real> {
    /// l = L/|L|.
    l: [T; 3],
    /// v = V/|V|.
    v: [T; 3],
    sin2_i: T,
    sin2_o: T,
    c: T,
    cos_h: T,
    sin2_h: T,
    tan2_h: T,
    /// cos_h ≥ [`GRAZING`] (tested on h's components in the h64 frame, see
    /// [`HalfParts::h_up`]).
    h_up: T::Mask,
    /// `|L|²` and `|V|²` (rounded to f32) inside [`LENGTH2_MIN`, `LENGTH2_MAX`].
    lengths_ok: T::Mask,
}

/// Lanes whose [`frame_local_h64`] can be formed: one f32 (its f64 part in one f64), or a
/// register (`cpu::register`, its f64 part half a register at a time).
pub(super) trait FrameLanes: Real {
    /// [`half_parts`] of these lanes, `near` their [`near_unit_lanes`] (not read with
    /// `NEAR`: every lane is near).
    fn half_parts<A: MulAdd, const NEAR: bool>(
        l: [Self; 3],
        v: [Self; 3],
        near: Self::Mask,
    ) -> HalfParts<Self>;
}

impl FrameLanes for f32 {
    #[inline(always)]
    fn half_parts<A: MulAdd, const NEAR: bool>(
        l: [f32; 3],
        v: [f32; 3],
        near: bool,
    ) -> HalfParts<f32> {
        let (l, v) = (l.map(f64::from), v.map(f64::from));
        half_parts::<A, f64, NEAR>(l, v, near)
    }
}

/// The local form's frame (N = +z) for Beckmann's lanes: h = L·s_l + V·s_v formed in f64
/// from the exact squared lengths and each component rounded once — so h turns by those
/// roundings only (tan θ_h within u, θ_h within u/2), as on the general f32 frame — and
/// the rest in f32: tan²θ_h = `(hx² + hy²)/hz²` from h's components (within 2u; D reads
/// only it), c = `√|h|²/2` (1.25u), h's scale where a term reads cos_h (3.5u) or
/// `|n × h|²` (7u), l = L·s_l and v = V·s_v with the scales rounded once (cos_i,
/// cos_o within u; `|n × l|²`, `|n × v|²` within 3u). D reads h's direction, which no
/// slope of D can magnify beyond the general frame's, so the bound holds on every lane
/// without a certificate (docs/CPU_ENGINE.md, "The local form's h64 frame"); what the
/// f32 scales add is ~21u of the rule's 1e-5. Five f64 values rounded (two scales, h's
/// three components) where [`frame_local64`] rounds eleven.
#[inline(always)]
pub(super) fn frame_local_h64<A: MulAdd, T: FrameLanes, const NEAR: bool>(
    l: [T; 3],
    v: [T; 3],
) -> Frame<T> {
    // With NEAR the mask is not read, and the compiler drops its arithmetic.
    let w = T::half_parts::<A, NEAR>(l, v, near_unit_lanes::<A, T>(l, v));
    let (lx, ly, lz) = (l[0] * w.il, l[1] * w.il, l[2] * w.il);
    let (vx, vy, vz) = (v[0] * w.iv, v[1] * w.iv, v[2] * w.iv);
    local_frame_of(LocalParts {
        l: [lx, ly, lz],
        v: [vx, vy, vz],
        sin2_i: A::mul_add(lx, lx, ly * ly),
        sin2_o: A::mul_add(vx, vx, vy * vy),
        c: w.c,
        cos_h: w.cos_h,
        sin2_h: w.sin2_h,
        tan2_h: w.tan2_h,
        h_up: w.h_up,
        lengths_ok: w.lengths_ok,
    })
}

/// What [`frame_local_h64`] forms in f64 ([`half_parts`]) rounded once to f32, and h's
/// scale, cos_h, c and `|n × h|²` from h's rounded components.
#[derive(Clone, Copy)]
pub(super) struct HalfParts<T: Real> {
    /// `1/|L|`.
    il: T,
    /// `1/|V|`.
    iv: T,
    c: T,
    cos_h: T,
    sin2_h: T,
    /// tan²θ_h from h's rounded components, `(hx² + hy²)/hz²`.
    tan2_h: T,
    /// cos_h ≥ [`GRAZING`], tested as `hz² ≥ GRAZING²·|h|²` (hz > 0 wherever l and v are
    /// above the horizon, which the frame tests too): from values formed early, so that
    /// the lane's flags do not wait on a root or a division (their bits leave the
    /// registers each step: a test on `tan2_h` instead cost 10 % of Beckmann's step), and
    /// a lane that reads neither cos_h nor `sin2_h` (Beckmann's D with smith-fast) forms
    /// no `1/|h|` at all.
    h_up: T::Mask,
    /// `|L|²` and `|V|²` (rounded to f32) inside [`LENGTH2_MIN`, `LENGTH2_MAX`].
    lengths_ok: T::Mask,
}

/// The f64 part of [`frame_local_h64`] from L and V in f64 lanes: each scale `1/|x|` and
/// h = L·s_l + V·s_v, each rounded once; then h's scale in f32.
///
/// The scales: on the lanes of `near` ([`near_unit_lanes`]: L's and V's squared lengths
/// within [`NEAR_UNIT`] of 1, as every input normalised in f32 or f64 is)
/// [`rsqrt64_near_unit`], a quadratic without a root or a division; on the others
/// [`rsqrt64_fast`]. `NEAR`: every lane is near (the register path tests a step's lanes
/// first), and the second is not formed at all.
#[inline(always)]
pub(super) fn half_parts<A: MulAdd, W: Wide, const NEAR: bool>(
    l: [W; 3],
    v: [W; 3],
    near: <W::Narrow as Real>::Mask,
) -> HalfParts<W::Narrow> {
    let ll = sq3_wide::<A, W>(l);
    let vv = sq3_wide::<A, W>(v);
    let q = [ll.narrow(), vv.narrow()];
    let (il, iv) = (rsqrt64_near_unit::<A, W>(ll), rsqrt64_near_unit::<A, W>(vv));
    let near_parts = scaled_parts::<A, W>(l, v, q, il, iv);
    if NEAR {
        // Every lane's f32 squared lengths are within NEAR_UNIT of 1, so inside
        // [LENGTH2_MIN, LENGTH2_MAX]: the test on `q` is true without forming it (`c < c`
        // is false for every c, NaN too; the compiler folds it).
        return HalfParts {
            lengths_ok: !near_parts.c.lt(near_parts.c),
            ..near_parts
        };
    }
    let (il, iv) = (rsqrt64_fast::<A, W>(ll), rsqrt64_fast::<A, W>(vv));
    near_parts.select(near, scaled_parts::<A, W>(l, v, q, il, iv))
}

/// [`half_parts`] from the scales `il = 1/|L|`, `iv = 1/|V|` (in f64) and the squared
/// lengths rounded to f32 (`q`).
#[inline(always)]
fn scaled_parts<A: MulAdd, W: Wide>(
    l: [W; 3],
    v: [W; 3],
    q: [W::Narrow; 2],
    il: W,
    iv: W,
) -> HalfParts<W::Narrow> {
    let h = [
        A::mul_add_wide(l[0], il, v[0] * iv),
        A::mul_add_wide(l[1], il, v[1] * iv),
        A::mul_add_wide(l[2], il, v[2] * iv),
    ];
    let (hx, hy, hz) = (h[0].narrow(), h[1].narrow(), h[2].narrow());
    let side2 = A::mul_add(hx, hx, hy * hy);
    let hh = A::mul_add(hz, hz, side2);
    let ih = rsqrt(hh);
    let tan2_h = side2 / (hz * hz);
    HalfParts {
        il: il.narrow(),
        iv: iv.narrow(),
        c: hh.sqrt() * 0.5,
        cos_h: hz * ih,
        sin2_h: side2 * (ih * ih),
        tan2_h,
        h_up: (hh * GRAZING2).le(hz * hz),
        // On the f32 roundings, as [`frame`] tests them.
        lengths_ok: length2_ok(q[0]) & length2_ok(q[1]),
    }
}

impl<T: Real> HalfParts<T> {
    /// `self` on the lanes of `m`, `other` on the rest.
    #[inline(always)]
    fn select(self, m: T::Mask, other: HalfParts<T>) -> HalfParts<T> {
        HalfParts {
            il: T::select(m, self.il, other.il),
            iv: T::select(m, self.iv, other.iv),
            c: T::select(m, self.c, other.c),
            cos_h: T::select(m, self.cos_h, other.cos_h),
            sin2_h: T::select(m, self.sin2_h, other.sin2_h),
            tan2_h: T::select(m, self.tan2_h, other.tan2_h),
            // Each lane's own h: the near scales' h is meaningless on the other lanes.
            h_up: (m & self.h_up) | (!m & other.h_up),
            lengths_ok: self.lengths_ok,
        }
    }
}

/// The f64 part of [`frame_local64`] from L and V in f64: l, v and h = l + v unrounded,
/// each scale `1/|x|` by [`rsqrt64_fast`], every result rounded once.
#[inline(always)]
fn wide_parts<A: MulAdd>(l: [f64; 3], v: [f64; 3]) -> LocalParts<f32> {
    let ll = sq3_wide::<A, f64>(l);
    let il = rsqrt64_fast::<A, f64>(ll);
    let l = [l[0] * il, l[1] * il, l[2] * il];
    let (lx, ly, lz) = (l[0].narrow(), l[1].narrow(), l[2].narrow());
    let sin2_i = side2_wide::<A, f64>(l).narrow();
    let vv = sq3_wide::<A, f64>(v);
    let iv = rsqrt64_fast::<A, f64>(vv);
    let v = [v[0] * iv, v[1] * iv, v[2] * iv];
    let (vx, vy, vz) = (v[0].narrow(), v[1].narrow(), v[2].narrow());
    let sin2_o = side2_wide::<A, f64>(v).narrow();
    let h = [l[0] + v[0], l[1] + v[1], l[2] + v[2]];
    let hh = sq3_wide::<A, f64>(h);
    let ih = rsqrt64_fast::<A, f64>(hh);
    let (cos_h, sin2_h) = (
        (h[2] * ih).narrow(),
        (side2_wide::<A, f64>(h) * (ih * ih)).narrow(),
    );
    LocalParts {
        l: [lx, ly, lz],
        v: [vx, vy, vz],
        sin2_i,
        sin2_o,
        c: (hh * ih * 0.5).narrow(),
        cos_h,
        sin2_h,
        // As [`frame`] forms it from the same values (the same bits).
        tan2_h: tan2_of(cos_h, sin2_h),
        h_up: cos_h.ge_scalar(GRAZING as f32),
        // On the f32 roundings, as [`frame`] tests them.
        lengths_ok: length2_ok(ll.narrow()) & length2_ok(vv.narrow()),
    }
}

/// `|a|²` of f64 lanes in [`frame`]'s order: `a₂² + (a₀² + a₁²)`.
#[inline(always)]
fn sq3_wide<A: MulAdd, W: Wide>(a: [W; 3]) -> W {
    A::mul_add_wide(a[2], a[2], A::mul_add_wide(a[0], a[0], a[1] * a[1]))
}

/// `a₀² + a₁²` of f64 lanes in [`frame`]'s order for N = +z: `|n × a|²`.
#[inline(always)]
fn side2_wide<A: MulAdd, W: Wide>(a: [W; 3]) -> W {
    A::mul_add_wide(a[1], a[1], a[0] * a[0])
}

/// The local form's frame (N = +z) in f32 alone, for the GGX lanes whose D
/// `terms::d::ggx::local_frame_ok` certifies against the frame's rounding of h: each unit
/// vector is its input times `1/√|x|²` in f32 (its scale within 3.5u, each component one
/// more rounding), so h = l + v turns by at most `3.5u tan θ_d + u/c + u ≤ u (4.5/c + 1)`
/// radians (the two scales' difference along `l − v`, the components' roundings, the
/// sum's). The cosines are single components (relative to 4.5u at any angle) and the sines
/// sums of squares of components, as in [`frame`] — which forms l, v and h in f64 to make
/// that turn `u·√3/2` whatever c, at ~25 instructions an evaluation more (AVX2). The
/// scales are [`rsqrt_near_unit`]'s where a squared length is within [`NEAR_UNIT`] of 1
/// (within 2.5u: `|x|²`'s γ₃ ≈ 3u halved, and the quadratic's last rounding), else [`rsqrt`]'s.
#[inline(always)]
pub(super) fn frame_local32<A: MulAdd, T: Real, const NEAR: bool>(
    l: [T; 3],
    v: [T; 3],
) -> Frame<T> {
    let [lx, ly, lz] = l;
    let [vx, vy, vz] = v;
    // The same squared lengths as `near_unit_lanes` tests.
    let (ll, vv) = (length2::<A, T>(l), length2::<A, T>(v));
    // Each value as soon as its operands are there, so that a register path holds few at
    // once (the lane loops' bits do not depend on the order).
    let lengths_ok = length2_ok(ll) & length2_ok(vv);
    let (il, iv) = (rsqrt_near_unit::<A, T>(ll), rsqrt_near_unit::<A, T>(vv));
    let (il, iv) = if NEAR {
        (il, iv)
    } else {
        // Each lane's own choice, whatever its neighbours' (the same bits on every path):
        // `near_unit_lanes` on the lengths already formed.
        let near = near_unit(ll) & near_unit(vv);
        (
            T::select(near, il, rsqrt(ll)),
            T::select(near, iv, rsqrt(vv)),
        )
    };
    let (lx, ly, lz) = (lx * il, ly * il, lz * il);
    let (vx, vy, vz) = (vx * iv, vy * iv, vz * iv);
    let sin2_i = A::mul_add(lx, lx, ly * ly);
    let sin2_o = A::mul_add(vx, vx, vy * vy);
    let (dx, dy, dz) = (lx - vx, ly - vy, lz - vz);
    let s2 = A::mul_add(dz, dz, A::mul_add(dx, dx, dy * dy)) * 0.25;
    let (hx, hy, hz) = (lx + vx, ly + vy, lz + vz);
    let hh = A::mul_add(hz, hz, A::mul_add(hx, hx, hy * hy));
    let ih = rsqrt(hh);
    let c = hh * ih * 0.5;
    let (cos_i, cos_o, cos_h) = (lz, vz, hz * ih);
    let sin2_h = A::mul_add(hx, hx, hy * hy) * (ih * ih);
    let g = GRAZING as f32;
    // `≥` is false for NaN: lanes that went non-finite are rescued too.
    let ok =
        lengths_ok & cos_i.ge_scalar(g) & cos_o.ge_scalar(g) & cos_h.ge_scalar(g) & c.ge_scalar(g);
    Frame {
        cos_i,
        cos_o,
        cos_h,
        c,
        s2,
        sin2_h,
        tan2_h: tan2_of(cos_h, sin2_h),
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

/// How far from 1 (`|1 − |x|²|` of the f32 squared length) [`rsqrt64_near_unit`] may be
/// used: its quadratic's truncation there is `5 a³/16 ≤ 4.6e-12` (a = |x|² − 1 ≤ 2⁻¹² + u),
/// which the h64 frame needs far below u (see there), and [`rsqrt_near_unit`]'s f32
/// quadratic `5 a³/16` below its one rounding. Inputs normalised in f32 are within ~3u of 1.
const NEAR_UNIT: f32 = 1.0 / 4096.0;

/// Whether the lanes' L and V both have squared lengths (in f32, as [`frame_local32`]
/// forms them) within [`NEAR_UNIT`] of 1: the lanes whose local frames take the near-unit
/// scales ([`rsqrt_near_unit`], [`rsqrt64_near_unit`]).
#[inline(always)]
pub(super) fn near_unit_lanes<A: MulAdd, T: Real>(l: [T; 3], v: [T; 3]) -> T::Mask {
    near_unit(length2::<A, T>(l)) & near_unit(length2::<A, T>(v))
}

/// `|a|²` in f32 as [`frame_local32`] forms it: `a₂² + (a₀² + a₁²)`.
#[inline(always)]
fn length2<A: MulAdd, T: Real>(a: [T; 3]) -> T {
    A::mul_add(a[2], a[2], A::mul_add(a[0], a[0], a[1] * a[1]))
}

/// Whether an f32 squared length `q` is within [`NEAR_UNIT`] of 1 (`1 − q` is exact there,
/// by Sterbenz's lemma; false for NaN).
#[inline(always)]
fn near_unit<T: Real>(q: T) -> T::Mask {
    (q.splat_as(1.0) - q).abs().le_scalar(NEAR_UNIT)
}

/// `1/√q` in f32 for q = 1 + a within [`NEAR_UNIT`] of 1: `1 − a/2 + 3a²/8` by Horner, a
/// exact, the quadratic's truncation ≤ 5|a|³/16 < 5e-12 and its last rounding (u = 2⁻²⁴,
/// the inner one is 2⁻¹² smaller) — within about u of the exact `1/√q` where [`rsqrt`] (a
/// root and a division) is within ~2u, without the divider.
#[inline(always)]
fn rsqrt_near_unit<A: MulAdd, T: Real>(q: T) -> T {
    let a = q - q.splat_as(1.0);
    let p = A::mul_add(a, q.splat_as(0.375), q.splat_as(-0.5));
    A::mul_add(a, p, q.splat_as(1.0))
}

/// `1/√x` for x = 1 + a near 1 (|a| ≤ [`NEAR_UNIT`], a formed exactly from the exact x):
/// the Taylor quadratic `1 − a/2 + 3a²/8` by Horner in f64, relative error below 4.6e-12
/// (the truncation `5|a|³/16`; the f64 roundings ~2e-16) — no root and no division, whose
/// latency the h64 frame's chain otherwise starts with. What the h64 frame needs of its
/// scales is that they agree to far better than u = 6e-8: their difference turns h by
/// `(ε_l − ε_v) tan θ_d/2 ≤ 4.6e-11` radians (tan θ_d ≤ 10 on its lanes), 8e-4 u.
/// (A cubic term took one more f64 multiply-add a half register for nothing it needs.)
#[inline(always)]
fn rsqrt64_near_unit<A: MulAdd, W: Wide>(x: W) -> W {
    let a = x + x.splat_as(-1.0);
    let p = A::mul_add_wide(a, x.splat_as(0.375), x.splat_as(-0.5));
    A::mul_add_wide(a, p, x.splat_as(1.0))
}

/// `1/√x` in f64 with one Newton step from f32's estimate: relative error below 1e-14
/// (1.5 e² for the estimate's e ≤ 6e-8), for the f32 frame, which rounds every result to
/// f32 and needs only that l and v be scaled alike to far better than u = 6e-8 (see
/// [`frame`]). Outside f32's range the result is 0, ∞ or NaN and the frame's tests fail.
#[inline(always)]
fn rsqrt64_fast<A: MulAdd, W: Wide>(x: W) -> W {
    let xf = x.narrow();
    let y0 = x.widen_like(xf.splat_as(1.0) / xf.sqrt());
    y0 * A::mul_add_wide(x * -0.5 * y0, y0, y0.splat_as(1.5))
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
/// `kernel::microfacet_block`); the local form's lanes carry N = (0, 0, 1).
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
