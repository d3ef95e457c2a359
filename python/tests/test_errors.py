"""Every error path: a vkbrdf.Error subclass that is also the built-in a user catches,
carrying the CLI's message."""

import os
import subprocess
import sys

import numpy as np
import pytest

import vkbrdf
from conftest import MATERIALS_TOML, make_tuples


@pytest.fixture(scope="module")
def mats():
    return vkbrdf.parse_materials(MATERIALS_TOML, "m.toml")


def test_malformed_toml():
    with pytest.raises(vkbrdf.MaterialError) as e:
        vkbrdf.parse_materials("[[material]]\nname = 'x'\nmodel = 'lambert'\ndiffuse = [2, 0]\n", "bad.toml")
    assert isinstance(e.value, ValueError) and isinstance(e.value, vkbrdf.Error)
    assert str(e.value).startswith("bad.toml:4: material `x`: key `diffuse`:")
    assert (e.value.source, e.value.line, e.value.material, e.value.key) == ("bad.toml", 4, "x", "diffuse")
    with pytest.raises(ValueError, match="bad.toml"):
        vkbrdf.parse_materials("[[material]\n", "bad.toml")
    with pytest.raises(vkbrdf.MaterialError, match="unknown"):
        vkbrdf.parse_materials("[[material]]\nname = 'x'\nmodel = 'nope'\n")


