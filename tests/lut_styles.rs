//! DFG tables in the engines' conventions (`vkbrdf table dfg --lut-style ue4|filament`,
//! `--roughness-axis`, `--sampling`): held to the engines' own generators, re-implemented
//! in NumPy (tests/lut_reference.py), within 1e-3 per texel on every backend; the axes put
//! the texels where they say; the engines' estimator and the project's converge to the same
//! integral.

mod common;

use exr::prelude::FlatSamples;
use std::path::Path;
use std::process::Command;
use vkbrdf::backend::Backend;
use vkbrdf::material::Geometry;
use vkbrdf::table::albedo::{Lobe, Microfacet, Sampler};
use vkbrdf::table::dfg::{self, Axes, DfgJob, LutStyle, RoughnessAxis, Sampling};
use vkbrdf::table::{Grid, Runner};

/// The agreement the issue asks of a style against its engine's generator.
const TEXEL_TOLERANCE: f64 = 1e-3;

/// `(channel name, values)` of the one layer of an EXR, channels in file order (R, G).
fn read_channels(path: &Path) -> Vec<(String, Vec<f64>)> {
    let image = exr::prelude::read_all_flat_layers_from_file(path).unwrap();
    let layer = image.layer_data.into_iter().next().unwrap();
    layer
        .channel_data
        .list
        .into_iter()
        .map(|c| {
            let values = match c.sample_data {
                FlatSamples::F32(v) => v.into_iter().map(f64::from).collect(),
                FlatSamples::F16(v) => v.into_iter().map(|x| f64::from(x.to_f32())).collect(),
                FlatSamples::U32(v) => v.into_iter().map(f64::from).collect(),
            };
            (c.name.to_string(), values)
        })
        .collect()
}

/// The job `--lut-style style` makes (as src/cli/table.rs builds it).
fn style_job(style: LutStyle, grid: Grid, samples: u32, output: &Path) -> DfgJob {
    DfgJob {
        spec: Microfacet {
            lobe: Lobe::Ggx,
            geometry: style.geometry(),
        },
        grid,
        samples,
        axes: style.axes(),
        layout: style.layout(),
        sampler: Sampler::Engine,
        style: Some(style),
        half: false,
        output: output.to_path_buf(),
    }
}

/// The Python that runs tests/lut_reference.py: `VKBRDF_PYTHON` (CI points it at its
/// venv, which has NumPy), else `python3`.
fn python() -> String {
    std::env::var("VKBRDF_PYTHON").unwrap_or_else(|_| "python3".into())
}

