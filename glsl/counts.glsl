// counts.glsl — the chunk's counts (Counts in bindings.glsl: invalid, below the horizon,
// saturated, and the first invalid row in the batch's order), reduced across a subgroup
// where the device can (USE_SUBGROUP_ARITHMETIC).

#ifndef VKBRDF_COUNTS_GLSL
#define VKBRDF_COUNTS_GLSL

#include "bindings.glsl"
#include "frame_fields.glsl"

// The chunk row that uploaded row `row` came from (see Order).
uint original_row(uint row) {
#if defined(BUCKETED)
    return order[row];
#else
    return row;
#endif
}

// Counts row `row`, whose status is `status` (saturated when STATUS_VALID), only where there
// is something to count: evaluate_row calls this for the invocations whose tuple is
// invalid, below the horizon or saturated, and llvmpipe skips the call altogether when a
// subgroup has none (the usual case). Subgroup operations inside it reduce over those
// active invocations only, so one atomic per subgroup, not per tuple (below-horizon
// tuples are common: per-tuple atomics would serialise on one address). Measured on
// lavapipe, 4M tuples with nothing to count: Lambert without loads and stores 148 ->
// ~270 M/s against a reduction over every invocation; the whole kernel 1.1-1.3x
// (`examples/kernel_time.rs`); with half the tuples below the horizon, no change.
// Deliberately not a workgroup reduction in shared memory: that needs barrier(), and
// llvmpipe runs any shader with a barrier through coroutines, which made the whole
// kernel 2.7x slower on lavapipe (measured: 280 vs 103 ms for 4M tuples of a
// load-and-store kernel).
void count_tuple(uint row, uint status) {
    bool invalid = status == STATUS_INVALID;
    bool below = status == STATUS_BELOW_HORIZON;
#if defined(USE_SUBGROUP_ARITHMETIC)
    // The three counts in one reduction, 10 bits each (a subgroup has at most 128
    // invocations): invalid, below-horizon << 10, saturated << 20; and the first invalid
    // row only when there is one (n_invalid is uniform over the active invocations).
    uint packed = subgroupAdd(invalid ? 1u : below ? 0x400u : 0x100000u);
    uint n_invalid = packed & 0x3ffu;
    uint n_below = (packed >> 10u) & 0x3ffu;
    uint n_saturated = packed >> 20u;
    uint first = 0xffffffffu;
    if (n_invalid != 0u) {
        first = subgroupMin(invalid ? original_row(row) : 0xffffffffu);
    }
    if (subgroupElect()) {
        if (n_invalid != 0u) {
            atomicAdd(invalid_count, n_invalid);
            atomicMin(first_invalid, first);
        }
        if (n_below != 0u) {
            atomicAdd(below_horizon_count, n_below);
        }
        if (n_saturated != 0u) {
            atomicAdd(saturated_count, n_saturated);
        }
    }
#else
    if (invalid) {
        atomicAdd(invalid_count, 1u);
        atomicMin(first_invalid, original_row(row));
    } else if (below) {
        atomicAdd(below_horizon_count, 1u);
    } else {
        atomicAdd(saturated_count, 1u);
    }
#endif
}

#endif
