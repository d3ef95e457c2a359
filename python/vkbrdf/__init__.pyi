"""vkbrdf: bulk BRDF evaluation -- NumPy arrays in, NumPy arrays out.

The same engines as the ``vkbrdf`` command: the Vulkan compute kernel, the native CPU
engine (f32 SIMD on every core) and the f64 CPU reference; for the same engine and the
same tuples the result equals ``vkbrdf eval``'s output bit for bit.

>>> import numpy as np, vkbrdf
>>> m = vkbrdf.parse_materials('''
... [[material]]
... name = "rough-gold"
... preset = "gold"
... roughness = 0.5
... ''')
>>> f = vkbrdf.evaluate(m, l=[0.3, 0.0, 1.0], v=[0.0, 0.0, 1.0], n=[0.0, 0.0, 1.0])
>>> f.shape, f.dtype
((3,), dtype('float32'))
"""

import os
from typing import Any, Dict, List, NamedTuple, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

from . import tables as tables

__version__: str

_ArrayLike = npt.ArrayLike
_F32 = npt.NDArray[np.float32]
_Path = Union[str, "os.PathLike[str]"]

class Error(Exception):
    """Base class of every error vkbrdf raises (besides ``KeyboardInterrupt``)."""

class MaterialError(Error, ValueError):
    """A materials file or text that does not parse or validate; the message is the
    CLI's, e.g. ``m.toml:4: material `x`: key `diffuse`: expected ...``.

    >>> try:
    ...     vkbrdf.parse_materials("[[material]]\\nname = 'x'\\nmodel = 'phong'\\nexponent = -1", "m.toml")
    ... except ValueError as e:
    ...     print(e.line, e.material, e.key)
    4 x exponent
    """

    source: Optional[str]
    line: Optional[int]
    material: Optional[str]
    key: Optional[str]

class BatchError(Error, ValueError):
    """Tuples that cannot be evaluated: wrong shape or dtype, a material index outside the
    table, an anisotropic material without tangent columns, or, with ``strict=True``,
    invalid tuples (then ``invalid``, ``total`` and ``first_invalid`` are set)."""

    invalid: Optional[int]
    total: Optional[int]
    first_invalid: Optional[int]

class DeviceError(Error, RuntimeError):
    """No usable Vulkan driver or device, or a Vulkan call that failed (the message says
    which call, which chunk and what to try)."""

class TableError(Error, ValueError):
    """A table that cannot be computed: an empty grid, an unknown material, an illegal
    model (``smith-fast`` needs ``beckmann``)."""

class UsageError(Error, ValueError):
    """A keyword value vkbrdf does not accept (backend, precision, distribution...)."""

class FileError(Error, OSError):
    """A file that cannot be read; ``errno``, ``strerror`` and ``filename`` as on OSError."""

class FileMissingError(FileError, FileNotFoundError):
    """A file that does not exist.

    >>> try:
    ...     vkbrdf.load_materials("missing.toml")
    ... except FileNotFoundError as e:
    ...     print(e.filename)
    missing.toml
    """

class FilePermissionError(FileError, PermissionError):
    """A file that may not be read."""

class Materials:
    """A table of materials (``load_materials``, ``parse_materials``, ``presets``). A
    tuple's material column, or ``evaluate(material=...)``, indexes it from 0.

    Immutable and shareable between threads; it pickles (as its TOML text, or as its file
    path, which the receiving process reads again), so it travels to Dask or Ray workers.

    >>> p = vkbrdf.presets()
    >>> p.names[:3]
    ['gold', 'silver', 'copper']
    >>> len(p), p.index("copper")
    (7, 2)
    """

    @property
    def names(self) -> List[str]:
        """The material names, in table order."""
    @property
    def models(self) -> List[str]:
        """Each material's model: lambert, phong, blinn-phong, rtr, ward, cook-torrance, merl."""
    @property
    def anisotropic(self) -> List[bool]:
        """Which materials need a tangent (roughness ``[mx, my]``)."""
    @property
    def source(self) -> str:
        """Where the table came from (file name, ``<string>``, ``the presets``)."""
    def index(self, name: str) -> int:
        """The index of material ``name``; ``MaterialError`` listing the names otherwise."""
    def __len__(self) -> int: ...
    def __repr__(self) -> str: ...

class Counts(NamedTuple):
    """Tuple counts of one evaluation (``return_counts=True``).

    ``first_invalid`` is the row of the first invalid tuple (``None`` if none); in the
    broadcasting form, an index into the flattened broadcast shape
    (``np.unravel_index(c.first_invalid, shape)``).
    """

    invalid: int
    below_horizon: int
    saturated: int
    first_invalid: Optional[int]

def load_materials(path: _Path) -> Materials:
    """Reads a materials file (TOML, one ``[[material]]`` table per material; every key
    and model: docs/MATERIALS.md).

    Raises ``MaterialError`` (a ValueError) naming file, line, material and key, or
    ``FileMissingError`` (a FileNotFoundError).

    >>> m = vkbrdf.load_materials("m.toml")
    >>> m.names
    ['rough-gold', 'seed-plastic']
    """

