"""HTSG's lobe beside Cook-Torrance's with the equivalent Beckmann roughness (FORMULAS.md §8):
f in the plane of incidence, green channel, for the htsg-aluminium preset (sigma0 = 0.0318 um,
tau = 0.3 um) and a rougher surface of the same material (sigma0 = 0.15 um), each against a
modern Cook-Torrance conductor with Beckmann m = 2 sigma0/tau, Smith G and the same eta.
Evaluated by the vkbrdf command line (the f64 reference), plotted with Matplotlib.

    python3 examples/htsg_lobe.py [--vkbrdf target/release/vkbrdf] [--output docs/images/htsg-lobe.png]
"""

import argparse
import os
import subprocess
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ETA = "ior = [1.3211, 0.88045, 0.59765]\nextinction = [7.41785, 6.1455, 5.2337]\n"


def materials(sigma0, tau):
    m = 2.0 * sigma0 / tau
    return (
        f'[[material]]\nname = "htsg"\nmodel = "htsg"\nsigma0 = {sigma0}\ntau = {tau}\n{ETA}\n'
        f'[[material]]\nname = "beckmann"\nmodel = "cook-torrance"\ndistribution = "beckmann"\n'
        f'roughness = {m}\ngeometry = "smith"\nfresnel = "conductor"\n{ETA}'
    )


def lobe(cli, toml, incidence_deg, samples=721):
    """theta_o (radians) and f_green (2, samples): HTSG's and Beckmann's."""
    ti = np.radians(incidence_deg)
    theta_o = np.linspace(-np.pi / 2 + 1e-3, np.pi / 2 - 1e-3, samples)
    rows = []
    for mat in (0, 1):
        for t in theta_o:
            rows.append([-np.sin(ti), 0, np.cos(ti), np.sin(t), 0, np.cos(t), 0, 0, 1, mat])
    with tempfile.TemporaryDirectory() as d:
        np.save(os.path.join(d, "t.npy"), np.array(rows, dtype=np.float32))
        with open(os.path.join(d, "m.toml"), "w") as f:
            f.write(toml)
        subprocess.run(
            [cli, "eval", "-m", os.path.join(d, "m.toml"), "-i", os.path.join(d, "t.npy"),
             "-o", os.path.join(d, "f.npy"), "--backend", "reference"],
            check=True, stderr=subprocess.DEVNULL)
        f = np.load(os.path.join(d, "f.npy"))[:, 1]
    return theta_o, f.reshape(2, samples)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--vkbrdf", default="target/release/vkbrdf")
    p.add_argument("--output", default="docs/images/htsg-lobe.png")
    a = p.parse_args()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for ax, (sigma0, tau) in zip(axes, [(0.0318, 0.3), (0.15, 0.3)]):
        toml = materials(sigma0, tau)
        for inc, style in [(30, "-"), (60, "--")]:
            t, f = lobe(a.vkbrdf, toml, inc)
            ax.semilogy(np.degrees(t), f[0], style, color="tab:blue",
                        label=f"HTSG, θi = {inc}°")
            ax.semilogy(np.degrees(t), f[1], style, color="tab:orange",
                        label=f"Beckmann m = {2 * sigma0 / tau:.3f}, θi = {inc}°")
        ax.set_title(f"σ0 = {sigma0} µm, τ = {tau} µm (σ0/τ = {sigma0 / tau:.3f}), green")
        ax.set_xlabel("θo in the plane of incidence (°; mirror side > 0)")
        ax.set_ylabel("f (1/sr); HTSG's mirror spike not drawn")
        ax.set_ylim(1e-3, 1e2)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(a.output, dpi=110)
    print(a.output)


if __name__ == "__main__":
    main()
