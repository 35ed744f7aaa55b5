#!/usr/bin/env python3
"""Horizontal profiles of convection runs and of fd_reference.py fields, side by side: the
mean temperature and the rms horizontal velocity against depth (2D runs).

    profiles.py --out FILE.png [--run PATH:LABEL ...] [--fd FILE.npz:LABEL ...]

PATH is a snapshot or checkpoint file, or a run's directory (its snap_final.* or highest
snap_N.*; a run continued by --restart may have its latest state only in checkpoint.pbin).
The particles are binned into rows of one lattice spacing; a --fd file (fd_reference.py
--save) gives its grid rows. It prints the snapshot's time, the volume mean temperature and
the largest |v_x| at the top and the bottom row of each. Not a test; docs/convection.md shows
its figures.
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


def run_profiles(run: Path):
    snaps = [run] if run.is_file() else sorted(run.glob("snap_final.*")) or sorted(run.glob("snap_[0-9]*.*"))
    if not snaps:
        sys.exit(f"profiles.py: error: no snapshot in {run}")
    try:
        s = pik.read_snapshot(snaps[-1])
    except pik.SnapshotError as e:
        sys.exit(f"profiles.py: error: {e}")
    if int(s.attrs.get("convection.dim", "2")) != 2:
        sys.exit(f"profiles.py: error: {run} is not a 2D run")
    c = float(s.attrs.get("convection.c", "1"))
    z, vx, t = s.pos[:, 1], s.vel[:, 0] / c, s["Temperature"]
    n = int(round(float(s.attrs.get("convection.nz", np.sqrt(len(z))))))
    rows = np.clip((z * n).astype(int), 0, n - 1)
    zc = (np.arange(n) + 0.5) / n
    tm = np.array([t[rows == r].mean() for r in range(n)])
    vr = np.array([np.sqrt(np.mean(vx[rows == r] ** 2)) for r in range(n)])
    top, bot = np.abs(vx[rows == n - 1]).max(), np.abs(vx[rows == 0]).max()
    return zc, tm, vr, float(t.mean()), top, bot, f"t = {s.time * c:g}"


def fd_profiles(path: Path):
    try:
        d = np.load(path)
        t, vx = d["T"], d["vx"]
    except (OSError, KeyError, ValueError) as e:
        sys.exit(f"profiles.py: error: cannot read {path}: {e}")
    n = t.shape[0] - 1
    zc = np.linspace(0.0, 1.0, n + 1)
    w = np.full(n + 1, 1.0 / n)
    w[[0, -1]] *= 0.5
    tmean = float(np.sum(w[:, None] * w[None, :] * t))
    return (zc, t.mean(axis=0), np.sqrt(np.mean(vx**2, axis=0)), tmean, np.abs(vx[:, -1]).max(),
            np.abs(vx[:, 0]).max(), f"{n} intervals")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--run", action="append", default=[], help="DIR:LABEL, a convection output directory")
    ap.add_argument("--fd", action="append", default=[], help="FILE.npz:LABEL, an fd_reference.py --save file")
    a = ap.parse_args()
    if not a.run and not a.fd:
        sys.exit("profiles.py: error: give at least one --run or --fd")
    fig, ax = plt.subplots(1, 2, figsize=(9, 4.5), sharey=True)
    items = [(r, run_profiles, "-o") for r in a.run] + [(f, fd_profiles, "--") for f in a.fd]
    for spec, fn, style in items:
        path, _, label = spec.partition(":")
        zc, tm, vr, tmean, top, bot, what = fn(Path(path))
        label = label or Path(path).name
        print(f"{label} ({what}): <T> {tmean:.3f}, max |v_x| top row {top:.1f}, bottom row {bot:.1f}")
        ax[0].plot(tm, zc, style, ms=3, lw=1.2, label=f"{label} (<T> {tmean:.3f})")
        ax[1].plot(vr, zc, style, ms=3, lw=1.2, label=label)
    ax[0].set_xlabel("horizontal mean T")
    ax[0].set_ylabel("z / d")
    ax[1].set_xlabel("rms v_x over x  [kappa/d]")
    ax[0].set_xlim(0, 1)
    ax[0].legend(fontsize=7)
    ax[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(a.out, dpi=90)
    print(f"wrote {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
