//! Previews, to look at a material instead of reading numbers: a lit sphere and a polar
//! plot of the lobe in the plane of incidence (like Figure 9.18 of Real-Time Rendering,
//! which the seed lecture cites). Both are evaluated through the backend, drawn by hand
//! into an RGB8 buffer and written as PNG (atomically), with provenance as text chunks.

pub use super::canvas::Canvas;
use super::{needs_tangents, push_row, Runner, TANGENT};
use crate::cancel::Cancel;
use crate::error::{Error, Result};
use crate::material::Material;
use crate::vector::{cross, normalize};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// Default sphere image size (pixels per side).
pub const DEFAULT_SPHERE_SIZE: usize = 256;
/// Default incidence angle of the polar plot, degrees from the normal.
pub const DEFAULT_INCIDENCE_DEG: f64 = 45.0;
/// Direction toward the light of the lit sphere: upper left, in front (view is +z).
pub const SPHERE_LIGHT: [f64; 3] = [-1.0, 1.0, 1.0];
/// Polar plot size, pixels.
pub const POLAR_SIZE: (usize, usize) = (512, 288);
/// Host bytes per sphere pixel: its tuple row (40), pixel record (24), f (12), RGB8 (3).
pub const SPHERE_BYTES_PER_PIXEL: u64 = 96;

/// What `vkbrdf table preview` writes.
#[derive(Debug, Clone)]
pub struct PreviewJob {
    /// The material.
    pub material: Material,
    /// The lit-sphere PNG, when wanted.
    pub sphere: Option<PathBuf>,
    /// The polar-plot PNG, when wanted.
    pub polar: Option<PathBuf>,
    /// Sphere image size, pixels per side.
    pub size: usize,
    /// Polar plot: light angle from the normal, degrees in [0, 90).
    pub incidence_deg: f64,
    /// Sphere exposure before tone mapping.
    pub exposure: f64,
}

impl PreviewJob {
    /// Everything that can be checked before evaluating: an output is asked for, the
    /// angle is legal, the sphere fits in memory, the outputs can be written.
    pub fn check(&self) -> Result<()> {
        if self.sphere.is_none() && self.polar.is_none() {
            return Err(Error::Table(
                "preview: give --sphere PNG, --polar PNG or both".into(),
            ));
        }
        check_incidence(self.incidence_deg)?;
        if !(self.exposure.is_finite() && self.exposure > 0.0) {
            return Err(Error::Table(format!(
                "--exposure {}: give a positive number",
                self.exposure
            )));
        }
        let grid = super::Grid::new(self.size, self.size)?;
        super::check_memory(
            super::table_bytes(grid, SPHERE_BYTES_PER_PIXEL),
            "the sphere preview",
        )?;
        for path in self.sphere.iter().chain(&self.polar) {
            super::check_output(path)?;
        }
        Ok(())
    }
}

/// Draws and writes the previews of `job`, after [`PreviewJob::check`].
pub fn write(runner: &mut Runner, job: &PreviewJob) -> Result<()> {
    job.check()?;
    let backend = runner.backend_name();
    let mut staged = Vec::new();
    if let Some(path) = &job.sphere {
        let canvas = sphere(runner, &job.material, job.size, job.exposure)?;
        let text = provenance(&job.material, "preview-sphere", &backend);
        staged.push(stage_png(path, &canvas, &text, runner.cancel())?);
    }
    if let Some(path) = &job.polar {
        let canvas = polar(runner, &job.material, job.incidence_deg)?;
        let mut text = provenance(&job.material, "preview-polar", &backend);
        text.push(("vkbrdf.incidence", format!("{} degrees", job.incidence_deg)));
        staged.push(stage_png(path, &canvas, &text, runner.cancel())?);
    }
    // Both pictures appear together or not at all.
    crate::atomic::commit(staged)
}

fn check_incidence(deg: f64) -> Result<()> {
    if (0.0..90.0).contains(&deg) {
        Ok(())
    } else {
        Err(Error::Table(format!(
            "--incidence {deg}: give an angle in [0, 90) degrees from the normal"
        )))
    }
}

