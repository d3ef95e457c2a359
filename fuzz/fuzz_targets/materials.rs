//! The materials TOML parser on arbitrary text: Ok or a clean error (rendered, as the CLI
//! prints it), never a panic. Relative `file` paths resolve against a directory that does
//! not exist, so the fuzzer reads no file of the checkout.
#![no_main]

use libfuzzer_sys::fuzz_target;
mod limit;

#[global_allocator]
static ALLOC: limit::Capped = limit::Capped;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    limit::set_for_input(data.len());
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let base = Path::new("/nonexistent/vkbrdf-fuzz");
    match vkbrdf::material::parse_materials_in(text, "fuzz.toml", base) {
        Ok(materials) => {
            assert!(!materials.is_empty());
            for m in &materials {
                let _ = (m.is_anisotropic(), m.is_reciprocal());
            }
        }
        Err(e) => {
            let message = e.to_string();
            assert!(message.contains("fuzz.toml"), "{message}");
        }
    }
});
