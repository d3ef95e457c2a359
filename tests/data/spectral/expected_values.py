#!/usr/bin/env python3
"""Expected values for the spectral tests, computed independently of the Rust code.

Reads, relative to the repository root:
  src/spectral/data/cie1931-2deg-5nm.csv   CIE 1931 2 deg CMFs, 360..830 nm step 5
  src/spectral/data/cie-d65-5nm.csv        CIE D65 relative SPD, 360..830 nm step 5
  src/spectral/data/*.yml                  refractiveindex.info files (CC0)
  tests/data/spectral/pbrt-v4-metals.toml  pbrt-v4 metal eta/k (Apache-2.0)

Needs Python >= 3.11 (tomllib), numpy and pyyaml. Run from anywhere:
  python3 tests/data/spectral/expected_values.py > tests/data/spectral/expected_values.txt

Reductions used:
  F0(l)  = ((n-1)^2 + k^2) / ((n+1)^2 + k^2), with n, k interpolated linearly in
           wavelength onto the 5 nm grid 360..830 (np.interp; no extrapolation).
  D65 / Filament reduction:  XYZ = sum(F0 * D65 * cmf) / sum(D65 * ybar), then linear sRGB.
  Mitsuba reduction (equal energy): XYZ = sum(v * cmf) / sum(ybar) for v = n and v = k
           separately, then linear sRGB, negatives clamped to 0.
  XYZ -> linear sRGB matrix derived from the sRGB primaries (0.64,0.33), (0.30,0.60),
  (0.15,0.06) and white (0.3127,0.3290), white normalised to Y = 1.
"""

import pathlib
import tomllib

import numpy as np
import yaml

ROOT = pathlib.Path(__file__).resolve().parents[3]
DATA = ROOT / "src" / "spectral" / "data"
PBRT = ROOT / "tests" / "data" / "spectral" / "pbrt-v4-metals.toml"

LAGARDE = {  # Lagarde, "metal reflectance" table, linear sRGB normalised
    "au": (1.000, 0.766, 0.336),
    "ag": (0.972, 0.960, 0.915),
    "cu": (0.955, 0.637, 0.538),
    "al": (0.913, 0.921, 0.925),
}


def fmt(v, p=9):
    return "(" + ", ".join(f"{x:.{p}f}" for x in v) + ")"


def load_csv(path):
    rows = [line.strip().split(",") for line in path.read_text().splitlines()[1:] if line.strip()]
    return np.array([[float(x) for x in r] for r in rows])


cmf_t = load_csv(DATA / "cie1931-2deg-5nm.csv")
d65_t = load_csv(DATA / "cie-d65-5nm.csv")
GRID = np.arange(360.0, 831.0, 5.0)
assert cmf_t.shape == (95, 4) and np.array_equal(cmf_t[:, 0], GRID)
assert d65_t.shape == (95, 2) and np.array_equal(d65_t[:, 0], GRID)
CMF = cmf_t[:, 1:]  # (95, 3)
D65 = d65_t[:, 1]


def xy_to_xyz(x, y):
    return np.array([x / y, 1.0, (1.0 - x - y) / y])


def srgb_matrices():
    prim = np.column_stack([xy_to_xyz(0.64, 0.33), xy_to_xyz(0.30, 0.60), xy_to_xyz(0.15, 0.06)])
    white = xy_to_xyz(0.3127, 0.3290)
    s = np.linalg.solve(prim, white)
    rgb_to_xyz = prim * s
    return rgb_to_xyz, np.linalg.inv(rgb_to_xyz)


RGB_TO_XYZ, XYZ_TO_RGB = srgb_matrices()


def xyz_d65(v):
    return (v * D65) @ CMF / np.sum(D65 * CMF[:, 1])


def xyz_ee(v):
    return v @ CMF / np.sum(CMF[:, 1])


def to_rgb(xyz):
    return XYZ_TO_RGB @ xyz


def fresnel_f0(n, k):
    return ((n - 1) ** 2 + k**2) / ((n + 1) ** 2 + k**2)


def interp(lam_nm, vals, label):
    lo, hi = float(np.min(lam_nm)), float(np.max(lam_nm))
    if lo > 360.0 or hi < 830.0:
        print(f"  WARNING {label}: data cover {lo:.3f}-{hi:.3f} nm, not all of 360-830 nm")
    order = np.argsort(lam_nm)
    return np.interp(GRID, np.asarray(lam_nm)[order], np.asarray(vals)[order])


