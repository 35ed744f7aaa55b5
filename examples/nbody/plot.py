#!/usr/bin/python3
"""Pictures of an nbody run: projected density of a snapshot, energy-error history.

    plot.py --snapshot OUT/snap_000724.pbin --log OUT/energy.txt --out DIR
    plot.py --run OUT --out DIR          (the last snapshot and energy.txt of OUT)

Reads every snapshot format pik writes through pik.read_snapshot (python/pik): pik
binary (".pbin", checksums verified), ASCII (".txt") and HDF5 (needs h5py), and
outputs written one part per rank under mpirun (OUT/snap_000724.pbin names the
parts snap_000724.0.pbin, .1.pbin, ...). Writes DIR/density.png and
DIR/energy.png and prints their paths. Bad input ends with "plot.py: error: ..." and exit status 1.
"""
from __future__ import annotations

import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


# The pik package (python/pik) from this source tree; an installed pik is used
# when the tree's copy is absent.
_PYTHON_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python")
if os.path.isdir(os.path.join(_PYTHON_DIR, "pik")):
    sys.path.insert(0, os.path.normpath(_PYTHON_DIR))
import pik  # noqa: E402


class InputError(Exception):
    """A file that cannot be read; the message names it."""


def read_output(path: str) -> pik.Snapshot:
    """One output: the file PATH, or the parts PATH-stem.K.ext that N ranks wrote,
    read and joined by pik.read_snapshot (every format, checksums verified)."""
    try:
        return pik.read_snapshot(path)
    except pik.SnapshotError as e:
        raise InputError(str(e)) from None


def read_binary(path: str) -> pik.Snapshot:
    """One pik binary file, every checksum verified (kept for scripts importing plot)."""
    if pik.detect_format(path) != "binary":
        raise InputError(f"{path}: not a pik binary snapshot")
    try:
        return pik.read_snapshot(path, parts=False)
    except pik.SnapshotError as e:
        raise InputError(str(e)) from None


def output_name(file: str) -> str:
    """snap_000724.3.pbin -> snap_000724.pbin (the output a part belongs to)."""
    stem, ext = os.path.splitext(file)
    base, dot, k = stem.rpartition(".")
    return base + ext if dot and k.isdigit() else file


def latest_snapshot(run: str) -> str:
    """The snapshot of a run folder with the highest step. An HDF5 snapshot without
    h5py is replaced by the run's checkpoint when that holds the same step."""
    try:
        snaps = sorted({output_name(f) for f in os.listdir(run) if f.startswith("snap_")})
    except OSError as e:
        raise InputError(f"{run}: {e.strerror}") from None
    chk = os.path.join(run, "checkpoint.pbin")
    have_chk = os.path.exists(chk) or os.path.exists(os.path.join(run, "checkpoint.0.pbin"))
    if not snaps:
        if have_chk:
            return chk
        raise InputError(f"{run}: no snapshot (snap_*) and no checkpoint.pbin")
    last = os.path.join(run, snaps[-1])
    if last.endswith(".hdf5") and have_chk:
        try:
            import h5py  # noqa: F401
        except ImportError:
            step = int(snaps[-1][5:].split(".")[0])
            if read_output(chk).step == step:
                return chk
    return last


def plot_density(snap: dict, out: str, extent: float) -> None:
    """Projected surface density on the x-y and x-z planes, log colour scale."""
    pos, mass = snap.pos, snap.mass
    fig, axes = plt.subplots(1, 2, figsize=(10, 5), constrained_layout=True)
    bins = int(min(256, max(48, np.sqrt(len(mass)))))  # about N^(1/2) pixels a side
    for ax, (a, b, label) in zip(axes, [(0, 1, "y"), (0, 2, "z")]):
        h, xe, ye = np.histogram2d(pos[:, a], pos[:, b], bins=bins, weights=mass,
                                   range=[[-extent, extent], [-extent, extent]])
        sigma = h / ((2 * extent / bins) ** 2)
        vmin = max(sigma.max(), 1e-30) * 10**-3.5  # 3.5 decades of contrast
        im = ax.imshow(np.log10(np.maximum(sigma.T, vmin)), origin="lower", cmap="magma",
                       extent=[xe[0], xe[-1], ye[0], ye[-1]], vmin=np.log10(vmin))
        ax.set_xlabel("x")
        ax.set_ylabel(label)
        ax.set_title(f"projected density, x-{label}")
    fig.colorbar(im, ax=axes, shrink=0.8, label="log10 surface density")
    fig.suptitle(f"{len(mass)} particles, t = {snap.time:.4g} (step {snap.step})")
    fig.savefig(out, dpi=110)
    plt.close(fig)


def plot_energy(log: str, out: str) -> None:
    try:
        with open(log) as f:
            cols = f.readline().lstrip("#").split()
        table = np.loadtxt(log, comments="#", ndmin=2)
    except (OSError, ValueError) as e:
        raise InputError(f"{log}: {e}") from None
    for c in ("time", "dE/E", "Px", "Py", "Pz"):
        if c not in cols:
            raise InputError(f"{log}: no column '{c}' (columns: {' '.join(cols)})")
    table = table[1:]  # step 0 defines E(0): its error is 0 by definition
    if len(table) == 0:
        raise InputError(f"{log}: no steps after step 0")
    t = table[:, cols.index("time")]
    de = np.maximum(table[:, cols.index("dE/E")], 1e-17)
    p = np.sqrt(sum(table[:, cols.index(c)] ** 2 for c in ("Px", "Py", "Pz")))
    fig, ax = plt.subplots(figsize=(7, 4.5), constrained_layout=True)
    ax.semilogy(t, de, label="|E(t) - E(0)| / |E(0)|")
    ax.semilogy(t, np.maximum(p, 1e-17), label="|P| (total momentum)", alpha=0.7)
    ax.set_xlabel("time (N-body units)")
    ax.set_title("conservation: energy error and momentum")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="plot.py", description=__doc__.splitlines()[0])
    ap.add_argument("--snapshot", help="snapshot file for the density picture")
    ap.add_argument("--log", help="energy.txt of the run for the energy-error history")
    ap.add_argument("--run", help="an nbody output folder: its last snapshot and energy.txt")
    ap.add_argument("--out", default=".", help="folder for the PNGs (default: .)")
    ap.add_argument("--extent", type=float, default=2.0,
                    help="half-width of the density picture (default 2)")
    args = ap.parse_args(argv)
    if not args.snapshot and not args.log and not args.run:
        ap.error("give --run, or --snapshot and/or --log")
    try:
        if args.run:
            args.snapshot = args.snapshot or latest_snapshot(args.run)
            args.log = args.log or os.path.join(args.run, "energy.txt")
        os.makedirs(args.out, exist_ok=True)
        if args.snapshot:
            path = os.path.join(args.out, "density.png")
            plot_density(read_output(args.snapshot), path, args.extent)
            print(f"plot.py: {path} (projected density of {args.snapshot})")
        if args.log:
            path = os.path.join(args.out, "energy.png")
            plot_energy(args.log, path)
            print(f"plot.py: {path} (energy error and momentum from {args.log})")
    except InputError as e:
        print(f"plot.py: error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
