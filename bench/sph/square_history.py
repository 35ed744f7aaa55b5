#!/usr/bin/env python3
"""The hydrostatic square over time, per scheme (docs/sph.md): corner loss and spread
of every snapshot (the measures `sph --problem square` prints at the end,
examples/sph/Problems.hpp) and the mass-weighted rms velocity of every step (log.txt's
K), for runs made with `--snapshots N`.

    square_history.py --out FILE.png [--title T ...] [--n N] RUN_DIR [RUN_DIR ...]

--n is the light fluid's lattice (particles per unit length, the runs' --n): it sets
the spread's margin 1/n. Also prints one line per snapshot and run.
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


def in_corners(pos: np.ndarray) -> np.ndarray:
    """The four corner squares 0.15 < |x - 1/2|, |y - 1/2| < 1/4 of the initial square."""
    ax, ay = np.abs(pos[:, 0] - 0.5), np.abs(pos[:, 1] - 0.5)
    return (ax > 0.15) & (ay > 0.15) & (ax < 0.25) & (ay < 0.25)


def measures(snap, n0: int, n: int) -> tuple[float, float]:
    """(corner loss |1 - N / N0|, spread) as Problems.hpp defines them."""
    pos, tag = np.asarray(snap.pos), np.asarray(snap["Tag"]).astype(int)
    dense = tag == 1
    corner = abs(1.0 - np.count_nonzero(dense & in_corners(pos)) / max(n0, 1))
    d = np.maximum(np.abs(pos[:, 0] - 0.5), np.abs(pos[:, 1] - 0.5)) - 0.25
    wrong = np.count_nonzero(dense & (d > 1.0 / n)) + np.count_nonzero((tag == 0) & (d < -1.0 / n))
    return corner, wrong / max(np.count_nonzero(dense), 1)


def history(run: Path, n: int):
    snaps = sorted(run.glob("snap_[0-9]*.*"))
    if not snaps:
        sys.exit(f"square_history.py: error: no numbered snapshots in {run} (run with --snapshots N)")
    first = pik.read_snapshot(snaps[0])
    n0 = int(np.count_nonzero((np.asarray(first["Tag"]) == 1) & in_corners(np.asarray(first.pos))))
    rows = []
    for f in snaps:
        s = pik.read_snapshot(f)
        rows.append((s.time, *measures(s, n0, n)))
    log = np.loadtxt(run / "log.txt", comments="#")
    mass = float(np.sum(np.asarray(first.mass))) if hasattr(first, "mass") else 1.0
    return np.array(rows), log[:, 1], np.sqrt(2 * log[:, 4] / mass)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--title", action="append", default=[])
    ap.add_argument("--n", type=int, default=32)
    ap.add_argument("runs", nargs="+", type=Path)
    a = ap.parse_args()
    fig, ax = plt.subplots(1, 2, figsize=(10, 3.6))
    for k, run in enumerate(a.runs):
        name = a.title[k] if k < len(a.title) else run.name
        rows, t, v = history(run, a.n)
        for time, corner, spread in rows:
            print(f"{name}: t = {time:.3f}  deformation {corner + spread:.4f} (corner loss {corner:.4f} + "
                  f"spread {spread:.4f})")
        line, = ax[0].plot(rows[:, 0], rows[:, 1] + rows[:, 2], "o-", label=name)
        ax[1].semilogy(t, v, color=line.get_color(), label=name)
    ax[0].set(xlabel="t", ylabel="deformation (corner loss + spread)", ylim=(0, None))
    ax[1].set(xlabel="t", ylabel="rms velocity (mass-weighted)")
    ax[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(a.out, dpi=90)
    return 0


if __name__ == "__main__":
    sys.exit(main())
