"""vkbrdf: bulk BRDF evaluation -- NumPy arrays in, NumPy arrays out, on the same engines
as the ``vkbrdf`` command (the Vulkan kernel, the native CPU engine, the f64 reference).

See ``docs/PYTHON.md`` and the stubs (``__init__.pyi``) for the API with examples.
"""

import collections as _collections
import os as _os

import numpy as _np

from . import _native
from ._errors import (
    BatchError,
    DeviceError,
    Error,
    FileError,
    FileMissingError,
    FilePermissionError,
    MaterialError,
    TableError,
    UsageError,
)
from ._native import Materials, presets
from . import tables

__version__ = _native.__version__

__all__ = [
    "BatchError",
    "Counts",
    "DeviceError",
    "Error",
    "FileError",
    "FileMissingError",
    "FilePermissionError",
    "MaterialError",
    "Materials",
    "TableError",
    "UsageError",
    "check",
    "evaluate",
    "fit",
    "load_materials",
    "parse_materials",
    "presets",
    "tables",
]

Counts = _collections.namedtuple(
    "Counts", ["invalid", "below_horizon", "saturated", "first_invalid"]
)
Counts.__doc__ = """Tuple counts of one evaluation (``return_counts=True``): invalid tuples (zero or
non-finite L, V, N, or a bad tangent; their f is 0), valid tuples below the horizon (f is
0), tuples with an output beyond float32's range (saturated to its largest value), and the
row of the first invalid tuple (``None`` when there is none; in the broadcasting form an
index into the flattened broadcast shape)."""


def load_materials(path):
    """Reads a materials file (TOML, ``[[material]]`` tables) into a :class:`Materials`."""
    return _native.load_materials(_os.fspath(path))


def parse_materials(text, source="<string>"):
    """Parses materials from TOML text; ``source`` names it in error messages."""
    return _native.parse_materials(text, source)


def _rebuild_materials(kind, payload, source):
    """Unpickles a Materials (see ``Materials.__reduce__``)."""
    if kind == "text":
        return _native.parse_materials(payload, source)
    if kind == "file":
        return _native.materials_from_file_text(payload, source)
    return _native.presets()


_FLOATS = (_np.dtype(_np.float32), _np.dtype(_np.float64))


def _tuples_array(tuples):
    a = _np.asarray(tuples)
    if a.dtype.kind in "iu":
        # Integers (a list of ints, an int array), converted as NumPy converts them, as the
        # l=, v=, n= form accepts them.
        a = a.astype(_np.float32)
    if a.dtype not in _FLOATS:
        raise BatchError(
            f"tuples: dtype {a.dtype} is not supported; expected float32 or float64 "
            "(as `vkbrdf eval` reads)"
        )
    if a.ndim != 2:
        raise BatchError(
            f"tuples: expected a 2-D array of shape (n, 10) or (n, 13), found shape {a.shape}"
        )
    # No copy when the array already is C-contiguous, aligned float32: the engine reads it in
    # place. (Arrays unpickled from a byte stream, as Dask workers receive them, may be
    # misaligned: those are copied.) float64 is rounded to float32 (nearest even), as
    # `vkbrdf eval` rounds a float64 file.
    return _np.require(a, dtype=_np.float32, requirements=["C_CONTIGUOUS", "ALIGNED"])


def _vectors(name, x):
    a = _np.asarray(x)
    if a.dtype.kind not in "fiu":
        raise BatchError(f"{name}: dtype {a.dtype} is not a real number type")
    if a.ndim == 0 or a.shape[-1] != 3:
        raise BatchError(f"{name}: expected an array of shape (..., 3), found shape {a.shape}")
    return a


def _material_indices(materials, material):
    if isinstance(material, str):
        return materials.index(material)
    m = _np.asarray(material)
    if m.dtype.kind == "U":
        lookup = {name: i for i, name in enumerate(materials.names)}
        missing = sorted({str(x) for x in m.ravel() if str(x) not in lookup})
        if missing:
            raise MaterialError(
                f"material `{missing[0]}` is not defined in {materials.source}; "
                f"it defines: {', '.join(materials.names)}"
            )
        return _np.vectorize(lookup.__getitem__, otypes=[_np.int64])(m)
    if m.dtype.kind not in "iu":
        raise BatchError(f"material: expected an index, a name or an integer array, found dtype {m.dtype}")
    return m


