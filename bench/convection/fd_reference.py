#!/usr/bin/env python3
"""A finite-difference cross-check for the Blankenbach et al. (1989) cases: the same
equations as examples/convection in the infinite-Prandtl limit, on a grid, to give what the
benchmark's table does not (the mean temperature, profiles of T and of the velocity at the
walls and across the layer) and to show how a grid method converges at a given resolution.

    fd_reference.py --n 64 [--ra 1e4] [--contrast 1000] [--t-end 0.3] [--dt 2e-4]
                    [--init FILE.npz] [--save FILE.npz] [--profiles]

Equations (unit box, free-slip walls, T = 1 at the bottom and 0 at the top, insulating
sides; eta = contrast^(-T), Ra at T = 0, as in the benchmark's case 2a; contrast 1: case 1):
the stream function psi (v_x = d psi / dz, v_z = -d psi / dx) obeys

    (d_zz - d_xx)[eta (psi_zz - psi_xx)] + 4 d_xz[eta psi_xz] = Ra dT/dx

(the curl of the Stokes equation with the full stress 2 eta e), with psi = 0 and
psi_nn = 0 on every wall (psi odd about each wall), on the nodes of an n x n grid: second-order
differences, eta on the nodes for the first term and in the cell centres for the second; a
sparse direct solve each step. The temperature takes backward-Euler steps of
dT/dt + v.grad T = lap T with second-order upwind advection (one sparse solve each), so
--dt can be far above the advective limit; a steady state does not depend on it.

Output: Nu at the top and the bottom (second-order one-sided dT/dz), v_rms, the mean
temperature; with --profiles the horizontal means of T and the largest |v_x|, |v_z| at a few
depths. Not a test; docs/convection.md quotes its runs. numpy and scipy (Debian python3-numpy,
python3-scipy).
"""
from __future__ import annotations

import argparse
import sys
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spl


