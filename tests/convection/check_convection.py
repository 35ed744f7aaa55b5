#!/usr/bin/env python3
"""Runs examples/convection at CI size and checks it against known values.

    check_convection.py TEST CONVECTION_BINARY OUT_DIR PLOT_PY

TEST is one of
  conduction  the conductive state (T = 1 - z, at rest): Nu = 1 exactly at both walls;
              the wall flux through the mirror particles within 2 % (2D and 3D)
  case1a      Blankenbach et al. (1989) case 1a (Ra = 1e4, isoviscous, aspect 1):
              Nu = 4.884409, v_rms = 42.864947 (their best estimates, as quoted in issue 12), time averages over the
              last third of the run at a coarse resolution, within the tolerance below; and
              the heat budget closes: the mean temperature changes by the heat the walls and
              particle shifting put in (the log's Nu_bot - Nu_top + Nu_shift, integrated over
              time) within TOL_BUDGET of the heat that flowed through the walls
  xi          VIM invariance: the inertia raised 10 times (xi, modified Pr 100 -> 10) gives
              the same steady Nu and v_rms within the tolerance below, in fewer steps
  case1a_3d   the same case in a 3D box (aspect 1 x 1 x 1, 8 across, 512 particles) started
              from the 2D roll (--mode roll: cos(pi x / L), uniform in y), an exact solution of
              the 3D equations between free-slip walls: Nu and v_rms within the 3D tolerances
              below of Blankenbach's 2D values, and the flow stays a roll (rms v_y below 10 %
              of v_rms)
  cli         bad parameters refused with a message and a non-zero exit; --help
  restart     a run continued from its checkpoint equals the uninterrupted run bit for bit
  plots       plot.py writes the two PNGs
  init        --init FILE: a coarse case-1a run (10 across) to t = 0.3, then runs started from its
              final snapshot at 16 across and from its checkpoint at 8 across (and from an ASCII
              snapshot, and HDF5 where built in): at t = 0 v_rms and the volume Nusselt number are
              within the tolerances below of the source's last, T stays in [0, 1] with the hot row at
              the bottom, and after 100 steps v_rms and the wall Nu are still within bounds (no
              blow-up); with --init-problem continuation a variable-viscosity run starts from the
              isoviscous field (its v_rms and volume Nu at t = 0 as above, the pressure perturbation
              0); a file of another Rayleigh number, aspect ratio, viscosity law or dimension
              (without continuation; the geometry with it too), a missing or corrupt file, --init
              with --restart and a continuation with --init-pressure yes are refused with a
              message and a non-zero exit
"""
from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np

NU_1A, VRMS_1A = 4.884409, 42.864947  # Blankenbach et al. (1989), case 1a (best estimates)

# CI-size case 1a: 16 particles across the depth (Wendland C2, support 4 spacings, particle
# shifting 2), modified Prandtl number 10 (xi = 2.5e24 with Pr = 2.5e25), RSST factor 5.
CASE1A = ["--nz", "16", "--xi", "2.5e24", "--rsst", "5", "--hfac", "4", "--shift", "2", "--t-end", "0.3",
          "--snapshots", "0"]
# at this resolution SPH's Nu and v_rms sit 5.5 % and 1.9 % below Blankenbach's values (measured
# 2026-12-05 with the difference pressure force and the volume drift removed, the defaults; 6.1 %
# and 4.7 % before, docs/convection.md); the tolerances sit just above the measured errors, so a
# regression of a per cent or two fails
TOL_NU_1A, TOL_VRMS_1A = 0.07, 0.035
# 3D, 8 across: measured -13.7 % (Nu) and -3.9 % (v_rms) (before 2026-12-05: -11.9 % and -7.2 %;
# the 2D run at 8 across then -14.7 % and -10.3 %, docs/convection.md); the bounds sit a few per cent above
TOL_NU_3D, TOL_VRMS_3D = 0.15, 0.06
CASE1A_3D = ["--dim", "3", "--mode", "roll", "--nz", "8", "--xi", "2.5e24", "--rsst", "5", "--t-end", "0.3",
             "--snapshots", "0"]
# measured 2026-12-06 at 16 across: 0.11 % (the rest is the change of the particles' volumes,
# which the budget does not count). It catches heat that conduction creates or loses between
# particles, and a wall flux that the log reports off by more than about 0.3 % (the residual
# moves by that error in full). It does not check Nu_shift itself: shifting adds only 0.1 % of
# the heat in case 1a, and leaving the column out gives 0.23 %, inside the tolerance.
TOL_BUDGET = 0.003
TOL_XI = 0.03  # steady Nu, v_rms of xi and 10 xi agree within 3 % (time averages; particle noise ~1 %)


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


