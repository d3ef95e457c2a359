#!/usr/bin/env bash
# The CPU engine's instruction counts against their ceilings (benches/cpu_count_ceilings.txt):
# deterministic where timings are not, so CI catches a lane loop that stopped vectorising
# (a `&&` in a lane loop once took the columns form from 70 to 180 instructions an
# evaluation, and no test, which compares bits, saw it). Needs valgrind and the
# cpu_engine_count example (built here if missing). Exit 1 when a count is over its
# ceiling, 2 on a set-up error; rows for an instruction set this CPU lacks are skipped.
set -euo pipefail
cd "$(dirname "$0")/.."
command -v valgrind >/dev/null || { echo "error: valgrind not found (apt-get install valgrind)" >&2; exit 2; }
bin=target/release/examples/cpu_engine_count
[ -x "$bin" ] || cargo build --release --example cpu_engine_count
over=0
while read -r scenario form isa ceiling _; do
  case "$scenario" in ''|'#'*) continue ;; esac
  if ! VKBRDF_CPU_ISA=$isa "$bin" "$scenario" 16 1 >/dev/null 2>&1; then
    echo "skipped: $scenario $form on $isa (this CPU cannot run it)"
    continue
  fi
  arg=""; [ "$form" = local ] || arg=$form
  line=$(VKBRDF_CPU_ISA=$isa bash benches/cpu_count.sh "$bin" "$scenario" $arg)
  count=$(echo "$line" | awk '{print $(NF-3)}')
  if awk -v c="$count" -v m="$ceiling" 'BEGIN { exit !(c > m) }'; then
    echo "OVER: $scenario $form $isa: $count instructions an evaluation, ceiling $ceiling"
    over=1
  else
    echo "ok: $scenario $form $isa: $count (ceiling $ceiling)"
  fi
done < benches/cpu_count_ceilings.txt
if [ "$over" = 1 ]; then
  echo "a count is over its ceiling: a loop lost vectorisation, or a change added work (raise the ceiling only on purpose, with the measurement)" >&2
  exit 1
fi