def _broadcast_columns(materials, l, v, n, t, material):
    """The directions and materials as columns: each a C-contiguous float32 ``(k, 3)``
    (``(k,)`` for the material) with k 1 (one for every row) or the row count; and the
    broadcast shape."""
    vecs = [_vectors("l", l), _vectors("v", v), _vectors("n", n)]
    if t is not None:
        vecs.append(_vectors("t", t))
    try:
        _np.broadcast_shapes(*(a.shape[:-1] for a in vecs))
    except ValueError as e:
        shapes = ", ".join(str(a.shape) for a in vecs)
        raise BatchError(
            f"l, v, n{', t' if t is not None else ''}: shapes {shapes} do not broadcast ({e})"
        ) from None
    if material is None:
        # No silent material 0 of a table of several (the CLI's 6-column form refuses a
        # multi-material file without --material too).
        if len(materials) != 1:
            raise UsageError(
                f"materials holds {len(materials)} materials ({materials.source}); say which with "
                "material=NAME, an index, or an array of them"
            )
        material = 0
    m = _material_indices(materials, material)
    try:
        shape = _np.broadcast_shapes(*(a.shape[:-1] for a in vecs), _np.shape(m))
    except ValueError as e:
        shapes = ", ".join(str(a.shape) for a in vecs)
        raise BatchError(
            f"l, v, n{', t' if t is not None else ''}, material: shapes {shapes}, {_np.shape(m)} "
            f"do not broadcast ({e})"
        ) from None

    def column(a, width):
        # One value for every row stays one; the rest are laid out a row each (a view
        # where NumPy can, the float32 rounding `vkbrdf eval` gives a float64 file).
        a = _np.asarray(a)
        if a.ndim == (1 if width else 0):
            return _np.ascontiguousarray(a, dtype=_np.float32).reshape((1, width) if width else (1,))
        full = _np.broadcast_to(a, shape + ((width,) if width else ()))
        return _np.ascontiguousarray(full.reshape((-1, width) if width else (-1,)), dtype=_np.float32)

    return [column(a, 3) for a in vecs], column(m, 0), shape


def _broadcast_rows(materials, l, v, n, t, material):
    columns, m, shape = _broadcast_columns(materials, l, v, n, t, material)
    count = int(_np.prod(shape, dtype=_np.int64))
    cols = 13 if t is not None else 10
    rows = _np.empty((count, cols), dtype=_np.float32)
    for k, a in enumerate(columns[:3]):
        rows[:, 3 * k : 3 * k + 3] = a
    rows[:, 9] = m
    if t is not None:
        rows[:, 10:13] = columns[3]
    return rows, shape


def evaluate(
    materials,
    tuples=None,
    *,
    l=None,
    v=None,
    n=None,
    t=None,
    material=None,
    backend="auto",
    terms=False,
    precision="exact",
    strict=False,
    return_counts=False,
    spike=False,
    wavelengths=None,
    color=None,
    illuminant="d65",
):
    """Evaluates the BRDF; see the stub (``vkbrdf/__init__.pyi``) for the full description."""
    if not isinstance(materials, Materials):
        raise UsageError(
            f"materials: expected a vkbrdf.Materials (load_materials, parse_materials, presets), "
            f"found {type(materials).__name__}"
        )
    if tuples is not None:
        if any(x is not None for x in (l, v, n, t)):
            raise UsageError("give either tuples or l=, v=, n= (and t=), not both")
        rows, shape = _tuples_array(tuples), None
    else:
        if l is None or v is None or n is None:
            raise UsageError("give tuples, or the directions l=, v= and n=")
        if wavelengths is None and color is None and not spike:
            # The columns go to the engine as they are: no (n, 10) array is built.
            columns, m, shape = _broadcast_columns(materials, l, v, n, t, material)
            count = int(_np.prod(shape, dtype=_np.int64))
            f, term_values, counts, _in_place = _native.evaluate_columns(
                materials, count, *columns[:3], columns[3] if t is not None else None, m,
                str(backend), bool(terms), str(precision), bool(strict),
            )
            return _results(f, term_values, None, counts, shape, terms, return_counts)
        rows, shape = _broadcast_rows(materials, l, v, n, t, material)
    if wavelengths is not None or color is not None:
        if terms or spike:
            raise UsageError(
                "wavelengths=/color=: a spectral evaluation returns f(λ) only; the terms and "
                "the spike are RGB outputs (evaluate them without wavelengths)"
            )
        if wavelengths is not None and not isinstance(wavelengths, str):
            wavelengths = ",".join(repr(float(x)) for x in _np.ravel(wavelengths))
        f, counts = _native.evaluate_spectral(
            materials, rows, str(backend), wavelengths, color, str(illuminant),
            str(precision), bool(strict),
        )
        if shape is not None:
            f = f.reshape(shape + (f.shape[1],))
        return (f, Counts(*counts)) if return_counts else f
    f, term_values, counts, _in_place = _native.evaluate(
        materials, rows, str(backend), bool(terms), str(precision), bool(strict)
    )
    weights = _native.spike(materials, rows) if spike else None
    return _results(f, term_values, weights, counts, shape, terms, return_counts)


