#!/usr/bin/env python3
"""End-to-end checks of the Lennard-Jones program (examples/md) at CI size.

usage: check_md.py MD_BINARY CASE      CASE: dense | gas | cli

dense, gas: runs md at T* = 0.85 and compares the potential energy per particle
(with the tail correction) with the NIST reference (Monte Carlo, LJ truncated at
3 sigma with analytic long-range corrections):
  rho* = 0.86:  U/N = -6.0305   must agree within 1 %, and the run's statistical
                error must be small enough (< 0.2 %) for that to mean something;
  rho* = 0.009: U/N = -9.3973e-2 must agree within 3 block-averaged standard
                errors (plus the reference's own last digit), and that error must
                be below 5 % of |U/N| so the comparison can fail.
Also the mean kinetic temperature must be T within its error (CSVR is canonical).
cli: --help, and bad options answered with a clear error and exit status 2.
"""
import os
import re
import subprocess
import sys
import tempfile

T_REF = 0.85
CASES = {
    # name: (rho, U/N reference, md options)
    "dense": (0.86, -6.0305, ["--cells", "5", "--steps-equil", "2000", "--steps-prod", "15000"]),
    # The gas decorrelates slowly (pairs form and break over ~20-40 time units; see
    # docs/md.md), so fewer, longer blocks: 10 blocks of 10000 steps (t = 50 each).
    "gas": (0.009, -9.3973e-2, ["--cells", "5", "--steps-equil", "10000", "--steps-prod", "100000",
                                "--blocks", "10"]),
}


def stat(out: str, name: str) -> tuple[float, float]:
    m = re.search(re.escape(name) + r"\s+(-?[0-9.eE+-]+) \+- ([0-9.eE+-]+)", out)
    if not m:
        sys.exit(f"check_md: no '{name}' line in the output:\n{out}")
    return float(m.group(1)), float(m.group(2))


def run_reference(md: str, case: str) -> int:
    rho, ref, opts = CASES[case]
    cmd = [md, "--rho", str(rho), "--temperature", str(T_REF), "--seed", "1", *opts]
    print("$", " ".join(cmd), flush=True)
    p = subprocess.run(cmd, capture_output=True, text=True)
    print(p.stdout, p.stderr, sep="")
    if p.returncode != 0:
        sys.exit(f"check_md: md exited with status {p.returncode}")
    u, du = stat(p.stdout, "U/N (with tail)")
    t, dt = stat(p.stdout, "T")
    fails = []
    if abs(t - T_REF) > 4 * dt + 1e-3:
        fails.append(f"mean temperature {t:.5f} +- {dt:.5f} is not {T_REF}")
    dev = abs(u - ref)
    if case == "dense":
        print(f"U/N = {u:.5f} +- {du:.5f}, NIST {ref}: {100 * dev / abs(ref):.3f} % off (limit 1 %)")
        if du > 0.002 * abs(ref):
            fails.append(f"statistical error {du:.2e} too large to test 1 %")
        if dev > 0.01 * abs(ref):
            fails.append(f"U/N {u:.5f} is more than 1 % from {ref}")
    else:
        limit = 3 * du + 5e-6  # + half a unit of the reference's last digit (rounded up)
        print(f"U/N = {u:.6f} +- {du:.6f}, NIST {ref}: off by {dev:.2e} = {dev / du:.2f} sigma "
              f"(limit 3 sigma)")
        if du > 0.05 * abs(ref):
            fails.append(f"statistical error {du:.2e} above 5 % of |U/N|: the run is too short")
        if dev > limit:
            fails.append(f"U/N {u:.6f} differs from {ref} by {dev:.2e} > 3 sigma = {3 * du:.2e}")
    for f in fails:
        print("FAIL:", f)
    return 1 if fails else 0


def run_cli(md: str) -> int:
    fails = []
    p = subprocess.run([md, "--help"], capture_output=True, text=True)
    if p.returncode != 0 or "--rho" not in p.stdout or "--steps-prod" not in p.stdout:
        fails.append(f"--help: status {p.returncode}, output {p.stdout!r}")
    bad = [
        (["--rho", "-1"], "--rho must be positive"),
        (["--rho", "dense"], "'dense' is not a number"),
        (["--temperature", "0"], "--temperature must be positive"),
        (["--dt", "0"], "--dt must be positive"),
        (["--n", "300"], "nearest: 256 or 500"),
        (["--n", "500", "--cells", "5"], "not both"),
        (["--cells", "0"], "--cells must be at least 1"),
        (["--ensemble", "npt"], "--ensemble must be nvt or nve"),
        (["--steps-prod", "10"], "--steps-prod must be at least"),
        (["--seed", "-3"], "not a non-negative integer"),
        (["--frobnicate"], "unknown option '--frobnicate'"),
        (["--rho"], "needs a value"),
    ]
    for args, msg in bad:
        p = subprocess.run([md, *args], capture_output=True, text=True)
        if p.returncode != 2 or msg not in p.stderr or not p.stderr.startswith("md: error:"):
            fails.append(f"md {' '.join(args)}: status {p.returncode}, stderr {p.stderr!r} "
                         f"(want 2 and '{msg}')")
    p = subprocess.run([md, "--n", "32", "--steps-equil", "10", "--steps-prod", "40", "--blocks", "4",
                        "--ensemble", "nve"], capture_output=True, text=True)
    if p.returncode != 0 or "U/N (with tail)" not in p.stdout:
        fails.append(f"small NVE run: status {p.returncode}\n{p.stdout}{p.stderr}")
    # Run-time failures: exit 1 with the reason, before any work for a bad --series
    # path; a blown-up run (overlapping atoms) stops instead of integrating nonsense.
    failing = [
        (["--series", "/nonexistent-dir/series.txt"], "cannot create a temporary file", "after equilibration"),
        (["--n", "32", "--rho", "100", "--steps-equil", "10", "--steps-prod", "40", "--blocks", "4"],
         "unstable run", "results"),
    ]
    for args, msg, never in failing:
        p = subprocess.run([md, *args], capture_output=True, text=True)
        if p.returncode != 1 or msg not in p.stderr or never in p.stdout:
            fails.append(f"md {' '.join(args)}: status {p.returncode}, stderr {p.stderr!r} (want 1 and '{msg}')")
    series = os.path.join(tempfile.mkdtemp(), "series.txt")
    p = subprocess.run([md, "--n", "32", "--steps-equil", "10", "--steps-prod", "40", "--blocks", "4",
                        "--series", series], capture_output=True, text=True)
    rows = open(series).read().splitlines() if os.path.exists(series) else []
    if p.returncode != 0 or len(rows) != 41:
        fails.append(f"--series: status {p.returncode}, {len(rows)} lines (want 41)")
    for f in fails:
        print("FAIL:", f)
    n_checks = len(bad) + len(failing) + 3
    print(f"cli: {n_checks - len(fails)} of {n_checks} checks passed")
    return 1 if fails else 0


def main() -> int:
    if len(sys.argv) != 3 or sys.argv[2] not in (*CASES, "cli"):
        sys.exit(__doc__)
    md, case = sys.argv[1], sys.argv[2]
    return run_cli(md) if case == "cli" else run_reference(md, case)


if __name__ == "__main__":
    sys.exit(main())
