"""Loads pik._pik, the compiled runtime bindings: next to this file in an installed
package, else from the build folder ($PIK_BUILD_DIR/python/pik/, see _paths.py)."""
from __future__ import annotations

import glob
import importlib.machinery
import importlib.util
import os
import sys
from functools import lru_cache

from pik._paths import paths


@lru_cache(maxsize=1)
def native():
    try:
        from pik import _pik  # type: ignore[attr-defined]
        return _pik
    except ImportError:
        pass
    build = paths().build_dir
    tried = []
    if build:
        for suffix in importlib.machinery.EXTENSION_SUFFIXES:
            tried += glob.glob(os.path.join(build, "python", "pik", "_pik" + suffix))
    for file in tried:
        spec = importlib.util.spec_from_file_location("pik._pik", file)
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        sys.modules["pik._pik"] = mod
        return mod
    where = os.path.join(build, "python", "pik") if build else "(no build folder: set PIK_BUILD_DIR)"
    raise ImportError("pik's compiled runtime bindings (_pik) are not built: build the target "
                      f"pik_python_ext (needs pybind11-dev; looked in {where})")
