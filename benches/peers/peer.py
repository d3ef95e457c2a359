#!/usr/bin/env python3
"""Throughput peers for `vkbrdf bench`.

    python peer.py --peer mitsuba|numpy|memcpy|torch|torch-compile|torch-copy \
        --scenario beckmann|ggx \
        --input T.npy --repeats R --out RESULT.json [--check BRDF_OUT.npy]

Input: float32 .npy of shape (n, 10), rows `Lx Ly Lz Vx Vy Vz Nx Ny Nz material`
(the material column is ignored: the scenario fixes the material, see SCENARIO below).

Output JSON (always written, even when the peer cannot run):
    {"name", "scenario", "tuples", "evals_per_s", "seconds_median", "repeats", ...extras}
or  {"name", "scenario", "skipped": "reason"}.

Exit status: 0 when RESULT.json holds a measurement or a "skipped" (peer unavailable);
2 when the request itself is bad (unreadable input, wrong shape, bad --check path): the
JSON is then a "skipped" that also carries "error": true.

`--check` writes the peer's BRDF f (n, 3) float32 (1/sr, RGB), from the last timed run.

If this script is not run by benches/peers/.venv/bin/python and that venv exists, it
re-executes itself with it (so `python3 peer.py ...` works); without the venv the
mitsuba and numpy peers report "skipped". The torch peers never re-execute: they use the
python3 that runs them (a GPU machine's own PyTorch) and report "skipped" where it has no
torch or no CUDA device (VKBRDF_PEER_TORCH_CPU=1 runs them on the CPU, for testing).
"""
import argparse
import glob
import json
import math
import os
import sys
import time
import traceback

HERE = os.path.dirname(os.path.abspath(__file__))
VENV_PY = os.path.join(HERE, ".venv", "bin", "python")

# ---------------------------------------------------------------------------
# The scenario: what vkbrdf must evaluate for the comparison to be the same BRDF.
# Modern Cook-Torrance f = D G F / (4 cos_i cos_o), separable Smith G, exact conductor
# Fresnel (complex eta = n + ik per RGB channel), roughness 0.3, c_spec = 1, no diffuse.
# ---------------------------------------------------------------------------
ALPHA = 0.3
ETA = (0.2, 0.92, 1.1)
K = (3.9, 2.45, 2.14)
SCENARIOS = ("beckmann", "ggx")

LLVM_CANDIDATES = (
    "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1",
    "/usr/lib/x86_64-linux-gnu/libLLVM-19.so",
    "/usr/lib/llvm-19/lib/libLLVM.so.19.1",
    "/usr/lib/llvm-19/lib/libLLVM-19.so",
)


class Skip(Exception):
    """The peer cannot run here (missing venv, import failure, libLLVM missing)."""


class BadRequest(Exception):
    """The request is wrong (input file, shape, output path)."""


def write_json(path, obj):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(obj, f, indent=2)
        f.write("\n")
    os.replace(tmp, path)


def maybe_reexec_in_venv():
    """Run under benches/peers/.venv when it exists and we are not already in it."""
    if os.environ.get("VKBRDF_PEER_NO_REEXEC"):
        return
    if any(a.startswith("torch") for a in sys.argv[1:]):
        return  # the torch peers use this python3's own torch
    if not os.path.exists(VENV_PY):
        return
    if os.path.realpath(sys.prefix) == os.path.realpath(os.path.join(HERE, ".venv")):
        return
    os.environ["VKBRDF_PEER_NO_REEXEC"] = "1"
    os.execv(VENV_PY, [VENV_PY, os.path.abspath(__file__)] + sys.argv[1:])


def import_numpy():
    try:
        import numpy as np  # noqa: F401
        return np
    except Exception as e:  # noqa: BLE001
        hint = "" if os.path.exists(VENV_PY) else " (venv missing: run benches/peers/install.sh)"
        raise Skip(f"numpy import failed: {e}{hint}")


def load_input(np, path):
    try:
        a = np.load(path, mmap_mode=None, allow_pickle=False)
    except Exception as e:  # noqa: BLE001
        raise BadRequest(f"cannot read input {path}: {e}")
    if a.ndim != 2 or a.shape[1] != 10:
        raise BadRequest(f"input {path} has shape {a.shape}, expected (n, 10)")
    if a.dtype != np.float32:
        a = a.astype(np.float32)
    return np.ascontiguousarray(a)


