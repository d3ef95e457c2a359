//! Profiling aid: kernel-only throughput of `vkbrdf bench` scenarios on Vulkan, for kernel
//! variants side by side in one process (interleaved rounds, so the machine's drift hits
//! every variant alike). A variant is a comma-separated list of extra GLSL definitions.
//!
//! Usage: cargo run --release --example kernel_time -- [--tuples N] [--rounds R]
//!            [--variant NAME=VALUE,NAME2 …]… [SCENARIO …]
//! Without --variant, the kernel as shipped. The variant token NO_GROUPING turns off the
//! grouping of mixed-material batches by material (`VulkanOptions::group_by_material`); the
//! tokens NO_FOLD and FOLD keep a single-material batch's material out of the kernel or
//! fold it in whatever the batch's size (`VulkanOptions::fold_material_min_tuples`).
use vkbrdf::backend::Request;
use vkbrdf::bench::scenarios;
use vkbrdf::gpu::{VulkanBackend, VulkanOptions};

fn parse_variant(spec: &str) -> Vec<(String, String)> {
    spec.split(',')
        .filter(|d| !d.is_empty())
        .map(|d| match d.split_once('=') {
            Some((k, v)) => (k.to_string(), v.to_string()),
            None => (d.to_string(), "1".to_string()),
        })
        .collect()
}

fn main() -> vkbrdf::Result<()> {
    let (mut n, mut rounds) = (1usize << 22, 3usize);
    let (mut variants, mut names) = (Vec::new(), Vec::new());
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--tuples" => {
                n = args
                    .next()
                    .and_then(|v| v.parse().ok())
                    .expect("--tuples N")
            }
            "--rounds" => {
                rounds = args
                    .next()
                    .and_then(|v| v.parse().ok())
                    .expect("--rounds R")
            }
            "--variant" => variants.push(args.next().expect("--variant SPEC")),
            _ => names.push(a),
        }
    }
    if variants.is_empty() {
        variants.push(String::new());
    }
    let chosen: Vec<_> = scenarios::all()
        .into_iter()
        .filter(|s| names.is_empty() || names.iter().any(|n| n == s.name))
        .collect();
    let mut gpus = Vec::new();
    for v in &variants {
        // The token NO_GROUPING turns the grouping of mixed batches by material off.
        let defines: Vec<_> = parse_variant(v)
            .into_iter()
            .filter(|(k, _)| !["NO_GROUPING", "NO_FOLD", "FOLD"].contains(&k.as_str()))
            .collect();
        let token = |t: &str| v.split(',').any(|d| d == t);
        let options = VulkanOptions {
            extra_defines: defines,
            group_by_material: !token("NO_GROUPING"),
            fold_material_min_tuples: match (token("NO_FOLD"), token("FOLD")) {
                (true, _) => usize::MAX,
                (false, true) => 0,
                _ => VulkanOptions::default().fold_material_min_tuples,
            },
            ..VulkanOptions::default()
        };
        gpus.push(VulkanBackend::new(None, options)?);
    }
    let mut batches: Vec<_> = chosen.iter().map(|s| scenarios::batch(s, n, 7)).collect();
    if std::env::var("SORT_BY_MATERIAL").is_ok() {
        // Rows grouped by material (a stable counting sort): subgroups see one material.
        for (b, sc) in batches.iter_mut().zip(&chosen) {
            let cols = b.columns();
            let mut rows: Vec<&[f32]> = b.as_slice().chunks(cols).collect();
            rows.sort_by_key(|r| r[9] as usize);
            let data: Vec<f32> = rows.concat();
            let k = sc.materials.len();
            *b = vkbrdf::batch::Batch::new(data, cols, k, std::path::Path::new("sorted"))?;
        }
    }
    if std::env::var("HALF_BELOW").is_ok() {
        // Every other row's V mirrored below the horizon (N = +z): the counts' heavy case.
        for b in &mut batches {
            let cols = b.columns();
            let mut data = b.as_slice().to_vec();
            for row in data.chunks_mut(cols).step_by(2) {
                row[5] = -row[5];
            }
            let k = chosen[0].materials.len().max(64);
            *b = vkbrdf::batch::Batch::new(data, cols, k, std::path::Path::new("half-below"))?;
        }
    }
    let mut best = vec![vec![0.0f64; variants.len()]; chosen.len()];
    for _ in 0..rounds {
        for (i, s) in chosen.iter().enumerate() {
            for (j, gpu) in gpus.iter_mut().enumerate() {
                let t =
                    gpu.kernel_seconds(&batches[i], &s.materials, &Request { terms: false }, 3)?;
                best[i][j] = best[i][j].max(n as f64 / t / 1e6);
            }
        }
    }
    print!("{:28}", "M/s (best of rounds' medians)");
    for v in &variants {
        print!(" {:>18}", if v.is_empty() { "shipped" } else { v });
    }
    println!();
    for (s, row) in chosen.iter().zip(&best) {
        print!("{:28}", s.name);
        for b in row {
            print!(" {b:18.1}");
        }
        println!();
    }
    Ok(())
}
