"""Plots a material's lobe in the plane of incidence and its half/difference slice with
Matplotlib, from vkbrdf's NumPy API, and writes one PNG.

    python examples/python/plot_lobe.py --material gold --output docs/images/python-lobe.png

Left: f(L, V) in 1/sr for light at --incidence degrees, V swept over the plane of
incidence (the broadcasting form: one L, a row of V); polar, one curve per RGB channel.
Right: `vkbrdf.tables.slice` -- f over (theta_h, theta_d) at phi_d = 90 degrees, red
channel, log scale.
"""

import argparse

import matplotlib
import matplotlib.ticker

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import vkbrdf  # noqa: E402


def lobe(materials, name, incidence_deg, samples=721, backend="auto"):
    """(theta_o, f): f (samples, 3) for V over the plane of incidence, light at incidence."""
    ti = np.radians(incidence_deg)
    light = np.array([-np.sin(ti), 0.0, np.cos(ti)])
    theta_o = np.linspace(-np.pi / 2, np.pi / 2, samples)
    view = np.stack([np.sin(theta_o), np.zeros_like(theta_o), np.cos(theta_o)], axis=-1)
    f = vkbrdf.evaluate(materials, l=light, v=view, n=[0, 0, 1], material=name, backend=backend)
    return theta_o, f


def plot(materials, name, incidence_deg, output, backend="auto", size=(90, 90)):
    theta_o, f = lobe(materials, name, incidence_deg, backend=backend)
    s = vkbrdf.tables.slice(name, materials, size=size, backend=backend)
    fig = plt.figure(figsize=(10, 4.2), dpi=100)
    ax = fig.add_subplot(1, 2, 1, projection="polar")
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(-1)  # viewing angles toward +x (the mirror side) on the right
    ax.set_thetamin(-90)
    ax.set_thetamax(90)
    for c, colour in enumerate(("tab:red", "tab:green", "tab:blue")):
        ax.plot(theta_o, f[:, c], color=colour, lw=1.5)
    ax.axvline(np.radians(incidence_deg), color="0.4", ls="--", lw=1, label="mirror direction")
    ax.yaxis.set_major_locator(matplotlib.ticker.MaxNLocator(4))
    ax.tick_params(axis="y", labelsize=7)
    ax.legend(loc="lower left", fontsize=8, frameon=False)
    ax.set_title(f"{name}: f in the plane of incidence\n(light at {incidence_deg:g}°, 1/sr)", fontsize=10)
    ax2 = fig.add_subplot(1, 2, 2)
    red = np.maximum(s[..., 0], 1e-6)
    w, h = size
    extent = (0, 1, 0, 90)
    im = ax2.imshow(np.log10(red), origin="lower", aspect="auto", extent=extent, cmap="magma")
    ticks = np.array([0, 10, 30, 50, 70, 90])
    ax2.set_xticks(np.sqrt(ticks / 90.0))
    ax2.set_xticklabels([f"{t}°" for t in ticks])
    ax2.set_xlabel("θ_h (square-root spacing, as MERL)")
    ax2.set_ylabel("θ_d (degrees)")
    ax2.set_title(f"half/difference slice, φ_d = 90° ({w}×{h}), red", fontsize=10)
    fig.colorbar(im, ax=ax2, label="log10 f (1/sr)")
    fig.tight_layout()
    fig.savefig(output)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--materials", help="materials file (TOML); default: the presets")
    ap.add_argument("--material", default="gold")
    ap.add_argument("--incidence", type=float, default=45.0, help="light angle in degrees")
    ap.add_argument("--backend", default="auto")
    ap.add_argument("--output", default="lobe.png")
    args = ap.parse_args()
    materials = vkbrdf.load_materials(args.materials) if args.materials else vkbrdf.presets()
    plot(materials, args.material, args.incidence, args.output, backend=args.backend)
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
