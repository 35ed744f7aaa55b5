#!/usr/bin/env python3
"""RSST study on the stratified (polytropic) convection layer of examples/convection.

    stratified_rsst.py --build BUILD [--nz 16] [--t-end 600] [--factors 1,10,30]
                       [--out DIR] [--plot docs/img/stratified_rsst.png] [--shift 6] [--gauge mean]
                       [--filter 0] [--from T] [--jobs 1]

Runs `convection --setup stratified` with each RSST factor xi (Hotta, Rempel & Yokoyama
2012: d rho1/dt = -(1/xi^2) div(rho0 v)) at the same physical parameters (density
contrast 3, gamma 5/3, Ra 1e4, Pr 1, superadiabaticity 5e-4), and prints a table: the
time averages over the second half of the run of v_rms (code units and kappa/d), Nu at
the top and bottom, the largest and rms Mach number against the reduced sound speed,
the mean time step, the number of steps and the wall time, each against xi = 1. With
--plot it draws v_rms(t) of every run and the step against xi. Not a test: the CI-size
check is tests/convection/check_stratified.py. The CPU model is printed (lscpu).
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

PHYS = ["--chi", "3", "--ra", "1e4", "--prandtl", "1", "--delta", "5e-4", "--aspect", "2"]


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


def summary(lg: dict[str, np.ndarray], t_from: float) -> dict[str, float]:
    t = lg["time"]
    keep = t >= t_from
    dt = lg["dt"][1:]
    return {"vrms": float(lg["v_rms"][keep].mean()), "pe": float(lg["Pe"][keep].mean()),
            "nut": float(lg["Nu_top"][keep].mean()), "nub": float(lg["Nu_bot"][keep].mean()),
            "mamax": float(lg["Ma_max"][keep].max()), "marms": float(lg["Ma_rms"][keep].mean()),
            "dt": float(np.median(dt)), "steps": int(lg["step"][-1])}


def block_error(lg: dict[str, np.ndarray], t_from: float, blocks: int = 5) -> float:
    """Standard error of the time mean of v_rms over [t_from, t_end]: the window cut into
    `blocks` equal blocks in time, the spread of the block means / sqrt(blocks - 1) (blocks
    long against the correlation time of the flow, about a turnover)."""
    t, v = lg["time"], lg["v_rms"]
    edges = np.linspace(t_from, t[-1], blocks + 1)
    means = [v[(t >= lo) & (t < hi)].mean() for lo, hi in zip(edges[:-1], edges[1:]) if ((t >= lo) & (t < hi)).any()]
    return float(np.std(means, ddof=1) / np.sqrt(len(means))) if len(means) > 1 else float("nan")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default="build")
    ap.add_argument("--nz", type=int, default=16)
    ap.add_argument("--t-end", type=float, default=600)
    ap.add_argument("--factors", default="1,10,30")
    ap.add_argument("--out", default="stratified_rsst_out")
    ap.add_argument("--plot", default="")
    ap.add_argument("--shift", default="6", help="particle shifting strength (convection --shift)")
    ap.add_argument("--gauge", default="mean", help="pressure gauge (convection --gauge mean|absolute)")
    ap.add_argument("--filter", default="0", help="acoustic filter strength (convection --filter; 0: off)")
    ap.add_argument("--from", dest="t_from", type=float, default=0.0,
                    help="start of the averaging window (0: the second half of the run)")
    ap.add_argument("--jobs", type=int, default=1, help="runs at once (each one thread)")
    ap.add_argument("--reuse", action="store_true", help="tabulate existing runs in --out without running")
    a = ap.parse_args()
    exe = Path(a.build) / "bin" / "convection"
    if not exe.exists():
        sys.exit(f"stratified_rsst.py: no {exe} (build the convection target)")
    factors = [float(f) for f in a.factors.split(",")]
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    t_from = a.t_from if a.t_from > 0 else a.t_end / 2
    res, logs, wall, err = {}, {}, {}, {}
    if not a.reuse:
        pending = list(factors)
        running: list[tuple[float, subprocess.Popen, float]] = []
        while pending or running:
            while pending and len(running) < max(a.jobs, 1):
                xi = pending.pop(0)
                cmd = [str(exe), "--setup", "stratified", *PHYS, "--nz", str(a.nz), "--rsst", f"{xi:g}",
                       "--shift", a.shift, "--gauge", a.gauge, "--filter", a.filter,
                       "--t-end", str(a.t_end), "--snapshots", "4", "--out", str(out / f"xi{xi:g}")]
                log = (out / f"xi{xi:g}.txt").open("w")
                running.append((xi, subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT), time.time()))
            time.sleep(0.5)
            for item in list(running):
                xi, p, t0 = item
                if p.poll() is None:
                    continue
                running.remove(item)
                wall[xi] = time.time() - t0
                if p.returncode != 0:
                    sys.exit(f"run xi = {xi:g} failed:\n{(out / f'xi{xi:g}.txt').read_text()}")
    for xi in factors:
        d = out / f"xi{xi:g}"
        if a.reuse:
            txt = (out / f"xi{xi:g}.txt").read_text()
            line = next(l for l in txt.splitlines() if l.startswith("final: t ="))
            wall[xi] = float(line.split("(")[1].split(" s")[0])
        logs[xi] = read_log(d / "log.txt")
        res[xi] = summary(logs[xi], t_from)
        err[xi] = block_error(logs[xi], t_from)
    b = res[factors[0]]
    print(f"RSST on the stratified layer: chi 3, gamma 5/3, Ra 1e4, Pr 1, delta 5e-4, aspect 2, {a.nz} rows, shift {a.shift}, "
          f"gauge {a.gauge}, filter {a.filter}; averages over t = {t_from:g}..{a.t_end:g} (+- the standard error of 5 block means); "
          f"CPU: {cpu()}")
    print(f"| xi | v_rms | v_rms (kappa/d) | vs xi={factors[0]:g} | Nu top | Nu bottom | Ma max | Ma rms | median dt | "
          f"dt x | steps | wall s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for xi in factors:
        r = res[xi]
        rel = r['vrms'] / b['vrms'] - 1
        erel = np.hypot(err[xi] / r['vrms'], err[factors[0]] / b['vrms']) * (1 + rel) if xi != factors[0] else err[xi] / b['vrms']
        print(f"| {xi:g} | {r['vrms']:.5g} +- {err[xi]:.2g} | {r['pe']:.4g} | {100 * rel:+.2f} +- {100 * erel:.2f} % | {r['nut']:.4f} | "
              f"{r['nub']:.4f} | {r['mamax']:.3f} | {r['marms']:.3f} | {r['dt']:.4g} | {r['dt'] / b['dt']:.2f} | "
              f"{r['steps']} | {wall[xi]:.0f} |")
    if a.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(1, 2, figsize=(10, 3.8))
        for xi in factors:
            lg = logs[xi]
            ax[0].plot(lg["time"], lg["Pe"], label=f"xi = {xi:g}", lw=1)
        ax[0].set_xlabel("t  [d / sqrt(R T_top)]")
        ax[0].set_ylabel("v_rms  [kappa / d]")
        ax[0].set_title("stratified layer, chi = 3: v_rms for each RSST factor")
        ax[0].legend()
        xs = np.array(factors)
        ax[1].loglog(xs, [res[x]["dt"] for x in factors], "o-", label="median step")
        ax[1].loglog(xs, b["dt"] * xs / xs[0], "k--", lw=0.8, label="proportional to xi")
        ax[1].set_xlabel("RSST factor xi")
        ax[1].set_ylabel("time step")
        ax[1].legend()
        fig.tight_layout()
        fig.savefig(a.plot, dpi=90)
        print(f"wrote {a.plot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
