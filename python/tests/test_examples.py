"""examples/python/plot_lobe.py writes its PNG; its lobe peaks near the mirror direction."""

import importlib.util

import numpy as np

import vkbrdf
from conftest import ROOT


def load(name):
    path = ROOT / "examples" / "python" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_plot_lobe_writes_a_png(tmp_path):
    ex = load("plot_lobe")
    out = tmp_path / "lobe.png"
    ex.plot(vkbrdf.presets(), "gold", 45.0, out, backend="cpu", size=(32, 16))
    data = out.read_bytes()
    assert data.startswith(b"\x89PNG\r\n\x1a\n") and len(data) > 10_000


def test_lobe_peaks_near_the_mirror_direction():
    ex = load("plot_lobe")
    theta_o, f = ex.lobe(vkbrdf.presets(), "gold", 45.0, backend="reference")
    assert f.shape == (721, 3)
    peak = np.degrees(theta_o[np.argmax(f[:, 0])])
    assert 40.0 <= peak <= 65.0  # at or beyond the mirror angle (off-specular shift)
    assert np.all(f[theta_o < -np.radians(80)] < f.max() / 10)
