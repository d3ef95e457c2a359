"""The NumPy conventions: dtypes, layouts, broadcasting, return forms, materials, tables."""

import tracemalloc

import numpy as np
import pytest

import vkbrdf
from conftest import MATERIALS_TOML, make_tuples


@pytest.fixture(scope="module")
def mats():
    return vkbrdf.parse_materials(MATERIALS_TOML, "m.toml")


def test_materials_object(mats):
    assert len(mats) == 4
    assert mats.names == ["rough-gold", "seed-plastic", "brushed", "matte"]
    assert mats.models == ["cook-torrance", "cook-torrance", "cook-torrance", "lambert"]
    assert mats.anisotropic == [False, False, True, False]
    assert mats.index("matte") == 3
    assert "brushed: cook-torrance" in repr(mats) and "m.toml" in repr(mats)
    p = vkbrdf.presets()
    assert "gold" in p.names and len(p) == len(p.models) >= 5


def test_float32_float64_and_non_contiguous_agree(mats):
    t64 = make_tuples(500)
    t32 = t64.astype(np.float32)
    f32 = vkbrdf.evaluate(mats, t32, backend="cpu")
    # float64 is rounded to float32 exactly as a float64 .npy is by `vkbrdf eval`.
    assert np.array_equal(vkbrdf.evaluate(mats, t64, backend="cpu"), f32)
    # Fortran order, a strided view and a reversed view: same rows, same values.
    assert np.array_equal(vkbrdf.evaluate(mats, np.asfortranarray(t32), backend="cpu"), f32)
    wide = np.zeros((500, 26), np.float32)
    wide[:, ::2] = t32
    assert not wide[:, ::2].flags.c_contiguous
    assert np.array_equal(vkbrdf.evaluate(mats, wide[:, ::2], backend="cpu"), f32)
    assert np.array_equal(vkbrdf.evaluate(mats, t32[::-1], backend="cpu"), f32[::-1])


def test_c_contiguous_float32_is_not_copied(mats):
    # 2M rows of 10 float32 = 80 MB: a copy would show in NumPy's traced allocations
    # (the engine's outputs are allocated by Rust and handed over, not traced).
    t = np.zeros((2_000_000, 10), np.float32)
    t[:, 2] = t[:, 5] = t[:, 8] = 1.0
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        f = vkbrdf.evaluate(mats, t, backend="cpu")
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert f.shape == (2_000_000, 3)
    assert peak < 8_000_000, f"{peak} bytes traced: the tuples were copied"
    # The same check does see a copy (float64 input is converted to float32).
    tracemalloc.start()
    try:
        t64 = t[:200_000].astype(np.float64)
        tracemalloc.reset_peak()
        vkbrdf.evaluate(mats, t64, backend="cpu")
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak >= 200_000 * 10 * 4


def test_misaligned_float32_is_evaluated(mats):
    # A float32 array one byte off alignment (as unpickled buffers can be) is copied first.
    t = make_tuples(100).astype(np.float32)
    raw = bytearray(t.nbytes + 1)
    mis = np.frombuffer(raw, dtype=np.float32, offset=1, count=t.size).reshape(t.shape)
    mis[...] = t
    assert not mis.flags.aligned and mis.flags.c_contiguous
    assert np.array_equal(vkbrdf.evaluate(mats, mis, backend="cpu"), vkbrdf.evaluate(mats, t, backend="cpu"))


def test_native_reads_in_place(mats):
    t = make_tuples(10).astype(np.float32)
    *_, in_place = vkbrdf._native.evaluate(mats, t, "cpu", False, "exact", False)
    assert in_place is True