def median(ts):
    st = sorted(ts)
    m = len(st)
    return st[m // 2] if m % 2 else 0.5 * (st[m // 2 - 1] + st[m // 2])


def time_median(fn, repeats):
    fn()  # warm-up (compiles the Dr.Jit kernel, faults the pages in)
    ts = []
    out = None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t0)
    return median(ts), ts, out


# ---------------------------------------------------------------------------
# NumPy peer: the plain vectorised float32 implementation a user would write.
# Follows FORMULAS.md (normalises L, V, N; general N; below horizon -> 0).
# ---------------------------------------------------------------------------
def erf_as(np, x):
    """Abramowitz & Stegun 7.1.26 (|error| <= 1.5e-7), used only without scipy."""
    s = np.sign(x)
    a = np.abs(x)
    t = np.float32(1.0) / (np.float32(1.0) + np.float32(0.3275911) * a)
    y = t * (np.float32(0.254829592) + t * (np.float32(-0.284496736) + t * (
        np.float32(1.421413741) + t * (np.float32(-1.453152027) + t * np.float32(1.061405429)))))
    return s * (np.float32(1.0) - y * np.exp(-a * a))


def make_numpy_brdf(np, scenario, beckmann_g):
    try:
        from scipy.special import erf as sp_erf
        erf = sp_erf
        erf_name = "scipy.special.erf"
    except Exception:  # noqa: BLE001
        erf = lambda x: erf_as(np, x)  # noqa: E731
        erf_name = "Abramowitz-Stegun 7.1.26"

    f32 = np.float32
    m = f32(ALPHA)
    m2 = f32(ALPHA * ALPHA)
    pi = f32(np.pi)
    eta = (np.array(ETA, np.float32) + 1j * np.array(K, np.float32)).astype(np.complex64)
    sqrt_pi = f32(np.sqrt(np.pi))

    def dot(a, b):
        return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]

    def normalize(a):
        return a / np.sqrt(dot(a, a))[:, None]

    def cross2(a, b):  # |a x b|^2
        cx = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
        cy = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
        cz = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
        return cx * cx + cy * cy + cz * cz

    def lam(tan2):
        if scenario == "ggx":
            return (np.sqrt(f32(1) + m2 * tan2) - f32(1)) * f32(0.5)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            a = f32(1) / (m * np.sqrt(tan2))
            L = (erf(a) - f32(1)) * f32(0.5) + np.exp(-a * a) / (f32(2) * a * sqrt_pi)
        return np.where(tan2 > 0, L, f32(0))

    def g1(tan2):
        if scenario == "beckmann" and beckmann_g == "fast":
            # Walter et al. 2007 rational fit (what Mitsuba's roughconductor uses for Beckmann)
            with np.errstate(divide="ignore", invalid="ignore"):
                a = f32(1) / (m * np.sqrt(tan2))
                g = (f32(3.535) * a + f32(2.181) * a * a) / (f32(1) + f32(2.276) * a + f32(2.577) * a * a)
            return np.where(a < f32(1.6), g, f32(1))
        return f32(1) / (f32(1) + lam(tan2))

    def brdf(t):
        l = normalize(t[:, 0:3])
        v = normalize(t[:, 3:6])
        n = normalize(t[:, 6:9])
        cos_i = dot(n, l)
        cos_o = dot(n, v)
        h = normalize(l + v)
        cos_h = dot(n, h)
        c = dot(v, h)
        cos2_h = cos_h * cos_h
        with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
            tan2_h = cross2(n, h) / cos2_h
            if scenario == "beckmann":
                D = np.exp(-tan2_h / m2) / (pi * m2 * cos2_h * cos2_h)
            else:
                s = m2 + tan2_h
                D = m2 / (pi * cos2_h * cos2_h * s * s)
            G = g1(cross2(n, l) / (cos_i * cos_i)) * g1(cross2(n, v) / (cos_o * cos_o))
            # exact conductor Fresnel, complex64, per RGB channel
            cc = c[:, None]
            sin2_t = (f32(1) - cc * cc) / (eta * eta)
            cos_t = np.sqrt(np.complex64(1) - sin2_t)
            ec = eta * cc
            r_par = (ec - cos_t) / (ec + cos_t)
            r_perp = (cc - eta * cos_t) / (cc + eta * cos_t)
            F = f32(0.5) * ((r_par.real ** 2 + r_par.imag ** 2) + (r_perp.real ** 2 + r_perp.imag ** 2))
            k = D * G / (f32(4) * cos_i * cos_o)
            f = F * k[:, None]
        ok = (cos_i > 0) & (cos_o > 0) & np.isfinite(k)
        return np.where(ok[:, None], f, f32(0)).astype(np.float32, copy=False)

    return brdf, erf_name


