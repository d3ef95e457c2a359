//! Table generators (`vkbrdf table`): scratch measurement.

use vkbrdf::backend::Backend;
use vkbrdf::material::{Geometry, Material};
use vkbrdf::reference::{self, CpuReference};
use vkbrdf::table::albedo::{self, Lobe, Microfacet};
use vkbrdf::table::Runner;

fn gl(n: usize) -> Vec<(f64, f64)> {
    albedo::gauss_legendre(n)
}

/// Independent: dense composite Gauss–Legendre over (θ_l, φ_l), sinh-mapped around the mirror direction.
fn independent<const K: usize>(
    m: &Material,
    mu: f64,
    alpha: f64,
    panels: usize,
    weight: &dyn Fn(f64) -> [f64; K],
) -> [f64; K] {
    let theta_o = mu.acos();
    let v = [theta_o.sin(), 0.0, mu];
    let wt = alpha.max(1e-3);
    let wp = (2.0 * alpha * mu / theta_o.sin().max(1e-9)).min(1.0);
    let q = 8;
    let nodes = gl(q);
    let ta = (-theta_o / wt).asinh();
    let tb = ((std::f64::consts::FRAC_PI_2 - theta_o) / wt).asinh();
    let sb = (std::f64::consts::PI / wp).asinh();
    let mut acc = [0.0; K];
    for pt in 0..panels {
        let (t0, t1) = (
            ta + (tb - ta) * pt as f64 / panels as f64,
            ta + (tb - ta) * (pt + 1) as f64 / panels as f64,
        );
        for &(xt, wt_) in &nodes {
            let t = t0 + (t1 - t0) * xt;
            let theta = theta_o + wt * t.sinh();
            let jt = wt * t.cosh() * (t1 - t0) * wt_;
            for ps in 0..panels {
                let (s0, s1) = (
                    sb * ps as f64 / panels as f64,
                    sb * (ps + 1) as f64 / panels as f64,
                );
                for &(xs, ws) in &nodes {
                    let s = s0 + (s1 - s0) * xs;
                    let phi = std::f64::consts::PI - wp * s.sinh();
                    let js = wp * s.cosh() * (s1 - s0) * ws;
                    let l = [
                        theta.sin() * phi.cos(),
                        theta.sin() * phi.sin(),
                        theta.cos(),
                    ];
                    let e = reference::evaluate(l, v, [0.0, 0.0, 1.0], None, m);
                    if e.brdf[0] == 0.0 {
                        continue;
                    }
                    let h = vkbrdf::reference::frame::normalize([
                        l[0] + v[0],
                        l[1] + v[1],
                        l[2] + v[2],
                    ])
                    .unwrap();
                    let c = vkbrdf::reference::frame::dot(v, h);
                    let w = weight(c);
                    let base = 2.0 * e.brdf[0] * theta.cos() * theta.sin() * jt * js;
                    for k in 0..K {
                        acc[k] += base * w[k];
                    }
                }
            }
        }
    }
    acc
}

#[test]
#[ignore]
fn measure() {
    let mut cpu = CpuReference::new();
    for (lobe, geom) in [
        (Lobe::Ggx, Geometry::SmithCorrelated),
        (Lobe::Beckmann, Geometry::SmithCorrelated),
        (Lobe::Beckmann, Geometry::CookTorrance),
    ] {
        let spec = Microfacet {
            lobe,
            geometry: geom,
        };
        let mut pts = vec![];
        for mu in [1.0 / 64.0, 0.1, 0.5, 0.99] {
            for a in [1.0 / 256.0, 1.0 / 64.0, 0.05, 0.2, 0.5, 0.99] {
                pts.push((mu, a));
            }
        }
        let t0 = std::time::Instant::now();
        let refs: Vec<(f64, f64)> = pts
            .iter()
            .map(|&(mu, a)| {
                let m = spec.material(a).unwrap();
                let e1 = independent(&m, mu, a, 48, &|_| [1.0])[0];
                let e2 = independent(&m, mu, a, 96, &|_| [1.0])[0];
                (e2, (e2 - e1).abs())
            })
            .collect();
        eprintln!("{lobe:?} {geom:?}: independent took {:?}", t0.elapsed());
        for n in [1u32 << 10, 1 << 12, 1 << 14, 1 << 16] {
            let t0 = std::time::Instant::now();
            let mut runner = Runner::new(&mut cpu as &mut dyn Backend);
            let e = albedo::directional_albedo(&mut runner, &spec, &pts, n).unwrap();
            let dt = t0.elapsed();
            let mut worst = (0.0, 0.0, 0.0);
            for (i, &(mu, a)) in pts.iter().enumerate() {
                let err = (e[i] - refs[i].0).abs();
                if err > worst.0 {
                    worst = (err, mu, a);
                }
            }
            eprintln!(
                "  N={n}: max err {:.2e} at mu={} a={} ({dt:?})",
                worst.0, worst.1, worst.2
            );
            if n == 1 << 16 {
                for (i, &(mu, a)) in pts.iter().enumerate() {
                    eprintln!(
                        "    mu={mu:.4} a={a:.4} E={:.6} ref={:.6} conv={:.1e} err={:.1e}",
                        e[i],
                        refs[i].0,
                        refs[i].1,
                        e[i] - refs[i].0
                    );
                }
            }
        }
    }
}

