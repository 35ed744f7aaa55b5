#!/usr/bin/env python3
"""Runs `convection --setup stratified` (the polytropic layer with the reduced speed of
sound technique) at CI size and checks the physics.

    check_stratified.py TEST CONVECTION_BINARY OUT_DIR

TEST is one of
  rsst     Hotta, Rempel & Yokoyama (2012): slowing the continuity equation by 1/xi^2
           leaves the convection unchanged while its Mach number against the reduced
           sound speed stays below ~0.7. A density contrast 3 layer (gamma 5/3, Ra 1e4,
           Pr 1, superadiabaticity 2e-3, 10 rows, aspect 2, particle shifting 6, the
           pressure gauge 'mean') with xi = 1, xi = 10 and a spatially varying xi
           (--rsst-law uniform, xi = 10 at the top), to t = 600 (about 0.45 thermal
           diffusion times, 16 turnovers): the time-averaged v_rms (second half) of each
           agrees with xi = 1 within 5 % (the issue's bound), the Mach number stays below
           0.7, and the median step is at least 8 times (xi = 10) the xi = 1 step (the step
           is sound-limited: it grows ~xi).
  onset    below the onset of convection (Ra 300; the Boussinesq free-slip critical value is
           27 pi^4 / 4 = 657.5, Chandrasekhar 1961, and stratification raises it) the initial
           perturbation decays and Nu returns to 1; at Ra 1e4 it grows into convection
           (Nu > 2). With xi = 10.
  restart  a run continued from its checkpoint equals the uninterrupted run bit for bit
  cli      bad parameters refused with a message and a non-zero exit; --help documents
           the layer
"""
from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np

LAYER = ["--setup", "stratified", "--chi", "3", "--ra", "1e4", "--prandtl", "1", "--delta", "2e-3", "--nz", "10",
         "--aspect", "2", "--snapshots", "0"]
TOL_VRMS = 0.05   # issue 12: convective v_rms agrees within 5 % across RSST factors
# the RSST comparison's scheme: shifting 6 (at 10 rows the default 2 leaves a disorder, rms
# |sum_j V_j gradW_ij| h ~ 0.1, whose spurious pressure force lowers v_rms by up to 12 %;
# docs/convection-stratified.md) and the pressure gauge 'mean' (the default)
RSST_SCHEME = ["--shift", "6", "--gauge", "mean"]
MA_LIMIT = 0.7    # Hotta et al. (2012): RSST holds below ~0.7