def test_return_forms(mats):
    t = make_tuples(64)
    f = vkbrdf.evaluate(mats, t, backend="reference")
    assert isinstance(f, np.ndarray) and f.shape == (64, 3)
    f2, terms = vkbrdf.evaluate(mats, t, backend="reference", terms=True)
    assert np.array_equal(f, f2) and terms.shape == (64, 6)
    f3, counts = vkbrdf.evaluate(mats, t, backend="reference", return_counts=True)
    assert np.array_equal(f, f3)
    assert isinstance(counts, vkbrdf.Counts) and counts._fields == (
        "invalid", "below_horizon", "saturated", "first_invalid")
    assert counts.invalid == 2 and counts.first_invalid == 3
    f4, terms4, counts4 = vkbrdf.evaluate(mats, t, backend="reference", terms=True, return_counts=True)
    assert np.array_equal(terms, terms4) and counts4 == counts
    # Invalid tuples give 0.
    assert np.all(f[[3, 5]] == 0)
    # An empty batch is fine.
    assert vkbrdf.evaluate(mats, np.zeros((0, 10), np.float32)).shape == (0, 3)


def test_broadcast_columns_equal_rows_across_chunks(mats):
    # The broadcast form goes to the engine as columns, gathered 262,144 rows at a time:
    # 600,001 rows cross two chunk boundaries. Same bits, counts, first invalid row and
    # errors as the same rows given as one array, on each engine.
    rng = np.random.default_rng(7)
    count = 600_001
    L = rng.normal(size=(count, 3))
    L[300_000] = 0.0  # invalid, in the second chunk
    V = np.array([0.3, 0.0, 0.95])
    N = rng.normal(size=(count, 3)) * [0.1, 0.1, 1.0] + [0, 0, 3.0]
    m = rng.integers(0, 4, size=count)
    m[m == 2] = 0  # `brushed` is anisotropic: it gets its own run with t= below
    for backend in ["cpu", "reference"]:
        f, terms, c = vkbrdf.evaluate(mats, l=L, v=V, n=N, material=m, backend=backend,
                                      terms=True, return_counts=True)
        rows = np.zeros((count, 10), np.float32)
        rows[:, 0:3], rows[:, 3:6], rows[:, 6:9], rows[:, 9] = L, V, N, m
        g, terms_g, c_g = vkbrdf.evaluate(mats, rows, backend=backend, terms=True,
                                          return_counts=True)
        assert np.array_equal(f, g, equal_nan=True) and np.array_equal(terms, terms_g, equal_nan=True)
        assert c == c_g and c.invalid == 1 and c.first_invalid == 300_000
    T = np.array([1.0, 0.0, 0.0])
    f_t = vkbrdf.evaluate(mats, l=L, v=V, n=N, t=T, material="brushed", backend="cpu")
    rows13 = np.zeros((count, 13), np.float32)
    rows13[:, 0:3], rows13[:, 3:6], rows13[:, 6:9], rows13[:, 9], rows13[:, 10:13] = L, V, N, 2, T
    assert np.array_equal(f_t, vkbrdf.evaluate(mats, rows13, backend="cpu"), equal_nan=True)
    with pytest.raises(vkbrdf.BatchError, match="first invalid row: 300000"):
        vkbrdf.evaluate(mats, l=L, v=V, n=N, material=m, backend="cpu", strict=True)
    # An anisotropic material without t= is named at its first row, in a later chunk.
    m2 = np.zeros(count, np.int64)
    m2[540_000] = 2
    with pytest.raises(vkbrdf.BatchError, match="row 540000"):
        vkbrdf.evaluate(mats, l=L, v=V, n=N, material=m2, backend="cpu")