def steady(out: Path) -> tuple[float, float, float, int]:
    """Time averages over the last third of the run: Nu (mean of top and bottom), v_rms,
    and the relative scatter of Nu; and the number of steps."""
    lg = log(out)
    t = lg["time"]
    keep = t >= t[-1] * 2 / 3
    nu = 0.5 * (lg["Nu_top"][keep] + lg["Nu_bot"][keep])
    return float(nu.mean()), float(lg["v_rms"][keep].mean()), float(nu.std() / nu.mean()), int(lg["step"][-1])


def heat_budget(lg: dict[str, np.ndarray]) -> tuple[float, float]:
    """The change of <T> that the wall fluxes and particle shifting do not explain, and the heat
    that flowed through the walls (the mean of top and bottom), both per unit volume (a log
    with a row every step; c = 1, so the log's time is in d^2 / kappa). The walls' fluxes
    enter the temperature half at each end of a step (trapezoid), shifting's at its end."""
    t, dt = lg["time"], np.diff(lg["time"])
    trap = lambda y: float(np.sum(0.5 * dt * (y[1:] + y[:-1])))
    walls = trap(lg["Nu_bot"] - lg["Nu_top"])
    shift = float(np.sum(dt * lg["Nu_shift"][1:]))
    through = trap(0.5 * (lg["Nu_bot"] + lg["Nu_top"]))
    return float(lg["T_mean"][-1] - lg["T_mean"][0]) - walls - shift, through


def test_conduction(binary: str, out: Path) -> None:
    for dim, nz in ((2, 16), (3, 8)):
        o = out / f"d{dim}"
        run(binary, ["--dim", str(dim), "--nz", str(nz), "--amplitude", "0", "--max-steps", "1", "--snapshots", "0",
                     "--xi", "2.5e23"], o)
        lg = log(o)
        nt, nb = lg["Nu_top"][0], lg["Nu_bot"][0]
        print(f"conduction {dim}D, {nz} across: Nu top {nt:.5f} bottom {nb:.5f} (exact 1)")
        if abs(nt - 1) > 0.02 or abs(nb - 1) > 0.02:
            sys.exit(f"FAIL: conductive Nusselt number {nt}, {nb} not within 2 % of 1")


def test_case1a(binary: str, out: Path) -> None:
    run(binary, CASE1A, out)
    nu, v, scatter, steps = steady(out)
    print(f"case 1a at 16 across: Nu {nu:.4f} ({100 * (nu / NU_1A - 1):+.2f} %), v_rms {v:.3f} "
          f"({100 * (v / VRMS_1A - 1):+.2f} %), Nu scatter {100 * scatter:.2f} %, {steps} steps; "
          f"tolerance {100 * TOL_NU_1A:.0f} % / {100 * TOL_VRMS_1A:.0f} %")
    if abs(nu / NU_1A - 1) > TOL_NU_1A or abs(v / VRMS_1A - 1) > TOL_VRMS_1A:
        sys.exit("FAIL: case 1a outside the tolerance of Blankenbach et al. (1989)")
    rest, through = heat_budget(log(out))
    print(f"heat budget: <T> changed by {rest:+.2e} more than the walls and shifting explain, "
          f"against {through:.3f} through the walls ({100 * abs(rest) / through:.2f} %, tolerance {100 * TOL_BUDGET:.1f} %)")
    if not abs(rest) <= TOL_BUDGET * through:
        sys.exit("FAIL: the heat budget does not close (conduction or the wall fluxes do not conserve heat)")


def test_xi(binary: str, out: Path) -> None:
    base = ["--nz", "12", "--rsst", "5", "--hfac", "4", "--shift", "2", "--t-end", "0.25", "--snapshots", "0"]
    res = {}
    for xi in ("2.5e23", "2.5e24"):
        run(binary, [*base, "--xi", xi], out / xi)
        res[xi] = steady(out / xi)
        print(f"xi {xi}: Nu {res[xi][0]:.4f}  v_rms {res[xi][1]:.3f}  scatter {100 * res[xi][2]:.2f} %  "
              f"steps {res[xi][3]}")
    (n1, v1, _, s1), (n2, v2, _, s2) = res["2.5e23"], res["2.5e24"]
    print(f"xi x10: Nu {100 * (n2 / n1 - 1):+.2f} %, v_rms {100 * (v2 / v1 - 1):+.2f} %, steps x{s1 / s2:.2f} fewer")
    if abs(n2 / n1 - 1) > TOL_XI or abs(v2 / v1 - 1) > TOL_XI:
        sys.exit(f"FAIL: the steady state changed by more than {100 * TOL_XI:.0f} % with xi raised 10 times")
    if not s2 < s1 / 2:
        sys.exit("FAIL: raising xi did not reduce the number of steps")


