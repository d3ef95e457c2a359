//! The judge's HTSG (FORMULAS.md §8): the contract's formulas as printed, in 1024-bit
//! arithmetic (`super`'s `X`), for `tests/judge.rs`.

use super::{addv, cross, dot, erfc, fresnel, pi, x, Exact, Fr, V3, X};
use vkbrdf::material::Fresnel;
use vkbrdf::reference::Status;

/// Where a term of an HTSG sum is negligible: far below f64 (2^-300 of the sum), well
/// above the 1024 bits carried, so that the series and Newton stop in reasonable time.
fn htsg_eps() -> X {
    x(2f64.powi(-300))
}

/// FORMULAS.md §8's `S1(θ)` as printed (Eq. 24–25 with the erratum), for `x = τ cot θ/(2σ0)`;
/// and `K(θ) = tan θ erfc(τ/(2σ0 tan θ))`. At normal incidence (sin θ = 0), and where x
/// is so large that `e^{−x²}` is below 2^-10^6 (then 1 − S1 and K are below every digit
/// carried), S1 = 1 and K = 0.
fn htsg_direction(fr: &Fr, w: &V3, cos: &X, p: &vkbrdf::terms::htsg::Htsg) -> (X, X) {
    let nxw = cross(&fr.n, w);
    let sin = dot(&nxw, &nxw).sqrt();
    let ratio = x(p.tau).div(&x(2.0 * p.sigma0));
    if sin.is_zero() || ratio.mul(cos).div(&sin).cmp(&x(1e3)) > 0 {
        return (x(1.0), x(0.0));
    }
    let xx = ratio.mul(cos).div(&sin);
    let erfc_x = erfc(&xx);
    let lambda = xx
        .sq()
        .neg()
        .exp()
        .div(&xx.mul(&pi().sqrt()))
        .sub(&erfc_x)
        .div(&x(2.0));
    let s1 = x(1.0).sub(&erfc_x.div(&x(2.0))).div(&lambda.add(&x(1.0)));
    let k = sin.div(cos).mul(&erfc_x);
    (s1, k)
}

/// The effective roughness σ0/√(1 + z²), `z e^{z²/2} = R` by Newton on `ln z + z²/2 = ln R`.
fn htsg_sigma(sigma0: f64, r: &X) -> X {
    if r.is_zero() {
        return x(sigma0);
    }
    let ln_r = r.ln();
    let mut z = if r.le(&x(1.0)) {
        r.clone()
    } else {
        x(2.0).mul(&x(1.0).add(r).ln()).sqrt()
    };
    for _ in 0..200 {
        let h = z.ln().add(&z.sq().div(&x(2.0))).sub(&ln_r);
        let step = z.mul(&h).div(&x(1.0).add(&z.sq()));
        z = z.sub(&step);
        if step.abs().le(&z.mul(&htsg_eps())) {
            break;
        }
    }
    x(sigma0).div(&x(1.0).add(&z.sq()).sqrt())
}

/// FORMULAS.md §8 as printed: `ρ_dd = F G S D/(π cos_i cos_r)` plus `a/π`.
pub(super) fn exact(fr: &Fr, p: &vkbrdf::terms::htsg::Htsg, diffuse: &[X; 3]) -> Exact {
    let s = addv(&fr.l, &fr.v);
    let s2 = dot(&s, &s);
    let ns = dot(&fr.n, &s);
    let c = s2.sqrt().div(&x(2.0));
    let g = s2.div(&ns).sq();
    let (s1_i, k_i) = htsg_direction(fr, &fr.l, &fr.cos_i, p);
    let (s1_o, k_o) = htsg_direction(fr, &fr.v, &fr.cos_o, p);
    let k = s1_i.mul(&s1_o).div(&pi().mul(&fr.cos_i).mul(&fr.cos_o));
    let r = k_i.add(&k_o).div(&x(8.0).mul(&pi()).sqrt());
    let sigma = htsg_sigma(p.sigma0, &r);
    let vxy2 = s2.sub(&ns.sq());
    let conductor = Fresnel::Conductor {
        ior: p.ior,
        extinction: p.extinction,
    };
    let mut d = [x(0.0), x(0.0), x(0.0)];
    let f: [X; 3] = std::array::from_fn(|ch| fresnel(&c, &conductor, ch));
    for (ch, d) in d.iter_mut().enumerate() {
        let lambda = x(p.wavelengths[ch]);
        let two_pi = x(2.0).mul(&pi());
        let gg = two_pi.mul(&sigma).mul(&ns).div(&lambda).sq();
        let t = two_pi.mul(&x(p.tau)).div(&lambda);
        let norm = pi().mul(&x(p.tau)).div(&x(2.0).mul(&lambda)).sq();
        let a = vxy2.mul(&t.sq()).div(&x(4.0));
        *d = if gg.cmp(&x(vkbrdf::terms::htsg::G_SWITCH)) > 0 {
            norm.mul(&a.div(&gg).neg().exp()).div(&gg)
        } else {
            // Σ e^{−g} g^m/(m!·m) e^{−a/m}, until m > g and the weight e^{−g} g^m/m! is
            // below 2^-300 of the sum.
            let mut weight = gg.neg().exp();
            let mut sum = x(0.0);
            let mut m = 1u32;
            loop {
                let mf = x(f64::from(m));
                weight = weight.mul(&gg).div(&mf);
                sum = sum.add(&weight.div(&mf).mul(&a.div(&mf).neg().exp()));
                if mf.cmp(&gg) > 0 && weight.le(&sum.mul(&htsg_eps())) || m > 5000 {
                    break;
                }
                m += 1;
            }
            norm.mul(&sum)
        };
    }
    let brdf = std::array::from_fn(|ch| f[ch].mul(&g).mul(&d[ch]).mul(&k).add(&diffuse[ch]));
    Exact {
        status: Status::Valid,
        brdf,
        d: d[1].clone(),
        g,
        f,
        k,
    }
}
