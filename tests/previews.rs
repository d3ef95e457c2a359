//! Pictures read without a caption: the lit sphere in display-referred sRGB (a white
//! Lambertian's peak is display white, a metal keeps its colour), the half/difference slice
//! as a PNG straight from `vkbrdf table slice --png`, and the polar plot's title and labels.

mod common;

use std::collections::HashMap;
use std::path::Path;
use vkbrdf::backend::Backend;
use vkbrdf::material::{parse_materials, presets};
use vkbrdf::table::{preview, Runner};

fn read_png(path: &Path) -> (u32, u32, Vec<u8>, HashMap<String, String>) {
    let decoder = png::Decoder::new(std::fs::File::open(path).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let text = reader
        .info()
        .utf8_text
        .iter()
        .map(|t| (t.keyword.clone(), t.get_text().unwrap()))
        .collect();
    (info.width, info.height, buf, text)
}

/// The sRGB encoding of a linear value, written out here (IEC 61966-2-1), not the library's.
fn srgb(x: f64) -> f64 {
    255.0
        * if x <= 0.0031308 {
            12.92 * x
        } else {
            1.055 * x.powf(1.0 / 2.4) - 0.055
        }
}

fn white_lambert() -> vkbrdf::material::Material {
    parse_materials(
        "[[material]]\nname = \"white\"\nmodel = \"lambert\"\ndiffuse = [1, 1, 1]\n",
        "test",
    )
    .unwrap()
    .remove(0)
}

fn sphere_pixels(backend: &mut dyn Backend, name: &str, size: usize) -> Vec<[u8; 3]> {
    let material = if name == "white" {
        white_lambert()
    } else {
        presets::preset(name).unwrap().unwrap()
    };
    let canvas = preview::sphere(&mut Runner::new(backend), &material, size, 1.0).unwrap();
    canvas.rgb.chunks(3).map(|c| [c[0], c[1], c[2]]).collect()
}

#[test]
fn white_lambert_peak_is_display_white() {
    for mut backend in common::backends() {
        let size = 256;
        let px = sphere_pixels(backend.as_mut(), "white", size);
        let peak = px.iter().map(|p| p[0]).max().unwrap();
        assert!(
            (254..=255).contains(&peak),
            "{}: white Lambert peak {peak}, want 255 ± 1",
            backend.name()
        );
        assert!(px.iter().all(|p| p[0] == p[1] && p[1] == p[2]), "grey");
        // The centre (n ≈ +z) sees cos_i = n·l = 1/√3: linear 0.577, not clipped.
        let centre = px[size / 2 * size + size / 2][0] as f64;
        let want = srgb(1.0 / 3f64.sqrt());
        assert!(
            (centre - want).abs() <= 2.0,
            "centre {centre}, want {want:.1}"
        );
    }
}

#[test]
fn gold_keeps_its_hue() {
    for mut backend in common::backends() {
        let px = sphere_pixels(backend.as_mut(), "gold", 256);
        // The highlight: the brightest pixel is scaled as a whole, not clipped per channel.
        let hi = px
            .iter()
            .max_by_key(|p| p[0] as u32 + p[1] as u32 + p[2] as u32)
            .unwrap();
        let (r, g, b) = (hi[0] as f64, hi[1] as f64, hi[2] as f64);
        // Gold's F0 is about (1.00, 0.77, 0.34) linear (Johnson & Christy), sRGB
        // (255, 227, 157): G/R ≈ 0.89, B/R ≈ 0.62. Per-channel tone mapping makes the
        // highlight near white (B/R > 0.8).
        assert!(r > g && g > b, "{}: highlight {hi:?}", backend.name());
        assert!(r >= 250.0, "highlight {hi:?}");
        assert!((0.8..=0.95).contains(&(g / r)), "G/R of {hi:?}");
        assert!((0.5..=0.72).contains(&(b / r)), "B/R of {hi:?}");
        // Every lit pixel is gold: R > G > B.
        for p in px.iter().filter(|p| p[0] >= 40 && *p != &[24, 24, 24]) {
            assert!(p[0] > p[1] && p[1] > p[2], "pixel {p:?} is not gold");
        }
    }
}

#[test]
fn display_srgb_scales_bright_pixels_as_a_whole() {
    assert_eq!(preview::display_srgb8([1.0, 1.0, 1.0]), [255, 255, 255]);
    assert_eq!(
        preview::display_srgb8([4.0, 2.0, 1.0]),
        preview::display_srgb8([1.0, 0.5, 0.25])
    );
    assert_eq!(preview::display_srgb8([f64::NAN, -1.0, 0.0]), [0, 0, 0]);
    let [r, g, b] = preview::display_srgb8([0.5, 0.2, 0.05]);
    for (got, x) in [(r, 0.5), (g, 0.2), (b, 0.05)] {
        assert!(
            (got as f64 - srgb(x)).abs() <= 0.5 + 1e-9,
            "{got} vs {}",
            srgb(x)
        );
    }
}

#[test]
fn polar_plot_has_a_title_naming_the_material_and_units() {
    let mut backend = vkbrdf::reference::CpuReference::new();
    let mut runner = Runner::new(&mut backend);
    let gold = presets::preset("gold").unwrap().unwrap();
    let copper = presets::preset("copper").unwrap().unwrap();
    let a = preview::polar(&mut runner, &gold, 45.0).unwrap();
    let b = preview::polar(&mut runner, &copper, 45.0).unwrap();
    let band = |c: &preview::Canvas, y0: usize, y1: usize| -> Vec<u8> {
        c.rgb[3 * y0 * c.width..3 * y1 * c.width].to_vec()
    };
    // Title text in the top rows, in its colour.
    let title = band(&a, 0, 12);
    let lit = title.chunks(3).filter(|p| p == &[200, 200, 200]).count();
    assert!(lit > 300, "title pixels {lit}");
    // The title names the material: gold's and copper's differ.
    assert_ne!(band(&a, 0, 12), band(&b, 0, 12));
    // The glyphs of "GOLD:" begin the title.
    let mut probe = preview::Canvas::new(a.width, 12, [16, 16, 16]);
    vkbrdf::table::font::draw(&mut probe, 6, 4, "GOLD:", [200, 200, 200]);
    let w = vkbrdf::table::font::width("GOLD:") + 6;
    for y in 0..12 {
        let row = |c: &preview::Canvas| c.rgb[3 * y * c.width..3 * (y * c.width + w)].to_vec();
        assert_eq!(row(&a), row(&probe), "title row {y}");
    }
    // Angle labels under the baseline.
    let labels = band(&a, a.height - 14, a.height);
    assert!(labels.chunks(3).filter(|p| p == &[200, 200, 200]).count() > 40);
}

#[test]
fn table_slice_writes_a_png() {
    let dir = tempfile::tempdir().unwrap();
    let m = dir.path().join("m.toml");
    std::fs::write(
        &m,
        "[[material]]\nname = \"white\"\nmodel = \"lambert\"\ndiffuse = [1, 1, 1]\n",
    )
    .unwrap();
    let (exr, png) = (dir.path().join("s.exr"), dir.path().join("s.png"));
    let o = common::vkbrdf(&[
        "table",
        "slice",
        "--backend",
        "reference",
        "-m",
        m.to_str().unwrap(),
        "--material",
        "white",
        "--size",
        "30x20",
        "-o",
        exr.to_str().unwrap(),
        "--png",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let (w, h, rgb, text) = read_png(&png);
    assert_eq!((w, h), (30, 20));
    // A white Lambertian: π·f = 1 everywhere above the horizon, display white.
    let white = rgb.chunks(3).filter(|p| p == &[255, 255, 255]).count();
    assert!(white > 500, "{white} white pixels of 600");
    assert_eq!(text["vkbrdf.material"], "white");
    assert!(text["vkbrdf.parameterisation"].contains("1/sr"));
    assert!(exr.exists());
    // Gold: its colour, R > G > B, on the lit texels.
    let (gexr, gpng) = (dir.path().join("g.exr"), dir.path().join("g.png"));
    let o = common::vkbrdf(&[
        "table",
        "slice",
        "--backend",
        "reference",
        "--material",
        "gold",
        "-o",
        gexr.to_str().unwrap(),
        "--png",
        gpng.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let (_, _, rgb, _) = read_png(&gpng);
    let lit: Vec<&[u8]> = rgb.chunks(3).filter(|p| p[0] >= 40).collect();
    assert!(lit.len() > 100);
    assert!(lit.iter().all(|p| p[0] > p[1] && p[1] > p[2]), "gold slice");
    // A --png that cannot be written fails before any work, leaving no EXR.
    let bad = dir.path().join("missing/dir/x.png");
    let e2 = dir.path().join("e2.exr");
    let o = common::vkbrdf(&[
        "table",
        "slice",
        "--backend",
        "reference",
        "--material",
        "gold",
        "-o",
        e2.to_str().unwrap(),
        "--png",
        bad.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", common::stderr(&o));
    assert!(!e2.exists());
}
