#!/usr/bin/python3
"""A new pairwise kernel from Python, in the style of a notebook.

    examples/python/new_kernel.py [--n 4096] [--out DIR] [--threads T]

1. writes a kernel the library does not have: a Yukawa (screened Coulomb)
   force between charged particles, phi(r) = q_i q_j exp(-r/lambda) / r
   (Debye-Hueckel screening; e.g. dusty plasmas, Ohta & Hamaguchi 2000, Phys.
   Rev. Lett. 84, 6026), with a Plummer-softened distance;
2. compiles it with pik.Kernel (pikg-gen + the C++ compiler, cached);
3. runs it on random particles held in a NumPy structured array (no copies);
4. compares it with a direct NumPy evaluation in float64;
5. plots the force against distance and the relative error, to DIR/yukawa.png.

Exits 1 if the kernel and NumPy differ by more than the float32 tolerance.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time

import numpy as np

# The pik package from this source tree (python/pik); an installed pik otherwise.
_PYTHON_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python")
if os.path.isdir(os.path.join(_PYTHON_DIR, "pik")):
    sys.path.insert(0, os.path.normpath(_PYTHON_DIR))
import pik  # noqa: E402

# ---- 1. the kernel, as a scientist would write it ------------------------------
YUKAWA = """\
// Screened Coulomb (Yukawa) interaction, softened: the force on i and the potential.
EPI   F32vec xi:pos
EPI   F32    qi:charge
EPJ   F32vec xj:pos
EPJ   F32    qj:charge
FORCE F32vec f:force
FORCE F32    phi:phi
F32 eps2        // softening length squared
F32 inv_lambda  // 1 / screening length

rij  = xi - xj
r2   = rij * rij + eps2
rinv = rsqrt(r2)
r    = r2 * rinv
e    = qi * qj * exp(-r * inv_lambda) * rinv          // q_i q_j exp(-r/lambda) / r
phi += e
f   += e * (rinv + inv_lambda) * rinv * rij            // -dphi/dr along rij / r
"""


def yukawa_numpy(pos, q, eps2, lam):
    """The same sums in float64 with NumPy broadcasting (O(N^2) memory: N <= 8192)."""
    d = pos[:, None, :] - pos[None, :, :]
    r2 = (d * d).sum(-1) + eps2
    rinv = 1 / np.sqrt(r2)
    r = r2 * rinv
    e = q[:, None] * q[None, :] * np.exp(-r / lam) * rinv
    f = ((e * (rinv + 1 / lam) * rinv)[..., None] * d).sum(1)
    return f, e.sum(1)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=4096, help="particles (default 4096, at most 8192)")
    ap.add_argument("--out", default=".", help="folder for yukawa.png (default .)")
    ap.add_argument("--threads", type=int, default=None, help="threads (default: all CPUs)")
    args = ap.parse_args()
    if not 2 <= args.n <= 8192:
        ap.error("--n must be in 2..8192 (the NumPy check holds N^2 doubles)")

    # ---- 2. compile (a second run finds the library in the cache) --------------
    src = os.path.join(tempfile.mkdtemp(prefix="pik-example-"), "yukawa.pik")
    with open(src, "w") as f:
        f.write(YUKAWA)
    t0 = time.perf_counter()
    k = pik.Kernel(src)
    print(f"compiled {k!r} in {time.perf_counter() - t0:.2f} s"
          f" ({'cache hit' if k.cache_hit else 'pikg-gen + C++ compiler'})")
    print(f"particle dtype {k.particle_dtype}\nforce dtype    {k.force_dtype}")

    # ---- 3. random particles in the kernel's own layout --------------------------
    rng = np.random.default_rng(7)
    p = np.zeros(args.n, k.particle_dtype)
    p["pos"] = rng.uniform(-1, 1, size=(args.n, 3))
    p["charge"] = rng.choice([-1.0, 1.0], size=args.n)
    eps2, lam = 1e-4, 0.3
    t0 = time.perf_counter()
    res = k(p, eps2=eps2, inv_lambda=1 / lam, threads=args.threads)
    dt = time.perf_counter() - t0
    print(f"{args.n} x {args.n} pairs in {dt * 1e3:.1f} ms ({args.n ** 2 / dt / 1e9:.2f} G pairs/s, {k.isa})")

    # ---- 4. the same in NumPy, float64 --------------------------------------------
    f64, phi64 = yukawa_numpy(p["pos"].astype(np.float64), p["charge"].astype(np.float64), eps2, lam)
    fmag = np.linalg.norm(f64, axis=1)
    err = np.linalg.norm(res["force"] - f64, axis=1) / np.maximum(fmag, 1e-30)
    perr = np.abs(res["phi"] - phi64) / np.maximum(np.abs(phi64), 1e-30)
    print(f"relative error vs NumPy float64: force median {np.median(err):.2e} max {err.max():.2e};"
          f" potential median {np.median(perr):.2e}")
    scale = np.abs(f64).max()
    ok = np.abs(res["force"] - f64).max() <= 1e-4 * scale

    # ---- 5. pictures ---------------------------------------------------------------
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.5), constrained_layout=True)
    r = np.linspace(0.02, 1.5, 300)
    a.loglog(r, np.exp(-r / lam) * (1 / r + 1 / lam) / r, label="Yukawa, lambda = 0.3")
    a.loglog(r, 1 / r ** 2, "--", label="Coulomb 1/r^2")
    a.set_xlabel("r")
    a.set_ylabel("|F| between two unit charges")
    a.set_title("the new kernel's pair force")
    a.legend()
    b.hist(np.log10(np.maximum(err, 1e-12)), bins=60, alpha=0.8, label="force")
    b.hist(np.log10(np.maximum(perr, 1e-12)), bins=60, alpha=0.6, label="potential")
    b.set_xlabel("log10 relative error (pik.Kernel float32 vs NumPy float64)")
    b.set_ylabel("particles")
    b.set_title(f"{args.n} random charges, {k.isa}")
    b.legend()
    os.makedirs(args.out, exist_ok=True)
    png = os.path.join(args.out, "yukawa.png")
    fig.savefig(png, dpi=100)
    print(f"wrote {png}")
    if not ok:
        print("new_kernel.py: error: kernel and NumPy disagree beyond the float32 tolerance", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
