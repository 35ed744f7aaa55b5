#!/usr/bin/env python3
"""Runs examples/sph at CI-friendly sizes and checks the printed measurements against
the reference physics (docs/sph.md). Usage: check_sph.py TEST SPH_BINARY OUT_DIR PLOT_PY

Each check fails when the physics is wrong: the Sod profile must approach the exact
solution as the resolution doubles, DISPH must keep the square clearly better than
SSPH, the KH mode must grow at a rate near the linear one, and the Evrard collapse
must conserve energy."""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path


def run(binary: str, out: Path, *args: str) -> str:
    cmd = [binary, *args, "--out", str(out)]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=280)
    print("$", " ".join(cmd))
    print(p.stdout + p.stderr)
    if p.returncode != 0:
        raise SystemExit(f"FAIL: exit status {p.returncode}")
    return p.stdout


def number(text: str, pattern: str) -> list[float]:
    m = re.search(pattern, text)
    if not m:
        raise SystemExit(f"FAIL: no match for {pattern!r}")
    return [float(g) for g in m.groups()]


def check(cond: bool, what: str) -> None:
    print(("ok    " if cond else "FAIL  ") + what)
    if not cond:
        raise SystemExit(1)


def sod(binary: str, out: Path) -> None:
    errs = {}
    for n in (24, 48):
        text = run(binary, out / f"n{n}", "--problem", "sod", "--scheme", "disph", "--kernel", "wendland2",
                   "--n", str(n))
        ps, us = number(text, r"p\* = ([\d.]+) u\* = ([\d.]+)")
        check(abs(ps - 0.30313) < 5e-5 and abs(us - 0.92745) < 5e-5, f"exact star state p* {ps}, u* {us}")
        errs[n] = number(text, r"rho ([\d.]+)\s+p ([\d.]+)\s+vx ([\d.]+)")
    for k, name in enumerate(("density", "pressure", "velocity")):
        check(errs[48][k] < 0.9 * errs[24][k], f"L1 {name} decreases with resolution: {errs[24][k]} -> {errs[48][k]}")
    for k, (name, bound) in enumerate((("density", 0.03), ("pressure", 0.035), ("velocity", 0.05))):
        check(errs[48][k] < bound, f"L1 {name} at n = 48: {errs[48][k]} < {bound}")


def square(binary: str, out: Path) -> None:
    d = {}
    for s in ("ssph", "disph"):
        text = run(binary, out / s, "--problem", "square", "--scheme", s, "--n", "24", "--t-end", "3")
        d[s] = number(text, r"square deformation \(t = [\d.]+\): ([\d.]+)")[0]
    check(d["disph"] < 0.2, f"DISPH keeps the square: deformation {d['disph']} < 0.2")
    check(d["ssph"] > 0.3 and d["ssph"] > 3 * d["disph"], f"SSPH rounds it: {d['ssph']} > 0.3 and > 3 x DISPH")


def kh(binary: str, out: Path) -> None:
    text = run(binary, out, "--problem", "kh", "--scheme", "disph", "--kernel", "wendland2", "--n", "32",
               "--t-end", "1.5")
    m0, m1, _t, m15, rate = number(
        text, r"M\(0\) = ([\d.]+)\s+M\(1\) = ([\d.]+)\s+M\(([\d.]+)\) = ([\d.]+)\s+growth rate \(0.25 <= t <= 1\) ([-\d.]+)")
    sigma0 = 4 * 3.141592653589793 * 2 ** 0.5 / 3  # incompressible vortex sheet: k dU sqrt(r1 r2) / (r1 + r2)
    check(abs(m0 - 0.01) < 0.002, f"seeded amplitude M(0) = {m0}")
    check(m15 > 4 * m0, f"the mode grows: M(1.5) = {m15} > 4 M(0)")
    check(0.3 * sigma0 < rate < sigma0, f"growth rate {rate} within (0.3, 1) x the vortex-sheet rate {sigma0:.3f}")


