"""The Python result equals `vkbrdf eval`'s output bit for bit on the same engine."""

import json
import os
import subprocess

import numpy as np
import pytest

import vkbrdf
from conftest import make_tuples


def run_cli(cli, materials_file, tuples, tmp_path, backend, precision="exact"):
    inp = tmp_path / f"t-{backend}-{tuples.dtype}.npy"
    np.save(inp, tuples)
    out = tmp_path / "f.npy"
    terms = tmp_path / "terms.npy"
    r = subprocess.run(
        [cli, "eval", "-m", str(materials_file), "-i", str(inp), "-o", str(out),
         "--terms", str(terms), "--backend", backend, "--precision", precision, "--json"],
        capture_output=True, text=True, env=os.environ,
    )
    assert r.returncode == 0, r.stderr
    return np.load(out), np.load(terms), json.loads(r.stdout)


@pytest.mark.parametrize("backend", ["cpu", "reference", "vulkan"])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_equals_cli_bit_for_bit(cli, materials_file, tmp_path, backend, dtype):
    tuples = make_tuples(3000).astype(dtype)
    f_cli, terms_cli, summary = run_cli(cli, materials_file, tuples, tmp_path, backend)
    m = vkbrdf.load_materials(materials_file)
    f, terms, counts = vkbrdf.evaluate(m, tuples, backend=backend, terms=True, return_counts=True)
    assert f.dtype == np.float32 and f.shape == (3000, 3)
    assert terms.dtype == np.float32 and terms.shape == (3000, 6)
    assert np.array_equal(f, f_cli)
    assert np.array_equal(terms, terms_cli, equal_nan=True)
    assert counts == vkbrdf.Counts(
        summary["invalid"], summary["below_horizon"], summary["saturated"],
        summary["first_invalid_row"],
    )
    assert counts.invalid == 2 and counts.first_invalid == 3
    assert counts.below_horizon > 0


def test_fast_precision_equals_cli(cli, materials_file, tmp_path):
    tuples = make_tuples(1000, seed=3).astype(np.float32)
    f_cli, _, _ = run_cli(cli, materials_file, tuples, tmp_path, "cpu", precision="fast")
    m = vkbrdf.load_materials(materials_file)
    f = vkbrdf.evaluate(m, tuples, backend="cpu", precision="fast")
    assert np.array_equal(f, f_cli)
    exact = vkbrdf.evaluate(m, tuples, backend="cpu")
    assert not np.array_equal(f, exact)  # the seed-plastic's dielectric Fresnel differs