def _results(f, term_values, weights, counts, shape, terms, return_counts):
    """What `evaluate` returns: f, then the terms, the spike's weights and the counts where
    asked for, each shaped as the broadcast inputs (``shape``) when they were."""
    if shape is not None:
        f = f.reshape(shape + (3,))
        if term_values is not None:
            term_values = term_values.reshape(shape + (6,))
        if weights is not None:
            weights = weights.reshape(shape + (3,))
    result = [f]
    if terms:
        result.append(term_values)
    if weights is not None:
        result.append(weights)
    if return_counts:
        result.append(Counts(*counts))
    return result[0] if len(result) == 1 else tuple(result)


def check(*, backend="vulkan", tuples=2000, seed=1, only=None):
    """Runs ``vkbrdf check`` (every legal model combination against the f64 reference) and
    returns its report as a list of dicts, one per combination."""
    return _native.check(str(backend), int(tuples), int(seed), only)



def fit(
    materials,
    material,
    *,
    free,
    merl=None,
    tuples=None,
    values=None,
    loss="l2",
    backend="auto",
    starts=8,
    seed=1,
    max_theta=None,
):
    """Fits a material's free parameters to measured data; see the stub (``vkbrdf/__init__.pyi``)."""
    if not isinstance(materials, Materials):
        raise UsageError(
            f"materials: expected a vkbrdf.Materials (load_materials, parse_materials, presets), "
            f"found {type(materials).__name__}"
        )
    if isinstance(free, str):
        free = [p for p in free.split(",") if p.strip()]
    arrays = []
    for name, a in (("tuples", tuples), ("values", values)):
        if a is not None:
            a = _np.ascontiguousarray(a, dtype=_np.float32)
            if a.ndim != 2:
                raise BatchError(f"{name}: must be 2-D; shape {a.shape}")
        arrays.append(a)
    result = _native.fit(
        materials,
        str(material),
        [str(p).strip() for p in free],
        None if merl is None else _os.fspath(merl),
        arrays[0],
        arrays[1],
        str(loss),
        str(backend),
        int(starts),
        int(seed),
        None if max_theta is None else float(max_theta),
    )
    result["material"] = parse_materials(result["toml"], source="vkbrdf.fit")
    return result


def _docstrings_from_the_stub():
    """The functions' full docstrings live in the stub (``__init__.pyi``, which type
    checkers and IDEs read); ``help()`` shows them too."""
    import ast
    import pathlib

    stub = pathlib.Path(__file__).with_name("__init__.pyi")
    try:
        tree = ast.parse(stub.read_text(encoding="utf-8"))
    except OSError:
        return
    seen = set()
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and node.name not in seen:
            doc = ast.get_docstring(node)
            target = globals().get(node.name)
            if doc and callable(target) and getattr(target, "__module__", "") == __name__:
                seen.add(node.name)
                target.__doc__ = doc


_docstrings_from_the_stub()
