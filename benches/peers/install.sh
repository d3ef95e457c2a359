#!/usr/bin/env bash
# Install the throughput peers for `vkbrdf bench` (idempotent).
#   - libllvm19 from Debian (Dr.Jit's LLVM backend needs it; LLVM 14 is too old, 15 crashes)
#   - a venv at benches/peers/.venv with mitsuba==3.9.1 drjit==1.5.0 numpy scipy
# Never fails the caller because a peer cannot be installed: it says what was skipped
# and exits 0 (peer.py then writes {"skipped": ...} for that peer).
set -u
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
VENV="$HERE/.venv"
PY="${PYTHON:-python3}"
LLVM_LIB=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1
t0=$(date +%s)
say() { echo "[peers/install] $*"; }

# 1. libLLVM 19 (for the Mitsuba peer only)
if [ -e "$LLVM_LIB" ]; then
  say "libllvm19: already installed ($LLVM_LIB)"
else
  SUDO=""
  if [ "$(id -u)" != 0 ]; then
    if command -v sudo >/dev/null 2>&1; then SUDO="sudo -n"; fi
  fi
  if ! command -v apt-get >/dev/null 2>&1; then
    say "libllvm19: SKIPPED (no apt-get on this machine); the mitsuba peer will report skipped"
  else
    if ! apt-cache show libllvm19 >/dev/null 2>&1; then
      $SUDO apt-get update -qq >/dev/null 2>&1 || true
    fi
    if apt-cache show libllvm19 >/dev/null 2>&1; then
      if DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq libllvm19 >/dev/null; then
        say "libllvm19: installed via apt-get ($LLVM_LIB)"
      else
        say "libllvm19: SKIPPED (apt-get install libllvm19 failed); the mitsuba peer will report skipped"
      fi
    else
      say "libllvm19: SKIPPED (no libllvm19 package in this machine's apt sources); the mitsuba peer will report skipped"
    fi
  fi
fi

# 2. the venv
if [ ! -x "$VENV/bin/python" ]; then
  if "$PY" -m venv "$VENV"; then
    say "venv: created $VENV"
  else
    say "venv: SKIPPED ($PY -m venv failed); the mitsuba and numpy peers will report skipped"
    exit 0
  fi
else
  say "venv: exists ($VENV)"
fi

PKGS=("mitsuba==3.9.1" "drjit==1.5.0" "numpy" "scipy")
if "$VENV/bin/python" - <<'PYEOF' >/dev/null 2>&1
import importlib.metadata as m
assert m.version("mitsuba") == "3.9.1" and m.version("drjit") == "1.5.0"
import numpy, scipy.special  # noqa
PYEOF
then
  say "pip: ${PKGS[*]} already present"
else
  if "$VENV/bin/python" -m pip install -q --disable-pip-version-check "${PKGS[@]}"; then
    say "pip: installed ${PKGS[*]}"
  else
    say "pip: SKIPPED (pip install ${PKGS[*]} failed); peers that need them will report skipped"
  fi
fi
"$VENV/bin/python" -c 'import importlib.metadata as m
for p in ("mitsuba","drjit","numpy","scipy"):
    try: print("[peers/install]   ", p, m.version(p))
    except Exception as e: print("[peers/install]   ", p, "MISSING")'
say "done in $(( $(date +%s) - t0 )) s"
exit 0
