#!/usr/bin/env python3
"""examples/convection under mpirun: the same problem as one process, and restart.

    check_convection_mpi.py TEST CONVECTION_BINARY OUT_DIR MPIEXEC [MPIRUN_FLAG ...]

TEST is one of
  ranks    Blankenbach et al. (1989) case 1a (Ra = 1e4, isoviscous, aspect 1; steady
           Nu = 4.884409, v_rms = 42.864947) at CI size (16 across, modified Pr 10, RSST
           factor 5), run to t = 0.03 d^2/kappa (the convective rise of Nu from 1 to ~2,
           ~940 steps) with 1, 2 and 4 ranks. The ranks see the same neighbours and wall
           images; only the order of the single-precision kernel sums differs. Every log
           row (Nu at the top and bottom, v_rms: the kinetic energy, <T>: the thermal
           energy, the time step) must agree with the 1-rank run:
             - without particle shifting (--shift 0) within TOL_EXACT (relative);
             - with the default shifting within TOL_SHIFT: shifting makes the particle
               arrangement sensitive to rounding (in ONE process, the initial amplitude
               changed by 1e-6 relative moves Nu by 3.5e-4 and v_rms by 6.5e-4 at step
               1400), so the bound is that sensitivity, not the rounding (measured
               between 1 and 2 ranks at this length: 2.3e-5).
           The number of steps must be the same, and the final snapshot (one file,
           gathered in id order) must hold every particle once. Plus a 3D box (10 across,
           1,000 particles, support 3 spacings) for 40 steps with 1, 2 and 4 ranks; and case
           2a's law (contrast 1e3, --stress local, the default for it) for 300 steps with 1
           and 2 ranks, within TOL_EXACT.
  restart  2 ranks: a run continued from its checkpoint equals the uninterrupted run bit
           for bit (log rows and every column of the final checkpoint); and a 1-rank
           checkpoint continued on 2 ranks agrees with the 1-rank continuation within
           TOL_EXACT.
  errors   the stratified setup refuses to run under mpirun with a clear message and a
           non-zero exit; a bad option under mpirun exits non-zero.
"""
from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "python"))
import pik  # noqa: E402  (python/pik: read_snapshot)

CASE1A = ["--nz", "16", "--xi", "2.5e24", "--rsst", "5", "--hfac", "4", "--shift", "2", "--snapshots", "0"]
CASE3D = ["--dim", "3", "--mode", "roll", "--nz", "10", "--hfac", "3", "--xi", "2.5e24", "--rsst", "5",
          "--snapshots", "0"]
# Relative agreement of the log rows between rank counts (measured largest differences,
# docs/convection-mpi.md: without shifting 4e-6 over 1,860 steps; with shifting 7e-4 at
# 1,860 steps and below 1e-6 up to step 600).
TOL_EXACT = 1e-4
TOL_SHIFT = 3e-4
COLUMNS = ["dt", "Nu_top", "Nu_bot", "v_rms", "T_mean", "Nu_vol"]


def run(cmd: list[str], check: bool = True) -> subprocess.CompletedProcess:
    p = subprocess.run(cmd, capture_output=True, text=True)
    if check and p.returncode != 0:
        sys.exit(f"FAIL: {' '.join(cmd)} exited {p.returncode}\n{p.stdout}\n{p.stderr}")
    return p


def conv(binary: str, mpi: list[str], np_: int, args: list[str], out: Path, check: bool = True):
    return run([*mpi, "-np", str(np_), binary, *args, "--out", str(out)], check)


def log(out: Path) -> dict[str, np.ndarray]:
    path = out / "log.txt"
    with path.open() as f:
        names = f.readline().lstrip("#").split()
    d = np.loadtxt(path, comments="#", ndmin=2)
    return {n: d[:, i] for i, n in enumerate(names)}


def compare(ref: Path, other: Path, what: str, tol: float = TOL_EXACT) -> float:
    a, b = log(ref), log(other)
    if len(a["step"]) != len(b["step"]):
        sys.exit(f"FAIL: {what}: {len(b['step'])} log rows against {len(a['step'])} with one rank")
    worst = 0.0
    for c in COLUMNS:
        x, y = a[c], b[c]
        if c == "dt":  # the last step ends on t_end: a remainder, not a criterion
            x, y = x[:-1], y[:-1]
        d = float(np.max(np.abs(y - x) / np.maximum(np.abs(x), 1e-30)))
        worst = max(worst, d)
        print(f"  {what}: {c:7s} largest relative difference {d:.2e}")
    if worst > tol:
        sys.exit(f"FAIL: {what}: log rows differ by {worst:.2e} > {tol:g} from one rank")
    return worst


