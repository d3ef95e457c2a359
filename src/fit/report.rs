//! What a fit leaves behind: the fitted material as a materials TOML (`vkbrdf eval` takes
//! it as is: it is parsed back before it is written), the parameters in the conventions
//! engines use, a Markdown report, and the residual slice (θ_h × θ_d) as EXR and PNG.

use super::data::FitData;
use super::losses::{Loss, Metrics, RRMS_FLOOR};
use super::FitResult;
use crate::error::{Error, Result};
use crate::material::merl::{bin_of, THETA_D_BINS, THETA_H_BINS};
use crate::material::{Distribution, Fresnel, Material, Model, Rgb};
use std::fmt::Write as _;

fn rgb(x: Rgb) -> String {
    format!("[{:?}, {:?}, {:?}]", x[0], x[1], x[2])
}

/// `material` as one `[[material]]` table, every key the model reads written out; an
/// error (a bug) if the text does not parse back to the same material.
pub fn material_toml(material: &Material) -> Result<String> {
    let mut s = String::from("[[material]]\n");
    let _ = writeln!(s, "name = {:?}", material.name);
    let key = |s: &mut String, k: &str, v: String| {
        let _ = writeln!(s, "{k} = {v}");
    };
    match &material.model {
        Model::Lambert => key(&mut s, "model", "\"lambert\"".into()),
        Model::Phong { exponent } | Model::BlinnPhong { exponent } | Model::Rtr { exponent } => {
            key(&mut s, "model", format!("{:?}", material.model.toml_name()));
            key(&mut s, "exponent", format!("{exponent:?}"));
        }
        Model::Ward { roughness } => {
            key(&mut s, "model", "\"ward\"".into());
            key(&mut s, "roughness", format!("{:?}", roughness.xy().0));
        }
        Model::CookTorrance(ct) => {
            key(&mut s, "model", "\"cook-torrance\"".into());
            key(
                &mut s,
                "convention",
                format!("{:?}", ct.convention.toml_name()),
            );
            key(
                &mut s,
                "distribution",
                format!("{:?}", ct.distribution.kind().toml_name()),
            );
            match ct.distribution {
                Distribution::Beckmann(r) | Distribution::Ggx(r) => {
                    key(&mut s, "roughness", format!("{:?}", r.xy().0))
                }
                Distribution::Gaussian { m } | Distribution::Charlie { m } => {
                    key(&mut s, "roughness", format!("{m:?}"))
                }
                Distribution::Blinn { exponent } => {
                    key(&mut s, "exponent", format!("{exponent:?}"))
                }
            }
            key(&mut s, "geometry", format!("{:?}", ct.geometry.toml_name()));
            key(
                &mut s,
                "fresnel",
                format!("{:?}", ct.fresnel.kind().toml_name()),
            );
            match ct.fresnel {
                Fresnel::None => {}
                Fresnel::Dielectric { ior } => key(&mut s, "ior", rgb(ior)),
                Fresnel::Conductor { ior, extinction } => {
                    key(&mut s, "ior", rgb(ior));
                    key(&mut s, "extinction", rgb(extinction));
                }
                Fresnel::Schlick { f0 } => key(&mut s, "f0", rgb(f0)),
            }
            key(&mut s, "diffuse_weight", format!("{:?}", ct.diffuse_weight));
            key(
                &mut s,
                "specular_weight",
                format!("{:?}", ct.specular_weight),
            );
        }
        Model::Measured(_) => {
            return Err(Error::Unsupported(
                "a measured material is not a fit's result".into(),
            ))
        }
        Model::Htsg(p) => {
            key(&mut s, "model", format!("{:?}", crate::terms::htsg::NAME));
            key(&mut s, "sigma0", format!("{:?}", p.sigma0));
            key(&mut s, "tau", format!("{:?}", p.tau));
            key(&mut s, "ior", rgb(p.ior));
            key(&mut s, "extinction", rgb(p.extinction));
            key(
                &mut s,
                "wavelengths",
                rgb(p.wavelengths.map(|l| l * 1000.0)),
            );
        }
    }
    key(&mut s, "diffuse", rgb(material.diffuse));
    if !matches!(material.model, Model::Lambert | Model::Htsg(_)) {
        key(&mut s, "specular", rgb(material.specular));
    }
    if material.precision == crate::material::precision::Precision::Fast {
        key(&mut s, "precision", "\"fast\"".into());
    }
    let back = crate::material::parse_materials(&s, "the fitted material")?;
    if back.len() != 1 || back[0] != *material {
        return Err(Error::Unsupported(format!(
            "the fitted material does not read back as itself (a bug):\n{s}"
        )));
    }
    Ok(s)
}