/// The sRGB transfer function (IEC 61966-2-1) of a linear value in [0, 1], as 8 bits.
pub fn srgb8(t: f64) -> u8 {
    let t = t.clamp(0.0, 1.0);
    let s = if t <= 0.003_130_8 {
        12.92 * t
    } else {
        1.055 * t.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round().clamp(0.0, 255.0) as u8
}

/// Linear scene RGB → display-referred sRGB8: 1.0 is display white, and a pixel whose
/// largest channel exceeds 1 is scaled down as a whole until it is 1, so its hue and
/// saturation are kept (a gold highlight stays gold; clipping each channel, or tone-mapping
/// each channel on its own, turns it toward white and khaki). Non-finite or negative
/// channels count as 0, except +∞, which counts as the brightest.
pub fn display_srgb8(rgb: [f64; 3]) -> [u8; 3] {
    let rgb = rgb.map(|x| if x.is_nan() { 0.0 } else { x.max(0.0) });
    let max = rgb.iter().fold(0.0f64, |m, &x| m.max(x));
    if max.is_infinite() {
        return rgb.map(|x| srgb8(if x.is_infinite() { 1.0 } else { 0.0 }));
    }
    let scale = if max > 1.0 { 1.0 / max } else { 1.0 };
    rgb.map(|x| srgb8(x * scale))
}

/// The lit sphere: orthographic view along −z of a unit sphere, one directional light of
/// irradiance π·`exposure` at normal incidence toward [`SPHERE_LIGHT`]; pixel =
/// f·cos_i·π·exposure, shown by [`display_srgb8`]. At exposure 1 a white Lambertian's
/// peak (where n faces the light) is 1, display white (255), and a brighter highlight keeps
/// its hue.
/// Anisotropic materials use the tangent `ŷ × n` (along the lines of latitude).
pub fn sphere(
    runner: &mut Runner,
    material: &Material,
    size: usize,
    exposure: f64,
) -> Result<Canvas> {
    let bytes = super::table_bytes(super::Grid::new(size, size)?, SPHERE_BYTES_PER_PIXEL);
    super::check_memory(bytes, "the sphere preview")?;
    let materials = std::slice::from_ref(material);
    let light = normalize(SPHERE_LIGHT).expect("constant");
    let mut rows = Vec::new();
    let mut pixels = Vec::new();
    for py in 0..size {
        for px in 0..size {
            let x = 2.0 * super::texel_centre(px, size) - 1.0;
            let y = 1.0 - 2.0 * super::texel_centre(py, size);
            let z2 = 1.0 - x * x - y * y;
            if z2 > 0.0 {
                let n = [x, y, z2.sqrt()];
                let t = needs_tangents(materials).then(|| cross([0.0, 1.0, 0.0], n));
                push_row(&mut rows, light, [0.0, 0.0, 1.0], n, 0, t);
                pixels.push((px, py, n[0] * light[0] + n[1] * light[1] + n[2] * light[2]));
            }
        }
    }
    runner.start("sphere", pixels.len() as u64);
    let out = evaluate_chunked(runner, rows, materials, pixels.len())?;
    runner.finish();
    let mut canvas = Canvas::new(size, size, [24, 24, 24]);
    for (r, &(px, py, cos_i)) in pixels.iter().enumerate() {
        let scale = cos_i.max(0.0) * PI * exposure;
        let c = display_srgb8(std::array::from_fn(|ch| f64::from(out[3 * r + ch]) * scale));
        canvas.put(px as i64, py as i64, c);
    }
    Ok(canvas)
}

/// Evaluates `tuples` rows in chunks of the runner's size; returns f (n × 3).
fn evaluate_chunked(
    runner: &mut Runner,
    rows: Vec<f32>,
    materials: &[Material],
    tuples: usize,
) -> Result<Vec<f32>> {
    if tuples == 0 {
        return Ok(Vec::new());
    }
    let columns = rows.len() / tuples;
    let mut out = Vec::with_capacity(tuples * 3);
    for chunk in rows.chunks(runner.chunk_tuples() * columns) {
        let o = runner.evaluate(chunk.to_vec(), materials, false)?;
        runner.advance((chunk.len() / columns) as u64);
        out.extend_from_slice(&o.brdf);
    }
    Ok(out)
}

/// The polar plot: f(l, v) for `v` swept through the plane of incidence (−90°…90° from the
/// normal, 0.1° apart), with `l` at `incidence_deg` on the left, drawn as a radius scaled
/// so the largest value of the curve reaches the plot's edge. Channels that differ are
/// drawn in red, green and blue, otherwise one white curve; the light direction is solid
/// yellow, the mirror direction dashed yellow, the largest radius a grey semicircle. The
/// title names the material, the quantity and its unit and the light's angle; the
/// baseline is labelled with the view angle (−90°, 0°, 90°), and the edge's value in 1/sr.
pub fn polar(runner: &mut Runner, material: &Material, incidence_deg: f64) -> Result<Canvas> {
    check_incidence(incidence_deg)?;
    let materials = std::slice::from_ref(material);
    let ti = incidence_deg.to_radians();
    let l = [-ti.sin(), 0.0, ti.cos()];
    let t = needs_tangents(materials).then_some(TANGENT);
    let angles: Vec<f64> = (0..=1800)
        .map(|k| (k as f64 / 10.0 - 90.0).to_radians())
        .collect();
    let mut rows = Vec::new();
    for &a in &angles {
        push_row(&mut rows, l, [a.sin(), 0.0, a.cos()], super::NORMAL, 0, t);
    }
    runner.start("polar", angles.len() as u64);
    let f = evaluate_chunked(runner, rows, materials, angles.len())?;
    runner.finish();
    let mut canvas = draw_polar(&angles, &f, ti);
    // HTSG's mirror spike is a delta (FORMULAS.md §8): f is ρ_dd + a/π, and the title says so.
    let title = match material.model {
        crate::material::Model::Htsg(_) => format!(
            "{}: f (1/sr), plane of incidence, light at {incidence_deg}°; spike not drawn",
            material.name
        ),
        _ => format!(
            "{}: f (1/sr) in the plane of incidence, light at {incidence_deg}°",
            material.name
        ),
    };
    label_polar(&mut canvas, &title, &f);
    Ok(canvas)
}

/// The polar plot's title and axis labels.
fn label_polar(canvas: &mut Canvas, title: &str, f: &[f32]) {
    use super::font;
    let (w, h) = (canvas.width as i64, canvas.height as i64);
    let text = [200, 200, 200];
    let max = f.iter().fold(0.0f32, |m, &x| m.max(x));
    font::draw(canvas, 6, 4, title, text);
    font::draw(
        canvas,
        6,
        14,
        &format!("radius = f, edge = {max:.3e} 1/sr; angle = view from the normal"),
        [150, 150, 150],
    );
    let base = h - 16;
    font::draw(canvas, 4, base + 4, "-90°", text);
    font::draw(canvas, w / 2 - 6, base + 4, "0°", text);
    font::draw(
        canvas,
        w - 4 - font::width("90°") as i64,
        base + 4,
        "90°",
        text,
    );
}

/// Draws the polar plot of `f` (n × 3) at `angles` for incidence `ti` (radians).
fn draw_polar(angles: &[f64], f: &[f32], ti: f64) -> Canvas {
    let (w, h) = POLAR_SIZE;
    let mut canvas = Canvas::new(w, h, [16, 16, 16]);
    // Room for two title lines above and the angle labels below.
    let origin = (w as f64 / 2.0, h as f64 - 20.0);
    let radius = (h as f64 - 48.0).min(w as f64 / 2.0 - 10.0);
    let at = |a: f64, r: f64| (origin.0 + r * a.sin(), origin.1 - r * a.cos());
    let max = f.iter().fold(0.0f32, |m, &x| m.max(x));
    canvas.line(
        (10.0, origin.1),
        (w as f64 - 10.0, origin.1),
        [110, 110, 110],
        0,
    );
    for k in 0..180 {
        let (a0, a1) = (
            (k as f64 - 90.0).to_radians(),
            (k as f64 - 89.0).to_radians(),
        );
        canvas.line(at(a0, radius), at(a1, radius), [60, 60, 60], 0);
    }
    canvas.line(origin, at(0.0, radius), [70, 70, 70], 4);
    canvas.line(origin, at(-ti, radius), [230, 200, 40], 0);
    canvas.line(origin, at(ti, radius), [230, 200, 40], 6);
    let grey = f.chunks_exact(3).all(|c| {
        (c[0] - c[1]).abs() <= 1e-6 * c[0].abs() && (c[0] - c[2]).abs() <= 1e-6 * c[0].abs()
    });
    let colours: &[(usize, [u8; 3])] = if grey {
        &[(0, [240, 240, 240])]
    } else {
        &[(0, [240, 70, 70]), (1, [70, 220, 70]), (2, [90, 120, 255])]
    };
    if max > 0.0 {
        for &(ch, colour) in colours {
            let point = |k: usize| at(angles[k], radius * f64::from(f[3 * k + ch] / max));
            for k in 1..angles.len() {
                canvas.line(point(k - 1), point(k), colour, 0);
            }
        }
    }
    canvas
}

/// Writes `canvas` as an 8-bit sRGB PNG with `text` chunks (keyword, value), atomically.
pub fn write_png(path: &Path, canvas: &Canvas, text: &[(&str, String)]) -> Result<()> {
    crate::atomic::commit(vec![stage_png(path, canvas, text, &Cancel::new())?])
}

/// [`write_png`] without making the file visible yet ([`crate::atomic::commit`]).
pub fn stage_png(
    path: &Path,
    canvas: &Canvas,
    text: &[(&str, String)],
    cancel: &Cancel,
) -> Result<crate::atomic::Staged> {
    crate::atomic::stage(path, cancel, |w| {
        let mut enc = png::Encoder::new(w, canvas.width as u32, canvas.height as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        for (k, v) in text {
            enc.add_itxt_chunk((*k).to_string(), v.clone())
                .map_err(std::io::Error::other)?;
        }
        let mut writer = enc.write_header().map_err(std::io::Error::other)?;
        writer
            .write_image_data(&canvas.rgb)
            .map_err(std::io::Error::other)?;
        writer.finish().map_err(std::io::Error::other)
    })
}

/// Provenance text chunks for a preview of `material`.
pub fn provenance(material: &Material, what: &str, backend: &str) -> Vec<(&'static str, String)> {
    let mut text = vec![
        ("vkbrdf.table", what.to_string()),
        ("vkbrdf.material", material.name.clone()),
        (
            "vkbrdf.convention",
            super::convention_name(material).to_string(),
        ),
        ("vkbrdf.backend", backend.to_string()),
        ("vkbrdf.version", super::VERSION.to_string()),
    ];
    if let crate::material::Model::Htsg(_) = material.model {
        text.push((
            "vkbrdf.spike",
            "HTSG (FORMULAS.md §8): f = rho_dd + a/pi; the mirror spike (a delta, weight rho_s) is not drawn".to_string(),
        ));
    }
    text
}