def test_cli(binary: str, out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    corrupt = out / "corrupt.pbin"
    corrupt.write_bytes(b"not a checkpoint at all")
    cases = [
        (["--viscosity", "exp", "--contrast", "-5"], "viscosity must be positive"),
        (["--xi", "0.5"], "must be at least 1"),
        (["--c", "0"], "must be at least 1"),
        (["--rsst", "0.2"], "must be at least 1"),
        (["--shift", "-1"], "shifting strength must be auto or in [0, 10]"),
        (["--shift", "often"], "'often' is not a number"),
        (["--nz", "0"], "particles across the depth"),
        (["--aspect", "0.001"], "box is empty"),
        (["--xi", "1e29"], "orders of magnitude"),
        (["--volume", "gas"], "disph or ssph"),
        (["--kernel", "gauss"], "unknown smoothing function"),
        (["--stress", "pair"], "--stress must be auto, full, morris, symmetric, split or local"),
        (["--bogus"], "unknown option"),
        (["--dim", "3", "--mode", "plume"], "--mode must be cell or roll"),
        (["--restart", str(corrupt), "--max-steps", "1"], "error"),
    ]
    for args, want in cases:
        p = run(binary, args, out / "bad", check=False)
        text = p.stdout + p.stderr
        if p.returncode == 0 or want not in text:
            sys.exit(f"FAIL: {args} gave exit {p.returncode}, wanted a non-zero exit and '{want}':\n{text}")
        print(f"refused {args}: {text.strip().splitlines()[-1]}")
    p = subprocess.run([binary, "--help"], capture_output=True, text=True)
    if p.returncode != 0 or "--rsst" not in p.stdout or "--xi" not in p.stdout:
        sys.exit("FAIL: --help")
    # a mild violation is a warning, not an error
    p = run(binary, ["--xi", "2.5e25", "--max-steps", "1", "--nz", "8"], out / "warn")
    if "warning: validity condition broken: modified Prandtl number" not in p.stderr:
        sys.exit(f"FAIL: no warning for a modified Prandtl number of 1:\n{p.stderr}")


def test_restart(binary: str, out: Path) -> None:
    common = ["--nz", "12", "--rsst", "5", "--hfac", "4", "--shift", "2", "--t-end", "1", "--snapshots", "0",
              "--amplitude", "0.3"]
    # isoviscous, and case 2a's law with the pass-1 stress (--stress local) and its own step limit
    for name, base in (("", [*common, "--xi", "2.5e24"]),
                       ("_exp", [*common, "--xi", "2.5e22", "--viscosity", "exp", "--contrast", "1000",
                                 "--xi-law", "viscosity", "--stress", "local"])):
        full, first, second = out / f"full{name}", out / f"first{name}", out / f"second{name}"
        run(binary, [*base, "--max-steps", "60"], full)
        run(binary, [*base, "--max-steps", "30"], first)
        shutil.copytree(first, second, dirs_exist_ok=True)  # a restart continues its own directory (log.txt)
        run(binary, [*base, "--max-steps", "60", "--restart", str(second / "checkpoint.pbin")], second)
        a = (full / "checkpoint.pbin").read_bytes()
        b = (second / "checkpoint.pbin").read_bytes()
        if a != b:
            sys.exit(f"FAIL: the restarted run{name} differs from the uninterrupted one")
        la, lb = log(full), log(second)
        if not np.array_equal(la["Nu_top"][-30:], lb["Nu_top"][-30:]):
            sys.exit(f"FAIL: the log rows after the restart{name} differ")
        print(f"restart{name}: checkpoints after 60 steps identical ({len(a)} bytes), log rows identical")


def test_plots(binary: str, out: Path, plot: str) -> None:
    run(binary, ["--nz", "8", "--xi", "2.5e24", "--rsst", "3", "--t-end", "0.01", "--snapshots", "2"], out)
    p = subprocess.run([sys.executable, plot, "--run", str(out), "--out", str(out / "plot")], capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"FAIL: plot.py: {p.stderr}")
    for name in ("plot_temperature.png", "plot_series.png"):
        f = out / name
        if not f.exists() or f.read_bytes()[:8] != b"\x89PNG\r\n\x1a\n":
            sys.exit(f"FAIL: {f} is not a PNG")
    print(p.stdout.strip())


def test_case1a_3d(binary: str, out: Path) -> None:
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "python"))
    import pik
    run(binary, CASE1A_3D, out)
    nu, v, scatter, steps = steady(out)
    s = pik.read_snapshot(sorted(out.glob("snap_final.*"))[0])
    vy = float(np.sqrt(np.mean(s.vel[:, 1] ** 2)))
    dn, dv = nu / NU_1A - 1, v / VRMS_1A - 1
    print(f"case 1a in 3D (roll, 8 across, {len(s.id)} particles): Nu {nu:.4f} ({100 * dn:+.2f} %), v_rms {v:.3f} "
          f"({100 * dv:+.2f} %), rms v_y {vy:.3g} ({100 * vy / v:.1f} % of v_rms), {steps} steps")
    if abs(dn) > TOL_NU_3D or abs(dv) > TOL_VRMS_3D:
        sys.exit(f"FAIL: 3D case 1a outside {100 * TOL_NU_3D:.0f} % / {100 * TOL_VRMS_3D:.0f} % of Blankenbach et al.")
    if vy > 0.1 * v:
        sys.exit(f"FAIL: the 3D roll did not stay a roll (rms v_y {vy:.3g} against v_rms {v:.3g})")


