//! `vkbrdf table spectral`: what a renderer would show of a spectral material's Fresnel
//! reflectance, θ from 0 to 90°: the spectral reflectance reduced to linear sRGB under D65
//! (FORMULAS.md §9) beside each RGB reduction's (Mitsuba's, Filament's), their per-channel
//! differences and ΔE*ab (CIELAB, D65 white).

use crate::error::{Error, Result};
use crate::material::spectral::rgb_fresnel;
use crate::material::{Fresnel, Material};
use crate::spectral::cie::{self, Illuminant, SAMPLES};
use crate::spectral::RgbReduction;
use crate::terms::f;
use crate::terms::FresnelKind;

/// One angle of the table.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// The angle of incidence θ (degrees), `c = cos θ`.
    pub theta_deg: f64,
    /// The spectral reflectance `F(λ, c)` reduced to linear sRGB under D65.
    pub spectral: [f64; 3],
    /// Each RGB reduction's reflectance, in [`RgbReduction::ALL`]'s order.
    pub rgb: [[f64; 3]; 2],
    /// ΔE*ab of each RGB reduction from the spectral colour.
    pub delta_e: [f64; 2],
}

/// F of an RGB Fresnel term at `c`, per channel (FORMULAS.md §4).
fn rgb_f(fresnel: &Fresnel, c: f64) -> [f64; 3] {
    std::array::from_fn(|ch| match *fresnel {
        Fresnel::None => 1.0,
        Fresnel::Dielectric { ior } => f::dielectric::f(c, ior[ch]),
        Fresnel::Conductor { ior, extinction } => f::conductor::f(c, ior[ch], extinction[ch]),
        Fresnel::Schlick { f0 } => f::schlick::f(c, f0[ch]),
    })
}

/// The table of `material` (which must have a spectral `ior`) at θ = 0, step, …, 90°.
pub fn reflectance(material: &Material, step_deg: f64) -> Result<Vec<Row>> {
    let s = material.spectral.as_ref().ok_or_else(|| {
        Error::Unsupported(format!(
            "material `{}` has no spectral ior; `table spectral` compares a measured spectrum with its RGB reductions (try gold-spectral, copper-spectral, aluminium-spectral)",
            material.name
        ))
    })?;
    if !(step_deg > 0.0 && step_deg <= 90.0) {
        return Err(Error::Unsupported(format!(
            "--step {step_deg}: must be in (0, 90] degrees"
        )));
    }
    let kind = s.fresnel;
    let bad = |e: String| Error::Unsupported(format!("material `{}`: {e}", material.name));
    let forms = RgbReduction::ALL.map(|r| rgb_fresnel(kind, &s.index, r));
    let forms = [
        forms[0].clone().map_err(bad)?,
        forms[1].clone().map_err(bad)?,
    ];
    // n, k on the CIE grid once.
    let nk: Vec<(f64, f64)> = (0..SAMPLES)
        .map(|i| s.index.at(cie::wavelength(i)))
        .collect::<std::result::Result<_, String>>()
        .map_err(bad)?;
    let steps = (90.0 / step_deg).round() as usize;
    Ok((0..=steps)
        .map(|i| {
            let theta_deg = (i as f64 * step_deg).min(90.0);
            let c = theta_deg.to_radians().cos().max(0.0);
            let values: Vec<f64> = nk
                .iter()
                .map(|&(n, k)| match kind {
                    FresnelKind::None => 1.0,
                    FresnelKind::Dielectric => f::dielectric::f(c, n),
                    FresnelKind::Conductor => f::conductor::f(c, n, k),
                    FresnelKind::Schlick => {
                        f::schlick::f(c, ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k))
                    }
                })
                .collect();
            let spectral = cie::to_srgb(&values, Illuminant::D65);
            let rgb = [rgb_f(&forms[0], c), rgb_f(&forms[1], c)];
            let delta_e = rgb.map(|x| cie::delta_e_srgb(x, spectral));
            Row {
                theta_deg,
                spectral,
                rgb,
                delta_e,
            }
        })
        .collect())
}

