"""pik from Python: snapshots, kernels and the runtime on NumPy arrays.

    import pik
    s = pik.read_snapshot("out/snap_000064.pbin")       # every pik snapshot format
    k = pik.Kernel("gravity.pik")                       # pikg-gen + C++ compiler, cached
    f = k(particles, eps2=1e-4)                         # structured arrays, no copies
    acc, pot = pik.gravity(pos, mass, eps=0.01, theta=0.5)   # Barnes-Hut tree
    nb = pik.neighbours(pos, radius=h)                  # short-range tree

See docs/python.md.
"""
from pik.kernel import BuildError, Kernel, KernelError
from pik.snapshot import Snapshot, SnapshotError, detect_format, part_path, read_snapshot
from pik.tree import Neighbours, gravity, neighbours, write_snapshot

__version__ = "0.1.0"
__all__ = ["BuildError", "Kernel", "KernelError", "Neighbours", "Snapshot", "SnapshotError",
           "detect_format", "gravity", "neighbours", "part_path", "read_snapshot", "write_snapshot"]
