"""The tables of ``vkbrdf table`` as NumPy arrays, with the CLI's options as keywords.

Texel centres as in the CLI: column i <-> x = (i + 0.5) / W, row j <-> y = (j + 0.5) / H.
"""

import os
from typing import Literal, Optional, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

from . import Materials

DEFAULT_SAMPLES: int
_Size = Union[int, str, Tuple[int, int]]

@overload
def slice(
    material: Union[str, int],
    materials: Union[None, Materials, str, "os.PathLike[str]"] = ...,
    *,
    size: _Size = ...,
    linear: bool = ...,
    terms: Literal[False] = ...,
    backend: str = ...,
) -> npt.NDArray[np.float32]:
    """f over half/difference angles at phi_d = 90 degrees (``vkbrdf table slice``).

    Returns f of shape ``(H, W, 3)`` (and with ``terms=True`` also the terms
    ``(H, W, 6)``): column i <-> theta_h = x^2 * 90 degrees (MERL's square-root spacing;
    ``linear=True``: x * 90 degrees), row j <-> theta_d = y * 90 degrees; n = +z, t = +x.
    ``material`` is a name or index in ``materials`` (a Materials, a file path, or None
    for the presets); ``size`` is N, ``"WxH"`` or ``(W, H)``.

    >>> s = vkbrdf.tables.slice("gold", size=(90, 90))
    >>> s.shape
    (90, 90, 3)
    """
@overload
def slice(
    material: Union[str, int],
    materials: Union[None, Materials, str, "os.PathLike[str]"] = ...,
    *,
    size: _Size = ...,
    linear: bool = ...,
    terms: Literal[True],
    backend: str = ...,
) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]: ...

@overload
def albedo(
    *,
    distribution: str = ...,
    geometry: str = ...,
    size: _Size = ...,
    samples: int = ...,
    average: Literal[False] = ...,
    backend: str = ...,
) -> npt.NDArray[np.float64]:
    """Directional albedo E(mu = cos_o, alpha) of Cook-Torrance with F = 1 (``vkbrdf table
    albedo``): shape ``(H, W)``, x = mu, y = alpha, float64 (the CLI's EXR rounds it to
    float32). ``average=True`` also returns E_avg(alpha) = 2 * integral of E(mu) mu dmu,
    shape ``(H,)``. ``samples``: quasi-Monte Carlo points per texel, 1 to 2^26.

    >>> E = vkbrdf.tables.albedo(size=(32, 32), samples=4096)
    >>> E.shape
    (32, 32)
    """
@overload
def albedo(
    *,
    distribution: str = ...,
    geometry: str = ...,
    size: _Size = ...,
    samples: int = ...,
    average: Literal[True],
    backend: str = ...,
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]: ...

def dfg(*, distribution: str = "ggx", geometry: str = "smith-correlated", size: _Size = "32x32", samples: int = 65536, backend: str = "auto") -> npt.NDArray[np.float64]:
    """The split-sum DFG table (Karis 2013; ``vkbrdf table dfg``): shape ``(H, W, 2)``,
    ``[..., 0]`` = A (scale), ``[..., 1]`` = B (bias), so E = F0 * A + B under Schlick.

    >>> ab = vkbrdf.tables.dfg(size=(32, 32), samples=4096)
    >>> ab.shape
    (32, 32, 2)
    """