def test_broadcasting_equals_explicit_tuples(mats):
    # A grid of light directions against one view direction and one normal.
    th = np.linspace(0.0, 1.5, 7)
    ph = np.linspace(0.0, 6.0, 5)
    TH, PH = np.meshgrid(th, ph, indexing="ij")
    L = np.stack([np.sin(TH) * np.cos(PH), np.sin(TH) * np.sin(PH), np.cos(TH)], -1)
    V = np.array([0.3, 0.0, 0.95])
    N = [0, 0, 1]
    f = vkbrdf.evaluate(mats, l=L, v=V, n=N, material="rough-gold", backend="cpu")
    assert f.shape == (7, 5, 3)
    rows = np.zeros((35, 10))
    rows[:, 0:3] = L.reshape(-1, 3)
    rows[:, 3:6] = V
    rows[:, 6:9] = N
    rows[:, 9] = 0
    assert np.array_equal(f.reshape(-1, 3), vkbrdf.evaluate(mats, rows, backend="cpu"))
    # material as an integer array broadcasting with the directions (one per phi column),
    # and as an array of names.
    per_col = np.array([0, 1, 3, 0, 1])
    g, c = vkbrdf.evaluate(mats, l=L, v=V, n=N, material=per_col, backend="cpu", return_counts=True)
    rows[:, 9] = np.broadcast_to(per_col, (7, 5)).reshape(-1)
    assert np.array_equal(g.reshape(-1, 3), vkbrdf.evaluate(mats, rows, backend="cpu"))
    names = np.array(mats.names)[per_col]
    assert np.array_equal(vkbrdf.evaluate(mats, l=L, v=V, n=N, material=names, backend="cpu"), g)
    # with a tangent and terms
    f_t, terms = vkbrdf.evaluate(mats, l=L, v=V, n=N, t=[1, 0, 0], material="brushed",
                                 backend="cpu", terms=True)
    assert f_t.shape == (7, 5, 3) and terms.shape == (7, 5, 6)
    rows13 = np.zeros((35, 13))
    rows13[:, :9] = rows[:, :9]
    rows13[:, 9] = 2
    rows13[:, 10:13] = [1, 0, 0]
    assert np.array_equal(f_t.reshape(-1, 3), vkbrdf.evaluate(mats, rows13, backend="cpu"))


def test_tables():
    s, t = vkbrdf.tables.slice("gold", size="8x4", terms=True, backend="reference")
    assert s.shape == (4, 8, 3) and t.shape == (4, 8, 6) and s.dtype == np.float32
    s_cpu = vkbrdf.tables.slice("gold", size=(8, 4), backend="cpu")
    assert np.allclose(s, s_cpu, rtol=1e-4, atol=1e-7)
    # The specular peak: small theta_h (first column) is brighter than grazing theta_h.
    assert np.all(s[:, 0, 0] > s[:, -1, 0])
    e = vkbrdf.tables.albedo(size=(4, 3), samples=4096, backend="cpu")
    ab = vkbrdf.tables.dfg(size=(4, 3), samples=4096, backend="cpu")
    assert e.shape == (3, 4) and ab.shape == (3, 4, 2)
    # E = A + B: the two tables integrate the same f with F = 1.
    assert np.allclose(ab[..., 0] + ab[..., 1], e, rtol=1e-9)
    assert np.all((e > 0) & (e <= 1.0 + 1e-3))
    e2, avg = vkbrdf.tables.albedo(size=(4, 3), samples=4096, average=True, backend="cpu")
    assert np.array_equal(e2, e) and avg.shape == (3,)
    # Smooth GGX with height-correlated Smith at normal incidence loses almost nothing.
    smooth = vkbrdf.tables.albedo(size=(64, 64), samples=1024, backend="cpu")
    assert abs(smooth[0, -1] - 1.0) < 2e-3


def test_check_report_is_data():
    report = vkbrdf.check(backend="cpu", tuples=50, only="lambert")
    assert report and all(r["pass"] for r in report)
    r = report[0]
    assert "lambert" in r["combination"] and r["tuples"] == 50 and r["counts_match"]
    assert set(r["column_max_rel"]) == {"brdf_r", "brdf_g", "brdf_b", "D", "G", "F_r", "F_g", "F_b", "K"}
    assert r["max_used"] <= 1.0