def parse_materials(text: str, source: str = "<string>") -> Materials:
    """Parses materials from TOML text; ``source`` names it in error messages.

    >>> m = vkbrdf.parse_materials('[[material]]\\nname = "matte"\\nmodel = "lambert"\\ndiffuse = 0.5')
    >>> vkbrdf.evaluate(m, l=[0, 0, 1], v=[0, 0, 1], n=[0, 0, 1])  # 0.5 / pi
    array([0.15915494, 0.15915494, 0.15915494], dtype=float32)
    """

def presets() -> Materials:
    """Every preset material (gold, silver, copper, aluminium, glass, water,
    shiny-plastic, htsg-aluminium, and the spectral forms gold-spectral, silver-spectral,
    copper-spectral, aluminium-spectral, glass-spectral, water-spectral), as one table."""

@overload
def evaluate(
    materials: Materials,
    tuples: _ArrayLike,
    *,
    backend: str = ...,
    terms: bool = ...,
    precision: str = ...,
    strict: bool = ...,
    return_counts: bool = ...,
    spike: bool = ...,
    wavelengths: Union[None, str, _ArrayLike] = ...,
    color: Optional[str] = ...,
    illuminant: str = ...,
) -> Any:
    """Evaluates the BRDF f (1/sr, RGB, without the cosine) of each tuple.

    Two forms:

    * ``evaluate(materials, tuples)``: ``tuples`` as ``vkbrdf eval`` reads them, shape
      ``(n, 10)`` (``Lx Ly Lz Vx Vy Vz Nx Ny Nz material``) or ``(n, 13)`` (plus
      ``Tx Ty Tz``), float32 or float64 (rounded to float32, as the CLI rounds a float64
      file), any memory layout. A C-contiguous float32 array is read in place, without a
      copy; any other is converted once. f has shape ``(n, 3)``.
    * ``evaluate(materials, l=L, v=V, n=N, t=None, material=None)``: L, V, N (and T) are
      ``(..., 3)`` arrays that broadcast against each other and against ``material`` (an
      index, a name, or an integer or name array; it may be left out only when
      ``materials`` holds one material); f has the broadcast shape + ``(3,)``.

    Integer arrays (a list of ints) are converted as NumPy converts them, in both forms.

    Directions need not be unit length. Invalid tuples (zero or non-finite L, V, N, a bad
    tangent) and tuples below the horizon give 0 and are counted; ``strict=True`` raises
    ``BatchError`` instead when any tuple is invalid.

    Args:
        backend: ``"auto"`` (Vulkan on a GPU or a device named by VKBRDF_DEVICE, else the
            native CPU engine; measured materials go to the reference), ``"vulkan"``,
            ``"cpu"`` or ``"reference"`` (f64).
        terms: also return the terms ``(..., 6)``: D, G, F_r, F_g, F_b, K.
        precision: ``"exact"`` or ``"fast"`` (Schlick for exact Fresnel, smith-fast for
            Smith-Beckmann), as ``vkbrdf eval --precision``.
        return_counts: also return a :class:`Counts`.
        spike: also return the mirror spike's weight rho_s ``(..., 3)`` of HTSG materials
            (FORMULAS.md §8: the spike is rho_s delta(w - w_mirror)/cos_i and is not in f);
            every tuple's material must be ``htsg`` (else ``UsageError``).
        wavelengths: evaluate at these wavelengths (nm) instead of in RGB (FORMULAS.md §9):
            ``"360:830:5"`` (START:END:STEP, both ends included), ``"450,550,650"`` or an
            array; f then has shape ``(..., W)``. Materials need a spectral form (a
            spectral ``ior`` such as the ``gold-spectral`` preset, or no index: RGB colours
            are up-sampled by Jakob & Hanika 2019). Not with ``terms`` or ``spike``.
        color: ``"xyz"`` or ``"srgb"``: reduce the spectral values to CIE 1931 XYZ or
            linear sRGB (unclamped), shape ``(..., 3)``, by the CIE quadrature on the 5 nm
            grid 360-830 nm (the default wavelengths with ``color``; another grid is an
            error).
        illuminant: ``"d65"`` (default) or ``"e"``, weighting ``color``.

    Returns:
        f, then terms when ``terms``, then rho_s when ``spike``, then Counts when
        ``return_counts``: ``f``, ``(f, terms)``, ``(f, counts)``, ``(f, terms, counts)``,
        ``(f, rho_s)`` and so on.

    The GIL is released while the engine runs (other Python threads go on; several threads
    may call evaluate at once), and Ctrl-C stops a long evaluation (KeyboardInterrupt).

    >>> m = vkbrdf.presets()
    >>> th = np.linspace(0, np.pi / 2, 91)
    >>> L = np.stack([np.sin(th), np.zeros_like(th), np.cos(th)], axis=-1)  # (91, 3)
    >>> f = vkbrdf.evaluate(m, l=L, v=[0, 0, 1], n=[0, 0, 1], material="gold")
    >>> f.shape
    (91, 3)
    >>> tuples = np.zeros((4, 10), np.float32); tuples[:, [2, 5, 8]] = 1
    >>> f, terms, counts = vkbrdf.evaluate(m, tuples, backend="cpu", terms=True, return_counts=True)
    >>> terms.shape, counts.invalid
    ((4, 6), 0)
    """