/// The table as Markdown.
pub fn markdown(material: &Material, rows: &[Row]) -> String {
    let reduction = material
        .spectral
        .as_ref()
        .map_or("", |s| s.reduction.name());
    let mut out = format!(
        "Fresnel reflectance of `{}` (linear sRGB, D65): the spectral value and the RGB reductions (the material's own is {reduction}); Δ = RGB − spectral, ΔE*ab in CIELAB (D65 white).\n\n",
        material.name
    );
    out += "| θ (°) | spectral R | G | B | mitsuba R | G | B | Δ R | Δ G | Δ B | ΔE | filament R | G | B | Δ R | Δ G | Δ B | ΔE |\n";
    out += &format!("|{}\n", "---:|".repeat(18));
    for r in rows {
        let mut line = format!(
            "| {:.0} | {:.4} | {:.4} | {:.4} ",
            r.theta_deg, r.spectral[0], r.spectral[1], r.spectral[2]
        );
        for k in 0..2 {
            let x = r.rgb[k];
            line += &format!(
                "| {:.4} | {:.4} | {:.4} | {:+.4} | {:+.4} | {:+.4} | {:.2} ",
                x[0],
                x[1],
                x[2],
                x[0] - r.spectral[0],
                x[1] - r.spectral[1],
                x[2] - r.spectral[2],
                r.delta_e[k]
            );
        }
        out += &line;
        out += "|\n";
    }
    out
}

/// The plot (SVG, plotters): each channel of the spectral reflectance (solid) and of each
/// RGB reduction (Mitsuba dashed, Filament dotted) against θ, and ΔE*ab on a second panel.
pub fn plot(path: &std::path::Path, material: &Material, rows: &[Row]) -> Result<()> {
    use plotters::prelude::*;
    let err = |e: &dyn std::fmt::Display| Error::Io {
        path: path.to_owned(),
        source: std::io::Error::other(e.to_string()),
    };
    let root = SVGBackend::new(path, (1000, 480)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let (left, right) = root.split_horizontally(600);
    let top = rows
        .iter()
        .flat_map(|r| r.spectral.iter().chain(r.rgb.iter().flatten()))
        .fold(1.0f64, |a, &b| a.max(b))
        * 1.05;
    let mut chart = ChartBuilder::on(&left)
        .caption(
            format!("{}: reflectance (linear sRGB)", material.name),
            ("sans-serif", 18),
        )
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(45)
        .build_cartesian_2d(0.0..90.0, 0.0..top)
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc("θ (degrees)")
        .y_desc("F")
        .draw()
        .map_err(|e| err(&e))?;
    let colours = [
        RGBColor(200, 30, 30),
        RGBColor(30, 150, 30),
        RGBColor(30, 60, 200),
    ];
    let names = [
        "spectral",
        "mitsuba (RGB n, k)",
        "filament (Schlick, D65 F0)",
    ];
    for (v, name) in names.iter().enumerate() {
        for (ch, colour) in colours.iter().enumerate() {
            let pts: Vec<(f64, f64)> = rows
                .iter()
                .map(|r| {
                    (
                        r.theta_deg,
                        if v == 0 {
                            r.spectral[ch]
                        } else {
                            r.rgb[v - 1][ch]
                        },
                    )
                })
                .collect();
            let style = colour.stroke_width(if v == 0 { 3 } else { 1 });
            let series = if v == 2 {
                // Filament's: points, so the three variants stay apart where they overlap.
                chart
                    .draw_series(pts.iter().map(|&p| Circle::new(p, 2, colour.filled())))
                    .map_err(|e| err(&e))?
            } else {
                chart
                    .draw_series(LineSeries::new(pts, style))
                    .map_err(|e| err(&e))?
            };
            if ch == 0 {
                series.label(*name).legend(
                    move |(x, y)| -> DynElement<'static, SVGBackend, (i32, i32)> {
                        if v == 2 {
                            Circle::new((x + 8, y), 3, BLACK.filled()).into_dyn()
                        } else {
                            let width = if v == 0 { 3 } else { 1 };
                            PathElement::new(vec![(x, y), (x + 16, y)], BLACK.stroke_width(width))
                                .into_dyn()
                        }
                    },
                );
            }
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| err(&e))?;
    let de_top = rows.iter().flat_map(|r| r.delta_e).fold(1.0f64, f64::max) * 1.1;
    let mut de = ChartBuilder::on(&right)
        .caption("ΔE*ab from the spectral colour", ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(45)
        .build_cartesian_2d(0.0..90.0, 0.0..de_top)
        .map_err(|e| err(&e))?;
    de.configure_mesh()
        .x_desc("θ (degrees)")
        .y_desc("ΔE*ab")
        .draw()
        .map_err(|e| err(&e))?;
    for (k, colour) in [(0usize, BLACK), (1, RGBColor(150, 150, 150))] {
        de.draw_series(LineSeries::new(
            rows.iter().map(|r| (r.theta_deg, r.delta_e[k])),
            colour.stroke_width(2),
        ))
        .map_err(|e| err(&e))?
        .label(RgbReduction::ALL[k].name())
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2)));
    }
    de.configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))
}