def test_ranks(binary: str, out: Path, mpi: list[str]) -> None:
    exact = [*CASE1A, "--t-end", "0.03", "--shift", "0"]
    for n in (1, 2, 4):
        conv(binary, mpi, n, exact, out / f"np{n}")
    lg = log(out / "np1")
    print(f"case 1a, 16 across, t = 0.03, no shifting: {int(lg['step'][-1])} steps, Nu top {lg['Nu_top'][-1]:.5f} "
          f"bottom {lg['Nu_bot'][-1]:.5f}, v_rms {lg['v_rms'][-1]:.4f}")
    for n in (2, 4):
        compare(out / "np1", out / f"np{n}", f"2D {n} ranks")
    s1 = pik.read_snapshot(str(out / "np1" / "snap_final.pbin"))
    s2 = pik.read_snapshot(str(out / "np2" / "snap_final.pbin"))
    if not np.array_equal(s1.id, s2.id) or not np.array_equal(s2.id, np.arange(len(s2.id))):
        sys.exit("FAIL: the 2-rank snapshot does not hold every particle once in id order")
    dpos = float(np.max(np.abs(s1.pos - s2.pos)))
    print(f"  final positions, 1 against 2 ranks: largest difference {dpos:.2e} (spacing 0.0625)")
    if dpos > 1e-5:
        sys.exit(f"FAIL: final positions differ by {dpos:.2e} between 1 and 2 ranks")
    shifted = [*CASE1A, "--t-end", "0.03"]
    for n in (1, 2):
        conv(binary, mpi, n, shifted, out / f"shift_np{n}")
    compare(out / "shift_np1", out / "shift_np2", "2D 2 ranks, shifting", TOL_SHIFT)
    # case 2a's law (viscosity contrast 1e3) with the default --stress auto = local: pass 1 and
    # its per-particle transpose part on halo particles and wall images (measured 3.5e-6)
    case2a = ["--viscosity", "exp", "--contrast", "1000", "--xi-law", "viscosity", "--xi", "2.5e22", "--rsst", "3",
              "--nz", "16", "--hfac", "4", "--shift", "0", "--snapshots", "0", "--t-end", "1", "--max-steps", "300"]
    for n in (1, 2):
        conv(binary, mpi, n, case2a, out / f"c2a_np{n}")
    compare(out / "c2a_np1", out / "c2a_np2", "case 2a law, --stress local, 2 ranks")
    args3 = [*CASE3D, "--t-end", "0.3", "--max-steps", "40"]
    for n in (1, 2, 4):
        conv(binary, mpi, n, args3, out / f"d3_np{n}")
    for n in (2, 4):
        compare(out / "d3_np1", out / f"d3_np{n}", f"3D {n} ranks")


def test_restart(binary: str, out: Path, mpi: list[str]) -> None:
    base = [*CASE1A, "--t-end", "1", "--amplitude", "0.3"]
    conv(binary, mpi, 2, [*base, "--max-steps", "60"], out / "full")
    conv(binary, mpi, 2, [*base, "--max-steps", "30"], out / "first")
    shutil.copytree(out / "first", out / "second")  # a restart continues its own directory (log.txt)
    conv(binary, mpi, 2, [*base, "--max-steps", "60", "--restart", str(out / "second" / "checkpoint.pbin")],
         out / "second")
    a, b = (out / "full" / "log.txt").read_text(), (out / "second" / "log.txt").read_text()
    if a != b:
        sys.exit("FAIL: the 2-rank log after the restart differs from the uninterrupted 2-rank run")
    ca = pik.read_snapshot(str(out / "full" / "checkpoint.pbin"))
    cb = pik.read_snapshot(str(out / "second" / "checkpoint.pbin"))
    arrays = {"id": (ca.id, cb.id), "mass": (ca.mass, cb.mass), "pos": (ca.pos, cb.pos), "vel": (ca.vel, cb.vel)}
    if sorted(ca.columns) != sorted(cb.columns):
        sys.exit("FAIL: the checkpoints after the 2-rank restart hold different columns")
    arrays.update({k: (ca.columns[k], cb.columns[k]) for k in ca.columns})
    names = list(arrays)
    for k, (x, y) in arrays.items():
        if not np.array_equal(x, y):
            sys.exit(f"FAIL: column {k} of the final checkpoint differs after the 2-rank restart")
    print(f"2 ranks: restart at step 30 equals the uninterrupted run bit for bit (log, {len(names)} columns)")
    # a checkpoint written by one process, continued on two ranks
    conv(binary, mpi, 1, [*base, "--max-steps", "30"], out / "one")
    for n in (1, 2):
        shutil.copytree(out / "one", out / f"one_to_{n}")
        conv(binary, mpi, n, [*base, "--max-steps", "60", "--restart", str(out / f"one_to_{n}" / "checkpoint.pbin")],
             out / f"one_to_{n}")
    compare(out / "one_to_1", out / "one_to_2", "1-rank checkpoint continued on 2 ranks")


def test_errors(binary: str, out: Path, mpi: list[str]) -> None:
    p = run([*mpi, "-np", "2", binary, "--setup", "stratified", "--max-steps", "1", "--out", str(out / "s")], check=False)
    if p.returncode == 0 or "one process only" not in p.stdout + p.stderr:
        sys.exit(f"FAIL: --setup stratified under mpirun -np 2 gave exit {p.returncode}:\n{p.stdout}\n{p.stderr}")
    print("refused: --setup stratified under mpirun -np 2")
    p = run([*mpi, "-np", "2", binary, "--xi", "0.5", "--out", str(out / "b")], check=False)
    if p.returncode == 0 or "must be at least 1" not in p.stdout + p.stderr:
        sys.exit(f"FAIL: --xi 0.5 under mpirun gave exit {p.returncode}:\n{p.stdout}\n{p.stderr}")
    print("refused: --xi 0.5 under mpirun -np 2")


def main() -> None:
    if len(sys.argv) < 5:
        sys.exit(__doc__)
    test, binary, out, mpi = sys.argv[1], sys.argv[2], Path(sys.argv[3]), sys.argv[4:]
    if out.exists():
        shutil.rmtree(out)
    out.mkdir(parents=True)
    {"ranks": test_ranks, "restart": test_restart, "errors": test_errors}[test](binary, out, mpi)
    print("PASS")


if __name__ == "__main__":
    main()
