//! The shard sidecar reader on arbitrary bytes: a batch part's and a table part's sidecar
//! parse to Ok or a clean error naming the file, never a panic, and a parsed batch sidecar's
//! validation (row range, counts, first invalid row) answers without overflow or panic;
//! no allocation beyond a small multiple of the input (`limit.rs`).
#![no_main]

use libfuzzer_sys::fuzz_target;
mod limit;

#[global_allocator]
static ALLOC: limit::Capped = limit::Capped;
use std::path::Path;
use vkbrdf::stream::shard::{parse_sidecar, Sidecar};
use vkbrdf::table::shard::TableSidecar;

fuzz_target!(|data: &[u8]| {
    limit::set_for_input(data.len());
    let text = String::from_utf8_lossy(data);
    let path = Path::new("part.npy.shard.json");
    match parse_sidecar::<Sidecar>(&text, path, "shard sidecar") {
        Ok(car) => {
            if car.validate().is_ok() {
                // A valid sidecar's counts fit in its rows.
                let c = car.counts();
                assert!(c.invalid + c.below_horizon + c.saturated <= c.tuples);
            }
        }
        Err(e) => assert!(e.to_string().contains("part.npy.shard.json"), "{e}"),
    }
    if let Err(e) = parse_sidecar::<TableSidecar>(&text, path, "table sidecar") {
        assert!(e.to_string().contains("part.npy.shard.json"), "{e}");
    }
});
