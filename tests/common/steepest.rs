//! Tuples where GGX's D is steepest in h, for the tests of the f32 local frames (the CPU
//! engine's `frame_local32`, the kernel's `frame_scalars_local32`): their error is D's
//! slope times the frame's turn of h, largest at tan θ_h = m and small c; and where
//! Beckmann's is, in its tails.

/// Unit `(l, v)` pairs about N = +z whose half vector sits at tan θ_h = m/2, m and 2m
/// (three azimuths each), with c = l·h from `c_min` to 1 in 40 steps and three planes of
/// l − v each; pairs with a cosine below 1e-3 are left out.
pub fn ggx_pairs(m: f64, c_min: f64) -> Vec<([f64; 3], [f64; 3])> {
    pairs_at(&[0.5 * m, m, 2.0 * m], c_min)
}

/// [`ggx_pairs`] for Beckmann, whose D's slope `2 tan θ_h (1/(m² cos² θ_h) − 2)` grows
/// without bound: h at tan θ_h = m, 3m and 9m (inside the f32 lanes' cut,
/// `beckmann::lane_exp_floor`: 9.1–9.3m for the tests' materials), and either side of
/// tan²θ_h/m² = 174 (13.19m), where `exp(−x/2)`'s own range ends at −87 (the reference's
/// D is not 0 there; the lanes' is).
pub fn beckmann_pairs(m: f64, c_min: f64) -> Vec<([f64; 3], [f64; 3])> {
    pairs_at(&[m, 3.0 * m, 9.0 * m, 13.18 * m, 13.2 * m], c_min)
}

/// The pairs of [`ggx_pairs`] with h at each of `tans` (tan θ_h).
fn pairs_at(tans: &[f64], c_min: f64) -> Vec<([f64; 3], [f64; 3])> {
    let mut pairs = Vec::new();
    for &t in tans {
        let th = t.atan();
        for phi in [0.3f64, 1.9, 4.0] {
            let h = [th.sin() * phi.cos(), th.sin() * phi.sin(), th.cos()];
            // Two unit vectors perpendicular to h.
            let a = [-phi.sin(), phi.cos(), 0.0];
            let b = [
                h[1] * a[2] - h[2] * a[1],
                h[2] * a[0] - h[0] * a[2],
                h[0] * a[1] - h[1] * a[0],
            ];
            for k in 0..40 {
                let c = c_min + (1.0 - c_min) * f64::from(k) / 39.0;
                let (cd, sd) = (c, (1.0 - c * c).sqrt());
                for psi in [0.2f64, 1.3, 2.6] {
                    let w: [f64; 3] = std::array::from_fn(|j| psi.cos() * a[j] + psi.sin() * b[j]);
                    let l: [f64; 3] = std::array::from_fn(|j| cd * h[j] + sd * w[j]);
                    let v: [f64; 3] = std::array::from_fn(|j| cd * h[j] - sd * w[j]);
                    if l[2] >= 1e-3 && v[2] >= 1e-3 {
                        pairs.push((l, v));
                    }
                }
            }
        }
    }
    pairs
}

/// TOML for Cook–Torrance materials of `distribution` at each roughness of `m_all`, one for
/// each `(geometry, Fresnel TOML)` of `kinds`: material `kinds.len() · i + g` has roughness
/// `m_all[i]` and kind `g`.
pub fn materials_toml(distribution: &str, m_all: &[f64], kinds: &[(&str, &str)]) -> String {
    let mut toml = String::new();
    for m in m_all {
        for (geometry, fresnel) in kinds {
            toml.push_str(&format!(
                "[[material]]\nname = \"m{m}-{geometry}\"\nmodel = \"cook-torrance\"\n\
                 distribution = \"{distribution}\"\ngeometry = \"{geometry}\"\n\
                 roughness = {m}\n{fresnel}\n"
            ));
        }
    }
    toml
}

/// Unit `(l, v)` pairs about N = +z.
pub type Pairs = Vec<([f64; 3], [f64; 3])>;

/// The local form's tuples `(L, V, material)` of `pairs(m, c_min)` for each roughness of
/// `m_all`, L and V of unit length in a quarter of them, of squared lengths just inside or
/// outside 1 ± 2⁻¹² in two more and far from unit in the rest (the frames' lengths are
/// part of their error, and the h64 frame takes unit ones another way), each pair
/// once for each of `per_m` materials (material `per_m · i + g`, as [`materials_toml`]
/// numbers them).
pub fn tuples(
    pairs: fn(f64, f64) -> Pairs,
    c_min: f64,
    m_all: &[f64],
    per_m: usize,
) -> Vec<([f32; 6], usize)> {
    let mut out = Vec::new();
    let mut i = 0usize;
    for (mi, &m) in m_all.iter().enumerate() {
        for (l, v) in pairs(m, c_min) {
            // Unit lengths (the h64 frame's near-unit scales), squared lengths just inside
            // and just outside its `NEAR_UNIT` (1 ± 2⁻¹²), and lengths far from 1.
            let near = (2.0f64).powi(-12);
            let (sl, sv) = match i % 4 {
                0 => (1.0, 1.0),
                1 => ((1.0 + 0.9 * near).sqrt(), (1.0 - 0.9 * near).sqrt()),
                2 => (1.0, (1.0 + 1.1 * near).sqrt()),
                _ => (1.0 + 0.37 * (i % 7) as f64, 0.6 + 0.29 * (i % 5) as f64),
            };
            i += 1;
            let lv = [
                l[0] * sl,
                l[1] * sl,
                l[2] * sl,
                v[0] * sv,
                v[1] * sv,
                v[2] * sv,
            ];
            for g in 0..per_m {
                out.push((lv.map(|x| x as f32), per_m * mi + g));
            }
        }
    }
    out
}

/// 10-column rows with N = +z of [`tuples`].
pub fn rows_z(pairs: fn(f64, f64) -> Pairs, c_min: f64, m_all: &[f64], per_m: usize) -> Vec<f32> {
    let mut rows = Vec::new();
    for (lv, material) in tuples(pairs, c_min, m_all, per_m) {
        rows.extend(lv);
        rows.extend([0.0f32, 0.0, 1.0, material as f32]);
    }
    rows
}

/// 10-column rows of [`tuples`] with N = +z in every other row and tilted (and not unit)
/// in the others: blocks whose lanes take either frame lane by lane.
pub fn rows_z_and_tilted(tuples: &[([f32; 6], usize)]) -> Vec<f32> {
    let mut rows = Vec::new();
    for (r, (lv, material)) in tuples.iter().enumerate() {
        rows.extend(lv);
        let n = if r % 2 == 0 {
            [0.0f32, 0.0, 1.0]
        } else {
            [0.03, -0.02, 1.7]
        };
        rows.extend(n);
        rows.push(*material as f32);
    }
    rows
}
