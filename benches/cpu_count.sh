#!/usr/bin/env bash
# Instructions an evaluation of the CPU engine on a `vkbrdf bench` scenario, by callgrind —
# the figure docs/CPU_ENGINE.md compares variants by, which repeats where timings on a
# shared machine do not. Counts the whole process at 1 and 3 repeats of the same batch; the
# difference over 2 x TUPLES is one evaluation's share, the set-up cancelling. valgrind
# hides AVX-512, so the counts are the AVX2 path's (or `scalar`'s with VKBRDF_CPU_ISA).
# Needs valgrind and the cpu_engine_count example:
#   cargo build --release --example cpu_engine_count
#   bash benches/cpu_count.sh target/release/examples/cpu_engine_count mitsuba-ggx [columns|planar|rows]
# (`columns`: the same L and V as (n, 3) columns, N given once, instead of the local form).
set -euo pipefail
bin=${1:?usage: cpu_count.sh CPU_ENGINE_COUNT_BINARY SCENARIO [columns|planar|rows]}
scenario=${2:?scenario}
form=${3:-}
tuples=65536
count() {
    valgrind --tool=callgrind --callgrind-out-file=/dev/null \
        "$bin" "$scenario" "$tuples" "$1" $form 2>&1 |
        grep -o 'Collected : [0-9]*' | awk '{print $3}'
}
a=$(count 1)
b=$(count 3)
awk -v a="$a" -v b="$b" -v n="$tuples" -v s="$scenario" -v f="${form:-local}" \
    'BEGIN { printf "%s (%s form): %.2f instructions an evaluation\n", s, f, (b - a) / (2 * n) }'
