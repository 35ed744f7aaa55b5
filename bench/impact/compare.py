"""Compares `impact collide` runs (resolutions, time-step schemes): disk mass, predicted
satellite mass (Ida, Canup & Stewart 1997), disk angular momentum and iron fraction
against time from each run's analysis.txt (`impact analyse --run DIR`), and the total
energy and angular momentum against time from its log.txt; prints markdown tables and
writes two PNGs.

usage: compare.py --out DIR [--hours 2,4,6,...] RUN:LABEL [RUN:LABEL ...]
writes DIR/impact_resolution.png (disk, moon, L_disk, iron against time) and
DIR/impact_energy.png (relative energy and angular-momentum change against time).
"""
import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def load(run):
    a = np.loadtxt(os.path.join(run, "analysis.txt"), ndmin=2)
    log = np.loadtxt(os.path.join(run, "log.txt"), ndmin=2)
    return a, log


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--hours", default="2,3,4,6,8,12,16,20,24")
    ap.add_argument("runs", nargs="+", help="RUN_DIR:LABEL")
    o = ap.parse_args()
    os.makedirs(o.out, exist_ok=True)
    hours = [float(x) for x in o.hours.split(",")]
    runs = []
    for r in o.runs:
        d, _, lab = r.partition(":")
        if not os.path.isfile(os.path.join(d, "analysis.txt")):
            sys.exit(f"compare.py: error: {d}/analysis.txt missing (run `impact analyse --run {d}`)")
        runs.append((lab or d, *load(d)))
    cols = {"M_disk (M_L)": 3, "M_moon predicted (M_L)": 7, "L_disk (L_EM)": 5, "iron in disk": 6,
            "M_esc (M_L)": 4, "M_planet (M_E)": 1}
    print("| t (h) | " + " | ".join(f"{h:g}" for h in hours) + " |")
    print("|---|" + "---|" * len(hours))
    for name, c in cols.items():
        for lab, a, _ in runs:
            vals = []
            for h in hours:
                k = np.where(np.abs(a[:, 0] - h) < 1e-3)[0]
                vals.append(f"{a[k[0], c]:.3g}" if len(k) else "–")
            print(f"| {name}, {lab} | " + " | ".join(vals) + " |")
    print()
    print("| run | rows | t_end (h) | E0 (J) | E_end (J) | max abs(E - E0)/abs(E0) | max abs(L - L0)/L0 |")
    print("|---|---|---|---|---|---|---|")
    for lab, _, log in runs:
        e, l = log[:, 3], np.linalg.norm(log[:, 7:10], axis=1)
        print(f"| {lab} | {len(log)} | {log[-1, 1] / 3600:.2f} | {e[0]:.4g} | {e[-1]:.4g} | "
              f"{np.max(np.abs(e - e[0])) / abs(e[0]):.2e} | {np.max(np.abs(l - l[0])) / l[0]:.2e} |")

    fig, ax = plt.subplots(2, 2, figsize=(9, 6.2), layout="constrained", sharex=True)
    for (name, c), axx in zip(list(cols.items())[:4], ax.flat):
        for lab, a, _ in runs:
            axx.plot(a[:, 0], a[:, c], label=lab)
        axx.set_ylabel(name)
        axx.grid(alpha=0.3)
    for axx in ax[1]:
        axx.set_xlabel("t (h)")
    ax[0, 0].legend(fontsize=8)
    fig.savefig(os.path.join(o.out, "impact_resolution.png"), dpi=90)

    fig, ax = plt.subplots(1, 2, figsize=(9, 3.2), layout="constrained")
    for lab, _, log in runs:
        t, e, l = log[:, 1] / 3600, log[:, 3], np.linalg.norm(log[:, 7:10], axis=1)
        ax[0].plot(t, (e - e[0]) / abs(e[0]), label=lab)
        ax[1].plot(t, (l - l[0]) / l[0], label=lab)
    ax[0].set_yscale("symlog", linthresh=1e-3)  # the runaway of the old code and the 1e-3 of the fixed one
    ax[0].set_ylabel("(E - E0) / |E0|  (symlog, linear below 1e-3)")
    ax[1].set_ylabel("(L - L0) / L0")
    for axx in ax:
        axx.set_xlabel("t (h)")
        axx.grid(alpha=0.3)
    ax[0].legend(fontsize=8)
    fig.savefig(os.path.join(o.out, "impact_energy.png"), dpi=90)


if __name__ == "__main__":
    main()
