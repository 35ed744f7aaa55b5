"""Where the package finds pikg-gen, the runtime headers, the kernel library and
its compiled bindings: in an installed pik (pik/_install_paths.py, written by
`make install`) or in the source tree the package was imported from
(python/pik/ -> the repository root), with the build folder named by
$PIK_BUILD_DIR or, failing that, <repository>/build."""
from __future__ import annotations

import os
from dataclasses import dataclass
from functools import lru_cache

_HERE = os.path.dirname(os.path.abspath(__file__))


@dataclass(frozen=True)
class Paths:
    pikg_gen: str | None  # the pikg-gen launcher, or None: run pik_gen from compiler_dir
    compiler_dir: str  # holds the pik_gen package
    include_dirs: tuple[str, ...]  # the runtime headers
    kernels_dir: str  # the .pik kernel library
    build_dir: str | None  # a pik build folder (source-tree use), or None


@lru_cache(maxsize=1)
def paths() -> Paths:
    try:
        from pik import _install_paths as inst  # type: ignore[attr-defined]
    except ImportError:
        inst = None
    if inst is not None:
        gen = os.environ.get("PIKG_GEN") or (inst.PIKG_GEN if os.path.exists(inst.PIKG_GEN) else None)
        return Paths(gen, inst.COMPILER_DIR, tuple(inst.INCLUDE_DIRS), inst.KERNELS_DIR, None)
    root = os.path.normpath(os.path.join(_HERE, "..", ".."))
    build = os.environ.get("PIK_BUILD_DIR") or os.path.join(root, "build")
    build = build if os.path.isdir(build) else None
    gen = os.environ.get("PIKG_GEN")
    if not gen and build and os.path.exists(os.path.join(build, "bin", "pikg-gen")):
        gen = os.path.join(build, "bin", "pikg-gen")
    return Paths(gen, os.path.join(root, "compiler"), (os.path.join(root, "runtime", "include"),),
                 os.path.join(root, "kernels"), build)
