"""Agreement with Mitsuba 3's `roughconductor` on the same directions, where the benchmark
peers' venv (benches/peers/install.sh) exists; skipped, saying why, where it does not."""

import json
import subprocess

import numpy as np
import pytest

import vkbrdf
from conftest import ROOT

PEERS = ROOT / "benches" / "peers"
VENV_PY = PEERS / ".venv" / "bin" / "python"

# The material of peer.py's scenarios (ALPHA, ETA, K there; `mitsuba-*` in
# src/bench/scenarios.rs): Mitsuba's GGX uses the separable Smith G, its Beckmann
# Walter's rational G1 (= smith-fast).
def material(distribution):
    geometry = "smith" if distribution == "ggx" else "smith-fast"
    return vkbrdf.parse_materials(
        f"""
[[material]]
name = "m"
model = "cook-torrance"
distribution = "{distribution}"
roughness = 0.3
geometry = "{geometry}"
ior = [0.2, 0.92, 1.1]
extinction = [3.9, 2.45, 2.14]
fresnel = "conductor"
""",
        "mitsuba-" + distribution,
    )


@pytest.mark.parametrize("distribution", ["ggx", "beckmann"])
def test_agrees_with_mitsuba_roughconductor(tmp_path, distribution):
    if not VENV_PY.exists():
        pytest.skip(f"{VENV_PY} not present (benches/peers/install.sh installs Mitsuba there)")
    rng = np.random.default_rng(3)
    n = 20_000
    t = np.zeros((n, 10), np.float32)
    for k in (0, 3):  # L and V: unit, upper hemisphere, away from grazing
        d = rng.normal(size=(n, 3))
        d[:, 2] = np.abs(d[:, 2]) + 0.2
        t[:, k:k + 3] = d / np.linalg.norm(d, axis=1, keepdims=True)
    t[:, 8] = 1.0
    np.save(tmp_path / "t.npy", t)
    r = subprocess.run(
        [str(VENV_PY), str(PEERS / "peer.py"), "--peer", "mitsuba", "--scenario", distribution,
         "--input", str(tmp_path / "t.npy"), "--repeats", "1", "--out", str(tmp_path / "r.json"),
         "--check", str(tmp_path / "f.npy")],
        capture_output=True, text=True,
    )
    result = json.loads((tmp_path / "r.json").read_text())
    if "skipped" in result and not result.get("error"):
        pytest.skip(f"Mitsuba peer unavailable: {result['skipped']}")
    assert r.returncode == 0, r.stderr
    theirs = np.load(tmp_path / "f.npy")
    ours = vkbrdf.evaluate(material(distribution), t, backend="reference")
    # Mitsuba evaluates in float32 throughout; the reference is f64 rounded once. Measured
    # (mitsuba 3.9.1, 20 000 tuples): max relative difference 1.2e-6 (ggx), 6.8e-6
    # (beckmann with Walter's G1).
    assert np.allclose(ours, theirs, rtol=5e-5, atol=1e-6), np.max(
        np.abs(ours - theirs) / np.maximum(np.abs(ours), 1e-6))