def run_numpy(args, np, t):
    brdf, erf_name = make_numpy_brdf(np, args.scenario, args.beckmann_g)
    if args.chunk and args.chunk < t.shape[0]:
        out = np.empty((t.shape[0], 3), np.float32)

        def run():
            for i in range(0, t.shape[0], args.chunk):
                out[i:i + args.chunk] = brdf(t[i:i + args.chunk])
            return out
    else:
        def run():
            return brdf(t)
    med, ts, f = time_median(run, args.repeats)
    extras = {"dtype": "float32", "numpy": np.__version__, "chunk": args.chunk or None,
              "G": ("smith-fast (Walter rational)" if (args.scenario == "beckmann" and args.beckmann_g == "fast")
                    else "smith (separable, exact Lambda)"),
              "erf": erf_name if args.scenario == "beckmann" else None}
    return med, ts, f, extras


# ---------------------------------------------------------------------------
# Mitsuba 3 peer: roughconductor, LLVM backend.
# ---------------------------------------------------------------------------
def find_libllvm():
    p = os.environ.get("DRJIT_LIBLLVM_PATH")
    if p:
        if not os.path.exists(p):
            raise Skip(f"DRJIT_LIBLLVM_PATH={p} does not exist")
        return p
    for c in LLVM_CANDIDATES:
        if os.path.exists(c):
            return c
    g = sorted(glob.glob("/usr/lib/*/libLLVM.so.19*") + glob.glob("/usr/lib/*/libLLVM-19*.so*"))
    if g:
        return g[0]
    raise Skip("libLLVM 19 missing (apt-get install -y libllvm19; LLVM 14 is too old, 15 crashes)")


# The instruction set of an AVX2-only CPU (AMD Zen 3): what Dr.Jit targets with --llvm-isa avx2.
AVX2_TARGET = (b"znver3", b"+avx,+avx2,+fma,+f16c,+bmi,+bmi2,+popcnt,+lzcnt,+movbe,+sse4.1,+sse4.2,+ssse3", 8)


def restrict_llvm_to_avx2(dr):
    """Dr.Jit's LLVM backend compiles for the host's best instruction set (AVX-512 here).
    For a comparison with an engine forced to AVX2 on the same machine, point it at an
    AVX2-only CPU, 8 lanes a vector, through drjit-core's jit_llvm_set_target (C++ symbol,
    no Python binding in Dr.Jit 1.5); its kernels then use no AVX-512 instruction."""
    import ctypes
    try:
        core = ctypes.CDLL(os.path.join(os.path.dirname(dr.__file__), "libdrjit-core.so"))
        set_target = core._Z19jit_llvm_set_targetPKcS0_j
    except (OSError, AttributeError) as e:
        raise Skip(f"--llvm-isa avx2: drjit-core's jit_llvm_set_target not found: {e}")
    set_target.argtypes = [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_uint32]
    set_target.restype = None
    set_target(*AVX2_TARGET)