/// The parameters in the conventions engines use, as `(name, value)` lines.
pub fn conventions(material: &Material) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let alpha = match &material.model {
        Model::Ward { roughness } => Some(roughness.xy().0),
        Model::CookTorrance(ct) => match ct.distribution {
            Distribution::Beckmann(r) | Distribution::Ggx(r) => Some(r.xy().0),
            _ => None,
        },
        _ => None,
    };
    if let Some(a) = alpha {
        out.push((
            "α (vkbrdf `roughness`, pbrt-v4 `alpha`)".into(),
            format!("{a:.6}"),
        ));
        out.push((
            "perceptual roughness √α (UE4, Filament)".into(),
            format!("{:.6}", a.sqrt()),
        ));
        out.push(("Mitsuba 3 `alpha`".into(), format!("{a:.6}")));
    }
    if let Some(ct) = material.cook_torrance() {
        let f0 = match ct.fresnel {
            Fresnel::Schlick { f0 } => Some(f0),
            Fresnel::Dielectric { ior } => Some(crate::material::f0_from_ior(ior, [0.0; 3])),
            Fresnel::Conductor { ior, extinction } => {
                out.push(("η (n, per channel)".into(), format!("{ior:.6?}")));
                out.push(("k (per channel)".into(), format!("{extinction:.6?}")));
                Some(crate::material::f0_from_ior(ior, extinction))
            }
            Fresnel::None => None,
        };
        if let (Some(f0), Fresnel::Dielectric { ior }) = (f0, ct.fresnel) {
            out.push(("η".into(), format!("{:.6}", ior[0])));
            out.push(("F0".into(), format!("{f0:.6?}")));
        } else if let Some(f0) = f0 {
            out.push(("F0".into(), format!("{f0:.6?}")));
            let s: Rgb = std::array::from_fn(|c| ct.specular_weight * material.specular[c] * f0[c]);
            out.push((
                "specular · F0 (normal-incidence reflectance)".into(),
                format!("{s:.6?}"),
            ));
        }
        let d: Rgb = material.diffuse.map(|x| x * ct.diffuse_weight);
        out.push(("diffuse albedo d·c_diff".into(), format!("{d:.6?}")));
    } else {
        out.push((
            "diffuse albedo c_diff".into(),
            format!("{:.6?}", material.diffuse),
        ));
        if !matches!(material.model, Model::Lambert) {
            out.push((
                "specular albedo c_spec".into(),
                format!("{:.6?}", material.specular),
            ));
        }
    }
    out
}

/// The residual slice: per θ_h × θ_d cell of MERL's bins (90 × 90, θ_h on MERL's square-root
/// spacing), the weighted mean over the cell's samples (every φ_d) of the relative
/// residual `(f − f_m)/max(f_m, ε)` per channel; cells without samples are NaN.
/// Row-major, θ_h fastest (column), θ_d the row.
pub fn residual_slice(data: &FitData, model: &[[f64; 3]]) -> [Vec<f32>; 3] {
    let cells = THETA_H_BINS * THETA_D_BINS;
    let mut sum = vec![[0.0f64; 3]; cells];
    let mut weight = vec![0.0f64; cells];
    for (i, (f, fm)) in model.iter().zip(&data.values).enumerate() {
        let (th, td) = data.angles[i];
        let (h, d, _) = bin_of(th, td, 0.0);
        let cell = d * THETA_H_BINS + h;
        let w = data.weight_e[i].max(1e-300);
        weight[cell] += w;
        for c in 0..3 {
            sum[cell][c] += w * (f[c] - fm[c]) / fm[c].max(RRMS_FLOOR);
        }
    }
    std::array::from_fn(|c| {
        (0..cells)
            .map(|k| {
                if weight[k] > 0.0 {
                    (sum[k][c] / weight[k]) as f32
                } else {
                    f32::NAN
                }
            })
            .collect()
    })
}

