//! Renders the RGB layer of a `vkbrdf table slice` EXR as a PNG for a person to look at:
//! log10 of f (1/sr) mapped over 4 decades below the maximum, θ_h along x (left = 0),
//! θ_d along y (top = 0), each channel separately.
//! Usage: cargo run --release --example slice_png -- SLICE.exr OUT.png [SCALE]

use exr::prelude::*;

fn main() -> std::result::Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        return Err("usage: slice_png SLICE.exr OUT.png [SCALE]".into());
    }
    let scale: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(4);
    let image = read_first_rgba_layer_from_file(
        &args[1],
        |res, _| {
            (
                res.width(),
                res.height(),
                vec![[0f32; 3]; res.width() * res.height()],
            )
        },
        |(w, _, px), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = [r, g, b]
        },
    )?;
    let (w, h, px) = image.layer_data.channel_data.pixels;
    let max = px.iter().flatten().fold(1e-30f32, |m, &v| m.max(v));
    let (lo, hi) = ((max / 1e4).log10(), max.log10());
    let mut rgb = vec![0u8; w * scale * h * scale * 3];
    for y in 0..h * scale {
        for x in 0..w * scale {
            let p = px[(y / scale) * w + x / scale];
            for c in 0..3 {
                let t = ((p[c].max(1e-30).log10() - lo) / (hi - lo)).clamp(0.0, 1.0);
                rgb[(y * w * scale + x) * 3 + c] = (t * 255.0).round() as u8;
            }
        }
    }
    let file = std::io::BufWriter::new(std::fs::File::create(&args[2])?);
    let mut enc = png::Encoder::new(file, (w * scale) as u32, (h * scale) as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.write_header()?.write_image_data(&rgb)?;
    println!(
        "wrote {} ({}×{}, log10 f in [{lo:.2}, {hi:.2}])",
        args[2],
        w * scale,
        h * scale
    );
    Ok(())
}
