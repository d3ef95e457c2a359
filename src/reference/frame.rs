//! FORMULAS.md §1: inputs of one evaluation, the validity rule and the derived quantities.

/// `a · b`.
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `a × b`.
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `|a|²`.
pub fn length_squared(a: [f64; 3]) -> f64 {
    dot(a, a)
}

/// `a / |a|`, or `None` for a zero-length or non-finite vector (an invalid input).
///
/// Scales by the largest |component| first: without it `|a|²` underflows to 0 for inputs
/// of length ~1e-170 and overflows for ~1e170 (f32 inputs never get there, but f64 callers can).
pub fn normalize(a: [f64; 3]) -> Option<[f64; 3]> {
    if !a.iter().all(|x| x.is_finite()) {
        return None;
    }
    let scale = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if scale == 0.0 {
        return None;
    }
    let s = a.map(|x| x / scale);
    let len = length_squared(s).sqrt();
    Some(s.map(|x| x / len))
}

/// Everything the terms read, derived once per tuple (the table of FORMULAS.md §1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Unit direction toward the light.
    pub l: [f64; 3],
    /// Unit direction toward the viewer.
    pub v: [f64; 3],
    /// Unit normal.
    pub n: [f64; 3],
    /// Unit half vector `normalize(l + v)` (meaningful when both cosines are > 0).
    pub h: [f64; 3],
    /// `cos_i = n·l`.
    pub cos_i: f64,
    /// `cos_o = n·v`.
    pub cos_o: f64,
    /// `cos_h = n·h` (cos δ).
    pub cos_h: f64,
    /// `c = v·h`, the Fresnel angle cosine.
    pub c: f64,
    /// `sin²δ = |n × h|²`: exact near the peak, where `1 − cos_h²` cancels to 0.
    pub sin2_h: f64,
    /// Unit tangent `t` and bitangent `b = n × t` (anisotropic materials only).
    pub tb: Option<([f64; 3], [f64; 3])>,
}

impl Frame {
    /// Builds the frame, or `None` when the tuple is invalid (FORMULAS.md §1): a zero or
    /// non-finite L, V or N, or for anisotropic materials a missing, zero, non-finite
    /// tangent or one parallel to N (`|T − n(n·T)| ≤ 1e-12 |T|`).
    pub fn new(
        l: [f64; 3],
        v: [f64; 3],
        n: [f64; 3],
        t: Option<[f64; 3]>,
        anisotropic: bool,
    ) -> Option<Frame> {
        let (l, v, n) = (normalize(l)?, normalize(v)?, normalize(n)?);
        let tb = if anisotropic {
            let t = normalize(t?)?; // unit T: the 1e-12 |T| test becomes 1e-12
            let nt = dot(n, t);
            let perp = [t[0] - n[0] * nt, t[1] - n[1] * nt, t[2] - n[2] * nt];
            // |T − n(n·T)| = |n × T| exactly, and the cross product keeps its relative
            // precision when T is nearly parallel to N, where the subtraction cancels.
            if length_squared(cross(n, t)).sqrt() <= 1e-12 {
                return None;
            }
            let t = normalize(perp)?;
            Some((t, cross(n, t)))
        } else {
            None
        };
        let cos_i = dot(n, l);
        let cos_o = dot(n, v);
        // l + v is zero for l = −v; then h is undefined, but that tuple is below the
        // horizon (cos_i = −cos_o), and the caller returns before reading h.
        let h = normalize([l[0] + v[0], l[1] + v[1], l[2] + v[2]]).unwrap_or(n);
        let cos_h = dot(n, h);
        Some(Frame {
            l,
            v,
            n,
            h,
            cos_i,
            cos_o,
            cos_h,
            c: dot(v, h),
            sin2_h: length_squared(cross(n, h)),
            tb,
        })
    }

    /// `tan²δ = sin²δ / cos²δ`.
    pub fn tan2_h(&self) -> f64 {
        self.sin2_h / (self.cos_h * self.cos_h)
    }

    /// `(h·t, h·b, h·n)`: the half vector in the tangent frame (anisotropic only).
    pub fn h_local(&self) -> Option<[f64; 3]> {
        self.tb
            .map(|(t, b)| [dot(self.h, t), dot(self.h, b), self.cos_h])
    }
}
