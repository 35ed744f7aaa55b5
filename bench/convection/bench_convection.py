#!/usr/bin/env python3
"""Benchmark of examples/convection: Blankenbach et al. (1989) case 1a to steady state.

    bench_convection.py --build BUILD [--nz 32] [--t-end 0.3] [--quick]

Prints two tables:
  1. the time step each method allows at the case 1a parameters (Ra = 1e4, Pr = 2.5e25
     and K = 1.3e6 from the benchmark's mantle values), from one step of the program:
     plain explicit SPH (xi = c = f = 1), VIM (xi for a modified Prandtl number of 10),
     VIM + RSST (f = 5), and the factor each buys against plain SPH;
  2. the run to steady state at the documented resolution: particles, steps, wall time,
     particle-steps per second, the time (d^2/kappa) and wall time at which Nu and v_rms
     reach steady state (the 0.02-long running mean stays within 2 % of the final mean),
     and the time-averaged Nu and v_rms against the benchmark's values.
The CPU model is printed with the table (lscpu). Not a test: nothing is asserted.
"""
from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

NU, VRMS = 4.884409, 42.864947  # Blankenbach et al. (1989), case 1a (best estimates)
METHODS = [("plain explicit SPH", ["--xi", "1", "--c", "1", "--rsst", "1"]),
           ("VIM (xi = 2.5e24, Pr' = 10)", ["--xi", "2.5e24", "--rsst", "1"]),
           ("VIM (xi = 2.5e23, c = 3.16, Pr' = 10)", ["--xi", "2.5e23", "--c", "3.16227766", "--rsst", "1"]),
           ("VIM + RSST (f = 5)", ["--xi", "2.5e24", "--rsst", "5"])]


def cpu() -> str:
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        return next(l.split(":", 1)[1].strip() for l in out.splitlines() if l.startswith("Model name"))
    except (OSError, StopIteration):
        return "unknown CPU"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default="build")
    ap.add_argument("--nz", type=int, default=32)
    ap.add_argument("--t-end", type=float, default=0.3)
    ap.add_argument("--quick", action="store_true", help="time steps only, no run to steady state")
    a = ap.parse_args()
    exe = Path(a.build) / "bin" / "convection"
    if not exe.exists():
        sys.exit(f"bench_convection.py: no {exe} (build the convection target)")
    print(f"convection benchmark, case 1a (Ra = 1e4), {a.nz} particles across the depth; CPU: {cpu()}")
    print(f"\n{'method':40s} {'dt (d^2/kappa)':>15s} {'limited by':>12s} {'vs plain':>10s}")
    plain = None
    with tempfile.TemporaryDirectory() as tmp:
        for name, opts in METHODS:
            p = subprocess.run([str(exe), "--nz", str(a.nz), *opts, "--max-steps", "1", "--snapshots", "0",
                                "--out", f"{tmp}/dt"], capture_output=True, text=True)
            m = re.search(r"time step ([0-9.eE+-]+) limited by (\w+)", p.stdout)
            c = re.search(r" c ([0-9.eE+-]+);", p.stdout)
            if not m:
                print(f"{name:40s} failed: {p.stderr.strip()[:100]}")
                continue
            dt = float(m.group(1)) * (float(c.group(1)) if c else 1.0)  # code time -> d^2/kappa
            plain = plain or dt
            print(f"{name:40s} {dt:15.4g} {m.group(2):>12s} {dt / plain:10.3g}")
        if a.quick:
            return 0
        out = Path(tmp) / "run"
        cmd = [str(exe), "--nz", str(a.nz), "--xi", "2.5e24", "--rsst", "5", "--t-end", str(a.t_end),
               "--snapshots", "0", "--out", str(out)]
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit(f"run failed: {p.stderr}")
        m = re.search(r"after (\d+) steps \(([0-9.]+) s, ([0-9.eE+-]+) particle-steps/s", p.stdout)
        n = re.search(r"(\d+) particles", p.stdout)
        names = (out / "log.txt").open().readline().lstrip("#").split()
        d = np.loadtxt(out / "log.txt", ndmin=2)
        lg = {k: d[:, i] for i, k in enumerate(names)}
        t, nu, v = lg["time"], 0.5 * (lg["Nu_top"] + lg["Nu_bot"]), lg["v_rms"]
        keep = t >= t[-1] * 2 / 3
        nu_f, v_f = nu[keep].mean(), v[keep].mean()
        # running means over 0.02 d^2/kappa; steady from the first time all later ones stay within 2 %
        win = max(1, int(np.searchsorted(t, 0.02)))
        run_nu = np.convolve(nu, np.ones(win) / win, mode="valid")
        run_v = np.convolve(v, np.ones(win) / win, mode="valid")
        bad = np.nonzero((np.abs(run_nu / nu_f - 1) > 0.02) | (np.abs(run_v / v_f - 1) > 0.02))[0]
        i_ss = min(len(run_nu) - 1, (bad[-1] + 1) if len(bad) else 0) + win - 1
        steps, wall, rate = int(m.group(1)), float(m.group(2)), float(m.group(3))
        print(f"\nrun: {' '.join(cmd[1:-2])}")
        print(f"{'particles':>10s} {'steps':>8s} {'wall s':>8s} {'part-steps/s':>13s} {'t_steady':>9s} "
              f"{'wall to steady':>15s} {'Nu':>8s} {'err':>7s} {'v_rms':>8s} {'err':>7s}")
        print(f"{n.group(1):>10s} {steps:8d} {wall:8.1f} {rate:13.3g} {t[i_ss]:9.3f} "
              f"{wall * lg['step'][i_ss] / steps:15.1f} {nu_f:8.4f} {100 * (nu_f / NU - 1):+6.2f}% {v_f:8.3f} "
              f"{100 * (v_f / VRMS - 1):+6.2f}%")
    return 0


if __name__ == "__main__":
    sys.exit(main())