# --init: the source is case 1a at 10 across to t = 0.3 (not quite steady: Nu still swings by
# about +-2 % over the last 0.1); the targets start from its snap_final (16 across) and its checkpoint (8 across). The
# fields the remap carries are compared at t = 0: v_rms and the volume Nusselt number <w T> + 1
# (measured on AMD EPYC Zen 5, family 26 model 2: +0.07 % and -1.6 % at 16 across). The wall
# Nusselt numbers are not: they are SPH's flux through the wall images, a property of the lattice
# (the 10-across run's own is 9 % below Blankenbach's value, a 16-across run's 6 %), and the
# 16-across lattice reads the coarse run's boundary layer as +26 % at t = 0, relaxing to +10 % in
# 100 steps (t = 0.003); checked only to stay within
# TOL_INIT_NU_WALL after those steps. v_rms after 100 steps, with the pressure perturbation
# carried (the default): -0.9 % (16 across) and -3.5 % (8 across, whose own run swings by +-6 %
# at this Ra: 38.1 to 43.8 over the next 0.1); with --init-pressure no +3.8 % and +7.8 % (the
# dynamic pressure rebuilt from 0 first accelerates the flow); bounded by TOL_INIT_VRMS_100.
INIT_SRC = ["--nz", "10", "--xi", "2.5e24", "--rsst", "5", "--hfac", "4", "--shift", "2", "--t-end", "0.3",
            "--snapshots", "0"]
TOL_INIT_VRMS, TOL_INIT_NU_VOL, TOL_INIT_NU_WALL, TOL_INIT_VRMS_100 = 0.03, 0.05, 0.20, 0.08