/// Whether that Python with NumPy runs here.
fn numpy() -> bool {
    Command::new(python())
        .args(["-c", "import numpy"])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// The engine generator's table (tests/lut_reference.py): `H·W` texels of `[R, G]`.
fn reference_table(style: LutStyle, grid: Grid, samples: u32, dir: &Path) -> Vec<[f64; 2]> {
    let out = dir.join(format!("{}.f64", style.name()));
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/lut_reference.py");
    let status = Command::new(python())
        .arg(&script)
        .args([
            style.name(),
            &grid.width.to_string(),
            &grid.height.to_string(),
            &samples.to_string(),
        ])
        .arg(&out)
        .status()
        .unwrap();
    assert!(status.success(), "lut_reference.py failed: {status}");
    let bytes = std::fs::read(&out).unwrap();
    assert_eq!(bytes.len(), grid.texels() * 16);
    bytes
        .chunks_exact(16)
        .map(|c| {
            let f = |b: &[u8]| f64::from_le_bytes(b.try_into().unwrap());
            [f(&c[..8]), f(&c[8..])]
        })
        .collect()
}

/// Writes the style's table on `backend` and returns the largest texel difference from the
/// engine's generator, asserting it is within [`TEXEL_TOLERANCE`].
fn compare(backend: &mut dyn Backend, style: LutStyle, grid: Grid, samples: u32) -> f64 {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("dfg.exr");
    let job = style_job(style, grid, samples, &path);
    dfg::write(&mut Runner::new(backend), &job).unwrap();
    let channels = read_channels(&path);
    // The exr crate lists channels alphabetically: G, R.
    let by_name = |n: &str| &channels.iter().find(|c| c.0 == n).unwrap().1;
    let (r, g) = (by_name("R"), by_name("G"));
    let want = reference_table(style, grid, samples, dir.path());
    let mut worst = (0.0f64, 0usize, 0usize);
    for (t, w) in want.iter().enumerate() {
        for (k, got) in [r[t], g[t]].into_iter().enumerate() {
            let err = (got - w[k]).abs();
            if err > worst.0 {
                worst = (err, t, k);
            }
        }
    }
    let (err, t, k) = worst;
    assert!(
        err <= TEXEL_TOLERANCE,
        "--lut-style {} on {}: texel (column {}, row {}) channel {} is {} against the engine's {} \
         (|diff| {err:.2e} > {TEXEL_TOLERANCE})",
        style.name(),
        backend.name(),
        t % grid.width,
        t / grid.width,
        ["R", "G"][k],
        [r[t], g[t]][k],
        want[t][k]
    );
    err
}

#[test]
fn lut_styles_match_the_engines_generators() {
    if !numpy() {
        // CI sets VKBRDF_PYTHON to its venv: there the comparison must run, never skip.
        assert!(
            std::env::var_os("VKBRDF_PYTHON").is_none(),
            "VKBRDF_PYTHON={} cannot import numpy",
            python()
        );
        eprintln!(
            "!!! SKIPPING: python3 with NumPy is not installed (apt-get install python3-numpy, or set VKBRDF_PYTHON)"
        );
        return;
    }
    for mut backend in common::backends() {
        let b = backend.as_mut();
        // UE4 names no size: 32x16 keeps the test quick; Filament's own 128x128 on the
        // reference (the judge), a quarter of it on the other backends.
        let ue4 = compare(b, LutStyle::Ue4, Grid::new(32, 16).unwrap(), 1024);
        let side = if b.name().contains("reference") {
            128
        } else {
            64
        };
        let filament = compare(b, LutStyle::Filament, Grid::new(side, side).unwrap(), 1024);
        eprintln!(
            "{}: largest |texel - engine generator|: ue4 {ue4:.2e}, filament {filament:.2e}",
            b.name()
        );
    }
}

#[test]
fn roughness_axis_and_sampling_place_the_texels() {
    let grid = Grid::new(5, 3).unwrap();
    let perceptual = Axes {
        roughness: RoughnessAxis::Perceptual,
        sampling: Sampling::Centres,
    };
    let p = perceptual.points(grid);
    // Row 1 of 3 at its centre: r = 0.5, α = 0.25; column 4 of 5: μ = 0.9.
    assert_eq!(p[5 + 4], (0.9, 0.25));
    let ends = Axes {
        roughness: RoughnessAxis::Alpha,
        sampling: Sampling::Endpoints,
    };
    let e = ends.points(grid);
    assert_eq!(e[5 + 4], (1.0, 0.5));
    assert_eq!(e[2 * 5 + 2], (0.5, 1.0));
    // The zero ends hold the limits, evaluated at the floor.
    assert_eq!(e[0], (dfg::ENDPOINT_FLOOR, dfg::ENDPOINT_FLOOR));
    // Filament's rows: row 0 clamped to r = 1, row j at (H - j + 0.5)/H.
    let f = LutStyle::Filament.axes().points(grid);
    assert_eq!(f[0].1, 1.0);
    assert!((f[5].1 - (2.5f64 / 3.0).powi(2)).abs() < 1e-15);
    assert!((f[10].1 - (1.5f64 / 3.0).powi(2)).abs() < 1e-15);
    // Endpoints need two texels a side.
    assert!(ends.check(Grid::new(1, 4).unwrap()).is_err());
}

/// The engines' estimator (D cos_h, 1024 points by default) and the project's (visible
/// normals) estimate the same integral: with 2^20 points for the engines' (it converges
/// slowly at grazing view: 5e-4 off at μ = α = 1/16 with 2^16) and the default 2^16 for the
/// project's they agree to 1e-4 on the UE4 axes and geometry, so a style's differences from
/// a converged table are the engines' sampling noise, not a different integrand.
#[test]
fn engine_estimator_converges_to_the_projects() {
    let mut backend = vkbrdf::reference::CpuReference::new();
    let mut runner = Runner::new(&mut backend);
    let spec = Microfacet {
        lobe: Lobe::Ggx,
        geometry: Geometry::SchlickSmith,
    };
    let points = LutStyle::Ue4.axes().points(Grid::new(4, 3).unwrap());
    let engine =
        dfg::split_sum_with(&mut runner, &spec, Sampler::Engine, &points, 1 << 20).unwrap();
    let visible =
        dfg::split_sum_with(&mut runner, &spec, Sampler::Visible, &points, 1 << 16).unwrap();
    for ((e, v), (mu, alpha)) in engine.iter().zip(&visible).zip(&points) {
        for k in 0..2 {
            assert!(
                (e[k] - v[k]).abs() < 1e-4,
                "mu={mu} alpha={alpha}: engine {e:?} vs visible {v:?}"
            );
        }
    }
}

fn vkbrdf_cmd() -> Command {
    Command::new(env!("CARGO_BIN_EXE_vkbrdf"))
}

#[test]
fn lut_style_conflicts_and_bad_grids_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("dfg.exr");
    let run = |args: &[&str]| {
        let o = vkbrdf_cmd()
            .args(["table", "dfg", "--backend", "reference", "--output"])
            .arg(&out)
            .args(args)
            .output()
            .unwrap();
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stderr).to_string(),
        )
    };
    let (code, err) = run(&["--lut-style", "ue4", "--geometry", "smith"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--geometry"), "{err}");
    let (code, err) = run(&["--lut-style", "unreal"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("ue4") && err.contains("filament"), "{err}");
    let (code, err) = run(&["--sampling", "endpoints", "--size", "1x8"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("at least 2 texels"), "{err}");
    let (code, err) = run(&["--roughness-axis", "r"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("perceptual"), "{err}");
    assert!(!out.exists());
}

#[test]
fn lut_style_writes_its_choices_into_the_provenance() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("f.exr");
    let o = vkbrdf_cmd()
        .args([
            "table",
            "dfg",
            "--backend",
            "reference",
            "--lut-style",
            "filament",
            "--size",
            "4x4",
            "--samples",
            "64",
            "--output",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let image = exr::prelude::read_all_flat_layers_from_file(&out).unwrap();
    let attrs = format!("{:?}", image.layer_data[0].attributes.other);
    assert!(attrs.contains("--lut-style filament"), "{attrs}");
    assert!(attrs.contains("mix(R, G, F0)"), "{attrs}");
    assert!(attrs.contains("smith-correlated"), "{attrs}");
    assert!(
        attrs.contains("64 per texel: the engines' estimator"),
        "{attrs}"
    );
}

/// An endpoint table holds the limits at its zero ends, not the 0 that f is at μ = 0: the
/// μ = 0 column is positive, and the mirror corner (μ = 1, α → 0) reflects everything
/// (A + B = 1, B = 0 at normal view).
#[test]
fn endpoint_tables_hold_the_limits_at_zero() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("e.exr");
    let grid = Grid::new(5, 4).unwrap();
    let job = DfgJob {
        spec: Microfacet {
            lobe: Lobe::Ggx,
            geometry: Geometry::SchlickSmith,
        },
        grid,
        samples: 1 << 14,
        axes: Axes {
            roughness: RoughnessAxis::Perceptual,
            sampling: Sampling::Endpoints,
        },
        layout: dfg::Layout::ScaleBias,
        sampler: Sampler::Visible,
        style: None,
        half: false,
        output: path.clone(),
    };
    let mut backend = vkbrdf::reference::CpuReference::new();
    dfg::write(&mut Runner::new(&mut backend), &job).unwrap();
    let channels = read_channels(&path);
    let by_name = |n: &str| &channels.iter().find(|c| c.0 == n).unwrap().1;
    let (a, b) = (by_name("R"), by_name("G"));
    for j in 0..grid.height {
        let t = j * grid.width;
        assert!(
            a[t] + b[t] > 0.01,
            "row {j}: mu = 0 column is {} + {}",
            a[t],
            b[t]
        );
    }
    let corner = grid.width - 1; // row 0 (r = 0), column W-1 (μ = 1)
    assert!(
        (a[corner] + b[corner] - 1.0).abs() < 1e-3,
        "{}",
        a[corner] + b[corner]
    );
    assert!(b[corner] < 1e-6, "{}", b[corner]);
}
