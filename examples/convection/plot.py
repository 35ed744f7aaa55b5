#!/usr/bin/env python3
"""PNG plots of an examples/convection run (matplotlib, Agg).

    plot.py --run DIR --out PREFIX

writes PREFIX_temperature.png (the temperature field of the last snapshot with the
velocity arrows; 3D runs: the particles of the middle slice) and PREFIX_series.png
(Nusselt number at the top and bottom and v_rms against time in d^2/kappa, from
DIR/log.txt, with the Blankenbach et al. 1989 value where the run is one of its
cases). Snapshots are read with the pik Python package (python/pik).
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

# Blankenbach et al. (1989), best estimates (their Table 9; 1b and 2a as tabulated by Wilson &
# van Keken 2023, doi:10.1186/s40645-023-00588-6, and ASPECT's benchmarks/blankenbach):
# (Ra, viscosity contrast) -> (case, Nu, v_rms)
REFERENCE = {(1e4, 1.0): ("1a", 4.884409, 42.864947), (1e5, 1.0): ("1b", 10.534095, 193.21454),
             (1e6, 1.0): ("1c", 21.972465, 833.98977), (1e4, 1e3): ("2a", 10.0660, 480.4334)}


def read_log(path: Path) -> dict[str, np.ndarray]:
    with path.open() as f:
        names = f.readline().lstrip("#").split()
    data = np.loadtxt(path, comments="#", ndmin=2)
    if data.shape[0] == 0:
        sys.exit(f"plot.py: error: {path} has no rows")
    return {n: data[:, i] for i, n in enumerate(names)}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--run", required=True, type=Path, help="output directory of convection (--out)")
    ap.add_argument("--out", required=True, help="prefix of the PNG files")
    a = ap.parse_args()
    snaps = sorted(a.run.glob("snap_final.*")) or sorted(a.run.glob("snap_[0-9]*.*"))
    if not snaps or not (a.run / "log.txt").exists():
        sys.exit(f"plot.py: error: no snapshot (snap_*) or log.txt in {a.run}")
    try:
        s = pik.read_snapshot(snaps[-1])
    except pik.SnapshotError as e:
        sys.exit(f"plot.py: error: {e}")
    dim = int(s.attrs.get("convection.dim", "2"))
    c = float(s.attrs.get("convection.c", "1"))
    ra = float(s.attrs.get("convection.ra", "0"))
    law = s.attrs.get("convection.law", "constant")
    contrast = float(s.attrs.get("convection.contrast", "1")) if law == "exp" else 1.0
    t = s["Temperature"]
    x, z, vx, vz = s.pos[:, 0], s.pos[:, dim - 1], s.vel[:, 0] / c, s.vel[:, dim - 1] / c
    if dim == 3:  # the middle slice in y
        y = s.pos[:, 1]
        dy = np.sort(np.unique(np.round(y, 6)))
        mid = dy[len(dy) // 2] if len(dy) else 0.5
        keep = np.abs(y - mid) < 0.5 * (dy[1] - dy[0] if len(dy) > 1 else 1)
        x, z, vx, vz, t = x[keep], z[keep], vx[keep], vz[keep], t[keep]
    width = float(np.max(s.pos[:, 0]) + np.min(s.pos[:, 0]))
    fig, ax = plt.subplots(figsize=(5.5 * max(width, 0.5) + 1.2, 5.2))
    sc = ax.scatter(x, z, c=t, s=max(2.0, 9000.0 / max(len(t), 1)), cmap="coolwarm", vmin=0, vmax=1)
    step = max(1, len(x) // 400)
    ax.quiver(x[::step], z[::step], vx[::step], vz[::step], color="k", alpha=0.6, width=0.003)
    ax.set_aspect("equal")
    ax.set_xlim(0, width), ax.set_ylim(0, 1)
    ax.set_xlabel("x / d"), ax.set_ylabel("z / d")
    ax.set_title(f"Ra = {ra:g}, t = {s.time * c:.4g} d$^2$/$\\kappa$, {len(s.id)} particles")
    fig.colorbar(sc, ax=ax, label="temperature")
    fig.tight_layout()
    fig.savefig(f"{a.out}_temperature.png", dpi=110)
    plt.close(fig)

    log = read_log(a.run / "log.txt")
    time = log["time"] * c
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    a1.plot(time, log["Nu_top"], label="Nu top", lw=1)
    a1.plot(time, log["Nu_bot"], label="Nu bottom", lw=1, alpha=0.7)
    a2.plot(time, log["v_rms"], label="v$_{rms}$", lw=1, color="C2")
    ref = REFERENCE.get((ra, contrast))
    if ref and dim == 2:
        a1.axhline(ref[1], color="k", ls="--", lw=0.8, label=f"Blankenbach et al. 1989 case {ref[0]}")
        a2.axhline(ref[2], color="k", ls="--", lw=0.8, label=f"case {ref[0]}")
    a1.set_ylabel("Nusselt number"), a2.set_ylabel("v$_{rms}$ ($\\kappa$/d)")
    a2.set_xlabel("t (d$^2$/$\\kappa$)")
    a1.legend(fontsize=8), a2.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(f"{a.out}_series.png", dpi=110)
    plt.close(fig)
    print(f"plot.py: wrote {a.out}_temperature.png and {a.out}_series.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
