//! An allocator that refuses any single allocation larger than a budget set from the
//! current input's size (the `Alloc` error aborts, which libFuzzer records as a crash with
//! the input saved): the check for "no allocation far beyond the input's size", without
//! a sanitizer runtime.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// A fixed allowance on top of the per-byte one: buffers (`BufReader`, parser tables)
/// that do not depend on the input.
pub const BASE: usize = 1 << 20;
/// Bytes one input byte may cost in a single allocation.
pub const PER_BYTE: usize = 16;

static LIMIT: AtomicUsize = AtomicUsize::new(usize::MAX);

/// Sets the budget for the input being run.
pub fn set_for_input(len: usize) {
    LIMIT.store(BASE + PER_BYTE * len, Ordering::Relaxed);
}

/// Lifts the budget (one-time set-up, such as a fixed table).
#[allow(dead_code)] // used by one target of four
pub fn lift() {
    LIMIT.store(usize::MAX, Ordering::Relaxed);
}

/// The capped allocator.
pub struct Capped;

// SAFETY: every method either refuses (null, which the `GlobalAlloc` contract allows for
// any request) or forwards its arguments unchanged to `System`, so the caller's guarantees
// on `layout`, `ptr` and `new_size` are exactly the ones `System` needs; `dealloc` and a
// refused `realloc` leave the block as it was.
unsafe impl GlobalAlloc for Capped {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if layout.size() > LIMIT.load(Ordering::Relaxed) {
            return std::ptr::null_mut();
        }
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if layout.size() > LIMIT.load(Ordering::Relaxed) {
            return std::ptr::null_mut();
        }
        System.alloc_zeroed(layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if new_size > LIMIT.load(Ordering::Relaxed) {
            return std::ptr::null_mut();
        }
        System.realloc(ptr, layout, new_size)
    }
}