class Grid:
    def __init__(self, n: int, ra: float, contrast: float):
        if n < 4:
            raise ValueError("--n must be at least 4")
        if contrast < 1:
            raise ValueError("--contrast must be at least 1")
        self.n, self.ra, self.b, self.h = n, ra, np.log(contrast), 1.0 / n
        x = np.linspace(0.0, 1.0, n + 1)
        self.X, self.Z = np.meshgrid(x, x, indexing="ij")  # [i, j]: x_i, z_j
        self._stokes = self._stokes_pattern()
        ni, nj = np.meshgrid(np.arange(n + 1), np.arange(1, n), indexing="ij")
        self.ti, self.tj = ni.reshape(-1), nj.reshape(-1)  # temperature unknowns: 0 < z < 1

    # ---- Stokes: the matrix is linear in eta; its pattern is built once
    def _psi_index(self, i: int, j: int):
        """(column, sign) of psi at node (i, j), folded by the odd reflection; None on a wall."""
        n, s = self.n, 1.0
        if i < 0:
            i, s = -i, -s
        if i > n:
            i, s = 2 * n - i, -s
        if j < 0:
            j, s = -j, -s
        if j > n:
            j, s = 2 * n - j, -s
        if i in (0, n) or j in (0, n):
            return None
        return (i - 1) * (n - 1) + (j - 1), s

    def _stokes_pattern(self):
        n, h4 = self.n, self.h**4
        rows, cols, w, k = [], [], [], []
        node = lambda i, j: i * (n + 1) + j  # index into [eta nodes, eta centres]
        centre = lambda i, j: (n + 1) ** 2 + i * n + j

        def add(r, i, j, weight, eta_index):
            c = self._psi_index(i, j)
            if c is not None:
                rows.append(r)
                cols.append(c[0])
                w.append(c[1] * weight)
                k.append(eta_index)

        for i in range(1, n):
            for j in range(1, n):
                r = (i - 1) * (n - 1) + (j - 1)
                # (d_zz - d_xx)[eta A], A = psi_zz - psi_xx at the nodes (zero on the walls)
                for kk, ll, s1 in ((i, j + 1, 1), (i, j - 1, 1), (i + 1, j, -1), (i - 1, j, -1)):
                    if 0 < kk < n and 0 < ll < n:
                        for a, c, s2 in ((kk, ll + 1, 1), (kk, ll - 1, 1), (kk + 1, ll, -1), (kk - 1, ll, -1)):
                            add(r, a, c, s1 * s2 / h4, node(kk, ll))
                # 4 d_xz[eta B], B = psi_xz in the cell centres; a centre outside the box mirrors
                # one inside (psi_xz is even about a wall)
                for ci, cj, s1 in ((i, j, 1), (i, j - 1, -1), (i - 1, j, -1), (i - 1, j - 1, 1)):
                    ei = ci if 0 <= ci < n else (-ci - 1 if ci < 0 else 2 * n - ci - 1)
                    ej = cj if 0 <= cj < n else (-cj - 1 if cj < 0 else 2 * n - cj - 1)
                    for a, c, s2 in ((ci + 1, cj + 1, 1), (ci + 1, cj, -1), (ci, cj + 1, -1), (ci, cj, 1)):
                        add(r, a, c, 4 * s1 * s2 / h4, centre(ei, ej))
        return np.array(rows), np.array(cols), np.array(w), np.array(k)

    def velocity(self, T: np.ndarray):
        n, h, m = self.n, self.h, self.n - 1
        eta_n = np.exp(-self.b * T)
        tc = 0.25 * (T[:-1, :-1] + T[1:, :-1] + T[:-1, 1:] + T[1:, 1:])
        rows, cols, w, k = self._stokes
        eta = np.concatenate([eta_n.reshape(-1), np.exp(-self.b * tc).reshape(-1)])
        A = sp.csc_matrix((w * eta[k], (rows, cols)), shape=(m * m, m * m))
        rhs = (self.ra * (T[2:, 1:-1] - T[:-2, 1:-1]) / (2 * h)).reshape(-1)
        psi = np.zeros_like(T)
        psi[1:-1, 1:-1] = spl.spsolve(A, rhs).reshape(m, m)
        vx, vz = np.zeros_like(T), np.zeros_like(T)
        vx[:, 1:-1] = (psi[:, 2:] - psi[:, :-2]) / (2 * h)
        vx[:, 0], vx[:, -1] = psi[:, 1] / h, -psi[:, -2] / h  # psi odd about the wall
        vz[1:-1, :] = -(psi[2:, :] - psi[:-2, :]) / (2 * h)
        vz[0, :], vz[-1, :] = -psi[1, :] / h, psi[-2, :] / h
        return vx, vz

    # ---- temperature: backward Euler, second-order upwind advection
    def temperature_step(self, T, vx, vz, dt):
        n, h = self.n, self.h
        I, J = self.ti, self.tj
        nt = len(I)
        row = I * (n - 1) + (J - 1)
        rows, cols, vals = [], [], []
        wall_rhs = np.zeros(nt)  # the known wall and ghost values, moved to the right-hand side

        def put(di, dj, coef):
            i, j = I + di, J + dj
            coef = np.broadcast_to(np.asarray(coef, dtype=float), I.shape)
            i = np.where(i < 0, -i, np.where(i > n, 2 * n - i, i))  # insulating sides: even
            sign, const = np.ones(nt), np.zeros(nt)
            below, above = j < 0, j > n
            sign[below], const[below] = -1.0, 2.0  # T(-z) = 2 - T(z) about T = 1
            sign[above] = -1.0  # T(1 + z) = -T(1 - z) about T = 0
            j = np.where(below, -j, np.where(above, 2 * n - j, j))
            const[j == 0] += 1.0  # the bottom wall's T = 1 (the top's is 0)
            inside = (j > 0) & (j < n)
            rows.append(row[inside])
            cols.append((i * (n - 1) + j - 1)[inside])
            vals.append((coef * sign)[inside])
            wall_rhs[:] -= coef * const * (~inside | below)

        put(0, 0, 1.0 / dt + 4.0 / h**2)
        for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            put(di, dj, -1.0 / h**2)
        for v, (ei, ej) in ((vx[I, J], (1, 0)), (vz[I, J], (0, 1))):
            up = v > 0  # backward (3T0 - 4T-1 + T-2) / 2h, or forward (-T2 + 4T1 - 3T0) / 2h
            a = v / (2 * h)
            put(0, 0, np.where(up, 3 * a, -3 * a))
            put(-ei, -ej, np.where(up, -4 * a, 0.0))
            put(-2 * ei, -2 * ej, np.where(up, a, 0.0))
            put(ei, ej, np.where(up, 0.0, 4 * a))
            put(2 * ei, 2 * ej, np.where(up, 0.0, -a))
        A = sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(nt, nt))
        out = T.copy()
        out[I, J] = spl.spsolve(A, T[I, J] / dt + wall_rhs)
        return out

    def stats(self, T, vx, vz):
        h = self.h
        w = np.full(T.shape, h * h)
        w[[0, -1], :] *= 0.5
        w[:, [0, -1]] *= 0.5
        nu_top, nu_bot = wall_nusselt(T)
        return nu_top, nu_bot, np.sqrt(np.sum(w * (vx**2 + vz**2))), np.sum(w * T)


