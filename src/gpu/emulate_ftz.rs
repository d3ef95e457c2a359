//! `VKBRDF_EMULATE_FTZ=1`: the host's SSE modes set to flush f32 subnormals while the
//! Vulkan device is created, so lavapipe's threads inherit them and compute as GPUs do.

/// Runs `f` — the device's creation, during which a CPU driver (lavapipe) starts the
/// threads that run the kernel — with the x86-64 flush-to-zero and denormals-are-zero
/// modes set when `VKBRDF_EMULATE_FTZ=1`: new threads inherit the floating-point
/// environment, so the kernel then runs on lavapipe with f32 subnormals flushed, as GPUs
/// run it. A testing aid (the stress corpus's subnormal rows behaved differently on an H200
/// than on lavapipe); the calling thread's mode is restored before `f`'s result returns.
pub(super) fn flush_to_zero_scope<T>(f: impl FnOnce() -> T) -> T {
    #[cfg(target_arch = "x86_64")]
    if std::env::var("VKBRDF_EMULATE_FTZ").as_deref() == Ok("1") {
        #[allow(deprecated)]
        use std::arch::x86_64::{_mm_getcsr, _mm_setcsr};
        // MXCSR bits 15 (flush to zero) and 6 (denormals are zero).
        const FTZ_DAZ: u32 = 0x8040;
        // SAFETY: reading MXCSR has no effect.
        #[allow(deprecated)]
        let old = unsafe { _mm_getcsr() };
        // SAFETY: writing MXCSR changes only this thread's SSE rounding and denormal modes;
        // the value read above is restored below, before any host code of vkbrdf computes
        // with subnormals on this thread.
        #[allow(deprecated)]
        unsafe {
            _mm_setcsr(old | FTZ_DAZ)
        };
        let out = f();
        // SAFETY: as above; restores the value read before.
        #[allow(deprecated)]
        unsafe {
            _mm_setcsr(old)
        };
        return out;
    }
    f()
}
