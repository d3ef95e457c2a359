//! The CPU engine on the local-frame form (`Lx Ly Lz Vx Vy Vz`, N = +z, one material),
//! held as rows or as six columns: bit for bit the 10-column rows with N = (0, 0, 1), its
//! refusals, and `vkbrdf eval` streaming it from a file.

mod common;

use common::materials;
use common::mixed::mixed_batch;
use vkbrdf::backend::{Backend, Request};
use vkbrdf::batch::{memory_source, Batch};
use vkbrdf::cpu::CpuEngine;
use vkbrdf::reference::CpuReference;

// ---------------------------------------------------------------------------------------
// The local-frame form: `Lx Ly Lz Vx Vy Vz`, N = +z, one material.

/// 6-column local rows with invalid (zero, NaN, infinite), below-horizon and grazing
/// tuples among ordinary ones.
fn local_rows(n: usize) -> Vec<f32> {
    let (batch, _) = mixed_batch(n);
    let mut rows = Vec::with_capacity(n * 6);
    for i in 0..n {
        let t = batch.tuple(i);
        let mut l = t.l;
        let mut v = t.v;
        match i % 211 {
            5 => l = [0.0; 3],
            17 => v[1] = f32::NAN,
            29 => l[0] = f32::INFINITY,
            41 => l = [1.0, 0.0, 1e-7], // grazing: the lanes hand it to the reference
            53 => v[2] = -1e-9,
            _ => {}
        }
        rows.extend_from_slice(&l);
        rows.extend_from_slice(&v);
    }
    rows
}

/// The same tuples as 10-column rows with N = (0, 0, 1) and material `m`.
fn as_rows(local: &[f32], m: usize, count: usize) -> Batch<'static> {
    let mut rows = Vec::with_capacity(local.len() / 6 * 10);
    for r in local.chunks_exact(6) {
        rows.extend_from_slice(r);
        rows.extend_from_slice(&[0.0, 0.0, 1.0, m as f32]);
    }
    Batch::new(rows, 10, count, &memory_source()).expect("rows")
}

#[test]
fn the_local_form_equals_the_ten_column_rows_bit_for_bit() {
    use vkbrdf::backend::Output;
    use vkbrdf::batch::LocalBatch;
    let (_, mats) = mixed_batch(1);
    // More than one chunk of the engine (16,384 rows) and a tail that is not a whole block.
    let local = local_rows(40_009);
    let request = Request { terms: true };
    for m in 0..mats.len() {
        let rows = as_rows(&local, m, mats.len());
        let rows_lb = LocalBatch::new(local.clone(), m, &mats, &memory_source()).expect("local");
        let columns_lb = rows_lb.to_layout(vkbrdf::batch::LocalLayout::Columns);
        assert_eq!(columns_lb.tuple(40_008), rows_lb.tuple(40_008));
        for (threads, lb) in [
            (1, &rows_lb),
            (3, &rows_lb),
            (1, &columns_lb),
            (3, &columns_lb),
        ] {
            let mut engine = CpuEngine::with_threads(threads);
            let want = engine.evaluate(&rows, &mats, &request).expect("rows");
            // A reused output full of stale values, longer than needed and with terms.
            let mut got = Output {
                brdf: vec![f32::NAN; 200_000],
                terms: Some(vec![7.0; 10]),
                ..Output::default()
            };
            engine
                .evaluate_local_into(lb, &mats, &request, &mut got)
                .expect("local");
            let layout = lb.layout();
            assert_eq!(got, want, "material {m}, {threads} thread(s), {layout:?}");
            assert!(want.counts.invalid > 0 && want.counts.below_horizon > 0);
            assert_eq!(want.counts.first_invalid, Some(5));
        }
    }
    // An engine that reads rows (the default: expanded chunk by chunk) gives its own
    // rows' result too, first invalid row counted from the batch's start.
    let lb = LocalBatch::new(local.clone(), 0, &mats, &memory_source()).expect("local");
    let rows = as_rows(&local, 0, mats.len());
    let mut reference = CpuReference::new();
    let want = reference.evaluate(&rows, &mats, &request).expect("rows");
    let mut got = Output::default();
    reference
        .evaluate_local_into(&lb, &mats, &request, &mut got)
        .expect("local");
    assert_eq!(got, want);
}

#[test]
fn a_local_batch_refuses_a_bad_material_or_shape() {
    use vkbrdf::batch::LocalBatch;
    let (_, mats) = mixed_batch(1);
    let e = LocalBatch::new(vec![0.0; 12], 4, &mats, &memory_source()).unwrap_err();
    assert!(
        e.to_string().contains("material 4 is not an index in 0..4"),
        "{e}"
    );
    let e = LocalBatch::new(vec![0.0; 13], 0, &mats, &memory_source()).unwrap_err();
    assert!(
        e.to_string()
            .contains("13 values do not make whole rows of 6"),
        "{e}"
    );
    let e = LocalBatch::with_layout(
        vec![0.0; 13],
        vkbrdf::batch::LocalLayout::Columns,
        0,
        &mats,
        &memory_source(),
    )
    .unwrap_err();
    assert!(
        e.to_string()
            .contains("13 values do not make six columns of equal length"),
        "{e}"
    );
    let aniso = materials(
        "[[material]]\nname = \"brushed\"\nmodel = \"cook-torrance\"\ndistribution = \"ggx\"\n\
         geometry = \"smith\"\nfresnel = \"none\"\nroughness = [0.1, 0.4]\n",
    );
    let e = LocalBatch::new(vec![0.0; 12], 0, &aniso, &memory_source()).unwrap_err();
    assert!(e.to_string().contains("`brushed`) is anisotropic"), "{e}");
}

