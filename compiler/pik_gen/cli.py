"""Command line of pikg-gen."""
from __future__ import annotations

import sys

from pik_gen import __version__

USAGE = """usage: pikg-gen KERNEL.pik -o OUT.hpp --target reference|avx2|avx512|auto [options]"""


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if "--version" in args:
        print(f"pikg-gen {__version__}")
        return 0
    if "--help" in args or "-h" in args:
        print(USAGE)
        return 0
    print("pikg-gen: error: code generation is not built yet", file=sys.stderr)
    return 1