def test_htsg_spike_weights():
    # FORMULAS.md §8: rho_s of the htsg-aluminium preset at theta_i = 30 and 60 degrees,
    # computed independently at 50 digits (docs/HTSG.md).
    p = vkbrdf.presets()
    th = np.radians([30.0, 60.0])
    light = np.stack([np.sin(th), np.zeros(2), np.cos(th)], axis=-1)
    view = light * [-1, -1, 1]
    f, rho_s = vkbrdf.evaluate(
        p, l=light, v=view, n=[0, 0, 1], material="htsg-aluminium", backend="cpu", spike=True
    )
    expected = np.array(
        [[0.683702224937, 0.592876646924, 0.50085854041],
         [0.814313178572, 0.779055711571, 0.741062561454]]
    )
    assert rho_s.shape == (2, 3)
    assert np.allclose(rho_s, expected, rtol=1e-6, atol=0)
    # f is rho_dd here (no diffuse): the mirror value at 30 degrees, green 0.293621038044.
    assert abs(f[0, 1] - 0.293621038044) < 3e-6
    with pytest.raises(vkbrdf.UsageError, match="htsg materials only"):
        vkbrdf.evaluate(p, l=light, v=view, n=[0, 0, 1], material="gold", spike=True)


def test_spectral_gold_matches_numpy_on_the_cie_tables():
    """FORMULAS.md §9: gold's spectral values reduced to sRGB by vkbrdf equal NumPy's own
    quadrature of the same values on the shipped CIE tables (an independent reduction)."""
    import csv
    import os

    root = os.path.join(os.path.dirname(__file__), "..", "..", "src", "spectral", "data")
    with open(os.path.join(root, "cie1931-2deg-5nm.csv")) as f:
        cmf = np.array([[float(x) for x in r[1:]] for r in list(csv.reader(f))[1:]])
    with open(os.path.join(root, "cie-d65-5nm.csv")) as f:
        d65 = np.array([float(r[1]) for r in list(csv.reader(f))[1:]])
    m = vkbrdf.presets()
    th = np.linspace(0, 1.4, 15)
    L = np.stack([np.sin(th), np.zeros_like(th), np.cos(th)], axis=-1)
    V = L * [-1, 1, 1]
    spectra = vkbrdf.evaluate(m, l=L, v=V, n=[0, 0, 1], material="gold-spectral", wavelengths="360:830:5", backend="cpu")
    assert spectra.shape == (15, 95)
    xyz = spectra.astype(np.float64) @ (cmf * d65[:, None]) / (d65 @ cmf[:, 1])
    x, y = 0.3127 / 0.3290, 1.0
    prim = np.array([[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]])
    P = np.stack([prim[:, 0] / prim[:, 1], np.ones(3), (1 - prim.sum(1)) / prim[:, 1]])
    S = np.linalg.solve(P, [x, y, (1 - 0.3127 - 0.3290) / 0.3290])
    srgb = xyz @ np.linalg.inv(P * S).T
    got = vkbrdf.evaluate(m, l=L, v=V, n=[0, 0, 1], material="gold-spectral", color="srgb", backend="cpu")
    assert got.shape == (15, 3)
    np.testing.assert_allclose(got, srgb, rtol=2e-6)
    # Gold's red at normal incidence is above its green and blue, and the F0 ratios are
    # Johnson & Christy's (F0 sRGB 1.0376, 0.7283, 0.3646).
    assert got[0, 0] / got[0, 1] == pytest.approx(1.037638 / 0.728341, rel=1e-4)
    with pytest.raises(vkbrdf.UsageError):
        vkbrdf.evaluate(m, l=L, v=V, n=[0, 0, 1], material="gold-spectral", color="srgb", terms=True)
    with pytest.raises(vkbrdf.UsageError, match="gold-spectral"):
        vkbrdf.evaluate(m, l=L, v=V, n=[0, 0, 1], material="gold", wavelengths=[500, 600])
