#!/usr/bin/env python3
"""PNG plots of an examples/sph run (matplotlib, Agg): density field or profiles.

    plot.py --run DIR --out FILE.png

Snapshots are read with the pik Python package (python/pik, `pik.read_snapshot`; every
pik format). The problem is read from the snapshot's attributes (dim) and the files in
DIR: with exact.txt (Sod) the density, pressure and velocity profiles against the exact
solution; 2D runs (square, kh) a density map of the last snapshot; 3D runs without
exact.txt (Evrard) the radial density profile and the energies of log.txt.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "python"))
import pik  # noqa: E402


def last_snapshot(run: Path) -> tuple[dict[str, np.ndarray], float, int]:
    """The final (or last numbered) snapshot as columns x, y, z, vx, rho, p, plus t and dim."""
    finals = sorted(run.glob("snap_final.*"))
    snaps = finals or sorted(run.glob("snap_[0-9]*.*"))
    if not snaps:
        sys.exit(f"plot.py: error: no snapshot (snap_*) in {run}")
    try:
        s = pik.read_snapshot(snaps[-1])
    except pik.SnapshotError as e:
        sys.exit(f"plot.py: error: {e}")
    d = {"x": s.pos[:, 0], "y": s.pos[:, 1], "z": s.pos[:, 2], "vx": s.vel[:, 0],
         "rho": s["Density"], "p": s["Pressure"]}
    return d, s.time, int(s.attrs.get("dim", "3"))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--run", required=True, type=Path, help="output directory of sph (--out)")
    ap.add_argument("--out", required=True, type=Path, help="PNG file to write")
    a = ap.parse_args()
    d, t, dim = last_snapshot(a.run)
    if (a.run / "exact.txt").exists():
        ex = np.loadtxt(a.run / "exact.txt")
        fig, ax = plt.subplots(1, 3, figsize=(13, 4))
        for k, (name, col) in enumerate((("density", "rho"), ("pressure", "p"), ("velocity", "vx"))):
            ax[k].plot(d["x"], d[col], ".", ms=1, alpha=0.3, label="SPH particles")
            ax[k].plot(ex[:, 0], ex[:, k + 1], "k-", lw=1, label="exact")
            ax[k].set_xlim(0, 1), ax[k].set_xlabel("x"), ax[k].set_title(f"{name}, t = {t:.3g}")
        ax[0].legend()
    elif dim == 2:
        fig, ax = plt.subplots(figsize=(6, 5.4))
        sc = ax.scatter(d["x"], d["y"], c=d["rho"], s=2, cmap="viridis", lw=0)
        fig.colorbar(sc, ax=ax, label="density")
        ax.set_aspect("equal"), ax.set_xlim(0, 1), ax.set_ylim(0, 1), ax.set_title(f"density, t = {t:.3g}")
    else:
        r = np.sqrt(d["x"] ** 2 + d["y"] ** 2 + d["z"] ** 2)
        log = np.loadtxt(a.run / "log.txt", ndmin=2)
        fig, ax = plt.subplots(1, 2, figsize=(11, 4))
        ax[0].loglog(r, d["rho"], ".", ms=1)
        ax[0].set_xlabel("r"), ax[0].set_ylabel("density"), ax[0].set_title(f"t = {t:.3g}")
        for c, name in ((3, "E"), (4, "K"), (5, "U"), (6, "W")):
            ax[1].plot(log[:, 1], log[:, c], label=name)
        ax[1].set_xlabel("t"), ax[1].legend(), ax[1].set_title("energies")
    fig.tight_layout()
    a.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(a.out, dpi=110)
    print(f"plot.py: wrote {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
