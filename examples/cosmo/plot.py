#!/usr/bin/env python3
"""Pictures of a cosmo run: projected density maps, the power spectrum against
linear theory, and the friends-of-friends halo mass function against the fit of
Tinker et al. 2008 (ApJ 688, 709; Delta = 200 mean, z = 0 parameters of their
table 2), using the run's linear spectrum (linear_pk.txt) and growth (growth.txt).

    plot.py --run cosmo_out --out docs/img   (writes cosmo_density.png, cosmo_pk.png,
                                              cosmo_hmf.png, and cosmo_hmf.txt: the FoF
                                              mass function over the fit, per bin)
"""
import argparse
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

RHO_CRIT = 2.77536627e11  # h^2 Msun / Mpc^3


def header_value(path, key):
    words = path.read_text().splitlines()[0].lstrip("# ").split()
    return float(words[words.index(key) + 1].rstrip(":,"))


def load(path):
    return np.loadtxt(path, comments="#", ndmin=2)


def sigma_of_r(k, pk, r):
    x = np.outer(r, k)
    w = 3 * (np.sin(x) - x * np.cos(x)) / x**3
    integrand = k**3 * pk * w**2 / (2 * math.pi**2)
    return np.sqrt(np.trapz(integrand, np.log(k), axis=1))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--run", required=True, help="output directory of cosmo")
    ap.add_argument("--out", default=".", help="where to write the PNG files")
    ap.add_argument("--omega-m", type=float, default=None, help="Omega_m (default: from linear_pk.txt)")
    args = ap.parse_args()
    run, out = Path(args.run), Path(args.out)
    pks = sorted(run.glob("pk_*.txt"))
    if not pks:
        sys.exit(f"plot.py: error: no pk_*.txt in {run} (is it a cosmo output directory?)")
    out.mkdir(parents=True, exist_ok=True)
    lin_path = run / "linear_pk.txt"
    if args.omega_m is not None:
        omega_m = args.omega_m
    elif lin_path.exists():
        omega_m = header_value(lin_path, "omega_m")
    else:
        sys.exit(f"plot.py: error: {lin_path} missing (give --omega-m)")

    # Projected density: the first and last outputs.
    projs = sorted(run.glob("proj_*.txt"))
    shown = [projs[0], projs[-1]] if len(projs) > 1 else projs
    fig, axes = plt.subplots(1, len(shown), figsize=(5 * len(shown), 4.6), squeeze=False)
    for ax, p in zip(axes[0], shown):
        m = load(p)
        a = header_value(p, "a")
        box = float(p.read_text().splitlines()[0].split("box")[1].split()[0])
        im = ax.imshow(np.log10(m.T + 1e-2), origin="lower", extent=[0, box, 0, box], cmap="magma",
                       vmin=-1, vmax=max(1.0, float(np.log10(m.max() + 1e-2))))
        ax.set_title(f"a = {a:.3g} (z = {1 / a - 1:.2f})")
        ax.set_xlabel("x [Mpc/h]")
        ax.set_ylabel("y [Mpc/h]")
        fig.colorbar(im, ax=ax, label="log10 projected density / mean")
    fig.tight_layout()
    fig.savefig(out / "cosmo_density.png", dpi=90)

    # P(k) at every output against D(a)^2 P_lin(k).
    fig, ax = plt.subplots(figsize=(6, 4.5))
    lin = load(lin_path) if lin_path.exists() else None
    for p in pks:
        d = load(p)
        a = header_value(p, "a")
        D = header_value(p, "D")
        line, = ax.loglog(d[:, 0], d[:, 1], "o-", ms=3, label=f"a = {a:.3g}")
        if lin is not None:
            sel = (lin[:, 0] > d[0, 0] / 2) & (lin[:, 0] < d[-1, 0] * 1.5)
            ax.loglog(lin[sel, 0], lin[sel, 1] * D * D, "--", color=line.get_color(), lw=1)
    shot = header_value(pks[0], "shot_noise")
    ax.axhline(shot, color="gray", lw=0.8, ls=":", label="Poisson V/N")
    ax.set_xlabel("k [h/Mpc]")
    ax.set_ylabel("P(k) [(Mpc/h)^3]")
    ax.set_title("measured (points) and linear theory D(a)^2 P_lin (dashed)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "cosmo_pk.png", dpi=90)

    # Halo mass function at the last output.
    fofs = sorted(run.glob("fof_*.txt"))
    if fofs and lin is not None:
        f = fofs[-1]
        h = load(f)
        a = header_value(f, "a")
        first = f.read_text().splitlines()[0]
        box = float(first.split("box")[1].split()[0])
        if h.size and len(h) >= 3:
            masses = h[:, 1]
            mp = float(first.split("particle mass")[1].split()[0])
            edges = np.logspace(np.log10(20 * mp), np.log10(masses.max() * 1.01), 9)
            counts, _ = np.histogram(masses, edges)
            centres = np.sqrt(edges[1:] * edges[:-1])
            dlnm = np.log(edges[1:] / edges[:-1])
            n = counts / box**3 / dlnm
            err = np.sqrt(np.maximum(counts, 1)) / box**3 / dlnm
            growth = load(run / "growth.txt")
            D = float(np.interp(a, growth[:, 0], growth[:, 1]))
            rho_m = omega_m * RHO_CRIT
            mgrid = np.logspace(np.log10(edges[0]), np.log10(edges[-1]), 40)
            r = (3 * mgrid / (4 * math.pi * rho_m)) ** (1 / 3)
            sig = D * sigma_of_r(lin[:, 0], lin[:, 1], r)
            # Tinker et al. 2008, Delta = 200 (mean), z = 0: A = 0.186, a = 1.47, b = 2.57, c = 1.19.
            A, aa, b, c = 0.186, 1.47, 2.57, 1.19
            fs = A * ((sig / b) ** (-aa) + 1) * np.exp(-c / sig**2)
            dlnsinv = -np.gradient(np.log(sig), np.log(mgrid))
            tinker = fs * rho_m / mgrid * dlnsinv
            fig, ax = plt.subplots(figsize=(6, 4.5))
            ok = counts > 0
            ax.errorbar(centres[ok], n[ok], yerr=err[ok], fmt="o", label=f"FoF b = 0.2, a = {a:.3g}")
            ax.loglog(mgrid, tinker, "-", label="Tinker et al. 2008 (Delta = 200m)")
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel("M [Msun/h]")
            ax.set_ylabel("dn / dln M [(h/Mpc)^3]")
            ax.legend(fontsize=8)
            fig.tight_layout()
            fig.savefig(out / "cosmo_hmf.png", dpi=90)
            # The comparison as numbers: FoF over the fit per bin, with the Poisson error.
            fit = np.exp(np.interp(np.log(centres), np.log(mgrid), np.log(tinker)))
            rows = ["# M [Msun/h]  particles  haloes  n_FoF/n_Tinker  Poisson error"]
            for mc, cnt, nn, ft in zip(centres, counts, n, fit):
                rel = 1 / math.sqrt(cnt) if cnt else float("inf")
                rows.append(f"{mc:12.4e} {mc / mp:10.0f} {cnt:7d} {nn / ft:15.3f} {nn / ft * rel:14.3f}")
            (out / "cosmo_hmf.txt").write_text("\n".join(rows) + "\n")
            print("\n".join(rows))
    print(f"plot.py: wrote {out}/cosmo_density.png, cosmo_pk.png" + (", cosmo_hmf.png" if fofs else ""))


if __name__ == "__main__":
    main()
