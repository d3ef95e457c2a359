"""vkbrdf.fit: known parameters come back from values made with them; bad input is an error."""

import numpy as np
import pytest

import vkbrdf

TOML = (
    '[[material]]\nname = "s"\nmodel = "cook-torrance"\ndistribution = "ggx"\n'
    'geometry = "smith-correlated"\nfresnel = "schlick"\nf0 = 0.04\nroughness = {r}\n'
    "diffuse = [0.2, 0.3, 0.4]\ndiffuse_weight = 1.0\n"
)


def rows(n=20000, seed=1):
    rng = np.random.default_rng(seed)
    t = np.zeros((n, 10), np.float32)
    t[:, 8] = 1.0  # N = +z, material 0
    for k in (0, 3):
        d = rng.normal(size=(n, 3))
        d[:, 2] = np.abs(d[:, 2]) + 1e-3
        t[:, k : k + 3] = d
    return t


def test_a_fit_recovers_the_parameters_that_made_the_values():
    t = rows()
    f = vkbrdf.evaluate(vkbrdf.parse_materials(TOML.format(r=0.25)), t, backend="cpu")
    start = vkbrdf.parse_materials(TOML.format(r=0.6).replace("[0.2, 0.3, 0.4]", "[0.5, 0.5, 0.5]"))
    r = vkbrdf.fit(start, "s", free="roughness,diffuse,specular", tuples=t, values=f, backend="cpu", starts=2)
    assert abs(r["parameters"]["roughness"][0] / 0.25 - 1) < 0.01, r["parameters"]
    assert np.allclose(r["parameters"]["diffuse"], [0.2, 0.3, 0.4], rtol=0.01), r["parameters"]
    assert r["metrics"]["l2_relative"] < 1e-6, r["metrics"]
    assert set(r["metrics"]) == {"l2", "l2_relative", "e1", "e2", "rrms", "energy"}
    # The fitted material evaluates as the data did.
    again = vkbrdf.evaluate(r["material"], t, backend="cpu")
    assert np.allclose(again, f, rtol=1e-3, atol=1e-6)
    assert r["samples"] == len(t) and r["evaluations"] > 0


def test_bad_input_is_a_clear_error():
    t = rows(100)
    f = np.ones((100, 3), np.float32)
    m = vkbrdf.parse_materials(TOML.format(r=0.3))
    with pytest.raises(vkbrdf.Error, match="no free parameter"):
        vkbrdf.fit(m, "s", free=[], tuples=t, values=f, backend="cpu")
    with pytest.raises(vkbrdf.Error, match="unknown parameter"):
        vkbrdf.fit(m, "s", free="shininess", tuples=t, values=f, backend="cpu")
    with pytest.raises(vkbrdf.Error, match="give the data"):
        vkbrdf.fit(m, "s", free="roughness", backend="cpu")
    bad = f.copy()
    bad[7, 1] = np.nan
    with pytest.raises(vkbrdf.Error, match="7"):
        vkbrdf.fit(m, "s", free="roughness", tuples=t, values=bad, backend="cpu")
    with pytest.raises(vkbrdf.Error, match="values"):
        vkbrdf.fit(m, "s", free="roughness", tuples=t, values=f[:, :2], backend="cpu")
    with pytest.raises(vkbrdf.MaterialError):
        vkbrdf.fit(m, "nope", free="roughness", tuples=t, values=f, backend="cpu")
