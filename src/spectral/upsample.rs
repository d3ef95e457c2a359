//! RGB → reflectance spectrum, by Jakob & Hanika 2019 ("A Low-Dimensional Function Space for
//! Efficient Spectral Upsampling", Computer Graphics Forum 38(2)), the method Mitsuba 3 and
//! pbrt-v4 use: `s(λ) = S(c0 t² + c1 t + c2)` with the sigmoid `S(x) = ½ + x / (2√(1 + x²))`
//! and `t = (λ − 360 nm) / 470 nm`, its three coefficients chosen so that the spectrum
//! reduces to the colour under D65 (FORMULAS.md §9). As in their `rgb2spec_opt`, the fit is
//! Gauss–Newton on the CIELAB difference, reached by continuation from the colour's grey.
//! A grey `(c, c, c)` is the constant spectrum `c`, exactly.

use super::cie::{self, Illuminant, SAMPLES};

/// A reflectance spectrum up-sampled from a linear sRGB colour.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Reflectance {
    /// The same value at every wavelength (a grey colour).
    Constant(f64),
    /// `scale · S(c0 t² + c1 t + c2)`; `scale` is 1 for colours inside [0, 1] and twice
    /// the largest channel above it (as pbrt-v4's unbounded spectra).
    Sigmoid {
        /// `c0, c1, c2`.
        c: [f64; 3],
        /// The factor outside the sigmoid.
        scale: f64,
    },
}

/// The sigmoid `S(x) = ½ + x / (2√(1 + x²))`, in (0, 1); `±∞` give 0 and 1.
fn sigmoid(x: f64) -> f64 {
    if x.is_infinite() {
        return if x > 0.0 { 1.0 } else { 0.0 };
    }
    0.5 + x / (2.0 * (1.0 + x * x).sqrt())
}

/// `t` of a wavelength: 0 at 360 nm, 1 at 830 nm.
fn t_of(nm: f64) -> f64 {
    (nm - cie::FIRST_NM) / (cie::STEP_NM * (SAMPLES - 1) as f64)
}

impl Reflectance {
    /// The value at `nm` (any wavelength: outside 360–830 nm the polynomial continues and
    /// the sigmoid keeps the value inside (0, scale)).
    pub fn at(&self, nm: f64) -> f64 {
        match *self {
            Reflectance::Constant(v) => v,
            Reflectance::Sigmoid { c, scale } => {
                let t = t_of(nm);
                scale * sigmoid((c[0] * t + c[1]) * t + c[2])
            }
        }
    }

    /// The spectrum of the linear sRGB colour `rgb` (channels ≥ 0).
    pub fn fit(rgb: [f64; 3]) -> Reflectance {
        if rgb[0] == rgb[1] && rgb[1] == rgb[2] {
            return Reflectance::Constant(rgb[0]);
        }
        let top = rgb.iter().copied().fold(0.0, f64::max);
        let scale = if top > 1.0 { 2.0 * top } else { 1.0 };
        let target = rgb.map(|x| x / scale);
        Reflectance::Sigmoid {
            c: fit_coefficients(target),
            scale,
        }
    }
}

/// The coefficients for a colour inside [0, 1]³: continuation in 16 steps from its grey
/// (an exact constant, `c = (0, 0, S⁻¹(grey))`), each step Gauss–Newton from the last.
fn fit_coefficients(rgb: [f64; 3]) -> [f64; 3] {
    let grey = ((rgb[0] + rgb[1] + rgb[2]) / 3.0).clamp(1e-6, 1.0 - 1e-6);
    let u = 2.0 * grey - 1.0;
    let mut c = [0.0, 0.0, u / (1.0 - u * u).sqrt()];
    const STEPS: usize = 16;
    for s in 1..=STEPS {
        let f = s as f64 / STEPS as f64;
        let target = std::array::from_fn(|i| grey + (rgb[i] - grey) * f);
        c = gauss_newton(c, target);
    }
    c
}

