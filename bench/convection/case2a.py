#!/usr/bin/env python3
"""Blankenbach et al. (1989) case 2a (Ra = 1e4 at the cold top, eta = exp(-b T), viscosity
contrast 1e3; reference Nu = 10.0660, v_rms = 480.4334, their Table 9 as tabulated by Wilson
& van Keken 2023 and ASPECT's benchmarks/blankenbach/reference_statistics.txt): tabulates
runs of `convection --viscosity exp --contrast 1000 ...` from their logs.

    case2a.py RUN_DIR [RUN_DIR ...] [--window 0.01 | --span T0 T1] [--plot docs/img/convection_2a_series.png]
                                                  (Nu, v_rms and <T> against time)

For each run (its out/log.txt, one row per step) it prints the time reached, the steps, the
means over the last --window (or over the fixed interval --span T0 T1, the same for every run) of Nu top, Nu bottom, Nu_vol and v_rms with their errors against
the reference, the spread of Nu top and bottom (a steady state has Nu top = Nu bottom), the
drift of v_rms between the two halves of the window, and the validity numbers of the window
(modified Prandtl number, the largest local Reynolds number, the largest Mach number and the
largest compression; Takeyama et al. 2017: Pr' > 10, Re < 1, Ma < 1; the program warns above
5 % compression), and the mean temperature against 0.742 (bench/convection/fd_reference.py; not
in the benchmark's table). It also prints the heat balance of the window: the drift of <T>
(a linear fit, per d^2/kappa) beside Nu bottom - Nu top, the heat the walls put in. In a steady
state both are zero; a <T> that still drifts means the window is not the run's steady state.
Logs with a Nu_shift column (the heat particle shifting adds, since 2026-12-06) also give its
mean: d<T>/dt = Nu bottom - Nu top + Nu_shift, up to the change of the particles' volumes.
Not a test. The runs and their commands are in docs/convection.md.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

NU_REF, VRMS_REF = 10.0660, 480.4334
# The mean temperature is not in the benchmark's table: bench/convection/fd_reference.py gives
# 0.7420, 0.7419 and 0.7415 on 64, 96 and 128 intervals (v_rms 499.5, 491.5, 487.4 there).
TMEAN_REF = 0.742


def read_log(path: Path) -> dict[str, np.ndarray]:
    with path.open() as f:
        names = f.readline().lstrip("#").split()
    d = np.loadtxt(path, comments="#", ndmin=2)
    return {n: d[:, i] for i, n in enumerate(names)}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--window", type=float, default=0.01, help="averaging window at the end of each run (d^2/kappa)")
    ap.add_argument("--span", type=float, nargs=2, default=None, metavar=("T0", "T1"),
                    help="average over T0 <= t <= T1 instead of the last --window")
    ap.add_argument("--plot", default="")
    ap.add_argument("--labels", default="", help="comma-separated legend labels (default: the directory names)")
    a = ap.parse_args()
    labels = a.labels.split(",") if a.labels else [Path(r).name for r in a.runs]
    logs = {}
    if a.span and not a.span[0] < a.span[1]:
        sys.exit(f"case2a.py: --span needs T0 < T1, not {a.span[0]} {a.span[1]}")
    what = f"t = {a.span[0]:g} to {a.span[1]:g}" if a.span else f"the last {a.window:g} d^2/kappa of each run"
    print(f"case 2a: means over {what}; reference Nu {NU_REF}, v_rms {VRMS_REF}, <T> {TMEAN_REF} (finite differences)")
    print("| run | t reached | steps | Nu top | Nu bottom | Nu_vol | v_rms | v_rms drift | <T> | d<T>/dt | Nu bot - top | Nu_shift | Pr' | Re max | Ma max | compression max |")
    print("|---|---:|---:|---|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for run, lab in zip(a.runs, labels):
        p = Path(run) / "log.txt"
        if not p.exists():
            sys.exit(f"case2a.py: no {p}")
        lg = read_log(p)
        logs[lab] = lg
        t = lg["time"]
        t0, t1 = (a.span[0], a.span[1]) if a.span else (t[-1] - a.window, t[-1])
        keep = (t >= t0) & (t <= t1)
        if not keep.any():
            sys.exit(f"case2a.py: {p} has no step in t = {t0:g} to {t1:g} (it reached {t[-1]:g})")
        half = keep & (t >= 0.5 * (t0 + t1))
        nut, nub, nuv, v, tm = (float(lg[k][keep].mean()) for k in ("Nu_top", "Nu_bot", "Nu_vol", "v_rms", "T_mean"))
        # d<T>/dt by a least-squares line through the window (code time = d^2/kappa when c = 1;
        # the walls' heat per unit area and time is Nu bottom - Nu top in the same units)
        dtdt = float(np.polyfit(t[keep], lg["T_mean"][keep], 1)[0]) if keep.sum() > 2 else float("nan")
        shift = f"{float(lg['Nu_shift'][keep].mean()):+.3f}" if "Nu_shift" in lg else "—"
        drift = float(lg["v_rms"][half].mean() / lg["v_rms"][keep & ~half].mean() - 1) if (keep & ~half).any() else float("nan")
        print(f"| {lab} | {t[-1]:.4f} | {int(lg['step'][-1])} | {nut:.3f} ({100 * (nut / NU_REF - 1):+.1f} %) | "
              f"{nub:.3f} ({100 * (nub / NU_REF - 1):+.1f} %) | {nuv:.3f} | {v:.1f} ({100 * (v / VRMS_REF - 1):+.1f} %) | "
              f"{100 * drift:+.1f} % | {tm:.3f} | {dtdt:+.3f} | {nub - nut:+.3f} | {shift} | {lg['Pr_mod'][keep].min():.3g} | {lg['Re'][keep].max():.3g} | {lg['Ma'][keep].max():.3g} | "
              f"{lg['compression'][keep].max():.3g} |")
    if a.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(1, 3, figsize=(14, 3.8))
        for lab, lg in logs.items():
            s = slice(None, None, max(1, len(lg["time"]) // 4000))
            ax[0].plot(lg["time"][s], lg["Nu_top"][s], lw=1, label=f"{lab} top")
            ax[0].plot(lg["time"][s], lg["Nu_bot"][s], lw=1, ls="--", label=f"{lab} bottom")
            ax[1].plot(lg["time"][s], lg["v_rms"][s], lw=1, label=lab)
            ax[2].plot(lg["time"][s], lg["T_mean"][s], lw=1, label=lab)
        ax[2].axhline(TMEAN_REF, color="k", lw=0.8, ls=":", label=f"finite differences {TMEAN_REF}")
        ax[2].set_xlabel("t  [d^2/kappa]")
        ax[2].set_ylabel("<T>")
        ax[2].set_title("case 2a: mean temperature")
        ax[2].legend(fontsize=7)
        ax[0].axhline(NU_REF, color="k", lw=0.8, ls=":", label="Blankenbach 10.066")
        ax[1].axhline(VRMS_REF, color="k", lw=0.8, ls=":", label="Blankenbach 480.4")
        ax[0].set_ylim(0, 25)
        ax[1].set_ylim(0, 1.6 * VRMS_REF)  # a run that blows up leaves the plot
        ax[0].set_xlabel("t  [d^2/kappa]")
        ax[0].set_ylabel("Nu")
        ax[1].set_xlabel("t  [d^2/kappa]")
        ax[1].set_ylabel("v_rms  [kappa/d]")
        ax[0].set_title("case 2a (contrast 1e3): Nusselt numbers")
        ax[1].set_title("case 2a: v_rms")
        ax[0].legend(fontsize=7)
        ax[1].legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(a.plot, dpi=90)
        print(f"wrote {a.plot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