def test_material_file_errors(tmp_path):
    with pytest.raises(FileNotFoundError) as e:
        vkbrdf.load_materials(tmp_path / "missing.toml")
    assert isinstance(e.value, vkbrdf.FileError) and isinstance(e.value, vkbrdf.Error)
    assert e.value.filename == str(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[[material]]\nname = 'x'\nmodel = 'phong'\nexponent = -1\n")
    with pytest.raises(vkbrdf.MaterialError, match=r"bad\.toml:4: material `x`: key `exponent`"):
        vkbrdf.load_materials(bad)
    with pytest.raises(OSError):
        vkbrdf.load_materials(tmp_path)  # a directory


def test_unknown_material_name(mats):
    with pytest.raises(vkbrdf.MaterialError, match="`nope` is not defined in m.toml; it defines: rough-gold"):
        vkbrdf.evaluate(mats, l=[0, 0, 1], v=[0, 0, 1], n=[0, 0, 1], material="nope")
    with pytest.raises(vkbrdf.MaterialError, match="`nope` is not defined"):
        vkbrdf.evaluate(mats, l=[0, 0, 1], v=[0, 0, 1], n=[0, 0, 1], material=np.array(["matte", "nope"]))


@pytest.mark.parametrize(
    "tuples, message",
    [
        (np.zeros((4, 7), np.float32), "expected 10 columns .* found 7"),
        (np.zeros(10, np.float32), r"expected a 2-D array .* found shape \(10,\)"),
        (np.zeros((2, 10), np.complex64), "dtype complex64 is not supported"),
        (np.array([[0, 0, 1, 0, 0, 1, 0, 0, 1, 9]], np.float32), "row 0: material value 9 is not an integer index in 0..4"),
        (np.array([[0, 0, 1, 0, 0, 1, 0, 0, 1, 0.5]], np.float32), "row 0: material value 0.5"),
        (np.array([[0, 0, 1, 0, 0, 1, 0, 0, 1, np.nan]], np.float32), "row 0: material value NaN"),
    ],
)
def test_wrong_tuples(mats, tuples, message):
    with pytest.raises(vkbrdf.BatchError, match=message) as e:
        vkbrdf.evaluate(mats, tuples, backend="cpu")
    assert isinstance(e.value, ValueError)


def test_anisotropic_without_tangents(mats):
    t = make_tuples(16, tangents=False)
    t[:, 9] = 2  # brushed
    with pytest.raises(vkbrdf.BatchError, match="brushed"):
        vkbrdf.evaluate(mats, t, backend="cpu")


def test_shapes_that_do_not_broadcast(mats):
    with pytest.raises(vkbrdf.BatchError, match="do not broadcast"):
        vkbrdf.evaluate(mats, l=np.zeros((4, 3)), v=np.zeros((5, 3)), n=[0, 0, 1])
    with pytest.raises(vkbrdf.BatchError, match=r"l: expected an array of shape \(\.\.\., 3\)"):
        vkbrdf.evaluate(mats, l=np.zeros((4, 2)), v=[0, 0, 1], n=[0, 0, 1])
    with pytest.raises(vkbrdf.UsageError):
        vkbrdf.evaluate(mats, make_tuples(4), l=[0, 0, 1])
    with pytest.raises(vkbrdf.UsageError):
        vkbrdf.evaluate(mats, l=[0, 0, 1])
    with pytest.raises(vkbrdf.UsageError, match="vkbrdf.Materials"):
        vkbrdf.evaluate("m.toml", make_tuples(4))


def test_nan_directions_counted_or_strict(mats):
    t = make_tuples(32)
    f, c = vkbrdf.evaluate(mats, t, backend="cpu", return_counts=True)
    assert c.invalid == 2 and c.first_invalid == 3 and np.all(f[3] == 0)
    with pytest.raises(vkbrdf.BatchError, match=r"2 of 32 tuples are invalid .*first invalid row: 3") as e:
        vkbrdf.evaluate(mats, t, backend="cpu", strict=True)
    assert (e.value.invalid, e.value.total, e.value.first_invalid) == (2, 32, 3)
    ok = make_tuples(32, invalid=False)
    assert vkbrdf.evaluate(mats, ok, backend="cpu", strict=True).shape == (32, 3)


def test_bad_keyword_values(mats):
    t = make_tuples(4)
    with pytest.raises(vkbrdf.UsageError, match="unknown backend `gpu`; expected one of: auto, vulkan, cpu, reference"):
        vkbrdf.evaluate(mats, t, backend="gpu")
    with pytest.raises(ValueError, match="precision"):
        vkbrdf.evaluate(mats, t, precision="approximate")
    with pytest.raises(vkbrdf.UsageError, match="distribution: unknown `ggxx`"):
        vkbrdf.tables.albedo(distribution="ggxx")
    with pytest.raises(vkbrdf.Error, match="smith-fast"):
        vkbrdf.tables.dfg(geometry="smith-fast", samples=16, size=2)
    with pytest.raises(vkbrdf.TableError, match="has no texels"):
        vkbrdf.tables.slice("gold", size="0x4")
    with pytest.raises(vkbrdf.TableError, match="not of the form"):
        vkbrdf.tables.slice("gold", size="4y4")
    with pytest.raises(vkbrdf.UsageError, match="samples"):
        vkbrdf.tables.albedo(samples=0, size=2)
    presets = len(vkbrdf.presets())
    with pytest.raises(vkbrdf.UsageError, match=f"material index -1 is out of range 0..{presets}"):
        vkbrdf.tables.slice(-1)
    with pytest.raises(vkbrdf.MaterialError, match="`tin` is not defined in the presets"):
        vkbrdf.tables.slice("tin")


def test_vulkan_unavailable_is_device_error(tmp_path):
    # In a fresh process whose Vulkan loader finds no driver.
    code = (
        "import vkbrdf, numpy as np\n"
        "m = vkbrdf.presets()\n"
        "try:\n"
        "    vkbrdf.evaluate(m, l=[0,0,1], v=[0,0,1], n=[0,0,1], material='gold', backend='vulkan')\n"
        "except vkbrdf.DeviceError as e:\n"
        "    assert isinstance(e, RuntimeError)\n"
        "    print('DeviceError:', e)\n"
        # auto falls back to the native CPU engine, as the CLI does
        "f = vkbrdf.evaluate(m, l=[0,0,1], v=[0,0,1], n=[0,0,1], material='gold', backend='auto')\n"
        "print('auto ok', f.shape)\n"
    )
    env = dict(os.environ, VK_DRIVER_FILES=str(tmp_path / "no-such-icd.json"), VK_ICD_FILENAMES=str(tmp_path / "no-such-icd.json"))
    env.pop("VKBRDF_DEVICE", None)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert r.returncode == 0, r.stderr
    assert "DeviceError:" in r.stdout and "auto ok (3,)" in r.stdout


def test_table_sizes_beyond_memory_raise_memory_error_not_abort():
    # Each would need far more than any machine's memory: refused before allocating,
    # as a MemoryError the caller can catch (these aborted or were OOM-killed before).
    with pytest.raises(MemoryError, match="memory"):
        vkbrdf.tables.slice("gold", size=100000, backend="cpu")
    with pytest.raises(MemoryError, match="memory"):
        vkbrdf.tables.dfg(size=100000, samples=1, backend="cpu")
    with pytest.raises(MemoryError, match="memory"):
        vkbrdf.tables.albedo(size=(100000, 100000), samples=1, backend="cpu")


def test_check_with_a_filter_that_matches_nothing_is_an_error():
    with pytest.raises(vkbrdf.UsageError, match="matches no combination"):
        vkbrdf.check(backend="cpu", only="nomatch")
    with pytest.raises(vkbrdf.UsageError, match="out of range"):
        vkbrdf.check(backend="cpu", tuples=10**12)


def test_broadcast_form_needs_a_material_when_the_table_has_several(mats):
    assert len(mats) > 1
    with pytest.raises(vkbrdf.UsageError, match="say which with material="):
        vkbrdf.evaluate(mats, l=[0, 0, 1], v=[0, 0, 1], n=[0, 0, 1], backend="cpu")
    one = vkbrdf.parse_materials("[[material]]\nname = 'm'\nmodel = 'lambert'\ndiffuse = 0.5\n")
    f = vkbrdf.evaluate(one, l=[0, 0, 1], v=[0, 0, 1], n=[0, 0, 1], backend="cpu")
    assert np.allclose(f, 0.5 / np.pi)


def test_integer_tuples_are_converted_as_numpy_would():
    one = vkbrdf.parse_materials("[[material]]\nname = 'm'\nmodel = 'lambert'\ndiffuse = 0.5\n")
    rows = [[0, 0, 1, 0, 0, 1, 0, 0, 1, 0]]
    f = vkbrdf.evaluate(one, rows, backend="cpu")
    g = vkbrdf.evaluate(one, np.asarray(rows, dtype=np.float32), backend="cpu")
    assert np.array_equal(f, g)


def test_help_shows_the_stubs_full_docstring():
    assert "Two forms" in vkbrdf.evaluate.__doc__
    assert len(vkbrdf.evaluate.__doc__.splitlines()) > 10


def test_a_pickled_file_loaded_table_keeps_its_materials_when_the_file_changes(tmp_path):
    import pickle

    f = tmp_path / "m.toml"
    f.write_text("[[material]]\nname = 'a'\nmodel = 'lambert'\ndiffuse = 0.5\n")
    m = vkbrdf.load_materials(f)
    data = pickle.dumps(m)
    f.write_text("[[material]]\nname = 'b'\nmodel = 'lambert'\ndiffuse = 0.25\n")
    back = pickle.loads(data)
    assert back.names == ["a"]
