"""Shared helpers of the compiler tests: run pikg-gen in-process, find the kernels."""
from __future__ import annotations

import contextlib
import io
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "compiler"))

KERNELS = sorted((ROOT / "kernels").glob("*.pik"))


def run_cli(args: list[str]) -> tuple[int, str, str]:
    """Run pikg-gen's main() in this process; returns (status, stdout, stderr)."""
    from pik_gen.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main([str(a) for a in args])
    return rc, out.getvalue(), err.getvalue()