/// The residual slice as a picture: the channels' mean relative residual on a diverging
/// map, blue (model too low) – white (0) – red (model too high), saturating at ±`range`;
/// grey where there is no sample. 4× the slice's size.
pub fn residual_png(slice: &[Vec<f32>; 3], range: f64) -> crate::table::preview::Canvas {
    let zoom = 4;
    let (w, h) = (THETA_H_BINS, THETA_D_BINS);
    let mut canvas = crate::table::preview::Canvas::new(w * zoom, h * zoom, [128, 128, 128]);
    for y in 0..h {
        for x in 0..w {
            let k = y * w + x;
            let r = (slice[0][k] + slice[1][k] + slice[2][k]) as f64 / 3.0;
            if !r.is_finite() {
                continue;
            }
            let t = (r / range).clamp(-1.0, 1.0);
            let a = (255.0 * (1.0 - t.abs())) as u8;
            let c = if t >= 0.0 { [255, a, a] } else { [a, a, 255] };
            for dy in 0..zoom {
                for dx in 0..zoom {
                    canvas.put((x * zoom + dx) as i64, (y * zoom + dy) as i64, c);
                }
            }
        }
    }
    canvas
}

/// The Markdown report of `result`.
pub fn markdown(result: &FitResult, data: &FitData, start: &Material, command: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Fit of `{}`\n", data.source.display());
    if result.interrupted {
        let _ = writeln!(
            s,
            "**Interrupted** (Ctrl-C): these are the best parameters found before the fit was stopped, not a converged fit.\n"
        );
    }
    let _ = writeln!(s, "Command: `{command}`\n");
    let _ = writeln!(
        s,
        "Data: {} samples fitted ({} read, {} masked: invalid, below the horizon or beyond the cut-off); weights: {}.\n",
        data.len(),
        data.read,
        data.masked,
        match data.measure {
            super::data::Measure::Given => "each sample's own solid angle",
            super::data::Measure::AngleGrid => "sin θ_i sin θ_o (L2), sin θ_i (E1, E2, relative RMS)",
        }
    );
    let _ = writeln!(
        s,
        "Start: material `{}`; loss minimised: `{}`.\n",
        start.name,
        result.loss.name()
    );
    let _ = writeln!(s, "## Metrics\n\n| metric | start | fit |\n|---|---|---|");
    let row = |s: &mut String, name: &str, a: f64, b: f64| {
        let _ = writeln!(s, "| {name} | {a:.6e} | {b:.6e} |");
    };
    let (a, b) = (&result.start_metrics, &result.metrics);
    row(&mut s, "Ngan L2", a.l2, b.l2);
    row(&mut s, "L2 / data energy", a.l2_relative, b.l2_relative);
    row(&mut s, "Löw E1", a.e1, b.e1);
    row(&mut s, "Löw E2", a.e2, b.e2);
    row(&mut s, "relative RMS", a.rrms, b.rrms);
    let _ = writeln!(s, "\nData energy Σ w (f_m cos θ_i)²: {:.6e}.\n", b.energy);
    let _ = writeln!(s, "## Parameters\n\n| convention | value |\n|---|---|");
    for (k, v) in conventions(&result.material) {
        let _ = writeln!(s, "| {k} | {v} |");
    }
    let _ = writeln!(
        s,
        "\n## Materials file\n\n```toml\n{}```\n",
        material_toml(&result.material).unwrap_or_default()
    );
    let _ = writeln!(
        s,
        "## Search\n\n| phase | start | loss | evaluations | stop |\n|---|---|---|---|---|"
    );
    for (k, st) in result.starts.iter().enumerate() {
        let _ = writeln!(
            s,
            "| {} | {k} | {:.6e} | {} | {:?} |",
            st.phase, st.minimum.value, st.minimum.evaluations, st.minimum.stop
        );
    }
    let _ = writeln!(
        s,
        "\n{} loss evaluations ({} sample evaluations) on {} in {:.2} s, {:.2} s of them in the engine: {:.1} loss evaluations/s, {:.1} M samples/s in the engine.",
        result.evaluations,
        result.sample_evaluations,
        result.backend,
        result.seconds,
        result.engine_seconds,
        result.evaluations as f64 / result.seconds.max(1e-9),
        result.sample_evaluations as f64 / result.engine_seconds.max(1e-9) / 1e6
    );
    s
}

/// The names of the metrics, as the CLI prints them.
pub fn metric_lines(m: &Metrics) -> Vec<(&'static str, f64)> {
    let mut v: Vec<(&'static str, f64)> = Loss::ALL.iter().map(|l| (l.name(), m.get(*l))).collect();
    v.insert(1, ("l2/energy", m.l2_relative));
    v
}