/// CIELAB (D65 white) of the spectrum with coefficients `c`.
fn lab_of(c: [f64; 3], w: &[[f64; 3]; SAMPLES], white: [f64; 3]) -> [f64; 3] {
    let mut xyz = [0.0; 3];
    for (i, wi) in w.iter().enumerate() {
        let t = i as f64 / (SAMPLES - 1) as f64;
        let s = sigmoid((c[0] * t + c[1]) * t + c[2]);
        for k in 0..3 {
            xyz[k] += s * wi[k];
        }
    }
    cie::lab(xyz, white)
}

/// Gauss–Newton on `Lab(c) − Lab(target)` with a forward-difference Jacobian (as
/// `rgb2spec_opt`), until the residual is below 1e-6 in ΔE or 30 steps.
fn gauss_newton(mut c: [f64; 3], target: [f64; 3]) -> [f64; 3] {
    let w = cie::weights(Illuminant::D65);
    let white = cie::d65_white();
    let goal = cie::lab(cie::srgb_to_xyz(target), white);
    let residual = |c: [f64; 3]| {
        let l = lab_of(c, &w, white);
        [l[0] - goal[0], l[1] - goal[1], l[2] - goal[2]]
    };
    for _ in 0..30 {
        let r = residual(c);
        if r.iter().map(|x| x * x).sum::<f64>().sqrt() < 1e-6 {
            break;
        }
        const H: f64 = 1e-5;
        let mut j = [[0.0; 3]; 3];
        for k in 0..3 {
            let mut ck = c;
            ck[k] += H;
            let rk = residual(ck);
            for row in 0..3 {
                j[row][k] = (rk[row] - r[row]) / H;
            }
        }
        let ji = cie::inverse(&j);
        let step: [f64; 3] =
            std::array::from_fn(|k| ji[k][0] * r[0] + ji[k][1] * r[1] + ji[k][2] * r[2]);
        if !step.iter().all(|x| x.is_finite()) {
            break; // a singular Jacobian: keep the best coefficients so far
        }
        // A step that makes the residual larger is halved (the sigmoid saturates near the
        // gamut's edge, where a full step overshoots).
        let norm = |r: [f64; 3]| r.iter().map(|x| x * x).sum::<f64>();
        let mut a = 1.0;
        let before = norm(r);
        loop {
            let trial = std::array::from_fn(|k| c[k] - a * step[k]);
            if norm(residual(trial)) < before || a < 1e-4 {
                c = trial;
                break;
            }
            a *= 0.5;
        }
        // Coefficients this large make a step function; beyond them the fit stops.
        if c.iter().any(|x| x.abs() > 1e4) {
            break;
        }
    }
    c
}

/// The linear sRGB a reflectance spectrum reduces to under D65 (its round trip).
pub fn round_trip(s: &Reflectance) -> [f64; 3] {
    let v: Vec<f64> = (0..SAMPLES).map(|i| s.at(cie::wavelength(i))).collect();
    cie::to_srgb(&v, Illuminant::D65)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grey_is_the_constant_spectrum() {
        for c in [0.0, 0.18, 0.5, 1.0, 3.0] {
            assert_eq!(Reflectance::fit([c; 3]), Reflectance::Constant(c));
        }
    }

    /// FORMULAS.md §9: an in-gamut colour returns to itself under D65 within 1e-3.
    #[test]
    fn in_gamut_colours_return_to_themselves() {
        let levels = [0.02, 0.1, 0.3, 0.5, 0.7, 0.9, 0.98];
        let mut worst = 0.0f64;
        for r in levels {
            for g in levels {
                for b in levels {
                    let rgb = [r, g, b];
                    let back = round_trip(&Reflectance::fit(rgb));
                    for k in 0..3 {
                        worst = worst.max((back[k] - rgb[k]).abs());
                    }
                }
            }
        }
        assert!(worst < 1e-3, "worst round trip {worst}");
    }

    #[test]
    fn brighter_than_white_keeps_its_colour() {
        let rgb = [1.8, 0.9, 0.3];
        let back = round_trip(&Reflectance::fit(rgb));
        for k in 0..3 {
            assert!((back[k] - rgb[k]).abs() < 2e-3, "{back:?}");
        }
    }
}