@overload
def evaluate(
    materials: Materials,
    tuples: None = ...,
    *,
    l: _ArrayLike,
    v: _ArrayLike,
    n: _ArrayLike,
    t: Optional[_ArrayLike] = ...,
    material: Union[int, str, _ArrayLike] = ...,
    backend: str = ...,
    terms: bool = ...,
    precision: str = ...,
    strict: bool = ...,
    return_counts: bool = ...,
    spike: bool = ...,
    wavelengths: Union[None, str, _ArrayLike] = ...,
    color: Optional[str] = ...,
    illuminant: str = ...,
) -> Any: ...

def check(
    *, backend: str = "vulkan", tuples: int = 2000, seed: int = 1, only: Optional[str] = None
) -> List[Dict[str, Any]]:
    """``vkbrdf check``: every legal model combination against the f64 reference, as data.

    One dict per combination: ``combination``, ``backend``, ``pass``, ``tuples``,
    ``max_rel``, ``p99_rel``, ``column_max_rel`` (per column: brdf_r..b, D, G, F_r..b,
    K), ``max_used`` (largest error / allowed error; <= 1 passes),
    ``max_rel_well_conditioned``, ``counts_match``, ``saturated`` (engine, reference) and
    ``worst`` (row, column, value, reference, allowed, l, v, n, t, material) or None.

    >>> report = vkbrdf.check(backend="cpu", tuples=200, only="ggx")
    >>> all(r["pass"] for r in report)
    True
    """

def fit(
    materials: Materials,
    material: Union[str, int],
    *,
    free: Union[str, Sequence[str]],
    merl: Optional[Union[str, "os.PathLike[str]"]] = None,
    tuples: Optional[npt.ArrayLike] = None,
    values: Optional[npt.ArrayLike] = None,
    loss: str = "l2",
    backend: str = "auto",
    starts: int = 8,
    seed: int = 1,
    max_theta: Optional[float] = None,
) -> Dict[str, Any]:
    """``vkbrdf fit``: fits the ``free`` parameters of ``materials[material]`` (the start;
    the others stay fixed) to measured data — a MERL binary (``merl=``), or tuples (``(n,
    6)`` local rows or ``(n, 10|13)`` rows) with measured RGB values ``(n, 3)`` — on an
    engine (``backend``). ``free``: any of ``roughness``, ``f0``, ``diffuse``,
    ``specular``, ``ior``, ``extinction``, ``exponent`` (a list or a comma-separated
    string). ``loss``: ``l2`` (Ngan et al.), ``e1``, ``e2`` (Löw et al.) or ``rrms``; every
    metric is reported whichever is minimised. ``max_theta`` (degrees) masks samples
    beyond it. Ctrl-C raises ``KeyboardInterrupt`` (the command line, unlike this
    function, writes the best parameters so far).

    Returns a dict: ``material`` (a :class:`Materials` of the fitted material), ``toml``
    (its materials-file text, which ``vkbrdf eval`` takes as is), ``parameters`` (each free
    parameter's values), ``metrics`` (``l2``, ``l2_relative``, ``e1``, ``e2``, ``rrms``,
    ``energy``), ``loss``, ``evaluations``, ``seconds``, ``backend``, ``samples``.
    See docs/FITTING.md.

    >>> toml = ('[[material]]\\nname = "s"\\nmodel = "cook-torrance"\\ndistribution = "ggx"\\n'
    ...         'fresnel = "schlick"\\nf0 = 0.04\\nroughness = {}\\n')
    >>> rng = np.random.default_rng(1)
    >>> rows = np.zeros((20000, 10), np.float32); rows[:, 8] = 1       # N = +z, material 0
    >>> for k in (0, 3):                                               # L, V: upper hemisphere
    ...     d = rng.normal(size=(20000, 3)); d[:, 2] = abs(d[:, 2]); rows[:, k:k + 3] = d
    >>> f = vkbrdf.evaluate(vkbrdf.parse_materials(toml.format(0.3)), rows, backend="cpu")
    >>> r = vkbrdf.fit(vkbrdf.parse_materials(toml.format(0.6)), "s", free="roughness,specular",
    ...                tuples=rows, values=f, backend="cpu")
    >>> round(r["parameters"]["roughness"][0], 3)
    0.3
    """
    ...