def run_mitsuba(args, np, t):
    llvm = find_libllvm()
    os.environ["DRJIT_LIBLLVM_PATH"] = llvm
    try:
        import drjit as dr
        import mitsuba as mi
    except Exception as e:  # noqa: BLE001
        hint = "" if os.path.exists(VENV_PY) else " (venv missing: run benches/peers/install.sh)"
        raise Skip(f"mitsuba/drjit import failed: {e}{hint}")
    try:
        mi.set_variant("llvm_ad_rgb")
    except Exception as e:  # noqa: BLE001
        raise Skip(f"mi.set_variant('llvm_ad_rgb') failed (LLVM backend unavailable?): {e}")
    if args.llvm_isa == "avx2":
        restrict_llvm_to_avx2(dr)

    bsdf = mi.load_dict({
        "type": "roughconductor",
        "distribution": args.scenario,
        "alpha": ALPHA,
        "eta": {"type": "rgb", "value": list(ETA)},
        "k": {"type": "rgb", "value": list(K)},
    })

    n = t.shape[0]
    # Mitsuba evaluates in the local shading frame (normal = +z): si.wi points toward the
    # viewer (V), wo toward the light (L); eval returns f * cos(theta_wo) = f * (N.L).
    L = t[:, 0:3].astype(np.float64)
    V = t[:, 3:6].astype(np.float64)
    N = t[:, 6:9].astype(np.float64)
    nz_up = bool(np.all(N[:, 0] == 0) and np.all(N[:, 1] == 0) and np.all(N[:, 2] > 0))
    if not nz_up:
        # General normals: rotate into a local frame outside the timed region (not free in vkbrdf).
        N = N / np.linalg.norm(N, axis=1, keepdims=True)
        sgn = np.where(N[:, 2] >= 0, 1.0, -1.0)
        a = -1.0 / (sgn + N[:, 2])
        b = N[:, 0] * N[:, 1] * a
        S = np.stack([1 + sgn * N[:, 0] ** 2 * a, sgn * b, -sgn * N[:, 0]], 1)
        T = np.stack([b, sgn + N[:, 1] ** 2 * a, -N[:, 1]], 1)

        def loc(w):
            w = w / np.linalg.norm(w, axis=1, keepdims=True)
            return np.stack([(w * S).sum(1), (w * T).sum(1), (w * N).sum(1)], 1)
        L, V = loc(L), loc(V)
    L = np.ascontiguousarray(L.astype(np.float32))
    V = np.ascontiguousarray(V.astype(np.float32))

    wo = mi.Vector3f(L[:, 0], L[:, 1], L[:, 2])
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(V[:, 0], V[:, 1], V[:, 2])
    ctx = mi.BSDFContext()
    dr.eval(wo, si.wi)
    dr.sync_thread()

    def once():
        val = bsdf.eval(ctx, si, wo)  # f * cos(theta_o)
        f = dr.select(wo.z > 0, val / wo.z, 0.0)  # -> f (1/sr), fused into the same kernel
        dr.eval(f)
        dr.sync_thread()
        return f

    med, ts, f = time_median(once, args.repeats)
    fnp = None
    if args.check:
        fnp = np.ascontiguousarray(np.array(f, dtype=np.float32).T)  # Color3f -> (3, n) -> (n, 3)
    extras = {"variant": "llvm_ad_rgb", "mitsuba": mi.__version__, "drjit": dr.__version__,
              "libllvm": llvm, "threads": dr.thread_count(), "llvm_isa": args.llvm_isa,
              "G": ("smith-fast (separable, Walter rational G1)" if args.scenario == "beckmann"
                    else "smith (separable, exact GGX G1)"),
              "local_frame_conversion_untimed": not nz_up}
    return med, ts, fnp, extras


# ---------------------------------------------------------------------------
# memcpy: the ceiling. Copies the bytes a kernel must read and write per tuple.
# ---------------------------------------------------------------------------
def run_memcpy(args, np, t):
    n = t.shape[0]
    bytes_per_tuple = 13 * 4  # n x 10 float32 in + n x 3 float32 out
    src = np.empty(n * 13, np.float32)
    src[: n * 10] = t.reshape(-1)
    src[n * 10:] = 1.0
    dst = np.empty_like(src)
    med, ts, _ = time_median(lambda: np.copyto(dst, src), args.repeats)
    extras = {"bytes_per_tuple": bytes_per_tuple,
              "copy_bytes_per_s": n * bytes_per_tuple / med,
              "note": "np.copyto of n*52 bytes (reads 52 B and writes 52 B per tuple): single thread"}
    return med, ts, None, extras


# ---------------------------------------------------------------------------
# PyTorch peers: the same Cook-Torrance on the GPU, float32, device-resident tensors in the
# row layout of the input; eager (one CUDA kernel per operation) and torch.compile (the
# operations fused into generated Triton kernels). Beckmann uses Walter's rational G1 (=
# vkbrdf's mitsuba-beckmann scenario and Mitsuba's roughconductor), GGX the exact G1.
# ---------------------------------------------------------------------------
def import_torch():
    try:
        import torch
    except Exception as e:  # noqa: BLE001
        raise Skip(f"torch import failed: {e}")
    if torch.cuda.is_available():
        return torch, torch.device("cuda")
    if os.environ.get("VKBRDF_PEER_TORCH_CPU") == "1":
        return torch, torch.device("cpu")
    raise Skip("torch has no CUDA device (VKBRDF_PEER_TORCH_CPU=1 runs it on the CPU)")