def test_init(binary: str, out: Path) -> None:
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "python"))
    import pik
    run(binary, [*INIT_SRC, "--format", "binary"], out / "src")
    src = log(out / "src")
    nu0, nv0 = 0.5 * (src["Nu_top"][-1] + src["Nu_bot"][-1]), src["Nu_vol"][-1]
    v0 = src["v_rms"][-1]
    snap = out / "src" / "snap_final.pbin"
    print(f"source: 10 across to t = {src['time'][-1]:.3g}, Nu (walls) {nu0:.4f}, Nu (volume) {nv0:.4f}, "
          f"v_rms {v0:.3f}")
    # up from the final snapshot, down from the checkpoint (both are snapshots of the run)
    for nz, f in (("16", snap), ("8", out / "src" / "checkpoint.pbin")):
        o = out / f"nz{nz}"
        p = run(binary, ["--nz", nz, "--xi", "2.5e24", "--rsst", "5", "--t-end", "0.3", "--max-steps", "100",
                         "--snapshots", "1", "--init", str(f)], o)
        if "--init" not in p.stdout or "the clock starts at t = 0" not in p.stdout:
            sys.exit(f"FAIL: the --init run does not say what it read:\n{p.stdout}")
        lg = log(o)
        nu, nv, v = 0.5 * (lg["Nu_top"][0] + lg["Nu_bot"][0]), lg["Nu_vol"][0], lg["v_rms"][0]
        nu_e, v_e = 0.5 * (lg["Nu_top"][-1] + lg["Nu_bot"][-1]), lg["v_rms"][-1]
        s = pik.read_snapshot(sorted(o.glob("snap_0000.*"))[0])
        t = s["Temperature"]
        n = int(nz)
        bottom, top = s.pos[:, 1] < 1 / n, s.pos[:, 1] > 1 - 1 / n
        print(f"--init at {nz} across: t = 0 v_rms {v:.3f} ({100 * (v / v0 - 1):+.2f} %), Nu (volume) {nv:.4f} "
              f"({100 * (nv / nv0 - 1):+.2f} %), Nu (walls) {nu:.4f} ({100 * (nu / nu0 - 1):+.2f} %); after "
              f"{int(lg['step'][-1])} steps v_rms {v_e:.3f} ({100 * (v_e / v0 - 1):+.2f} %), Nu (walls) {nu_e:.4f} "
              f"({100 * (nu_e / nu0 - 1):+.2f} %); T in [{t.min():.4f}, {t.max():.4f}], mean T of the bottom row "
              f"{t[bottom].mean():.4f}, top row {t[top].mean():.4f}")
        if lg["time"][0] != 0:
            sys.exit("FAIL: the --init run's clock does not start at 0")
        if abs(v / v0 - 1) > TOL_INIT_VRMS or abs(nv / nv0 - 1) > TOL_INIT_NU_VOL:
            sys.exit(f"FAIL: the remapped state's v_rms / volume Nu are not within {100 * TOL_INIT_VRMS:.0f} % / "
                     f"{100 * TOL_INIT_NU_VOL:.0f} % of the source's")
        if abs(v_e / v0 - 1) > TOL_INIT_VRMS_100 or abs(nu_e / nu0 - 1) > TOL_INIT_NU_WALL:
            sys.exit(f"FAIL: after 100 steps v_rms / wall Nu are not within {100 * TOL_INIT_VRMS_100:.0f} % / "
                     f"{100 * TOL_INIT_NU_WALL:.0f} % of the source's (a transient after the remap)")
        if t.min() < 0 or t.max() > 1 or t[bottom].mean() < 0.6 or t[top].mean() > 0.4:
            sys.exit("FAIL: the remapped temperature broke the wall values or left [0, 1]")
    # another VIM factor c (xi c^2 kept, so the same modified numbers): the file's code velocities
    # are c_old v, the new run's c_new v, and the physical v_rms must carry over
    run(binary, ["--nz", "12", "--xi", "6.25e23", "--c", "2", "--rsst", "5", "--max-steps", "1", "--snapshots", "0",
                 "--init", str(snap)], out / "c2")
    vc = log(out / "c2")["v_rms"][0]
    print(f"--init with c = 2 (source c = 1): t = 0 v_rms {vc:.3f} ({100 * (vc / v0 - 1):+.2f} %)")
    if abs(vc / v0 - 1) > TOL_INIT_VRMS:
        sys.exit("FAIL: --init with another c did not rescale the velocities")
    # a parameter continuation: the isoviscous cell as the start of a variable-viscosity run
    # (another problem), the remapped field as for the same problem, the pressure perturbation 0
    p = run(binary, ["--nz", "12", "--viscosity", "exp", "--contrast", "10", "--xi", "2.5e22", "--max-steps", "1",
                     "--snapshots", "0", "--init", str(snap), "--init-problem", "continuation"], out / "cont")
    if "the snapshot's problem is Ra 10000, viscosity constant" not in p.stdout or \
            "(pressure perturbation 0)" not in p.stdout:
        sys.exit(f"FAIL: the continuation does not say what it started from:\n{p.stdout}")
    lc = log(out / "cont")
    vcont, nvcont = lc["v_rms"][0], lc["Nu_vol"][0]
    print(f"--init-problem continuation (exp, contrast 10, from the isoviscous run): t = 0 v_rms {vcont:.3f} "
          f"({100 * (vcont / v0 - 1):+.2f} %), Nu (volume) {nvcont:.4f} ({100 * (nvcont / nv0 - 1):+.2f} %)")
    if abs(vcont / v0 - 1) > TOL_INIT_VRMS or abs(nvcont / nv0 - 1) > TOL_INIT_NU_VOL:
        sys.exit("FAIL: the continuation's initial field is not the source's")
    # the other formats the driver writes
    run(binary, [*INIT_SRC, "--t-end", "0.02", "--format", "ascii"], out / "ascii")
    run(binary, ["--nz", "12", "--max-steps", "1", "--snapshots", "0", "--init", str(out / "ascii" / "snap_final.txt")],
        out / "ascii_init")
    print("--init from an ASCII snapshot: read")
    p = run(binary, ["--nz", "12", "--max-steps", "1", "--snapshots", "0", "--init", str(snap), "--init-pressure", "no"],
            out / "nopressure")
    if "(pressure perturbation 0)" not in p.stdout:
        sys.exit(f"FAIL: --init-pressure no does not say so:\n{p.stdout}")
    if pik_has_hdf5(binary, out):
        run(binary, [*INIT_SRC, "--t-end", "0.02", "--format", "hdf5"], out / "h5")
        run(binary, ["--nz", "12", "--max-steps", "1", "--snapshots", "0", "--init",
                     str(out / "h5" / "snap_final.hdf5")], out / "h5_init")
        print("--init from an HDF5 snapshot: read")
    else:
        print("--init from an HDF5 snapshot: not tested (this convection binary was built without HDF5)")
    # refusals: another problem, a bad file, with --restart
    corrupt = out / "corrupt.pbin"
    corrupt.write_bytes(b"PIKSNAP but not really, truncated")
    bad = [
        (["--ra", "2e4", "--init", str(snap)], "Rayleigh number 10000, this run 20000 (--ra)"),
        (["--ra", "2e4", "--init", str(snap)], "--init-problem continuation: from another Ra"),
        (["--aspect", "2", "--init", str(snap), "--init-problem", "continuation"], "aspect ratio 1, this run 2"),
        (["--ra", "2e4", "--init", str(snap), "--init-problem", "continuation", "--init-pressure", "yes"],
         "--init-pressure yes needs --init-problem same"),
        (["--init", str(snap), "--init-problem", "other"], "--init-problem must be same or continuation"),
        (["--aspect", "2", "--init", str(snap)], "aspect ratio 1, this run 2 (--aspect)"),
        (["--viscosity", "exp", "--contrast", "10", "--xi", "2.5e22", "--init", str(snap)],
         "viscosity law constant, this run exp"),
        (["--dim", "3", "--init", str(snap)], "dimension 2, this run 3 (--dim)"),
        (["--init", str(out / "missing.pbin")], "cannot read the snapshot"),
        (["--init", str(corrupt)], "cannot read the snapshot"),
        (["--init", str(snap), "--restart", str(out / "src" / "checkpoint.pbin")], "exclude each other"),
        (["--init", str(snap), "--init-pressure", "maybe"], "--init-pressure must be auto, yes or no"),
    ]
    for args, want in bad:
        p = run(binary, ["--nz", "8", "--max-steps", "1", "--snapshots", "0", *args], out / "bad", check=False)
        text = p.stdout + p.stderr
        if p.returncode == 0 or want not in text:
            sys.exit(f"FAIL: {args} gave exit {p.returncode}, wanted a non-zero exit and '{want}':\n{text}")
        print(f"refused {args[:2]}...: {text.strip().splitlines()[-1]}")


def pik_has_hdf5(binary: str, out: Path) -> bool:
    p = run(binary, ["--nz", "8", "--max-steps", "0", "--format", "hdf5", "--t-end", "0.001"], out / "probe", check=False)
    return "not available" not in p.stderr


def main() -> int:
    test, binary, out, plot = sys.argv[1], sys.argv[2], Path(sys.argv[3]), sys.argv[4]
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)
    if test == "conduction":
        test_conduction(binary, out)
    elif test == "case1a":
        test_case1a(binary, out)
    elif test == "case1a_3d":
        test_case1a_3d(binary, out)
    elif test == "xi":
        test_xi(binary, out)
    elif test == "cli":
        test_cli(binary, out)
    elif test == "restart":
        test_restart(binary, out)
    elif test == "plots":
        test_plots(binary, out, plot)
    elif test == "init":
        test_init(binary, out)
    else:
        sys.exit(f"unknown test {test}")
    print("PASS")
    return 0


if __name__ == "__main__":
    sys.exit(main())
