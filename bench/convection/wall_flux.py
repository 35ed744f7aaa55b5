#!/usr/bin/env python3
"""How well the SPH conduction operator of examples/convection carries a given temperature
field's heat through the walls: the converged finite-difference solution of a case
(fd_reference.py --save) is put onto SPH lattices of several resolutions and supports, and
the program's first evaluation (step 0, before any time step) gives Nu at the top and the
bottom (the heat the particles exchange with the wall images) and Nu_vol (<w T> + 1, the
interior's flux), next to the FD solution's own wall gradients:

    wall_flux.py --build BUILD --fd c1000_128.npz [--nz 32,48,64,96,128] [--hfac 4,3]
                 [--contrast 1000] [--work DIR]

Where the thermal boundary layer is thinner than the support, the SPH flux through the wall
is the wall-normal gradient averaged over the support, not the gradient at the wall: it reads
low, and more so at the thinner of the two layers. A run then has to adjust its interior
temperature until its own fluxes balance, which is what case 2a's interior does (docs/
convection.md, "2026-12-06 (second session)"). Not a test: a run of the binary per row (about
a second each, 128 across included), plus one template run at the finest resolution.
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from case2a import read_log  # noqa: E402
from fd_reference import wall_nusselt  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", required=True, help="the build directory (its bin/convection)")
    ap.add_argument("--fd", required=True, help="an fd_reference.py --save file (T, vx, vz)")
    ap.add_argument("--nz", default="32,48,64,96,128", help="particles across the depth, comma-separated")
    ap.add_argument("--hfac", default="4,3", help="supports in particle spacings, comma-separated")
    ap.add_argument("--contrast", type=float, default=1000.0, help="the FD solution's viscosity contrast (1: case 1)")
    ap.add_argument("--work", default="", help="keep the runs here (default: a temporary directory)")
    a = ap.parse_args()
    exe = Path(a.build) / "bin" / "convection"
    if not exe.exists():
        sys.exit(f"wall_flux.py: error: no {exe}")
    try:
        nzs = [int(v) for v in a.nz.split(",")]
        hfacs = [float(v) for v in a.hfac.split(",")]
        T = np.load(a.fd)["T"]
    except (ValueError, OSError, KeyError) as e:
        sys.exit(f"wall_flux.py: error: {e}")
    if min(nzs) < 4 or min(hfacs) <= 0:
        sys.exit("wall_flux.py: error: --nz must be at least 4 and --hfac positive")
    problem = ["--viscosity", "exp", "--contrast", f"{a.contrast:g}"] if a.contrast > 1 else []
    problem += ["--xi-law", "viscosity", "--xi", "2.5e22"] if a.contrast > 1 else ["--xi", "2.5e24"]
    work_tmp = None if a.work else tempfile.TemporaryDirectory()
    work = Path(a.work or work_tmp.name)
    work.mkdir(parents=True, exist_ok=True)

    def run(*args: str) -> None:
        r = subprocess.run([str(exe), *problem, *args], capture_output=True, text=True)
        if r.returncode:
            sys.exit(f"wall_flux.py: error: convection {' '.join(args)} failed:\n{r.stderr[-2000:]}")

    # the FD field on a lattice as fine as its grid (or the finest row's), the source every
    # row interpolates from: a coarser source would smooth the boundary layers before the
    # operator does
    fine = max(nzs + [T.shape[0] - 1])
    run("--nz", str(fine), "--max-steps", "1", "--snapshots", "1", "--out", str(work / "template"))
    src = work / "fd_field.pbin"
    src.unlink(missing_ok=True)
    r = subprocess.run([sys.executable, str(HERE / "fd_to_snapshot.py"), "--fd", a.fd, "--template",
                        str(work / "template" / "snap_0000.pbin"), "--out", str(src)], capture_output=True, text=True)
    if r.returncode:
        sys.exit(f"wall_flux.py: error: fd_to_snapshot.py failed:\n{r.stderr[-2000:]}")
    top, bot = wall_nusselt(T)
    print(f"FD field {a.fd} ({T.shape[0] - 1} intervals): Nu top {top:.3f}, bottom {bot:.3f}")
    print("| across | support (spacings) | Nu top (vs FD) | Nu bottom (vs FD) | Nu_vol | <T> |")
    print("|---:|---:|---|---|---:|---:|")
    for nz in nzs:
        for hf in hfacs:
            out = work / f"nz{nz}_h{hf:g}"
            run("--nz", str(nz), "--hfac", f"{hf:g}", "--init", str(src), "--init-pressure", "no",
                "--max-steps", "1", "--snapshots", "0", "--out", str(out))
            r0 = {k: float(v[0]) for k, v in read_log(out / "log.txt").items()}  # step 0
            print(f"| {nz} | {hf:g} | {r0['Nu_top']:.3f} ({100 * (r0['Nu_top'] / top - 1):+.1f} %) | "
                  f"{r0['Nu_bot']:.3f} ({100 * (r0['Nu_bot'] / bot - 1):+.1f} %) | {r0['Nu_vol']:.3f} | {r0['T_mean']:.4f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
