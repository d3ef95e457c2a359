//! The `.npy` tuple reader on arbitrary bytes: Ok or a clean error, never a panic, and no
//! allocation beyond a small multiple of the input (`limit.rs`). The
//! stream is read twice, with its length known (as from a file) and unknown (as from a
//! pipe): both must agree whenever both succeed, and the length check may only reject
//! earlier, never accept what the stream reading rejects.
#![no_main]

use libfuzzer_sys::fuzz_target;
mod limit;

#[global_allocator]
static ALLOC: limit::Capped = limit::Capped;
use std::path::Path;
use vkbrdf::batch::{read_npy_f32_from, Batch};

fuzz_target!(|data: &[u8]| {
    limit::set_for_input(data.len());
    let source = Path::new("fuzz.npy");
    let known = read_npy_f32_from(data, Some(data.len() as u64), source);
    let unknown = read_npy_f32_from(data, None, source);
    match (&known, &unknown) {
        (Ok(a), Ok(b)) => assert_eq!(
            (a.0.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), &a.1),
            (b.0.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), &b.1)
        ),
        (Ok(_), Err(e)) => {
            panic!("the length-aware read accepted what the stream read rejects: {e}")
        }
        (Err(e), _) => assert!(e.to_string().contains("fuzz.npy"), "{e}"),
    }
    if known.is_err() {
        return;
    }
    if let Ok(batch) = Batch::read_npy_from(data, Some(data.len() as u64), 3, source) {
        for i in 0..batch.len() {
            let t = batch.tuple(i);
            assert!(t.material < 3 && batch.material(i) == t.material);
        }
    }
});
