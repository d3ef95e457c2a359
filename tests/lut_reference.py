#!/usr/bin/env python3
"""The engines' own DFG generators, re-implemented in NumPy from their published sources,
for tests/lut_styles.rs to hold `vkbrdf table dfg --lut-style ue4|filament` to.

- ue4: `IntegrateBRDF(Roughness, NoV)` of Karis 2013, "Real Shading in Unreal Engine 4"
  (SIGGRAPH course notes): Hammersley points (i/N, radical inverse of i), GGX normals drawn
  by D cos_h (`ImportanceSampleGGX`, a = Roughness^2), L = V reflected about H, and for
  NoL > 0 the weight G_Vis = G * VoH / (NoH * NoV) with G the Schlick-Smith G of the notes
  for image-based lighting (k = a/2); A += (1 - Fc) G_Vis, B += Fc G_Vis, Fc = (1 - VoH)^5.
  The table: x = NoV = (i + 0.5)/W, y = Roughness = (j + 0.5)/H; R = A, G = B.
- filament: `CubemapIBL::DFG` with `DFV_Multiscatter` (libs/ibl/src/CubemapIBL.cpp of
  google/filament, read at commit 5b2652fadddc0fa81fcc8c7684f62639149addad; its engine LUT
  is built with --ibl-dfg-multiscatter, filament/CMakeLists.txt): the same points and
  sampling, weight v = Vis(NoV, NoL, a) * NoL * VoH / NoH with Vis the height-correlated
  Smith-GGX visibility 0.5 / (NoL sqrt(NoV^2 (1 - a^2) + a^2) + NoV sqrt(NoL^2 (1 - a^2) + a^2)),
  R = 4/N sum v Fc, G = 4/N sum v. The table: x = NoV = (i + 0.5)/W, row j holds
  coord = clamp((H - j + 0.5)/H, 0, 1), a = coord^2.

Written from the published descriptions; no code is copied. Arithmetic is float64 (the
engines use float32: a difference of order 1e-6).

Usage: lut_reference.py STYLE W H SAMPLES OUT
writes OUT as H*W*2 little-endian float64, row-major, channels (R, G).
"""

import sys

import numpy as np


def radical_inverse(i):
    """Van der Corput radical inverse in base 2 of the uint32 array i."""
    b = i.astype(np.uint64)
    result = np.zeros_like(b, dtype=np.float64)
    scale = 0.5
    for _ in range(32):
        result += (b & 1).astype(np.float64) * scale
        b >>= 1
        scale *= 0.5
    return result


def ggx_normals(a, n):
    """The n normals drawn by D cos_h for GGX alpha a: phi = 2 pi i/n from the first
    Hammersley coordinate, cos^2 theta = (1 - u) / (1 + (a^2 - 1) u) from the second."""
    i = np.arange(n, dtype=np.uint32)
    phi = 2.0 * np.pi * (i.astype(np.float64) / n)
    u = radical_inverse(i)
    cos2 = (1.0 - u) / (1.0 + (a * a - 1.0) * u)
    sin = np.sqrt(np.maximum(0.0, 1.0 - cos2))
    return np.stack([sin * np.cos(phi), sin * np.sin(phi), np.sqrt(cos2)], axis=-1)


def kinematics(nov, a, n):
    """NoL, NoH, VoH for every (NoV, sample) pair; nov is a 1-D array."""
    h = ggx_normals(a, n)  # (n, 3)
    v = np.stack([np.sqrt(1.0 - nov * nov), np.zeros_like(nov), nov], axis=-1)  # (w, 3)
    voh = v @ h.T  # (w, n)
    lz = 2.0 * voh * h[None, :, 2] - v[:, None, 2]
    nol = np.clip(lz, 0.0, 1.0)
    noh = np.clip(np.broadcast_to(h[None, :, 2], voh.shape), 0.0, 1.0)
    return nol, noh, np.clip(voh, 0.0, 1.0)


def ue4_row(nov, roughness, n):
    a = roughness * roughness
    nol, noh, voh = kinematics(nov, a, n)
    k = a / 2.0

    def g1(x):
        return x / (x * (1.0 - k) + k)

    with np.errstate(divide="ignore", invalid="ignore"):
        g_vis = g1(nov[:, None]) * g1(nol) * voh / (noh * nov[:, None])
    g_vis = np.where(nol > 0.0, g_vis, 0.0)
    fc = (1.0 - voh) ** 5
    scale = np.sum((1.0 - fc) * g_vis, axis=1) / n
    bias = np.sum(fc * g_vis, axis=1) / n
    return np.stack([scale, bias], axis=-1)


def filament_row(nov, a, n):
    nol, noh, voh = kinematics(nov, a, n)
    a2 = a * a
    nv = nov[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        ggxl = nv * np.sqrt((nol - nol * a2) * nol + a2)
        ggxv = nol * np.sqrt((nv - nv * a2) * nv + a2)
        vis = 0.5 / (ggxv + ggxl)
        v = vis * nol * (voh / noh)
    v = np.where(nol > 0.0, v, 0.0)
    fc = (1.0 - voh) ** 5
    return np.stack([np.sum(v * fc, axis=1), np.sum(v, axis=1)], axis=-1) * (4.0 / n)


def table(style, width, height, n):
    nov = np.clip((np.arange(width) + 0.5) / width, 0.0, 1.0)
    out = np.zeros((height, width, 2))
    for j in range(height):
        if style == "ue4":
            out[j] = ue4_row(nov, (j + 0.5) / height, n)
        else:
            coord = min(1.0, max(0.0, (height - j + 0.5) / height))
            out[j] = filament_row(nov, coord * coord, n)
    return out


def main():
    if len(sys.argv) != 6 or sys.argv[1] not in ("ue4", "filament"):
        sys.exit("usage: lut_reference.py ue4|filament W H SAMPLES OUT")
    style, width, height, n, path = (
        sys.argv[1],
        int(sys.argv[2]),
        int(sys.argv[3]),
        int(sys.argv[4]),
        sys.argv[5],
    )
    table(style, width, height, n).astype("<f8").tofile(path)


if __name__ == "__main__":
    main()
