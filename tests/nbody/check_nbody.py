#!/usr/bin/python3
"""End-to-end checks of the nbody example (small N, a few seconds each).

    check_nbody.py NBODY WORKDIR restart|conservation|cli|plot|ranks [--np N --mpiexec MPIEXEC FLAG...]

restart       a run stopped at a checkpoint (and one that ran past it, as a crash
              would leave it) and restarted ends bit for bit like an uninterrupted run
conservation  direct summation (theta = 0) conserves momentum to rounding and energy
              to the integrator's error; the tree conserves momentum to its force error
cli           usage errors exit 2 with a clear message, --help exits 0, bad files exit 1
plot          plot.py turns a run into PNGs and refuses a corrupt snapshot
ranks         (with --np) N ranks give 1 rank's energy history to the tree error, and
              direct summation to rounding; every particle is in exactly one part of
              a snapshot; a checkpoint of N ranks restarts on 1 rank

With --np N --mpiexec ..., every nbody run of the check goes through
`MPIEXEC FLAG... -np N` (restart identity under MPI: one checkpoint part per rank).
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
PLOT = os.path.join(HERE, "..", "..", "examples", "nbody", "plot.py")
sys.path.insert(0, os.path.dirname(PLOT))
import plot  # noqa: E402  (its pik binary reader verifies every checksum)

failures: list[str] = []


def check(ok: bool, what: str) -> None:
    print(("ok     " if ok else "FAILED ") + what)
    if not ok:
        failures.append(what)


LAUNCH: list[str] = []  # the MPI launcher prefix, empty for one process
NP = 1


def run(nbody: str, *args: str, expect: int = 0, launch: list[str] | None = None) -> subprocess.CompletedProcess:
    launch = LAUNCH if launch is None else launch
    p = subprocess.run([*launch, nbody, *args], capture_output=True, text=True,
                       env={**os.environ, "OMP_NUM_THREADS": os.environ.get("OMP_NUM_THREADS", "2")})
    if p.returncode != expect:
        print(p.stdout, p.stderr, sep="\n")
        raise SystemExit(f"{' '.join(launch)} nbody {' '.join(args)}: exit {p.returncode}, expected {expect}")
    return p


def parts(path: str, n: int) -> list[str]:
    """The files of one output written by n ranks: PATH itself, or PATH's parts
    (snap.pbin -> snap.0.pbin, snap.1.pbin, ...)."""
    if n == 1:
        return [path]
    stem, ext = os.path.splitext(path)
    return [f"{stem}.{k}{ext}" for k in range(n)]


def fields(path: str) -> dict[str, bytes]:
    """Raw bytes of every field of a pik binary file, plus time and step."""
    data = open(path, "rb").read()
    plot.read_binary(path)  # verifies the checksums
    n_fields = int.from_bytes(data[64:68], "little")
    out = {"time+step": data[48:64]}
    for k in range(n_fields):
        e = data[128 + 64 * k: 128 + 64 * (k + 1)]
        name = e[:32].rstrip(b"\0").decode()
        off = int.from_bytes(e[40:48], "little")
        nbytes = int.from_bytes(e[48:56], "little")
        out[name] = data[off: off + nbytes]
    return out


def log_table(path: str) -> tuple[list[str], np.ndarray]:
    with open(path) as f:
        cols = f.readline().lstrip("#").split()
    return cols, np.loadtxt(path, ndmin=2)


def restart(nbody: str, work: str) -> None:
    # Under MPI more particles than the decomposition samples (1000 a rank), so that
    # the sampling is random and a restart that lost the decomposition state would
    # show (with fewer, every particle is a sample and the cuts never change).
    common = ["--n", "600" if NP == 1 else "3000", "--seed", "5", "--theta", "0.6", "--dt", "1/128", "--eps", "1/32",
              "--checkpoint-every", "8", "--snapshot-every", "1000"]
    a, b = os.path.join(work, "whole"), os.path.join(work, "pieces")
    run(nbody, *common, "--t-end", "24/128", "--out", a)
    run(nbody, *common, "--t-end", "8/128", "--out", b)       # stops at step 8
    saved = os.path.join(work, "step8.pbin")
    for src, dst in zip(parts(os.path.join(b, "checkpoint.pbin"), NP), parts(saved, NP)):
        shutil.copy(src, dst)
    # Go on past the checkpoint (rows 9..13 in energy.txt), then "crash".
    run(nbody, "--restart", saved, "--t-end", "13/128", "--out", b)
    run(nbody, "--restart", saved, "--t-end", "24/128", "--out", b)
    on = f" ({NP} ranks)" if NP > 1 else ""
    for pa, pb in zip(parts(os.path.join(a, "checkpoint.pbin"), NP), parts(os.path.join(b, "checkpoint.pbin"), NP)):
        fa, fb = fields(pa), fields(pb)
        part = os.path.basename(pa)
        check(fa.keys() == fb.keys(), f"restart{on}: same checkpoint fields in {part}")
        for k in fa:
            check(fa[k] == fb.get(k), f"restart{on}: '{k}' of {part} identical bit for bit after 16 more steps")
    sa = open(os.path.join(a, "energy.txt")).read()
    sb = open(os.path.join(b, "energy.txt")).read()
    check(sa == sb, f"restart{on}: energy.txt identical (rows past the checkpoint were dropped)")
    check([fields(f)["Coordinates"] for f in parts(os.path.join(a, "snap_000024.pbin"), NP)] ==
          [fields(f)["Coordinates"] for f in parts(os.path.join(b, "snap_000024.pbin"), NP)],
          f"restart{on}: final snapshots agree")


def conservation(nbody: str, work: str) -> None:
    # Direct summation, two step sizes: leapfrog is second order, so halving dt cuts
    # the energy error by about 4.
    err = {}
    for dt in (128, 256):
        d = os.path.join(work, f"direct{dt}")
        run(nbody, "--n", "256", "--theta", "0", "--dt", f"1/{dt}", "--eps", "1/32", "--t-end", "0.25",
            "--checkpoint-every", "0", "--out", d)
        cols, t = log_table(os.path.join(d, "energy.txt"))
        err[dt] = t[:, cols.index("dE/E")].max()
        p = np.sqrt(sum(t[:, cols.index(c)] ** 2 for c in ("Px", "Py", "Pz")))
        # Scale of the momentum: sum m |v| ~ 0.7 in N-body units. Forces are summed in
        # single precision (about 6e-8 relative), so pairs cancel to about that.
        check(p.max() < 1e-8, f"direct dt=1/{dt}: |P| stays below 1e-8 (max {p.max():.2e})")
    check(err[256] < 3e-5, f"direct: |dE/E| < 3e-5 at dt = 1/256 (max {err[256]:.2e})")
    ratio = err[128] / err[256]
    check(3.0 < ratio < 5.5, f"direct: energy error is second order in dt (ratio {ratio:.2f}, expect 4)")

    tr = os.path.join(work, "tree")
    run(nbody, "--n", "2048", "--theta", "0.5", "--dt", "1/256", "--eps", "1/64", "--t-end", "32/256",
        "--checkpoint-every", "0", "--out", tr)
    cols, t = log_table(os.path.join(tr, "energy.txt"))
    p = np.sqrt(sum(t[:, cols.index(c)] ** 2 for c in ("Px", "Py", "Pz")))
    check(p.max() < 1e-4, f"tree theta=0.5: |P| < 1e-4, the tree's force error (max {p.max():.2e})")
    check(p.max() > 1e-8, "tree theta=0.5: momentum error is the tree's, not zero")
    de = t[:, cols.index("dE/E")].max()
    check(de < 5e-4, f"tree theta=0.5: |dE/E| < 5e-4 over 32 steps (max {de:.2e})")

    q = os.path.join(work, "quad")
    run(nbody, "--n", "2048", "--theta", "0.5", "--quadrupole", "--dt", "1/256", "--eps", "1/64",
        "--t-end", "8/256", "--checkpoint-every", "0", "--out", q)
    _, tq = log_table(os.path.join(q, "energy.txt"))
    pq = np.sqrt(sum(tq[:, cols.index(c)] ** 2 for c in ("Px", "Py", "Pz")))
    check(pq.max() < p[: len(pq)].max(), f"quadrupole: smaller momentum error than monopole "
          f"({pq.max():.2e} vs {p[: len(pq)].max():.2e})")


def cli(nbody: str, work: str) -> None:
    p = run(nbody, "--help")
    check("--theta" in p.stdout and "--restart" in p.stdout, "--help lists the options")
    p = run(nbody, "--bogus", expect=2)
    check("unknown option '--bogus'" in p.stderr, "unknown option: exit 2, named")
    p = run(nbody, "--theta", expect=2)
    check("needs a value" in p.stderr, "missing value: exit 2")
    p = run(nbody, "--dt", "fast", expect=2)
    check("'fast' is not a number" in p.stderr, "bad number: exit 2")
    p = run(nbody, "--eps", "0", "--out", os.path.join(work, "x"), expect=2)
    check("--eps must be positive" in p.stderr, "eps = 0 refused")
    p = run(nbody, "--format", "fits", expect=2)
    check("unknown snapshot format 'fits'" in p.stderr, "unknown format refused")
    missing = os.path.join(work, "missing.pbin")
    p = run(nbody, "--restart", missing, expect=1)
    check(missing in p.stderr and "cannot open" in p.stderr, "missing checkpoint: exit 1, named")
    check("on rank" not in p.stderr, "one process: no 'on rank 0' in the error")
    p = run(nbody, "--ic", work, "--t-end", "1/256", "--out", os.path.join(work, "x"), expect=1)
    check("is a directory" in p.stderr, "a directory as --ic: exit 1, said so")
    p = run(nbody, "--t-end", "-1", "--out", os.path.join(work, "x"), expect=2)
    check("--t-end must be non-negative" in p.stderr, "negative --t-end refused (not 2^64 steps)")
    p = run(nbody, "--t-end", "1e30", "--out", os.path.join(work, "x"), expect=2)
    check("more than 1e15 steps" in p.stderr, "huge --t-end / --dt refused")
    p = run(nbody, "--n", "1", "--t-end", "2/256", "--out", os.path.join(work, "one"))
    check("nan" not in p.stdout, "one particle (E0 = 0): |dE/E| is a number, not nan")
    out = os.path.join(work, "c")
    run(nbody, "--n", "64", "--t-end", "2/256", "--out", out, "--snapshot-every", "1")
    p = run(nbody, "--restart", os.path.join(out, "snap_000001.pbin"), expect=1)
    check("not a checkpoint" in p.stderr, "a snapshot is not a checkpoint")
    p = run(nbody, "--restart", os.path.join(out, "checkpoint.pbin"), "--theta", "0.7", expect=2)
    check("--theta differs from the checkpoint" in p.stderr, "restart refuses a changed theta")
    chk = open(os.path.join(out, "checkpoint.pbin"), "rb").read()
    cut = os.path.join(work, "cut.pbin")
    open(cut, "wb").write(chk[: len(chk) // 2])
    p = run(nbody, "--restart", cut, expect=1)
    check(cut in p.stderr and "truncated" in p.stderr, "truncated checkpoint refused")
    # A snapshot as initial conditions; ids and masses come from the file.
    p = run(nbody, "--ic", os.path.join(out, "snap_000002.pbin"), "--t-end", "1/256",
            "--out", os.path.join(work, "d"))
    check("nbody: 64 particles" in p.stdout, "--ic FILE reads the particles")
    p = run(nbody, "--ic", os.path.join(out, "snap_000002.pbin"), "--n", "10", expect=2)
    check("--n applies to generated" in p.stderr, "--n with --ic FILE refused")


def plots(nbody: str, work: str) -> None:
    out = os.path.join(work, "p")
    run(nbody, "--n", "1000", "--t-end", "4/256", "--out", out, "--snapshot-every", "2")
    png = os.path.join(work, "png")
    p = subprocess.run([sys.executable, PLOT, "--run", out, "--out", png], capture_output=True, text=True)
    check(p.returncode == 0, f"plot.py --run exits 0 ({p.stderr.strip()})")
    for name in ("density.png", "energy.png"):
        f = os.path.join(png, name)
        check(os.path.exists(f) and open(f, "rb").read(8) == b"\x89PNG\r\n\x1a\n", f"{name} is a PNG")
    snap = os.path.join(out, "snap_000004.pbin")
    data = bytearray(open(snap, "rb").read())
    data[len(data) // 2] ^= 1
    bad = os.path.join(work, "bad.pbin")
    open(bad, "wb").write(bytes(data))
    p = subprocess.run([sys.executable, PLOT, "--snapshot", bad, "--out", png], capture_output=True, text=True)
    check(p.returncode == 1 and "checksum mismatch" in p.stderr, "plot.py refuses a corrupt snapshot")


def ranks(nbody: str, work: str) -> None:
    if NP == 1:
        raise SystemExit("check 'ranks' needs --np N --mpiexec ...")
    tree = ["--n", "1000", "--seed", "3", "--theta", "0.5", "--dt", "1/256", "--eps", "1/64",
            "--t-end", "16/256", "--checkpoint-every", "8"]
    one, many = os.path.join(work, "one"), os.path.join(work, "many")
    run(nbody, *tree, "--out", one, launch=[])
    p = run(nbody, *tree, "--out", many, "--snapshot-every", "16")
    check(p.stdout.count("summary") == 1, f"{NP} ranks: one summary (output from rank 0 only)")
    check(f"{NP} ranks" in p.stdout, f"{NP} ranks: the banner says so")
    cols, t1 = log_table(os.path.join(one, "energy.txt"))
    _, tn = log_table(os.path.join(many, "energy.txt"))
    e = cols.index("E")
    check(t1.shape == tn.shape, f"{NP} ranks: energy.txt has the same rows")
    # The local essential trees open cells other than one tree would; theta = 0.5
    # monopole forces are good to about 1e-3, energies to a few 1e-5 (measured 5e-5).
    diff = np.abs(tn[:, e] - t1[:, e]).max() / abs(t1[0, e])
    check(diff < 3e-4, f"{NP} ranks: energy history equals 1 rank's to the tree error ({diff:.1e} < 3e-4)")
    check(diff > 0 or NP == 1, f"{NP} ranks: and differs from it (a distinct run, {diff:.1e})")
    de = tn[:, cols.index("dE/E")].max()
    check(de < 5e-4, f"{NP} ranks: |dE/E| < 5e-4 ({de:.1e})")
    ids = np.concatenate([np.frombuffer(fields(f)["ParticleIDs"], dtype="<u8")
                          for f in parts(os.path.join(many, "snap_000016.pbin"), NP)])
    check(np.array_equal(np.sort(ids), np.arange(1000)), f"{NP} ranks: each particle in exactly one snapshot part")
    png = os.path.join(work, "png")
    p = subprocess.run([sys.executable, PLOT, "--run", many, "--out", png], capture_output=True, text=True)
    check(p.returncode == 0 and "snap_000016.pbin" in p.stdout,
          f"plot.py --run reads the {NP} parts of the last snapshot ({p.stderr.strip()})")
    # Direct summation: the same forces up to summation order.
    direct = ["--n", "500", "--theta", "0", "--dt", "1/256", "--eps", "1/32", "--t-end", "4/256",
              "--checkpoint-every", "0"]
    run(nbody, *direct, "--out", os.path.join(work, "d1"), launch=[])
    run(nbody, *direct, "--out", os.path.join(work, "dn"))
    _, d1 = log_table(os.path.join(work, "d1", "energy.txt"))
    _, dn = log_table(os.path.join(work, "dn", "energy.txt"))
    diff = np.abs(dn[:, e] - d1[:, e]).max() / abs(d1[0, e])
    check(diff < 1e-6, f"{NP} ranks, direct summation: energies equal 1 rank's to rounding ({diff:.1e})")
    # Another rank count reads the checkpoint in equal shares and carries on.
    half = os.path.join(work, "half")
    run(nbody, *tree[:-4], "--t-end", "8/256", "--checkpoint-every", "8", "--out", half)
    run(nbody, "--restart", os.path.join(half, "checkpoint.pbin"), "--t-end", "16/256", "--out", half, launch=[])
    _, th = log_table(os.path.join(half, "energy.txt"))
    diff = np.abs(th[:, e] - tn[:, e]).max() / abs(t1[0, e])
    check(th.shape == tn.shape and np.array_equal(th[:9], tn[:9]) and diff < 3e-4,
          f"checkpoint of {NP} ranks restarted on 1: 8 more steps, energy as the {NP}-rank run's ({diff:.1e})")


def main() -> int:
    global LAUNCH, NP
    nbody, work, what = sys.argv[1], sys.argv[2], sys.argv[3]
    rest = sys.argv[4:]
    if rest:
        if len(rest) < 4 or rest[0] != "--np" or rest[2] != "--mpiexec":
            raise SystemExit("usage: check_nbody.py NBODY WORKDIR CHECK [--np N --mpiexec MPIEXEC FLAG...]")
        NP = int(rest[1])
        LAUNCH = [*rest[3:], "-np", str(NP)]
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    {"restart": restart, "conservation": conservation, "cli": cli, "plot": plots, "ranks": ranks}[what](nbody, work)
    if failures:
        print(f"{len(failures)} check(s) failed")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