def load_yml(name):
    """Return (n, k, description) on GRID from a refractiveindex.info YAML file."""
    doc = yaml.safe_load((DATA / name).read_text())
    n = k = None
    kinds = []
    for d in doc["DATA"]:
        t = d["type"]
        kinds.append(t)
        if t.startswith("tabulated"):
            a = np.array([[float(x) for x in line.split()] for line in d["data"].strip().splitlines()])
            lam = a[:, 0] * 1000.0
            if t == "tabulated nk":
                n, k = interp(lam, a[:, 1], name), interp(lam, a[:, 2], name)
            elif t == "tabulated n":
                n = interp(lam, a[:, 1], name)
            elif t == "tabulated k":
                k = interp(lam, a[:, 1], name)
        elif t == "formula 1":
            lo, hi = (float(x) * 1000.0 for x in d["wavelength_range"].split())
            if lo > 360.0 or hi < 830.0:
                print(f"  WARNING {name}: formula valid {lo}-{hi} nm only")
            c = [float(x) for x in d["coefficients"].split()]
            l2 = (GRID / 1000.0) ** 2
            n2 = 1.0 + c[0]
            for i in range(1, len(c) - 1, 2):
                n2 = n2 + c[i] * l2 / (l2 - c[i + 1] ** 2)
            n = np.sqrt(n2)
        else:
            raise ValueError(f"{name}: unsupported DATA type {t}")
    if k is None:
        k = np.zeros_like(GRID)
    return n, k, ", ".join(kinds)


def load_pbrt():
    out = {}
    for m in tomllib.loads(PBRT.read_text())["material"]:
        a = np.array(m["ior"], dtype=float)
        out[m["name"].split("-")[0]] = (interp(a[:, 0], a[:, 1], m["name"]), interp(a[:, 0], a[:, 2], m["name"]))
    return out


def report(label, n, k, lagarde=None):
    f0 = fresnel_f0(n, k)
    rgb = to_rgb(xyz_d65(f0))
    norm = rgb / np.max(rgb)
    print(f"{label}")
    print(f"  F0 linear sRGB (D65 / Filament)  {fmt(rgb)}")
    print(f"  F0 normalised to max channel      {fmt(norm)}")
    if lagarde is not None:
        diff = np.abs(norm - np.array(lagarde))
        print(f"  Lagarde table                     {fmt(lagarde, 3)}  max |diff| = {np.max(diff):.4f}")
        raw = np.max(np.abs(np.minimum(rgb, 1.0) - np.array(lagarde)))
        print(f"  (Lagarde vs un-normalised F0 clamped to <= 1: max |diff| = {raw:.4f})")
    eta_rgb = np.maximum(to_rgb(xyz_ee(n)), 0.0)
    k_rgb = np.maximum(to_rgb(xyz_ee(k)), 0.0)
    print(f"  Mitsuba eta (equal energy, >=0)   {fmt(eta_rgb)}")
    print(f"  Mitsuba k   (equal energy, >=0)   {fmt(k_rgb)}")
    print(f"  F0 from Mitsuba RGB eta,k         {fmt(fresnel_f0(eta_rgb, k_rgb))}")


def main():
    np.set_printoptions(precision=10)
    print("== Colour-matching checks ==")
    print(f"sum(ybar) * 5 nm                  = {np.sum(CMF[:, 1]) * 5.0:.6f}   (expect 106.857 +- 1e-3)")
    wxyz = xyz_d65(np.ones_like(GRID))
    print(f"D65 white XYZ (Y = 1)             = {fmt(wxyz, 6)}   (expect 0.95047, 1, 1.08897 +- 1e-4)")
    print(f"D65 white -> linear sRGB          = {fmt(to_rgb(wxyz), 6)}   (expect 1, 1, 1 +- 5e-4)")
    exyz = xyz_ee(np.ones_like(GRID))
    print(f"Equal-energy XYZ (sum v cmf/sum y) = {fmt(exyz, 6)}")
    print(f"Equal-energy -> linear sRGB        = {fmt(to_rgb(exyz), 6)}   (expect ~1.205, 0.948, 0.909)")
    print("XYZ -> linear sRGB matrix (10 significant digits):")
    for row in XYZ_TO_RGB:
        print("  [" + ", ".join(f"{x:.10g}" for x in row) + "]")
    print("linear sRGB -> XYZ matrix (10 significant digits):")
    for row in RGB_TO_XYZ:
        print("  [" + ", ".join(f"{x:.10g}" for x in row) + "]")
    print()
    print("== pbrt-v4 metals (tests/data/spectral/pbrt-v4-metals.toml) ==")
    pbrt = load_pbrt()
    for m in ("au", "ag", "cu", "al"):
        report(f"{m}-pbrt", *pbrt[m], LAGARDE[m])
    print()
    print("== refractiveindex.info files (CC0, src/spectral/data) ==")
    for m, f in (("au", "au-johnson-christy.yml"), ("ag", "ag-johnson-christy.yml"),
                 ("cu", "cu-johnson-christy.yml"), ("al", "al-rakic.yml"),
                 (None, "sio2-malitson.yml"), (None, "h2o-hale-querry.yml")):
        n, k, kinds = load_yml(f)
        report(f"{f} [{kinds}]  n(590 nm) = {np.interp(590.0, GRID, n):.6f}",
               n, k, LAGARDE.get(m))


if __name__ == "__main__":
    main()
