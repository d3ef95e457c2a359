#!/usr/bin/env bash
# The streaming proof of docs/STREAMING.md: peak resident memory of `vkbrdf eval` at the
# default memory budget, for batch sizes from 10^6 to 2·10^8 tuples (8 GB of input), on
# each engine; prints a Markdown table row per size.
#
#   bash benches/stream_memory.sh [DIR] [SIZES...]     (default: a directory under $TMPDIR;
#                                                       1e6 1e7 5e7 2e8)
#
# Needs /usr/bin/time (Debian: `time`) and free disk of 52 bytes per tuple of the largest
# size (input 40, output 12). Each input is generated once, then read once so that every
# engine reads it from the page cache. The reference is skipped above 5·10^7 tuples (it
# evaluates ~5 M tuples/s here, so 2·10^8 takes minutes and says nothing new about memory).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=./target/release/vkbrdf
dir=${1:-$(mktemp -d "${TMPDIR:-/tmp}/vkbrdf-stream-memory.XXXXXX")}
shift || true
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(1000000 10000000 50000000 200000000)
[ -x /usr/bin/time ] || { echo "error: /usr/bin/time missing (apt-get install time)" >&2; exit 2; }
mkdir -p "$dir"
cat >"$dir/m.toml" <<'EOF'
[[material]]
name = "gold"
preset = "gold"

[[material]]
name = "white"
model = "lambert"
diffuse = 0.8
EOF
engines=(cpu vulkan reference)
echo "| tuples | input |$(printf ' %s |' "${engines[@]}")"
echo "|---:|---:|$(printf -- '---:|%.0s' "${engines[@]}")"
for n in "${sizes[@]}"; do
  n=$(printf '%.0f' "$n")
  if [ "$n" -le 100000000 ]; then
    "$bin" generate -m "$dir/m.toml" -n "$n" -o "$dir/t.npy" >/dev/null 2>&1
  else
    # generate builds its batch in memory (at most 10^8 tuples): beyond that, one block of
    # 10^8 repeated under a header of the full shape (n a multiple of 10^8).
    "$bin" generate -m "$dir/m.toml" -n 100000000 -o "$dir/block.npy" >/dev/null 2>&1
    python3 - "$dir/block.npy" "$dir/t.npy" "$n" <<'PY'
import sys, struct, shutil
block, out, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
with open(block, "rb") as f:
    head = f.read(10)
    hlen = struct.unpack("<H", head[8:10])[0]
    f.read(hlen)
    start = 10 + hlen
d = "{'descr': '<f4', 'fortran_order': False, 'shape': (%d, 10), }" % n
pad = (-(10 + len(d) + 1)) % 64
d = d + " " * pad + "\n"
with open(out, "wb") as o:
    o.write(b"\x93NUMPY\x01\x00" + struct.pack("<H", len(d)) + d.encode())
    for _ in range(n // 100000000):
        with open(block, "rb") as f:
            f.seek(start)
            shutil.copyfileobj(f, o, 1 << 24)
PY
    rm -f "$dir/block.npy"
  fi
  cat "$dir/t.npy" >/dev/null # into the page cache
  row="| $n | $(( $(stat -c %s "$dir/t.npy") / 1000000 )) MB |"
  for e in "${engines[@]}"; do
    if [ "$e" = reference ] && [ "$n" -gt 50000000 ]; then row+=" (skipped) |"; continue; fi
    /usr/bin/time -f '%M' -o "$dir/peak" "$bin" eval -m "$dir/m.toml" -i "$dir/t.npy" \
      -o "$dir/o.npy" --backend "$e" >/dev/null 2>"$dir/err" \
      || { echo "error: eval --backend $e on $n tuples failed:" >&2; cat "$dir/err" >&2; exit 1; }
    row+=" $(( $(tail -n 1 "$dir/peak") / 1024 )) MiB |"
    rm -f "$dir/o.npy"
  done
  echo "$row"
  rm -f "$dir/t.npy"
done
