//! A batch given as columns (`vkbrdf::batch::columns::ColumnBatch`, the Python package's
//! broadcast form) gives the results, counts and first invalid row of the same rows given
//! as one array, bit for bit: on the CPU engine, which reads the columns in place, on each
//! instruction set this machine has; on the reference, which reads its tuples from the
//! columns; on Vulkan, which gathers each chunk while the device works on the ones before
//! it (one chunk, and several under a small memory limit); and through the trait's default
//! (rows gathered a part at a time), for an engine that reads rows only.

mod common;

use std::path::Path;
use vkbrdf::backend::{Backend, Output, Request};
use vkbrdf::batch::columns::ColumnBatch;
use vkbrdf::batch::Batch;
use vkbrdf::cpu::{CpuEngine, Isa};
use vkbrdf::material::{parse_materials, Material};
use vkbrdf::reference::CpuReference;

/// The columns of 13-column rows: L, V, N, T (3 floats a row each) and the material.
fn split(rows: &[f32]) -> [Vec<f32>; 5] {
    let mut c: [Vec<f32>; 5] = Default::default();
    for r in rows.chunks_exact(13) {
        for (k, col) in c.iter_mut().take(4).enumerate() {
            let at = if k < 3 { 3 * k } else { 10 };
            col.extend_from_slice(&r[at..at + 3]);
        }
        c[4].push(r[9]);
    }
    c
}

fn same(a: &Output, b: &Output, what: &str) {
    let bits = |x: &[f32]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&a.brdf), bits(&b.brdf), "{what}: brdf");
    assert_eq!(
        a.terms.as_deref().map(bits),
        b.terms.as_deref().map(bits),
        "{what}: terms"
    );
    assert_eq!(a.counts, b.counts, "{what}: counts");
}

/// An engine with rows only (the reference's `evaluate`): the trait's defaults serve it.
struct RowsOnly(CpuReference);

impl Backend for RowsOnly {
    fn name(&self) -> String {
        "rows only".into()
    }

    fn evaluate(
        &mut self,
        batch: &Batch,
        materials: &[Material],
        request: &Request,
    ) -> vkbrdf::Result<Output> {
        self.0.evaluate(batch, materials, request)
    }
}

fn engines() -> Vec<(String, Box<dyn Backend>)> {
    let mut e: Vec<(String, Box<dyn Backend>)> = Isa::available_all()
        .into_iter()
        .map(|isa| {
            let b: Box<dyn Backend> = Box::new(CpuEngine::with_isa(2, isa));
            (format!("cpu {}", isa.name()), b)
        })
        .collect();
    e.push(("reference".into(), Box::new(CpuReference::new())));
    e.push((
        "the trait's default".into(),
        Box::new(RowsOnly(CpuReference::new())),
    ));
    if let Some(v) = common::vulkan() {
        e.push(("vulkan".into(), Box::new(v)));
    }
    // Chunks of about 15 K rows: the corpus spans several, each gathered from the columns.
    let small = vkbrdf::gpu::VulkanOptions {
        validation: true,
        max_gpu_memory: 4 << 20,
        ..vkbrdf::gpu::VulkanOptions::default()
    };
    if let Some(v) = common::vulkan_with(small) {
        e.push(("vulkan, 4 MiB".into(), Box::new(v)));
    }
    e
}

/// The stress corpus (every material kind, adversarial directions: zero, NaN, grazing,
/// below the horizon, mixed materials, tangents), a length that leaves a tail block, as
/// rows and as columns.
#[test]
fn the_stress_corpus_as_columns_is_the_rows_bit_for_bit() {
    let n = 40_000 + 7;
    let (materials, batch, _) = vkbrdf::stress::corpus::corpus(n, 11);
    assert_eq!(batch.columns(), 13);
    let [l, v, nn, t, m] = split(batch.as_slice());
    let cols = ColumnBatch::new([&l, &v, &nn], Some(&t), &m, n, &materials, Path::new("c"))
        .expect("the corpus's columns are valid");
    let request = Request { terms: true };
    for (name, mut e) in engines() {
        let rows = e.evaluate(&batch, &materials, &request).unwrap();
        let mut out = Output::default();
        e.evaluate_columns_into(&cols, &materials, &request, &mut out)
            .unwrap();
        same(&rows, &out, &name);
        assert!(rows.counts.invalid > 0 && rows.counts.first_invalid.is_some());
    }
}

/// The broadcast form: l one a row, v and n one vector for every row (n = +z, which the
/// engine runs on its N = +z variants, and a tilted n), one material or one a row.
#[test]
fn broadcast_vectors_are_the_rows_bit_for_bit() {
    let materials: Vec<Material> = parse_materials(
        "[[material]]\nname = \"gold\"\nmodel = \"cook-torrance\"\ndistribution = \"ggx\"\n\
         roughness = 0.2\ngeometry = \"smith-correlated\"\nfresnel = \"conductor\"\nior = [0.18, 0.42, 1.37]\n\
         extinction = [3.4, 2.35, 1.77]\n\
         [[material]]\nname = \"b\"\nmodel = \"blinn-phong\"\nexponent = 40\n\
         [[material]]\nname = \"d\"\nmodel = \"cook-torrance\"\ndistribution = \"beckmann\"\n\
         roughness = 0.08\ngeometry = \"smith\"\nfresnel = \"dielectric\"\nior = 1.5\n",
        "t",
    )
    .unwrap();
    let n = 5_000 + 3;
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut uniform = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
    };
    let l: Vec<f32> = (0..3 * n).map(|_| uniform()).collect();
    let each_m: Vec<f32> = (0..n).map(|i| (i % 3) as f32).collect();
    let v = [0.1f32, -0.3, 0.9];
    let request = Request { terms: true };
    for nv in [[0.0f32, 0.0, 1.0], [0.2, 0.1, 0.95]] {
        for (m, which) in [(&[0.0f32][..], "one material"), (&each_m[..], "one a row")] {
            let cols =
                ColumnBatch::new([&l, &v, &nv], None, m, n, &materials, Path::new("c")).unwrap();
            let mut rows = Vec::with_capacity(10 * n);
            for i in 0..n {
                rows.extend_from_slice(&l[3 * i..3 * i + 3]);
                rows.extend_from_slice(&v);
                rows.extend_from_slice(&nv);
                rows.push(m[if m.len() == 1 { 0 } else { i }]);
            }
            let batch = Batch::new(rows, 10, materials.len(), Path::new("r")).unwrap();
            for (name, mut e) in engines() {
                let want = e.evaluate(&batch, &materials, &request).unwrap();
                let mut out = Output::default();
                e.evaluate_columns_into(&cols, &materials, &request, &mut out)
                    .unwrap();
                same(&want, &out, &format!("{name}, n = {nv:?}, {which}"));
            }
        }
    }
}
