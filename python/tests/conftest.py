"""Shared fixtures: the repository, the CLI built from it, a materials file and tuples."""

import os
import pathlib
import subprocess

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]

# The README's two materials, plus an anisotropic one (needs tangents) and a Lambertian.
MATERIALS_TOML = """
[[material]]
name = "rough-gold"
preset = "gold"
roughness = 0.5

[[material]]
name = "seed-plastic"
model = "cook-torrance"
convention = "seed"
distribution = "beckmann"
roughness = 0.3
geometry = "cook-torrance"
fresnel = "dielectric"
ior = 1.5
diffuse = [0.8, 0.1, 0.1]
diffuse_weight = 0.9
specular_weight = 0.1

[[material]]
name = "brushed"
model = "cook-torrance"
distribution = "ggx"
roughness = [0.1, 0.4]
geometry = "smith-correlated"
fresnel = "schlick"
f0 = [0.9, 0.6, 0.3]

[[material]]
name = "matte"
model = "lambert"
diffuse = 0.5
"""


@pytest.fixture(scope="session")
def cli():
    """The `vkbrdf` binary of this checkout (VKBRDF_CLI overrides; CI builds it first)."""
    path = pathlib.Path(os.environ.get("VKBRDF_CLI", ROOT / "target" / "release" / "vkbrdf"))
    if not path.exists():
        subprocess.run(["cargo", "build", "--release", "--bin", "vkbrdf"], cwd=ROOT, check=True)
    return str(path)


@pytest.fixture(scope="session")
def materials_file(tmp_path_factory):
    p = tmp_path_factory.mktemp("materials") / "m.toml"
    p.write_text(MATERIALS_TOML)
    return p


def make_tuples(n, seed=7, tangents=True, material_count=4, invalid=True):
    """Seeded tuples: unnormalised directions around +z (some below the horizon), a few
    invalid rows (NaN, zero vectors) when asked, every material."""
    rng = np.random.default_rng(seed)
    cols = 13 if tangents else 10
    t = np.zeros((n, cols), dtype=np.float64)
    t[:, 0:3] = rng.normal(size=(n, 3)) * [1, 1, 0.5] + [0, 0, 0.6]
    t[:, 3:6] = rng.normal(size=(n, 3)) * [1, 1, 0.5] + [0, 0, 0.6]
    t[:, 6:9] = rng.normal(size=(n, 3)) * 0.1 + [0, 0, 1]
    t[:, 9] = rng.integers(0, material_count, n)
    if tangents:
        t[:, 10:13] = np.cross(t[:, 6:9], [0.0, 1.0, 0.0])
    if invalid and n >= 8:
        t[3, 0] = np.nan
        t[5, 3:6] = 0.0
    return t
