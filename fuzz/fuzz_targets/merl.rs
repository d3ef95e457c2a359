//! The MERL reader on arbitrary bytes: Ok or a clean error, never a panic, never an
//! allocation of a table's worth (35 MB) for a short input. (A valid table is 35 MB, far
//! past any fuzz input: `merl_lookup` drives lookups into one fixed table instead.)
#![no_main]

use libfuzzer_sys::fuzz_target;
mod limit;

#[global_allocator]
static ALLOC: limit::Capped = limit::Capped;
use std::path::Path;
use vkbrdf::table::merl;

fuzz_target!(|data: &[u8]| {
    limit::set_for_input(data.len());
    let source = Path::new("fuzz.binary");
    if let Err(e) = merl::read_from(data, source) {
        assert!(e.to_string().contains("fuzz.binary"), "{e}");
    }
});