def evrard(binary: str, out: Path) -> None:
    text = run(binary, out, "--problem", "evrard", "--n", "14", "--kernel", "wendland2", "--eps", "0.02",
               "--t-end", "1.5")
    e0, e, k, u, w, final, worst = number(
        text, r"E0 ([-\d.]+)\s+E ([-\d.]+) \(K ([\d.]+) U ([\d.]+) W ([-\d.]+)\)\s+\|dE/E0\| final ([\d.]+) max ([\d.]+)")
    check(-0.75 < e0 < -0.5, f"initial energy {e0} (about 0.05 - 2/3 with softening)")
    check(u > 0.3, f"the collapse heated the gas: U = {u} > 0.3 at t = 1.5")
    check(worst < 0.03, f"energy conserved: max |dE/E0| = {worst} < 0.03")


def cli(binary: str, out: Path) -> None:
    for args, msg in ((["--problem", "nope"], "--problem must be"), (["--scheme", "x"], "--scheme must be"),
                      (["--kernel", "gauss"], "--kernel must be"), (["--cfl", "0"], "--cfl must be"),
                      # negative values once fell back silently to the problem's default
                      (["--gamma", "-1"], "--gamma must be positive"),
                      (["--t-end", "-1"], "--t-end must be positive"),
                      (["--nngb", "-5"], "--nngb must be positive"),
                      (["--problem", "evrard", "--theta", "-1"], "--theta must be in [0, 2]"),
                      (["--n", "100000"], "--n and --ny must be at most 1000"),
                      (["--format", "xml"], "--format: unknown snapshot format")):
        p = subprocess.run([binary, *args, "--out", str(out)], capture_output=True, text=True)
        check(p.returncode == 2 and msg in p.stderr, f"{' '.join(args)}: exit 2, '{msg}'")


def restart(binary: str, out: Path) -> None:
    """A run stopped after 20 steps and restarted from its checkpoint ends bit for bit like
    an uninterrupted one (final snapshot and log); a checkpoint of other physics is refused."""
    args = ["--problem", "square", "--scheme", "disph", "--n", "16", "--t-end", "0.3"]
    run(binary, out / "whole", *args)
    run(binary, out / "split", *args, "--max-steps", "20")
    text = run(binary, out / "split", *args, "--restart", str(out / "split" / "checkpoint.pbin"))
    check("steps" in text, "the restarted run finished")
    for f in ("snap_final.pbin", "log.txt"):
        a, b = (out / "whole" / f).read_bytes(), (out / "split" / f).read_bytes()
        check(a == b, f"{f} of the restarted run equals the uninterrupted run's ({len(a)} bytes)")
    p = subprocess.run([binary, "--problem", "square", "--scheme", "ssph", "--n", "16", "--restart",
                        str(out / "split" / "checkpoint.pbin"), "--out", str(out / "other")],
                       capture_output=True, text=True)
    check(p.returncode == 1 and "scheme = disph" in p.stderr, f"a checkpoint of another scheme is refused: {p.stderr.strip()}")
    p = subprocess.run([binary, "--restart", str(out / "missing.pbin"), "--out", str(out / "other")],
                       capture_output=True, text=True)
    check(p.returncode == 1 and "missing.pbin" in p.stderr, f"a missing checkpoint is named: {p.stderr.strip()}")


def plots(binary: str, out: Path, plot_py: str) -> None:
    run(binary, out / "sod", "--problem", "sod", "--n", "16", "--t-end", "0.05")
    run(binary, out / "kh", "--problem", "kh", "--n", "16", "--t-end", "0.05")
    for name in ("sod", "kh"):
        png = out / f"{name}.png"
        p = subprocess.run([sys.executable, plot_py, "--run", str(out / name), "--out", str(png)],
                           capture_output=True, text=True)
        check(p.returncode == 0 and png.exists() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n",
              f"plot.py wrote {png} {p.stderr}")


def main() -> int:
    test, binary, out, plot_py = sys.argv[1], sys.argv[2], Path(sys.argv[3]), sys.argv[4]
    out.mkdir(parents=True, exist_ok=True)
    if test == "plots":
        plots(binary, out, plot_py)
    else:
        {"sod": sod, "square": square, "kh": kh, "evrard": evrard, "cli": cli, "restart": restart}[test](binary, out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
