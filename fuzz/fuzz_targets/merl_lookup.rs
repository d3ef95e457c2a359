//! Lookups into one fixed MERL table (read once through the reader): any nine f64 of the
//! input as `(l, v, n)`, and any three as half/difference angles, must give finite,
//! non-negative f from a table of finite values, and never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
mod limit;

#[global_allocator]
static ALLOC: limit::Capped = limit::Capped;
use std::path::Path;
use std::sync::OnceLock;
use vkbrdf::table::merl::{self, MeasuredMerl, FILE_BYTES, SAMPLES};

fn table() -> &'static MeasuredMerl {
    static TABLE: OnceLock<MeasuredMerl> = OnceLock::new();
    TABLE.get_or_init(|| {
        limit::lift();
        let mut bytes = Vec::with_capacity(FILE_BYTES);
        for dim in [90i32, 90, 180] {
            bytes.extend(dim.to_le_bytes());
        }
        // Values of every sign, the invalid marker, and zeros.
        for s in 0..3 * SAMPLES {
            let x = match s % 7 {
                0 => merl::INVALID,
                1 => 0.0,
                k => (s % 1000) as f64 * k as f64 * 0.01,
            };
            bytes.extend(x.to_le_bytes());
        }
        merl::read_from(&bytes[..], Path::new("table.binary")).expect("a valid table")
    })
}

fuzz_target!(|data: &[u8]| {
    let table = table();
    limit::set_for_input(data.len());
    let x: Vec<f64> = data
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
        .collect();
    if x.len() >= 9 {
        let f = table.lookup([x[0], x[1], x[2]], [x[3], x[4], x[5]], [x[6], x[7], x[8]]);
        assert!(
            f.iter().all(|v| v.is_finite() && *v >= 0.0),
            "{f:?} at {x:?}"
        );
    }
    if x.len() >= 3 {
        let f = table.lookup_half_diff(x[0], x[1], x[2]);
        assert!(
            f.iter().all(|v| v.is_finite() && *v >= 0.0),
            "{f:?} at {x:?}"
        );
    }
});