def wall_nusselt(T):
    """Nu at the top and the bottom of a field on the grid (T[i, j] at x_i, z_j of n + 1 nodes
    each way): second-order one-sided dT/dz, trapezoidal in x."""
    n = T.shape[0] - 1
    h = 1.0 / n
    wx = np.full(n + 1, h)
    wx[[0, -1]] *= 0.5
    nu_top = -np.sum(wx * (3 * T[:, -1] - 4 * T[:, -2] + T[:, -3]) / (2 * h))
    nu_bot = -np.sum(wx * (-3 * T[:, 0] + 4 * T[:, 1] - T[:, 2]) / (2 * h))
    return float(nu_top), float(nu_bot)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, required=True, help="grid intervals across the depth (and the width)")
    ap.add_argument("--ra", type=float, default=1e4, help="Rayleigh number at T = 0 (default 1e4)")
    ap.add_argument("--contrast", type=float, default=1000.0, help="viscosity contrast eta(0)/eta(1) (default 1000)")
    ap.add_argument("--t-end", type=float, default=0.3, help="end time in d^2/kappa (default 0.3)")
    ap.add_argument("--dt", type=float, default=2e-4, help="time step (default 2e-4)")
    ap.add_argument("--init", help="start from the T of a --save file (any n; interpolated)")
    ap.add_argument("--save", help="write T, v_x, v_z to this .npz")
    ap.add_argument("--profiles", action="store_true", help="print horizontal profiles at the end")
    a = ap.parse_args()
    try:
        g = Grid(a.n, a.ra, a.contrast)
        if a.t_end <= 0 or a.dt <= 0:
            raise ValueError("--t-end and --dt must be positive")
    except ValueError as e:
        sys.exit(f"fd_reference.py: error: {e}")
    T = 1 - g.Z + 0.01 * np.cos(np.pi * g.X) * np.sin(np.pi * g.Z)  # Blankenbach et al., sec. 3
    if a.init:
        try:
            t0 = np.load(a.init)["T"]
        except (OSError, KeyError, ValueError) as e:
            sys.exit(f"fd_reference.py: error: cannot read T from {a.init}: {e}")
        from scipy.interpolate import RegularGridInterpolator

        s = np.linspace(0.0, 1.0, t0.shape[0])
        T = RegularGridInterpolator((s, s), t0)((g.X, g.Z))
    vx, vz = g.velocity(T)
    t, step, start = 0.0, 0, time.time()
    while t < a.t_end * (1 - 1e-12):
        dt = min(a.dt, a.t_end - t)
        T = g.temperature_step(T, vx, vz, dt)
        vx, vz = g.velocity(T)
        t, step = t + dt, step + 1
        if step % 100 == 0:
            nt, nb, vr, tm = g.stats(T, vx, vz)
            print(f"step {step} t {t:.4f}  Nu {nt:.4f} {nb:.4f}  v_rms {vr:.3f}  <T> {tm:.4f}  ({time.time() - start:.0f} s)",
                  flush=True)
    nt, nb, vr, tm = g.stats(T, vx, vz)
    print(f"final: n {a.n} Ra {a.ra:g} contrast {a.contrast:g} t {t:g}: Nu top {nt:.4f} bottom {nb:.4f}  "
          f"v_rms {vr:.3f}  <T> {tm:.4f}")
    if a.profiles:
        for zz in (0.0, 0.02, 0.05, 0.1, 0.25, 0.5, 0.75, 0.9, 0.95, 0.98, 1.0):
            j = int(round(zz * a.n))
            print(f"  z {j / a.n:.3f}: <T> {T[:, j].mean():.3f}  max|v_x| {np.abs(vx[:, j]).max():8.1f}  "
                  f"max|v_z| {np.abs(vz[:, j]).max():8.1f}")
    if a.save:
        np.savez(a.save, T=T, vx=vx, vz=vz)
    return 0


if __name__ == "__main__":
    sys.exit(main())