def run(binary: str, args: list[str], out: Path, check: bool = True) -> subprocess.CompletedProcess:
    cmd = [binary, *args, "--out", str(out)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if check and p.returncode != 0:
        sys.exit(f"FAIL: {' '.join(cmd)} exited {p.returncode}\n{p.stdout}\n{p.stderr}")
    return p


def log(out: Path) -> dict[str, np.ndarray]:
    path = out / "log.txt"
    with path.open() as f:
        names = f.readline().lstrip("#").split()
    d = np.loadtxt(path, comments="#", ndmin=2)
    return {n: d[:, i] for i, n in enumerate(names)}


def averages(out: Path, frac: float = 2 / 3) -> dict[str, float]:
    """Time averages over the part of the run after frac of its end time."""
    lg = log(out)
    keep = lg["time"] >= lg["time"][-1] * frac
    return {"vrms": float(lg["v_rms"][keep].mean()), "pe": float(lg["Pe"][keep].mean()),
            "nu": float(0.5 * (lg["Nu_top"][keep] + lg["Nu_bot"][keep]).mean()),
            "ma": float(lg["Ma_max"][keep].max()), "dt": float(np.median(lg["dt"][1:])), "steps": int(lg["step"][-1])}


def test_rsst(binary: str, out: Path) -> None:
    runs = {"xi 1": ["--rsst", "1"], "xi 10": ["--rsst", "10"], "xi 10 uniform": ["--rsst", "10", "--rsst-law", "uniform"]}
    res = {}
    for name, opts in runs.items():
        d = out / name.replace(" ", "_")
        run(binary, [*LAYER, *opts, *RSST_SCHEME, "--t-end", "600"], d)
        res[name] = r = averages(d, 0.5)
        print(f"{name:14s}: v_rms {r['vrms']:.5f} ({r['pe']:.2f} kappa/d)  Nu {r['nu']:.3f}  Ma max {r['ma']:.3f}  "
              f"median dt {r['dt']:.4g}  steps {r['steps']}")
    base = res["xi 1"]
    if base["nu"] < 2:
        sys.exit(f"FAIL: no convection at Ra 1e4 (Nu {base['nu']:.3f})")
    for name in ("xi 10", "xi 10 uniform"):
        r = res[name]
        dv, grow = r["vrms"] / base["vrms"] - 1, r["dt"] / base["dt"]
        print(f"{name}: v_rms {100 * dv:+.2f} % against xi = 1 (tolerance {100 * TOL_VRMS:.0f} %), Nu "
              f"{100 * (r['nu'] / base['nu'] - 1):+.2f} %, step x{grow:.2f}, {base['steps'] / r['steps']:.1f}x fewer steps")
        if abs(dv) > TOL_VRMS:
            sys.exit(f"FAIL: {name}: v_rms differs from the xi = 1 run by {100 * dv:+.2f} %")
        if r["ma"] > MA_LIMIT:
            sys.exit(f"FAIL: {name}: Mach number {r['ma']:.3f} above {MA_LIMIT} against the reduced sound speed")
        if grow < 8:
            sys.exit(f"FAIL: {name}: the step grew only x{grow:.2f} with xi = 10 (sound-limited: ~x10 expected)")


def test_onset(binary: str, out: Path) -> None:
    base = [*LAYER, "--rsst", "10", "--amplitude", "1"]
    run(binary, [*base, "--ra", "300", "--t-end", "150"], out / "sub")
    lg = log(out / "sub")
    vmax, vend, nuend = lg["v_rms"].max(), lg["v_rms"][-1], lg["Nu_top"][-1]
    print(f"Ra 300: v_rms max {vmax:.3g}, at the end {vend:.3g}; Nu top at the end {nuend:.4f}")
    if not (vend < 0.2 * vmax and abs(nuend - 1) < 0.05):
        sys.exit("FAIL: below the onset the perturbation did not decay")
    run(binary, [*base, "--t-end", "150"], out / "super")
    lg = log(out / "super")
    nu = 0.5 * (lg["Nu_top"][-1] + lg["Nu_bot"][-1])
    print(f"Ra 1e4: Nu at the end {nu:.3f}, v_rms {lg['v_rms'][-1]:.3g} ({lg['Pe'][-1]:.1f} kappa/d)")
    if not nu > 2:
        sys.exit("FAIL: above the onset no convection developed")


def test_restart(binary: str, out: Path) -> None:
    # with the acoustic filter on: its kernel average is recomputed from the state each pass
    base = [*LAYER, "--rsst", "10", "--t-end", "1000", "--amplitude", "1", "--filter", "1"]
    run(binary, [*base, "--max-steps", "60"], out / "full")
    run(binary, [*base, "--max-steps", "30"], out / "first")
    shutil.copytree(out / "first", out / "second")
    run(binary, [*base, "--max-steps", "60", "--restart", str(out / "second" / "checkpoint.pbin")], out / "second")
    a = (out / "full" / "checkpoint.pbin").read_bytes()
    b = (out / "second" / "checkpoint.pbin").read_bytes()
    if a != b:
        sys.exit("FAIL: the restarted run differs from the uninterrupted one")
    la, lb = log(out / "full"), log(out / "second")
    if not np.array_equal(la["v_rms"][-30:], lb["v_rms"][-30:]):
        sys.exit("FAIL: the log rows after the restart differ")
    # a checkpoint of other physics is refused
    p = run(binary, [*base, "--rsst", "3", "--max-steps", "61", "--restart", str(out / "full" / "checkpoint.pbin")],
            out / "other", check=False)
    if p.returncode == 0 or "another stratified.rsst" not in p.stderr:
        sys.exit(f"FAIL: a checkpoint with another RSST factor was accepted:\n{p.stderr}")
    p = run(binary, [*base, "--filter", "0.5", "--max-steps", "61", "--restart", str(out / "full" / "checkpoint.pbin")],
            out / "other_filter", check=False)
    if p.returncode == 0 or "another stratified.filter" not in p.stderr:
        sys.exit(f"FAIL: a checkpoint with another acoustic filter was accepted:\n{p.stderr}")
    print(f"restart: checkpoints after 60 steps identical ({len(a)} bytes), log rows identical; other physics refused")


def test_cli(binary: str, out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    corrupt = out / "corrupt.pbin"
    corrupt.write_bytes(b"not a checkpoint")
    s = ["--setup", "stratified"]
    cases = [
        (["--prandtl", "-1"], "Prandtl number must be positive"),
        (["--rsst", "0.5"], "RSST factor must be at least 1"),
        (["--rsst-law", "random"], "--rsst-law must be"),
        (["--chi", "1"], "density contrast"),
        (["--delta", "0"], "superadiabaticity"),
        (["--gamma", "1"], "specific heats"),
        (["--nz", "2"], "particle rows"),
        (["--aspect", "0.01"], "box is empty"),
        (["--rsst", "1000"], "order of magnitude"),
        (["--kernel", "cubic"], "wendland2 and wendland4"),
        (["--bogus", "1"], "unknown option"),
        (["--gauge", "zero"], "--gauge must be mean or absolute"),
        (["--filter", "-1"], "acoustic filter strength --filter must be in [0, 2]"),
        (["--restart", str(corrupt), "--max-steps", "1"], "error"),
    ]
    for args, want in cases:
        p = run(binary, [*s, *args], out / "bad", check=False)
        text = p.stdout + p.stderr
        if p.returncode == 0 or want not in text:
            sys.exit(f"FAIL: {args} gave exit {p.returncode}, wanted a non-zero exit and '{want}':\n{text}")
        print(f"refused {args}: {text.strip().splitlines()[-1]}")
    p = run(binary, ["--setup", "nonsense"], out / "bad", check=False)
    if p.returncode == 0 or "--setup must be" not in p.stderr:
        sys.exit(f"FAIL: --setup nonsense accepted:\n{p.stdout}{p.stderr}")
    p = subprocess.run([binary, *s, "--help"], capture_output=True, text=True)
    if p.returncode != 0 or "--rsst" not in p.stdout or "--chi" not in p.stdout or "Hotta" not in p.stdout:
        sys.exit("FAIL: convection --setup stratified --help")
    p = subprocess.run([binary, "--help"], capture_output=True, text=True)
    if p.returncode != 0 or "--setup" not in p.stdout:
        sys.exit("FAIL: convection --help does not document --setup")
    p = run(binary, [*s, "--rsst", "80", "--max-steps", "1", "--nz", "6"], out / "warn")
    if "warning: validity condition broken: estimated Mach number" not in p.stderr:
        sys.exit(f"FAIL: no warning for an estimated Mach number above 0.7:\n{p.stderr}")
    print("help and warnings: ok")


def main() -> int:
    test, binary, out = sys.argv[1], sys.argv[2], Path(sys.argv[3])
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)
    tests = {"rsst": test_rsst, "onset": test_onset, "restart": test_restart, "cli": test_cli}
    if test not in tests:
        sys.exit(f"unknown test {test}")
    tests[test](binary, out)
    print("PASS")
    return 0


if __name__ == "__main__":
    sys.exit(main())
