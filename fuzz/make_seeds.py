#!/usr/bin/env python3
"""Writes the fuzzers' seed inputs into fuzz/corpus/<target>/ (ignored by git):
the presets rendered to TOML and one table per model, small .npy files in every layout
the reader meets, and tiny MERL headers. Standard library only (no numpy)."""
import os
import re
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def out(target, name, data):
    d = os.path.join(HERE, "corpus", target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, "seed-" + name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


# ---- materials: the presets, rendered as a user would write them -----------------------
src = open(os.path.join(ROOT, "src/material/presets.rs")).read()
consts = dict(re.findall(r'const (\w+): &str = r#"(.*?)"#;', src, re.S))
arms = re.findall(r'"([\w-]+)" => \{?\s*(?:(\w+)\.trim_end\(\)\.to_owned\(\)\s*\+\s*"(.*?)"|(\w+)\.to_owned\(\))', src, re.S)
presets = []
for name, base, extra, whole in arms:
    body = consts[base].strip() + "\n" + extra.encode().decode("unicode_escape") if base else consts[whole]
    presets.append(name)
    out("materials", "preset-" + name, f'[[material]]\nname = "{name}"\n{body.strip()}\n')
assert len(presets) == 7, presets
out("materials", "all-presets", "".join(f'[[material]]\nname = "p{i}"\npreset = "{p}"\n\n' for i, p in enumerate(presets)))
models = {
    "lambert": 'model = "lambert"\ndiffuse = [0.5, 0.4, 0.3]\n',
    "phong": 'model = "phong"\nexponent = 50\ndiffuse = 0.2\nspecular = [1, 1, 1]\ndiffuse_weight = 0.5\nspecular_weight = 0.5\n',
    "blinn-phong": 'model = "blinn-phong"\nexponent = 20.5\n',
    "rtr": 'model = "rtr"\nexponent = 8\nprecision = "fast"\n',
    "ward": 'model = "ward"\nroughness = [0.1, 0.4]\n',
    "ct-1982": 'model = "cook-torrance"\nconvention = "cook-torrance-1982"\ndistribution = "beckmann"\nroughness = 0.3\ngeometry = "cook-torrance"\nfresnel = "schlick"\nf0 = [0.9, 0.8, 0.7]\n',
    "ct-seed": 'model = "cook-torrance"\nconvention = "seed"\ndistribution = "gaussian"\nroughness = 0.2\ngeometry = "none"\nfresnel = "none"\n',
    "ct-blinn": 'model = "cook-torrance"\ndistribution = "blinn"\nexponent = 30\ngeometry = "cook-torrance"\nfresnel = "dielectric"\nior = [1.4, 1.5, 1.6]\n',
    "ct-aniso": 'model = "cook-torrance"\ndistribution = "ggx"\nroughness = [0.05, 0.5]\ngeometry = "smith"\nfresnel = "conductor"\nior = 0.2\nextinction = [3, 2, 1]\n',
    "ct-fast": 'model = "cook-torrance"\ndistribution = "beckmann"\nroughness = 0.5\ngeometry = "smith-fast"\nfresnel = "schlick"\nior = 1.5\n',
    "override": 'preset = "gold"\nroughness = 0.05\nspecular = [0.9, 0.9, 0.9]\n',
    "merl": 'model = "merl"\nfile = "gold.binary"\n',
}
for name, body in models.items():
    out("materials", "model-" + name, f'[[material]]\nname = "{name}"\n{body}')
out("materials", "inline-tables", 'material = [ { name = "a", model = "lambert" }, { name = "b", preset = "glass" } ]\n')


# ---- .npy ---------------------------------------------------------------------------------
def npy(descr, shape, data, fortran=False, version=1):
    shape_s = "(" + ", ".join(str(d) for d in shape) + ("," if len(shape) == 1 else "") + ")"
    header = "{'descr': '%s', 'fortran_order': %s, 'shape': %s, }" % (descr, "True" if fortran else "False", shape_s)
    size_fmt, pre = ("<H", 10) if version == 1 else ("<I", 12)
    pad = (64 - (pre + len(header) + 1) % 64) % 64
    header = header + " " * pad + "\n"
    return b"\x93NUMPY" + bytes([version, 0]) + struct.pack(size_fmt, len(header)) + header.encode() + data


def rows(n, cols):
    vals = []
    for r in range(n):
        row = [0.3, 0.1, 0.9, -0.2, 0.0, 1.0, 0.0, 0.0, 1.0, float(r % 3)]
        if cols == 13:
            row += [1.0, 0.0, 0.0]
        vals += row
    return vals


f4 = lambda v: struct.pack(f"<{len(v)}f", *v)
f8 = lambda v: struct.pack(f"<{len(v)}d", *v)
out("npy", "f4-2x10", npy("<f4", (2, 10), f4(rows(2, 10))))
out("npy", "f8-3x13", npy("<f8", (3, 13), f8(rows(3, 13))))
out("npy", "f4-0x10", npy("<f4", (0, 10), b""))
out("npy", "v2-f4-1x10", npy("<f4", (1, 10), f4(rows(1, 10)), version=2))
out("npy", "v3-f4-1x13", npy("<f4", (1, 13), f4(rows(1, 13)), version=3))
out("npy", "fortran", npy("<f4", (1, 10), f4(rows(1, 10)), fortran=True))
out("npy", "i4", npy("<i4", (1, 10), bytes(40)))
out("npy", "be-f4", npy(">f4", (1, 10), bytes(40)))
out("npy", "1d", npy("<f4", (10,), f4(rows(1, 10))))
out("npy", "3d", npy("<f4", (1, 1, 10), f4(rows(1, 10))))
out("npy", "truncated", npy("<f4", (2, 10), f4(rows(2, 10)))[:-7])
out("npy", "nan-material", npy("<f4", (1, 10), f4(rows(1, 10)[:9] + [float("nan")])))

# ---- MERL ---------------------------------------------------------------------------------
dims = struct.pack("<3i", 90, 90, 180)
out("merl", "header", dims)
out("merl", "header-and-samples", dims + f8([0.5, -1.0, 1e-3, 0.0]))
out("merl", "wrong-dims", struct.pack("<3i", 90, 90, 360) + f8([0.5]))
out("merl", "short", b"\x5a\x00\x00")
# ---- MERL lookups: (l, v, n) then (theta_h, theta_d, phi_d), as f64 ----------------------
out("merl_lookup", "mirror", f8([0.3, 0.0, 1.0, -0.3, 0.0, 1.0, 0.0, 0.0, 1.0]))
out("merl_lookup", "grazing", f8([1.0, 0.0, 1e-300, 0.0, 1.0, 1e-300, 0.0, 0.0, 1.0]))
out("merl_lookup", "angles", f8([0.2, 1.5707963267948966, 3.141592653589793]))
print("seeds written under", os.path.join(HERE, "corpus"), file=sys.stderr)
