#!/usr/bin/python3
"""Print the hot loop of a generated kernel and its instructions per interaction.

    bench/kernels/hot_loop.py KERNEL.pik ISA [--cxx g++] [--flags "-O2"] [--print]

Generates the kernel for ISA with pikg-gen, compiles it in a small translation
unit (particles stored as double, like bench_kernels), disassembles it with
objdump and takes the i-parallel main loop: the backward branch whose body holds
the most vector instructions among the innermost loops. Instructions per interaction = instructions in
that loop / (lanes x i-vectors per block), since one iteration handles one
j-particle against U x W i-particles.
"""
from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "compiler"))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("kernel")
    ap.add_argument("isa", choices=("avx2", "avx512"))
    ap.add_argument("--cxx", default="g++")
    ap.add_argument("--flags", default="-O2")
    ap.add_argument("--print", action="store_true", help="print the loop")
    ap.add_argument("--unroll", type=int, help="override the i-vectors per block (experiments)")
    args = ap.parse_args()

    from pik_gen.backends import ISAS, Options
    from pik_gen.backends.emit import render_header
    from pik_gen.driver import frontend, lower

    source = Path(args.kernel).read_text()
    ck = frontend(source, args.kernel)
    k = lower(source, args.kernel, "K")
    cls = ISAS[args.isa]
    if args.unroll:
        cls = type(cls.__name__, (cls,), {"unroll": lambda self, n_acc, n_ivals: args.unroll})
    isa = cls(Options(name="K"))
    ctx = isa.context(k, "probe")
    W, U = ctx["W"], ctx["U"]
    with tempfile.TemporaryDirectory() as d:
        hdr = Path(d) / "K.hpp"
        hdr.write_text(render_header(k, [cls], Options(name="K"), source, args.kernel))
        structs = []
        for role in ("EPI", "EPJ", "FORCE"):
            ms = [m for m in ck.members if m.role == role]
            fields = []
            for m in ms:
                t = "double" if m.type.scalar.is_float else "long long"
                fields.append(f"{t} {m.name};" if m.type.lanes == 1 else
                              f"struct {{ {t} {', '.join('xyzw'[: m.type.lanes])}; }} {m.name};")
            structs.append(f"struct {role} {{ {' '.join(fields)} }};")
        tu = Path(d) / "tu.cpp"
        tu.write_text("\n".join(structs) + '\n#include "K.hpp"\n'
                      f"__attribute__((noinline)) void run(const K& k, const EPI* a, int ni, const EPJ* b, int nj, FORCE* f)"
                      " { k(a, ni, b, nj, f); }\n")
        obj = Path(d) / "tu.o"
        subprocess.run([args.cxx, "-std=c++20", *args.flags.split(), "-c", str(tu), "-o", str(obj), f"-I{d}"],
                       check=True)
        dis = subprocess.run(["objdump", "-d", "--no-show-raw-insn", str(obj)], check=True, capture_output=True,
                             text=True).stdout
    ins = []
    for line in dis.splitlines():
        m = re.match(r"\s+([0-9a-f]+):\s+(\S+)\s*(.*)", line)
        if m:
            ins.append((int(m.group(1), 16), m.group(2), m.group(3)))
    loops = []  # (start, end) of every backward branch
    for a, op, arg in ins:
        m = re.match(r"([0-9a-f]+) <", arg)
        if op.startswith("j") and m and int(m.group(1), 16) < a:
            loops.append((int(m.group(1), 16), a))
    best: list = []
    for lo, hi in loops:
        if any(lo <= lo2 and hi2 <= hi and (lo2, hi2) != (lo, hi) for lo2, hi2 in loops):
            continue  # not innermost
        body = [x for x in ins if lo <= x[0] <= hi]
        if sum(x[1].startswith("v") for x in body) > sum(x[1].startswith("v") for x in best):
            best = body
    if args.print:
        for _a, op, arg in best:
            print(f"  {op:<14} {arg[:70]}")
    n = len(best)
    print(f"{Path(args.kernel).name} {args.isa}: hot loop {n} instructions for {U} x {W} interactions = "
          f"{n / (U * W):.2f} per interaction")
    return 0


if __name__ == "__main__":
    sys.exit(main())
