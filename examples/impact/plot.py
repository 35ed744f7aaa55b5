"""Pictures of an `impact collide` run: equatorial slices coloured by material and by
density at a few times, and the disk mass (and predicted moon mass) against time.

usage: plot.py --run DIR [--out DIR] [--times N]
Reads DIR/snap_*.{pbin,hdf5} (pik's Python reader, python/pik) and DIR/analysis.txt
(written by `impact analyse --run DIR`); writes impact_slices.png and impact_disk.png.
"""
import argparse
import glob
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python"))

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import pik  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--run", required=True, help="output directory of impact collide")
    ap.add_argument("--out", default=None, help="where to write the PNGs (default: the run directory)")
    ap.add_argument("--times", type=int, default=4, help="number of snapshots in the slice figure")
    a = ap.parse_args()
    out = a.out or a.run
    os.makedirs(out, exist_ok=True)
    snaps = sorted(glob.glob(os.path.join(a.run, "snap_*.pbin")) + glob.glob(os.path.join(a.run, "snap_*.hdf5")))
    if not snaps:
        sys.exit(f"plot.py: error: no snapshots in {a.run}")
    pick = [snaps[int(round(i))] for i in np.linspace(0, len(snaps) - 1, min(a.times, len(snaps)))]
    fig, ax = plt.subplots(2, len(pick), figsize=(3.2 * len(pick) + 1, 6.6), squeeze=False, layout="constrained")
    for k, path in enumerate(pick):
        s = pik.read_snapshot(path)
        mat, body = s.columns["Material"], s.columns["Body"]
        rho, h = s.columns["Density"], s.columns["SmoothingLength"]
        # centre on the target's core
        core = (body == 0) & (mat == 0)
        c = np.average(s.pos[core], axis=0, weights=s.mass[core])
        x = (s.pos - c) / 1e6
        slab = np.abs(x[:, 2]) < 0.5 * h / 1e6 + 0.3
        lim = 25
        colours = np.where(mat == 0, np.where(body == 0, "#8c2d04", "#fd8d3c"), np.where(body == 0, "#2171b5", "#9ecae1"))
        ax[0, k].scatter(x[slab, 0], x[slab, 1], s=2, c=colours[slab], lw=0)
        sc = ax[1, k].scatter(x[slab, 0], x[slab, 1], s=2, c=np.log10(rho[slab]), cmap="inferno", vmin=1.5, vmax=4.3, lw=0)
        for r in (0, 1):
            ax[r, k].set_xlim(-lim, lim), ax[r, k].set_ylim(-lim, lim), ax[r, k].set_aspect("equal")
            ax[r, k].set_xlabel("x (1000 km)")
        ax[0, k].set_title(f"t = {s.time / 3600:.2f} h")
    ax[0, 0].set_ylabel("y (1000 km)   material")
    ax[1, 0].set_ylabel("y (1000 km)   density")
    fig.colorbar(sc, ax=ax[1, :].tolist(), label="log10 density (kg/m^3)", shrink=0.8)
    fig.suptitle("equatorial slice: iron (brown: target, orange: impactor), granite (blue: target, light: impactor)",
                 fontsize=9)
    fig.savefig(os.path.join(out, "impact_slices.png"), dpi=90)
    print("wrote", os.path.join(out, "impact_slices.png"))

    table = os.path.join(a.run, "analysis.txt")
    if os.path.exists(table):
        d = np.atleast_2d(np.loadtxt(table))
        fig, ax = plt.subplots(figsize=(6, 4))
        ax.plot(d[:, 0], d[:, 3], "o-", label="disk mass")
        ax.plot(d[:, 0], d[:, 7], "s--", label="predicted moon (Ida et al. 1997)")
        ax.plot(d[:, 0], d[:, 4], "^:", label="escaping mass")
        ax.axhline(1, color="grey", lw=0.8)
        ax.set_xlabel("time (h)"), ax.set_ylabel("mass (lunar masses)"), ax.legend()
        fig.tight_layout()
        fig.savefig(os.path.join(out, "impact_disk.png"), dpi=90)
        print("wrote", os.path.join(out, "impact_disk.png"))
    else:
        print(f"no {table}: run `impact analyse --run {a.run}` for the disk-mass plot")


if __name__ == "__main__":
    main()
