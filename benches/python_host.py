"""NumPy in, NumPy out through the Python package: the row form (an (n, 10) float32 array,
read in place) beside the broadcast form (l= an (n, 3) array, v= and n= one vector each:
the columns gathered in cache-sized chunks), the broadcast form as it was (the rows built
in NumPy first), and a copy of the row form's bytes (the memory's ceiling for reading
them), each the median of five runs, in M tuples/s.

    target/python-venv/bin/python benches/python_host.py [--tuples N] [--backend cpu]
"""

import argparse
import statistics
import time

import numpy as np

import vkbrdf


def numpy_rows(L, V, N, m):
    """The rows the broadcast form built in NumPy before it went to the engine as columns
    (the package's code until 2026-12, for the before/after figure)."""
    out = np.empty(L.shape[:-1] + (10,), dtype=np.float32)
    for k, x in enumerate((L, V, N)):
        out[..., 3 * k : 3 * k + 3] = x
    out[..., 9] = m
    return out.reshape(-1, 10)


def median_seconds(f, repeats=5):
    f()  # warm: the engine's pool, the pages of the result
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--tuples", type=int, default=4_000_000)
    p.add_argument("--backend", default="cpu")
    p.add_argument("--material", default="gold")
    a = p.parse_args()
    n = a.tuples
    mats = vkbrdf.presets()
    m = mats.index(a.material)
    rng = np.random.default_rng(1)
    L = rng.normal(size=(n, 3)).astype(np.float32)
    L[:, 2] = np.abs(L[:, 2]) + 0.1
    V = np.array([0.3, 0.0, 0.95], np.float32)
    N = np.array([0.0, 0.0, 1.0], np.float32)
    rows = np.empty((n, 10), np.float32)
    rows[:, 0:3], rows[:, 3:6], rows[:, 6:9], rows[:, 9] = L, V, N, m
    scratch = np.empty_like(rows)
    cases = {
        "rows (n, 10)": lambda: vkbrdf.evaluate(mats, rows, backend=a.backend),
        "broadcast l=(n, 3), v=, n=": lambda: vkbrdf.evaluate(
            mats, l=L, v=V, n=N, material=m, backend=a.backend
        ),
        "broadcast, rows built in NumPy": lambda: vkbrdf.evaluate(
            mats, numpy_rows(L, V, N, m), backend=a.backend
        ),
        "copy of the rows' bytes": lambda: np.copyto(scratch, rows),
    }
    assert np.array_equal(cases["rows (n, 10)"](), cases["broadcast l=(n, 3), v=, n="]())
    print(f"{n} tuples of `{a.material}` on {a.backend}, NumPy in and out (M tuples/s):")
    for name, f in cases.items():
        print(f"  {name:<32} {n / median_seconds(f) / 1e6:8.1f}")


if __name__ == "__main__":
    main()
