"""The tables of ``vkbrdf table`` as NumPy arrays, with the CLI's options as keywords."""

import os as _os
import re as _re

from . import _native
from ._errors import TableError as _TableError
from ._errors import UsageError as _UsageError

__all__ = ["albedo", "dfg", "slice"]

DEFAULT_SAMPLES = _native.DEFAULT_SAMPLES


def _size(size):
    """(width, height) from N, "WxH" / "N", or (W, H)."""
    if isinstance(size, str):
        m = _re.fullmatch(r"\s*(\d+)\s*(?:[xX×]\s*(\d+)\s*)?", size)
        if not m:
            raise _TableError(f"table size `{size}` is not of the form WxH (e.g. 32x32) or N")
        w = int(m.group(1))
        return w, int(m.group(2)) if m.group(2) else w
    if isinstance(size, int):
        return size, size
    try:
        w, h = size
        return int(w), int(h)
    except (TypeError, ValueError):
        raise _UsageError(f"size: expected N, 'WxH' or (W, H), found {size!r}") from None


def _checked_size(size):
    w, h = _size(size)
    if w < 1 or h < 1:
        raise _TableError(f"table size {w}x{h} has no texels; give W and H of at least 1")
    return w, h


def _materials(materials):
    if materials is None:
        return _native.presets()
    if isinstance(materials, _native.Materials):
        return materials
    return _native.load_materials(_os.fspath(materials))


def slice(material, materials=None, *, size="90x90", linear=False, terms=False, backend="auto"):
    """f over half/difference angles (theta_h, theta_d) at phi_d = 90 degrees, as
    ``vkbrdf table slice`` computes it; see the stub for the layout."""
    table = _materials(materials)
    index = table.index(material) if isinstance(material, str) else int(material)
    if not 0 <= index < len(table):
        raise _UsageError(f"material index {index} is out of range 0..{len(table)}")
    w, h = _checked_size(size)
    f, t = _native.table_slice(table, index, w, h, bool(linear), bool(terms), str(backend))
    return (f, t) if terms else f


def albedo(
    *,
    distribution="ggx",
    geometry="smith-correlated",
    size="32x32",
    samples=DEFAULT_SAMPLES,
    average=False,
    backend="auto",
):
    """Directional albedo E(mu, alpha) of Cook-Torrance with F = 1, as ``vkbrdf table
    albedo`` computes it; with ``average=True`` also E_avg(alpha)."""
    w, h = _checked_size(size)
    e, avg = _native.table_albedo(
        str(distribution), str(geometry), w, h, int(samples), bool(average), str(backend)
    )
    return (e, avg) if average else e


def dfg(*, distribution="ggx", geometry="smith-correlated", size="32x32", samples=DEFAULT_SAMPLES, backend="auto"):
    """The split-sum DFG table (Karis 2013): ``[..., 0]`` = A (scale), ``[..., 1]`` = B
    (bias), as ``vkbrdf table dfg`` computes it."""
    w, h = _checked_size(size)
    return _native.table_dfg(str(distribution), str(geometry), w, h, int(samples), str(backend))