#[test]
#[ignore]
fn scan() {
    let mut cpu = CpuReference::new();
    let h: usize = std::env::var("SCAN_H")
        .map(|s| s.parse().unwrap())
        .unwrap_or(32);
    let rows: usize = std::env::var("SCAN_ROWS")
        .map(|s| s.parse().unwrap())
        .unwrap_or(h);
    for lobe in [Lobe::Ggx, Lobe::Beckmann] {
        let spec = Microfacet {
            lobe,
            geometry: Geometry::SmithCorrelated,
        };
        let mut pts = vec![];
        for j in 0..rows {
            for i in 0..32 {
                pts.push(((i as f64 + 0.5) / 32.0, (j as f64 + 0.5) / h as f64));
            }
        }
        let refs: Vec<[f64; 3]> = pts
            .iter()
            .map(|&(mu, a)| {
                let m = spec.material(a).unwrap();
                let ab = independent(&m, mu, a, 64, &|c| {
                    let w = (1.0 - c).powi(5);
                    [1.0, 1.0 - w, w]
                });
                ab
            })
            .collect();
        for n in [1u32 << 14, 1 << 16] {
            let mut runner = Runner::new(&mut cpu as &mut dyn Backend);
            let t0 = std::time::Instant::now();
            let e = albedo::directional_albedo(&mut runner, &spec, &pts, n).unwrap();
            let t1 = t0.elapsed();
            let ab = vkbrdf::table::dfg::split_sum(&mut runner, &spec, &pts, n).unwrap();
            let mut worst = [(0.0, 0.0, 0.0); 3];
            for (i, &(mu, a)) in pts.iter().enumerate() {
                let errs = [
                    e[i] - refs[i][0],
                    ab[i][0] - refs[i][1],
                    ab[i][1] - refs[i][2],
                ];
                for k in 0..3 {
                    if errs[k].abs() > worst[k].0 {
                        worst[k] = (errs[k].abs(), mu, a);
                    }
                }
            }
            eprintln!(
                "{lobe:?} N={n} ({t1:?} per table): worst E {:?} A {:?} B {:?}",
                worst[0], worst[1], worst[2]
            );
        }
    }
}

#[test]
#[ignore]
fn scan_avg() {
    let mut cpu = CpuReference::new();
    for lobe in [Lobe::Ggx, Lobe::Beckmann] {
        let spec = Microfacet {
            lobe,
            geometry: Geometry::SmithCorrelated,
        };
        let alphas = [1.0 / 64.0, 0.05, 0.2, 0.5, 0.99];
        let mut runner = Runner::new(&mut cpu as &mut dyn Backend);
        let prod = albedo::average_albedo(&mut runner, &spec, &alphas, 1 << 16).unwrap();
        for (i, &a) in alphas.iter().enumerate() {
            let m = spec.material(a).unwrap();
            let ind = |k: usize, panels: usize| -> f64 {
                gl(k)
                    .iter()
                    .map(|&(mu, w)| 2.0 * mu * w * independent(&m, mu, a, panels, &|_| [1.0])[0])
                    .sum()
            };
            let (i32_, i64_, i128_) = (ind(32, 24), ind(64, 24), ind(128, 24));
            let i64b = ind(64, 48);
            eprintln!("{lobe:?} a={a}: prod {:.7} ind32 {:.7} ind64 {:.7} ind128 {:.7} ind64(48p) {:.7} err {:.1e}", prod[i], i32_, i64_, i128_, i64b, prod[i] - i128_);
        }
    }
}
