"""Plots of a cosmo_gas run: P(k) of the dark matter and the gas against linear theory
at every output, and the gas temperature against a (with the adiabatic a^-2 line).

    python3 examples/cosmo/plot_gas.py --run gas --out docs/img   # cosmo_gas_pk.png
"""
import argparse
import glob
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--run", required=True, help="the cosmo_gas --out directory")
ap.add_argument("--out", default=".", help="where cosmo_gas_pk.png goes")
args = ap.parse_args()
files = sorted(glob.glob(f"{args.run}/pk_*.txt"))
if not files or not Path(f"{args.run}/gas.txt").exists():
    sys.exit(f"plot_gas.py: no pk_*.txt / gas.txt in {args.run}")
fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.5))
for i, f in enumerate(files):
    head = open(f).readline().split()
    a = float(head[2])
    d = np.loadtxt(f)
    c = f"C{i}"
    ax.loglog(d[:, 0], d[:, 1], "-", color=c, label=f"dark matter, a = {a:.3g}")
    ax.loglog(d[:, 0], d[:, 2], "o", ms=3, color=c, label="gas" if i == 0 else None)
    ax.loglog(d[:, 0], d[:, 4], ":", color=c)
ax.set_xlabel("k [h/Mpc]")
ax.set_ylabel("P(k) [(Mpc/h)$^3$]")
ax.set_title("P(k): dark matter (lines), gas (dots), linear (dotted)")
ax.legend(fontsize=7)
g = np.atleast_2d(np.loadtxt(f"{args.run}/gas.txt"))
bx.loglog(g[:, 1], g[:, 3], "o-", label="mass-weighted mean T")
bx.loglog(g[:, 1], g[:, 5], "s--", label="largest T")
bx.loglog(g[:, 1], g[0, 3] * (g[0, 1] / g[:, 1]) ** 2, "k:", label="adiabatic, T ∝ a$^{-2}$")
bx.set_xlabel("a")
bx.set_ylabel("T [K]")
bx.set_title("gas temperature")
bx.legend(fontsize=8)
fig.tight_layout()
out = Path(args.out) / "cosmo_gas_pk.png"
fig.savefig(out, dpi=90)
print(f"wrote {out}")
