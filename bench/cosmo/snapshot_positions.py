#!/usr/bin/env python3
"""Write a positions file (what bench_cosmo --ic, ewald_ref --ic and the FDPS
comparison of docs/cosmo.md read) from a snapshot of examples/cosmo.

    snapshot_positions.py SNAP.hdf5 OUT.pos [--box 100] [--every 1] [--omega-m 0.3]

The file is int64 n, then n records of 4 doubles: x, y, z in box units [0, 1) and
the mass. The mass is 3 Omega_m / (8 pi n) for every particle: the mean density
3 Omega_m / 8 pi of code units with G = H0 = 1 and a unit box (pik's and FDPS's
TreePM sample's convention). --every k keeps the particles whose lattice indices
(ParticleIDs = (i n + j) n + l of the initial grid) are all multiples of k: a
clustered set of (n/k)^3 particles with the same large-scale structure.
"""
import argparse
import math
import sys

import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("snapshot")
    ap.add_argument("out")
    ap.add_argument("--box", type=float, default=100.0, help="box side of the snapshot, Mpc/h")
    ap.add_argument("--every", type=int, default=1, help="keep every k-th lattice site per dimension")
    ap.add_argument("--omega-m", type=float, default=0.3)
    a = ap.parse_args()
    if a.every < 1 or a.box <= 0:
        sys.exit("snapshot_positions: --every must be >= 1 and --box positive")
    import h5py
    try:
        with h5py.File(a.snapshot, "r") as f:
            x = np.asarray(f["PartType1/Coordinates"], dtype=np.float64)
            ids = np.asarray(f["PartType1/ParticleIDs"], dtype=np.int64)
    except (OSError, KeyError) as e:
        sys.exit(f"snapshot_positions: cannot read {a.snapshot}: {e}")
    n = round(len(ids) ** (1 / 3))
    if n ** 3 != len(ids):
        sys.exit(f"snapshot_positions: {len(ids)} particles is not a cube")
    if a.every > 1:
        i, j, l = ids // (n * n), (ids // n) % n, ids % n
        keep = (i % a.every == 0) & (j % a.every == 0) & (l % a.every == 0)
        x, ids = x[keep], ids[keep]
    order = np.argsort(ids, kind="stable")
    u = np.mod(x[order] / a.box, 1.0)
    u[u >= 1.0] = 0.0
    m = 3 * a.omega_m / (8 * math.pi * len(u))
    rec = np.empty((len(u), 4))
    rec[:, :3], rec[:, 3] = u, m
    with open(a.out, "wb") as f:
        np.array([len(u)], dtype=np.int64).tofile(f)
        rec.tofile(f)
    print(f"snapshot_positions: {len(u)} particles from {a.snapshot} -> {a.out}")


if __name__ == "__main__":
    main()
