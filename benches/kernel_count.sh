#!/usr/bin/env bash
# Instructions a tuple of a `vkbrdf bench` scenario's kernel on lavapipe, by callgrind —
# a figure that repeats where timings on a shared machine do not (docs/VULKAN.md, "The
# local frames"). Counts the whole process at 65,536 and 196,608 tuples; the difference
# over 4 x 131,072 (kernel_time's warm-up and three timed passes) is the kernel's share,
# compilation and set-up cancelling. A first run under valgrind fills every cache (Mesa's
# key includes the CPU features, and valgrind hides AVX-512, so llvmpipe compiles for
# AVX2 there). Needs valgrind and the kernel_time example:
#   cargo build --release --example kernel_time
#   VK_DRIVER_FILES=/usr/share/vulkan/icd.d/lvp_icd.json \
#     bash benches/kernel_count.sh target/release/examples/kernel_time mitsuba-ggx FOLD
# (the third argument is a kernel_time --variant, e.g. FOLD or FOLD,NO_LOCAL32_FRAME).
set -euo pipefail
bin=${1:?usage: kernel_count.sh KERNEL_TIME_BINARY SCENARIO [VARIANT]}
scenario=${2:?scenario}
variant=${3:-}
export LP_NUM_THREADS=1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
valgrind --tool=none --smc-check=all "$bin" --tuples 65536 --rounds 1 --variant "$variant" "$scenario" >/dev/null 2>&1
count() {
    valgrind --tool=callgrind --smc-check=all --callgrind-out-file="$tmp/out" \
        "$bin" --tuples "$1" --rounds 1 --variant "$variant" "$scenario" 2>&1 |
        grep -o 'Collected : [0-9]*' | awk '{print $3}'
}
a=$(count 65536)
b=$(count 196608)
echo "$scenario ${variant:-shipped}: $(( (b - a) / (4 * 131072) )) instructions a tuple"
