"""Evaluates a chunked Dask array of tuples with vkbrdf on a local cluster of two worker
processes (`map_blocks`): each worker evaluates its blocks with the engine it picks.

    python examples/python/dask_map_blocks.py --tuples 4000000 --chunk 500000

The same `evaluate_dask` runs unchanged on a multi-machine Dask cluster: replace the
LocalCluster by `Client("tcp://scheduler:8786")` (every worker needs `pip install ./python`
and, for Vulkan, a driver). A `vkbrdf.Materials` pickles (as its TOML text, or its file
path, which each worker then reads), so it travels to the workers with the task.
"""

import argparse
import time

import dask.array as da
import numpy as np
from dask.distributed import Client, LocalCluster

import vkbrdf

MATERIALS = """
[[material]]
name = "rough-gold"
preset = "gold"
roughness = 0.5

[[material]]
name = "matte"
model = "lambert"
diffuse = 0.5
"""


def _evaluate_block(block, materials, backend):
    # One block: an (n, 10) or (n, 13) array of whole rows, evaluated in this worker.
    return vkbrdf.evaluate(materials, block, backend=backend)


def evaluate_dask(materials, tuples, backend="auto"):
    """f for a Dask array of tuples (n, 10|13), chunked by rows: a Dask array (n, 3)."""
    tuples = tuples.rechunk({1: -1})  # every block holds whole rows
    return tuples.map_blocks(
        _evaluate_block,
        materials,
        backend,
        dtype=np.float32,
        chunks=(tuples.chunks[0], (3,)),
    )


def random_tuples(n, material_count, seed=1):
    """Seeded tuples with L, V in the upper hemisphere and N = +z."""
    rng = np.random.default_rng(seed)
    t = np.zeros((n, 10), np.float32)
    t[:, 0:3] = rng.normal(size=(n, 3))
    t[:, 3:6] = rng.normal(size=(n, 3))
    t[:, 2] = np.abs(t[:, 2])
    t[:, 5] = np.abs(t[:, 5])
    t[:, 8] = 1.0
    t[:, 9] = rng.integers(0, material_count, n)
    return t


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tuples", type=int, default=1_000_000)
    ap.add_argument("--chunk", type=int, default=250_000)
    ap.add_argument("--backend", default="auto")
    args = ap.parse_args()
    materials = vkbrdf.parse_materials(MATERIALS, "example")
    tuples = da.from_array(random_tuples(args.tuples, len(materials)), chunks=(args.chunk, 10))
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True) as cluster, Client(cluster):
        t0 = time.perf_counter()
        f = evaluate_dask(materials, tuples, args.backend).compute()
        dt = time.perf_counter() - t0
    print(f"{args.tuples} tuples in {len(tuples.chunks[0])} blocks on 2 worker processes: "
          f"{dt:.2f} s, f.shape {f.shape}, mean f {f.mean(axis=0)}")


if __name__ == "__main__":
    main()
