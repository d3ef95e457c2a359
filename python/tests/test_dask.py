"""examples/python/dask_map_blocks.py on a local cluster of two worker processes gives
what one direct call gives; Materials travel to other processes by pickling."""

import importlib.util
import pickle

import numpy as np

import vkbrdf
from conftest import MATERIALS_TOML, ROOT


def load_example():
    path = ROOT / "examples" / "python" / "dask_map_blocks.py"
    spec = importlib.util.spec_from_file_location("dask_map_blocks", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_materials_pickle(tmp_path):
    text = vkbrdf.parse_materials(MATERIALS_TOML, "m.toml")
    p = tmp_path / "m.toml"
    p.write_text(MATERIALS_TOML)
    for m in (text, vkbrdf.load_materials(p), vkbrdf.presets()):
        back = pickle.loads(pickle.dumps(m))
        assert back.names == m.names and back.models == m.models and back.source == m.source
    t = np.array([[0.3, 0, 1, 0, 0, 1, 0, 0, 1, 0]], np.float32)
    assert np.array_equal(vkbrdf.evaluate(pickle.loads(pickle.dumps(text)), t), vkbrdf.evaluate(text, t))


def test_dask_map_blocks_on_two_worker_processes():
    import dask.array as da
    from dask.distributed import Client, LocalCluster

    ex = load_example()
    materials = vkbrdf.parse_materials(ex.MATERIALS, "example")
    tuples = ex.random_tuples(40_000, len(materials), seed=5)
    direct = vkbrdf.evaluate(materials, tuples, backend="cpu")
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        assert len(client.scheduler_info()["workers"]) == 2
        lazy = ex.evaluate_dask(materials, da.from_array(tuples, chunks=(7_000, 10)), "cpu")
        assert lazy.shape == (40_000, 3) and lazy.numblocks == (6, 1)
        f = lazy.compute()
    assert np.array_equal(f, direct)
