#!/usr/bin/env bash
# Runs the fuzz targets one after another, one job each, on the nightly toolchain, for
# SECONDS each (default 600) or 10^7 executions, whichever comes first; logs in
# fuzz/logs/<target>.log. Usage: fuzz/run.sh [SECONDS] [TARGET...]
set -euo pipefail
cd "$(dirname "$0")"
seconds=${1:-600}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(merl merl_lookup npy materials sidecar)
[ -d corpus ] || python3 make_seeds.py
mkdir -p logs
for t in "${targets[@]}"; do
  # Seed from the kept corpus too, so a run starts where the last one stopped.
  mkdir -p "corpus/$t" && cp -n ../tests/fuzz_corpus/"$t"/* "corpus/$t/" 2>/dev/null || true
  start=$(date +%s)
  cargo +nightly fuzz run -a -s none "$t" -- \
    -runs=10000000 -max_total_time="$seconds" -timeout=10 \
    -rss_limit_mb=2048 -malloc_limit_mb=2048 -max_len=8192 -print_final_stats=1 \
    >"logs/$t.log" 2>&1 || echo "$t: exit $?" >>"logs/$t.log"
  echo "$t: $(( $(date +%s) - start )) s wall" >>"logs/$t.log"
done