/// The mixed materials as a TOML file, and 6- and 10-column (material `m`) `.npy` files of
/// the same tuples.
fn local_files(dir: &std::path::Path, n: usize, m: usize) -> [std::path::PathBuf; 3] {
    let toml = dir.join("m.toml");
    std::fs::write(
        &toml,
        "[[material]]\nname = \"ggx\"\nmodel = \"cook-torrance\"\ndistribution = \"ggx\"\n\
         geometry = \"smith-correlated\"\nfresnel = \"conductor\"\nior = [0.2, 0.9, 1.1]\n\
         extinction = [3.9, 2.4, 2.2]\nroughness = 0.3\n\
         [[material]]\nname = \"matte\"\nmodel = \"lambert\"\ndiffuse = [0.5, 0.4, 0.3]\n\
         [[material]]\nname = \"brushed\"\nmodel = \"cook-torrance\"\ndistribution = \"ggx\"\n\
         geometry = \"smith\"\nfresnel = \"none\"\nroughness = [0.1, 0.4]\n",
    )
    .unwrap();
    let local = local_rows(n);
    let six = dir.join("local.npy");
    vkbrdf::batch::write_npy_f32(&six, &local, 6).unwrap();
    let ten = dir.join("rows.npy");
    let rows = as_rows(&local, m, 3);
    vkbrdf::batch::write_npy_f32(&ten, rows.as_slice(), 10).unwrap();
    [toml, six, ten]
}

#[test]
fn eval_streams_the_local_form_with_the_rows_results() {
    let dir = tempfile::tempdir().unwrap();
    let [toml, six, ten] = local_files(dir.path(), 30_011, 0);
    for backend in ["cpu", "reference"] {
        let outs: Vec<(Vec<f32>, Vec<f32>)> = [(&six, Some("ggx")), (&ten, None)]
            .iter()
            .enumerate()
            .map(|(k, (input, material))| {
                let o = dir.path().join(format!("b{k}-{backend}.npy"));
                let t = dir.path().join(format!("t{k}-{backend}.npy"));
                let mut extra = vec![
                    "-o",
                    common::path(&o),
                    "--terms",
                    common::path(&t),
                    "--backend",
                    backend,
                    // Several chunks: the stream reuses its output buffers.
                    "--max-memory",
                    "1MiB",
                ];
                if let Some(m) = material {
                    extra.extend_from_slice(&["--material", m]);
                }
                let r = common::eval(&toml, input, &extra);
                assert!(r.status.success(), "{backend}: {}", common::stderr(&r));
                (
                    vkbrdf::batch::read_npy_f32(&o).unwrap().0,
                    vkbrdf::batch::read_npy_f32(&t).unwrap().0,
                )
            })
            .collect();
        assert_eq!(outs[0].0.len(), 30_011 * 3);
        assert!(
            outs[0] == outs[1],
            "{backend}: the local form's results differ"
        );
    }
    // By index too, and the only material of a one-material file needs no --material.
    let o = dir.path().join("by-index.npy");
    let r = common::eval(&toml, &six, &["-o", common::path(&o), "--material", "0"]);
    assert!(r.status.success(), "{}", common::stderr(&r));
    let one = dir.path().join("one.toml");
    let text = std::fs::read_to_string(&toml).unwrap();
    std::fs::write(
        &one,
        &text[..text.find("[[material]]\nname = \"matte\"").unwrap()],
    )
    .unwrap();
    let o2 = dir.path().join("single.npy");
    let r = common::eval(&one, &six, &["-o", common::path(&o2), "--backend", "cpu"]);
    assert!(r.status.success(), "{}", common::stderr(&r));
    assert_eq!(
        vkbrdf::batch::read_npy_f32(&o2).unwrap().0,
        vkbrdf::batch::read_npy_f32(&o).unwrap().0
    );
}

#[test]
fn eval_refuses_a_local_batch_without_a_usable_material() {
    let dir = tempfile::tempdir().unwrap();
    let [toml, six, ten] = local_files(dir.path(), 100, 0);
    let o = dir.path().join("o.npy");
    let seven = dir.path().join("seven.npy");
    vkbrdf::batch::write_npy_f32(&seven, &[0.5; 14], 7).unwrap();
    let cases: [(&std::path::Path, Option<&str>, &str); 6] = [
        (
            &six,
            None,
            "choose one with --material NAME|INDEX (0 `ggx`, 1 `matte`, 2 `brushed`)",
        ),
        (
            &six,
            Some("gold"),
            "--material \"gold\" is neither a material's name nor an index in 0..3",
        ),
        (
            &six,
            Some("3"),
            "is neither a material's name nor an index in 0..3",
        ),
        (
            &six,
            Some("brushed"),
            "is anisotropic (roughness [mx, my]) and needs a tangent",
        ),
        (
            &ten,
            Some("ggx"),
            "applies only to a 6-column local-frame batch",
        ),
        (
            &seven,
            None,
            "or 6 (Lx Ly Lz Vx Vy Vz in the local frame, N = +z, one material), found 7",
        ),
    ];
    for (input, material, want) in cases {
        let mut extra = vec!["-o", common::path(&o), "--backend", "cpu"];
        if let Some(m) = material {
            extra.extend_from_slice(&["--material", m]);
        }
        let r = common::eval(&toml, input, &extra);
        assert_eq!(
            r.status.code(),
            Some(2),
            "{input:?} {material:?}: {}",
            common::stderr(&r)
        );
        assert!(common::stderr(&r).contains(want), "{}", common::stderr(&r));
        assert!(!o.exists(), "nothing is written");
    }
}
