//! SVG plots of a benchmark run (plotters): throughput against batch size, run time against
//! error (the Pareto chart), and specialised against all-features kernels.

use super::ResultRow;
use crate::error::{Error, Result};
use plotters::prelude::*;
use std::collections::BTreeMap;
use std::path::Path;

const COLORS: [RGBColor; 8] = [
    BLUE,
    RED,
    GREEN,
    MAGENTA,
    CYAN,
    BLACK,
    RGBColor(255, 140, 0),
    RGBColor(128, 0, 128),
];

fn plot_err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Io {
        path: path.to_owned(),
        source: std::io::Error::other(e.to_string()),
    }
}

/// Log-log lines of evals/s against tuples, one per (backend, scenario, mode, precision).
pub fn throughput(path: &Path, rows: &[ResultRow]) -> Result<()> {
    let mut series: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
    for r in rows {
        series
            .entry(format!(
                "{} {} {} {}",
                r.backend, r.scenario, r.mode, r.precision
            ))
            .or_default()
            .push((r.tuples as f64, r.evals_per_s));
    }
    series.retain(|_, pts| pts.len() > 1);
    let (xmin, xmax, ymin, ymax) = bounds(series.values().flatten().copied());
    let root = SVGBackend::new(path, (1100, 700)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption("Throughput against batch size", ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d((xmin..xmax).log_scale(), (ymin..ymax).log_scale())
        .map_err(|e| plot_err(path, e))?;
    chart
        .configure_mesh()
        .x_desc("tuples per call")
        .y_desc("evaluations / s")
        .draw()
        .map_err(|e| plot_err(path, e))?;
    for (i, (name, mut pts)) in series.into_iter().enumerate() {
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let c = COLORS[i % COLORS.len()];
        chart
            .draw_series(LineSeries::new(pts, c.stroke_width(2)))
            .map_err(|e| plot_err(path, e))?
            .label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))
}

/// Scatter of seconds per million tuples against max relative error, one point per
/// (backend, precision, scenario) at the largest batch: the run-time/error trade-off.
pub fn pareto(path: &Path, rows: &[ResultRow]) -> Result<()> {
    let pts: Vec<(String, f64, f64)> = rows
        .iter()
        .map(|r| {
            (
                format!("{} {} {} {}", r.backend, r.precision, r.scenario, r.mode),
                r.max_rel_err.max(1e-9),
                1e6 / r.evals_per_s,
            )
        })
        .collect();
    let (xmin, xmax, ymin, ymax) = bounds(pts.iter().map(|p| (p.1, p.2)));
    let root = SVGBackend::new(path, (1100, 700)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption("Run time against error (largest batch)", ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d((xmin..xmax).log_scale(), (ymin..ymax).log_scale())
        .map_err(|e| plot_err(path, e))?;
    chart
        .configure_mesh()
        .x_desc("max relative error vs f64 reference")
        .y_desc("seconds per million tuples")
        .draw()
        .map_err(|e| plot_err(path, e))?;
    for (i, (name, x, y)) in pts.into_iter().enumerate() {
        let c = COLORS[i % COLORS.len()];
        chart
            .draw_series(std::iter::once(Circle::new((x, y), 5, c.filled())))
            .map_err(|e| plot_err(path, e))?
            .label(name)
            .legend(move |(x, y)| Circle::new((x + 8, y), 4, c.filled()));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))
}

fn bounds(pts: impl Iterator<Item = (f64, f64)> + Clone) -> (f64, f64, f64, f64) {
    let fold = |f: fn(f64, f64) -> f64, init: f64, sel: fn(&(f64, f64)) -> f64| {
        pts.clone().map(|p| sel(&p)).fold(init, f)
    };
    let (xmin, xmax) = (
        fold(f64::min, f64::INFINITY, |p| p.0),
        fold(f64::max, 0.0, |p| p.0),
    );
    let (ymin, ymax) = (
        fold(f64::min, f64::INFINITY, |p| p.1),
        fold(f64::max, 0.0, |p| p.1),
    );
    if !xmin.is_finite() {
        return (1.0, 10.0, 1.0, 10.0);
    }
    (xmin / 2.0, xmax * 2.0, ymin / 2.0, ymax * 2.0)
}

/// Specialised against all-features kernels: evals/s per scenario, two series.
pub fn specialisation(path: &Path, rows: &[ResultRow]) -> Result<()> {
    let scen: Vec<String> = {
        let mut s: Vec<String> = rows.iter().map(|r| r.scenario.clone()).collect();
        s.dedup();
        s
    };
    let ymax = rows.iter().map(|r| r.evals_per_s).fold(0.0, f64::max) * 1.2;
    let root = SVGBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption("Specialised vs all-features kernel", ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(-0.5f64..(scen.len() as f64 - 0.5), 0f64..ymax.max(1.0))
        .map_err(|e| plot_err(path, e))?;
    chart
        .configure_mesh()
        .x_labels(scen.len().max(1))
        .x_label_formatter(&|x| scen.get(x.round() as usize).cloned().unwrap_or_default())
        .y_desc("evaluations / s")
        .draw()
        .map_err(|e| plot_err(path, e))?;
    for (k, (variant, c)) in [("specialised", BLUE), ("all-features", RED)]
        .into_iter()
        .enumerate()
    {
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.precision == variant)
            .filter_map(|r| {
                scen.iter()
                    .position(|s| *s == r.scenario)
                    .map(|i| (i as f64, r.evals_per_s))
            })
            .collect();
        let off = if k == 0 { -0.15 } else { 0.15 };
        chart
            .draw_series(pts.iter().map(|&(x, y)| {
                Rectangle::new([(x + off - 0.12, 0.0), (x + off + 0.12, y)], c.filled())
            }))
            .map_err(|e| plot_err(path, e))?
            .label(variant)
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], c.filled()));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))
}
