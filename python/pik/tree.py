"""Tree forces and neighbour search through the pik runtime (pik._pik, pybind11).

    acc, pot = pik.gravity(pos, mass, eps=0.01, theta=0.5)
    nb = pik.neighbours(pos, radius=0.1)       # nb[i]: indices j with |x_i - x_j| < r_i

Both release the GIL and run the runtime's OpenMP threads (`threads=`, default:
every CPU this process may use).
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from pik._native import native


def _threads(threads: int | None) -> int:
    if threads is None:
        return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    if int(threads) < 1:
        raise ValueError("threads must be >= 1")
    return int(threads)


def gravity(pos, mass, eps: float, theta: float = 0.5, *, leaf: int = 8, group: int = 64,
            opening: str = "box", precision: str = "f32", threads: int | None = None,
            stats: bool = False):
    """Softened Newtonian gravity (G = 1) by the Barnes-Hut tree of the runtime
    (pik::LongRangeTree; modified tree algorithm, Barnes 1990, J. Comput. Phys. 87,
    161) with monopole cells and the kernels of kernels/gravity.pik (precision
    "f32") or kernels/gravity_f64.pik ("f64"):

        a_i = -sum_j m_j (x_i - x_j) / (|x_i - x_j|^2 + eps^2)^(3/2)
        phi_i = -sum_j m_j / (|x_i - x_j|^2 + eps^2)^(1/2)     (the i = j term included: -m_i/eps)

    pos (N, 3) and mass (N,) are converted to float64 when needed. theta = 0 opens
    every cell (direct summation). Returns (acc (N, 3), pot (N,)), float64; with
    stats=True also a dict of interaction counts.
    """
    pos = np.ascontiguousarray(pos, dtype=np.float64)
    mass = np.ascontiguousarray(mass, dtype=np.float64)
    if not (theta >= 0):
        raise ValueError("theta must be >= 0")
    acc, pot, n_ep, n_sp = native().gravity(pos, mass, float(eps), float(theta), int(leaf), int(group),
                                            opening, precision, _threads(threads))
    if stats:
        return acc, pot, {"particle_interactions": n_ep, "cell_interactions": n_sp}
    return acc, pot


@dataclass(frozen=True)
class Neighbours:
    """Neighbour lists in compressed-row form: the neighbours of particle i are
    indices[offsets[i]:offsets[i + 1]], sorted (a particle is its own neighbour)."""

    offsets: np.ndarray  # int64 (N + 1,)
    indices: np.ndarray  # int64 (offsets[-1],)

    def __len__(self) -> int:
        return len(self.offsets) - 1

    def __getitem__(self, i: int) -> np.ndarray:
        return self.indices[self.offsets[i]:self.offsets[i + 1]]

    def counts(self) -> np.ndarray:
        return np.diff(self.offsets)

    def pairs(self) -> tuple[np.ndarray, np.ndarray]:
        """(i, j) arrays of every pair, for NumPy evaluation of SPH-style sums."""
        return np.repeat(np.arange(len(self)), self.counts()), self.indices


def neighbours(pos, radius, *, mode: str = "gather", box=None, threads: int | None = None) -> Neighbours:
    """Every j with |x_i - x_j| < r through the runtime's short-range tree
    (pik::ShortRangeTree): r = radius[i] (mode "gather", SPH's h_i), radius[j]
    ("scatter") or the larger of the two ("symmetric"). radius is a number or an
    (N,) array. box=[[xlo, ylo, zlo], [xhi, yhi, zhi]] makes every dimension
    periodic (distances to the nearest image; a particle within r of several
    images appears once per image)."""
    pos = np.ascontiguousarray(pos, dtype=np.float64)
    radius = np.ascontiguousarray(radius, dtype=np.float64)
    if box is not None:
        box = np.ascontiguousarray(box, dtype=np.float64)
    offsets, indices = native().neighbours(pos, radius, mode, box, _threads(threads))
    return Neighbours(offsets, indices)


def write_snapshot(path, snap, format: str = "binary") -> None:
    """Writes a pik.Snapshot (or any object with id, mass, pos, vel and optional
    columns, attrs, time, step, part, n_parts, first_index, n_total) with the
    runtime's writer (pik::io::write_snapshot_part: atomic; format "binary",
    "ascii" or "hdf5"); part k of n goes to stem.k.ext."""
    n = len(snap.pos)
    cols = [(k, np.ascontiguousarray(v, dtype=np.float64)) for k, v in getattr(snap, "columns", {}).items()]
    native().write_snapshot(os.fspath(path), format, np.ascontiguousarray(snap.id, dtype=np.uint64),
                            snap.mass, snap.pos, snap.vel, cols, dict(getattr(snap, "attrs", {})),
                            float(getattr(snap, "time", 0.0)), int(getattr(snap, "step", 0)),
                            int(getattr(snap, "part", 0)), int(getattr(snap, "n_parts", 1)),
                            int(getattr(snap, "first_index", 0)), int(getattr(snap, "n_total", 0) or n))
