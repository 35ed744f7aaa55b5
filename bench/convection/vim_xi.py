#!/usr/bin/env python3
"""VIM inertia study with examples/convection (Boussinesq, Blankenbach et al. 1989 case 1a).

    vim_xi.py --build BUILD [--nz 10] [--t-end 0.25] [--factors 1,10,100,1000]
              [--xi0 2.5e21] [--rsst 5] [--out DIR] [--plot PNG] [--reuse]

The talk's claim (Takeyama, Saitoh & Makino 2017): with the inertia raised by xi (and c)
inside the validity range (modified Prandtl number Pr' = Pr / (xi c^2) > 10, Re < 1,
Ma < 1), the steady state is unchanged while the number of steps falls. Each run uses
the same physics (Ra 1e4, Pr 2.5e25, K = 130 Ra, RSST factor --rsst) and xi = xi0 times
the factor (xi0 = 2.5e21: Pr' = 1e4). The table gives the time averages over the last
third of the run of Nu (mean of top and bottom) and v_rms against the lowest-xi run, the
steps to steady state (the first time the 0.02-long running mean of Nu stays within 1 %
of the final average), the steps in all, what limited the step, and the largest Re and Ma
of the last third (validity). Not a test; the CI check is tests/convection/check_vim_xi.py.
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

import numpy as np


def cpu() -> str:
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        return next(l.split(":", 1)[1].strip() for l in out.splitlines() if l.startswith("Model name"))
    except (OSError, StopIteration):
        return "unknown CPU"


def read_log(path: Path) -> dict[str, np.ndarray]:
    with path.open() as f:
        names = f.readline().lstrip("#").split()
    d = np.loadtxt(path, comments="#", ndmin=2)
    return {n: d[:, i] for i, n in enumerate(names)}


def summary(lg: dict[str, np.ndarray], c: float, tol: float = 0.01, window: float = 0.02) -> dict[str, float]:
    t = lg["time"] * c  # d^2 / kappa
    keep = t >= t[-1] * 2 / 3
    nu = 0.5 * (lg["Nu_top"] + lg["Nu_bot"])
    nbar, vbar = float(nu[keep].mean()), float(lg["v_rms"][keep].mean())
    # running mean of Nu over `window`, on the log rows
    cs = np.concatenate([[0], np.cumsum(nu[1:] * np.diff(t))])
    steady_step = int(lg["step"][-1])
    ok = np.zeros(len(t), bool)
    for i in range(len(t)):
        j = np.searchsorted(t, t[i] + window)
        if j >= len(t):
            break
        ok[i] = abs((cs[j] - cs[i]) / (t[j] - t[i]) / nbar - 1) < tol
    # the first row from which every later window is within tol
    last_bad = np.where(~ok[: np.searchsorted(t, t[-1] - window)])[0]
    i0 = int(last_bad[-1]) + 1 if len(last_bad) else 0
    steady_step = int(lg["step"][min(i0, len(t) - 1)])
    return {"nu": nbar, "vrms": vbar, "steps": int(lg["step"][-1]), "steady": steady_step,
            "tsteady": float(t[min(i0, len(t) - 1)]), "re": float(lg["Re"][keep].max()), "ma": float(lg["Ma"][keep].max()),
            "pr": float(lg["Pr_mod"][keep].min()), "dt": float(np.median(lg["dt"][1:])) * c}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default="build")
    ap.add_argument("--nz", type=int, default=10)
    ap.add_argument("--t-end", type=float, default=0.25)
    ap.add_argument("--factors", default="1,10,100,1000")
    ap.add_argument("--xi0", type=float, default=2.5e21)
    ap.add_argument("--c", type=float, default=1)
    ap.add_argument("--rsst", type=float, default=5)
    ap.add_argument("--extra", default="", help="more options for every run (one string)")
    ap.add_argument("--out", default="vim_xi_out")
    ap.add_argument("--plot", default="")
    ap.add_argument("--reuse", action="store_true", help="tabulate existing runs in --out")
    a = ap.parse_args()
    exe = Path(a.build) / "bin" / "convection"
    if not exe.exists():
        sys.exit(f"vim_xi.py: no {exe} (build the convection target)")
    out = Path(a.out)
    factors = [float(f) for f in a.factors.split(",")]
    res, logs, wall, lim = {}, {}, {}, {}
    for f in factors:
        d = out / f"x{f:g}"
        xi = a.xi0 * f
        if not a.reuse:
            t0 = time.time()
            p = subprocess.run([str(exe), "--nz", str(a.nz), "--xi", f"{xi:.6g}", "--c", f"{a.c:g}", "--rsst", f"{a.rsst:g}",
                                "--t-end", str(a.t_end), "--snapshots", "0", *a.extra.split(), "--out", str(d)],
                               capture_output=True, text=True)
            wall[f] = time.time() - t0
            (out / f"x{f:g}.txt").write_text(p.stdout + p.stderr)
            if p.returncode != 0:
                sys.exit(f"run xi = {xi:g} failed:\n{p.stdout}\n{p.stderr}")
        txt = (out / f"x{f:g}.txt").read_text()
        fin = next(l for l in txt.splitlines() if l.startswith("final: t ="))
        wall[f] = float(fin.split("(")[1].split(" s")[0])
        lim[f] = fin.split("limited by ")[1].rstrip(")")
        logs[f] = read_log(d / "log.txt")
        res[f] = summary(logs[f], a.c)
    b = res[factors[0]]
    print(f"VIM study: Ra 1e4 (Blankenbach case 1a), {a.nz} across, xi0 = {a.xi0:g} (Pr' = {2.5e25 / a.xi0 / a.c**2:g}), "
          f"c = {a.c:g}, RSST factor {a.rsst:g}, t_end {a.t_end:g} d^2/kappa; CPU: {cpu()}")
    print("| xi / xi0 | Pr' | Nu | vs xi0 | v_rms | vs xi0 | steps to steady | fewer x | steps | median dt | limited by | "
          "Re max | Ma max | wall s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for f in factors:
        r = res[f]
        print(f"| {f:g} | {r['pr']:.3g} | {r['nu']:.4f} | {100 * (r['nu'] / b['nu'] - 1):+.2f} % | {r['vrms']:.3f} | "
              f"{100 * (r['vrms'] / b['vrms'] - 1):+.2f} % | {r['steady']} (t {r['tsteady']:.3f}) | "
              f"{b['steady'] / max(r['steady'], 1):.1f} | {r['steps']} | {r['dt']:.3g} | {lim[f]} | {r['re']:.3g} | "
              f"{r['ma']:.3g} | {wall[f]:.0f} |")
    if a.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(1, 2, figsize=(10, 3.8))
        for f in factors:
            lg = logs[f]
            nu = 0.5 * (lg["Nu_top"] + lg["Nu_bot"])
            ax[0].plot(lg["time"] * a.c, nu, lw=1, label=f"xi = {f:g} xi0")
            ax[1].plot(lg["time"] * a.c, lg["v_rms"], lw=1, label=f"xi = {f:g} xi0")
        ax[0].set_ylabel("Nu (mean of top and bottom)")
        ax[1].set_ylabel("v_rms  [kappa / d]")
        for x in ax:
            x.set_xlabel("t  [d^2 / kappa]")
            x.legend(fontsize=8)
        fig.suptitle(f"VIM: case 1a at {a.nz} across, inertia raised by " + ", ".join(f"{f:g}" for f in factors))
        fig.tight_layout()
        fig.savefig(a.plot, dpi=90)
        print(f"wrote {a.plot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
