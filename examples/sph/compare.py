#!/usr/bin/env python3
"""Side-by-side particle maps of 2D examples/sph runs (the contact problems), coloured
by fluid (Tag: 0 light, 1 dense, 2 wall), for docs/sph.md.

    compare.py --out FILE.png [--snap N] [--title T ...] [--ylim LO HI] [--size S] RUN_DIR [RUN_DIR ...]

--snap picks snap_NNNN (default: the final or last snapshot of each run).
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


def snapshot(run: Path, index: int | None):
    if index is not None:
        snaps = sorted(run.glob(f"snap_{index:04d}.*"))
    else:
        snaps = sorted(run.glob("snap_final.*")) or sorted(run.glob("snap_[0-9]*.*"))
    if not snaps:
        sys.exit(f"compare.py: error: no snapshot in {run}")
    try:
        return pik.read_snapshot(snaps[-1])
    except pik.SnapshotError as e:
        sys.exit(f"compare.py: error: {e}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=Path)
    ap.add_argument("--out", required=True, type=Path)
    ap.add_argument("--snap", type=int)
    ap.add_argument("--title", action="append", default=[])
    ap.add_argument("--ylim", type=float, nargs=2)
    ap.add_argument("--size", type=float, default=0.6, help="marker size (points^2)")
    a = ap.parse_args()
    height = 2.4 * (a.ylim[1] - a.ylim[0] if a.ylim else 1.0) + 0.4
    fig, axs = plt.subplots(1, len(a.runs), figsize=(2.6 * len(a.runs), height), squeeze=False)
    for k, (ax, run) in enumerate(zip(axs[0], a.runs)):
        s = snapshot(run, a.snap)
        tag = s["Tag"]
        for t, c in ((0, "tab:blue"), (1, "tab:red"), (2, "0.3")):
            m = tag == t
            ax.scatter(s.pos[m, 0], s.pos[m, 1], s=a.size, c=c, lw=0)
        ax.set_aspect("equal")
        ax.set_xlim(0, 1)
        if a.ylim:
            ax.set_ylim(*a.ylim)
        ax.set_xticks([]), ax.set_yticks([])
        title = a.title[k] if k < len(a.title) else run.name
        ax.set_title(f"{title}, t = {s.time:.3g}", fontsize=8)
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main())