def make_torch_brdf(torch, scenario, device):
    m = ALPHA
    m2 = ALPHA * ALPHA
    eta = torch.tensor(ETA, dtype=torch.float32, device=device)
    k = torch.tensor(K, dtype=torch.float32, device=device)
    eta2, k2 = eta * eta, k * k

    def dot(a, b):
        return (a * b).sum(dim=1)

    def unit(a):
        return a * torch.rsqrt(dot(a, a))[:, None]

    def tan2(cos):
        c2 = cos * cos
        return torch.clamp(1.0 - c2, min=0.0) / c2

    def g1(t2):
        if scenario == "beckmann":
            a = 1.0 / (m * torch.sqrt(t2))
            g = (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
            return torch.where(a < 1.6, g, torch.ones_like(g))
        return 2.0 / (1.0 + torch.sqrt(1.0 + m2 * t2))

    def fresnel(c):
        # Exact conductor Fresnel in real arithmetic (complex eta = n + ik, outside medium
        # of index 1): the same function as the complex form the NumPy peer uses.
        c = c[:, None]
        c2 = c * c
        s2 = 1.0 - c2
        t0 = eta2 - k2 - s2
        a2b2 = torch.sqrt(t0 * t0 + 4.0 * eta2 * k2)
        a = torch.sqrt(torch.clamp(0.5 * (a2b2 + t0), min=0.0))
        t1 = a2b2 + c2
        t2 = 2.0 * a * c
        rs = (t1 - t2) / (t1 + t2)
        t3 = c2 * a2b2 + s2 * s2
        t4 = t2 * s2
        rp = rs * (t3 - t4) / (t3 + t4)
        return 0.5 * (rp + rs)

    def brdf(t):
        l = unit(t[:, 0:3])
        v = unit(t[:, 3:6])
        n = unit(t[:, 6:9])
        cos_i = dot(n, l)
        cos_o = dot(n, v)
        h = unit(l + v)
        cos_h = dot(n, h)
        c = dot(v, h)
        c2h = cos_h * cos_h
        t2h = tan2(cos_h)
        if scenario == "beckmann":
            d = torch.exp(-t2h / m2) / (math.pi * m2 * c2h * c2h)
        else:
            s = m2 + t2h
            d = m2 / (math.pi * c2h * c2h * s * s)
        g = g1(tan2(cos_i)) * g1(tan2(cos_o))
        kk = d * g / (4.0 * cos_i * cos_o)
        f = fresnel(c) * kk[:, None]
        ok = (cos_i > 0) & (cos_o > 0) & torch.isfinite(kk)
        return torch.where(ok[:, None], f, torch.zeros_like(f))

    return brdf


def time_torch(torch, device, fn, repeats, warmups=3):
    """Median seconds of fn() on the device: CUDA events around each call (after warm-ups,
    which also compile), or wall time on the CPU."""
    out = None
    for _ in range(warmups):
        out = fn()
    if device.type == "cuda":
        torch.cuda.synchronize()
    ts = []
    for _ in range(repeats):
        if device.type == "cuda":
            start = torch.cuda.Event(enable_timing=True)
            end = torch.cuda.Event(enable_timing=True)
            start.record()
            out = fn()
            end.record()
            end.synchronize()
            ts.append(start.elapsed_time(end) * 1e-3)
        else:
            t0 = time.perf_counter()
            out = fn()
            ts.append(time.perf_counter() - t0)
    return median(ts), ts, out


def run_torch(args, np, t, compiled=False):
    torch, device = import_torch()
    td = torch.from_numpy(t).to(device)  # device-resident, same row layout
    brdf = make_torch_brdf(torch, args.scenario, device)
    fn = brdf
    extras = {"torch": torch.__version__, "dtype": "float32",
              "device": torch.cuda.get_device_name(device) if device.type == "cuda" else "cpu",
              "G": ("smith-fast (separable, Walter rational G1)" if args.scenario == "beckmann"
                    else "smith (separable, exact GGX G1)"),
              "F": "exact conductor (real form)"}
    if compiled:
        t0 = time.perf_counter()
        try:
            fn = torch.compile(brdf, fullgraph=True, dynamic=False)
            fn(td)
        except Exception as e:  # noqa: BLE001
            raise Skip(f"torch.compile failed: {type(e).__name__}: {e}")
        extras["compile_seconds"] = time.perf_counter() - t0
    with torch.no_grad():
        med, ts, f = time_torch(torch, device, lambda: fn(td), args.repeats)
    fnp = f.float().cpu().numpy() if args.check else None
    return med, ts, fnp, extras


def run_torch_compile(args, np, t):
    return run_torch(args, np, t, compiled=True)


def run_torch_copy(args, np, t):
    """The device's copy ceiling for the bytes a tuple moves: a device-to-device copy of
    26 bytes per tuple reads 26 and writes 26, the 52 bytes (40 in, 12 out) of a tuple."""
    torch, device = import_torch()
    n = t.shape[0]
    src = torch.ones(n * 13 // 2, dtype=torch.float32, device=device)
    dst = torch.empty_like(src)
    med, ts, _ = time_torch(torch, device, lambda: dst.copy_(src), args.repeats)
    moved = 2 * src.numel() * 4
    extras = {"torch": torch.__version__, "bytes_per_tuple": 52,
              "copy_bytes_per_s": moved / med,
              "device": torch.cuda.get_device_name(device) if device.type == "cuda" else "cpu",
              "note": "torch Tensor.copy_ of n*26 bytes on the device (reads and writes 52 B per tuple)"}
    return med, ts, None, extras


PEERS = {"mitsuba": run_mitsuba, "numpy": run_numpy, "memcpy": run_memcpy,
         "torch": run_torch, "torch-compile": run_torch_compile, "torch-copy": run_torch_copy}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--peer", required=True, choices=sorted(PEERS))
    ap.add_argument("--scenario", required=True, choices=SCENARIOS)
    ap.add_argument("--input", required=True)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--out", required=True)
    ap.add_argument("--check", default=None, help="write the peer's f (n, 3) float32 here")
    ap.add_argument("--beckmann-g", choices=("exact", "fast"), default="exact",
                    help="numpy peer only: Beckmann G1 with erf (exact, default) or Walter's "
                         "rational fit (fast, = Mitsuba's)")
    ap.add_argument("--llvm-isa", choices=("native", "avx2"), default="native",
                    help="mitsuba peer only: compile Dr.Jit's kernels for this CPU's best "
                         "instruction set (native, default) or for an AVX2-only CPU, 8 lanes")
    ap.add_argument("--chunk", type=int, default=0,
                    help="numpy peer only: evaluate in blocks of this many rows (default 0: the "
                         "whole array at once, as written plainly)")
    args = ap.parse_args(argv)
    name = {"mitsuba": "mitsuba3-llvm", "numpy": "numpy-float32", "memcpy": "memcpy",
            "torch": "torch-eager", "torch-compile": "torch-compile",
            "torch-copy": "torch-copy"}[args.peer]
    base = {"name": name, "scenario": args.scenario}

    # A placeholder first, so that even a hard crash (e.g. in the LLVM code generator)
    # leaves a JSON behind.
    try:
        write_json(args.out, dict(base, skipped="peer process died before finishing"))
    except Exception as e:  # noqa: BLE001
        print(f"peer.py: cannot write {args.out}: {e}", file=sys.stderr)
        return 2

    try:
        if args.repeats < 1:
            raise BadRequest("--repeats must be >= 1")
        np = import_numpy()
        t = load_input(np, args.input)
        med, ts, f, extras = PEERS[args.peer](args, np, t)
        n = int(t.shape[0])
        res = dict(base, tuples=n, evals_per_s=n / med, seconds_median=med, repeats=args.repeats,
                   seconds_all=ts, **extras)
        if args.check:
            if f is None:
                res["check"] = "not written: this peer computes no BRDF"
            else:
                try:
                    np.save(args.check, np.ascontiguousarray(f, dtype=np.float32))
                except Exception as e:  # noqa: BLE001
                    raise BadRequest(f"cannot write --check {args.check}: {e}")
                res["check"] = args.check
        write_json(args.out, res)
        print(json.dumps({k: res[k] for k in ("name", "scenario", "tuples", "evals_per_s", "seconds_median")}))
        return 0
    except Skip as e:
        write_json(args.out, dict(base, skipped=str(e)))
        print(f"peer.py: {name} skipped: {e}", file=sys.stderr)
        return 0
    except BadRequest as e:
        write_json(args.out, dict(base, skipped=str(e), error=True))
        print(f"peer.py: {e}", file=sys.stderr)
        return 2
    except Exception as e:  # noqa: BLE001
        traceback.print_exc()
        write_json(args.out, dict(base, skipped=f"{type(e).__name__}: {e}", error=True))
        return 2


if __name__ == "__main__":
    maybe_reexec_in_venv()
    sys.exit(main())
