"""The compiled hot loop of a generated kernel: extraction, stack traffic, llvm-mca.

`hot_loop()` generates a kernel for an x86 ISA, compiles it in a small
translation unit (particles stored as double, as bench_kernels does) with the
given compiler and flags (default `-O3 -march=native`), disassembles it with
objdump and returns the i-parallel j loop: among the innermost loops (backward
branches with no other backward branch inside), the one with the most FMA
instructions (of equal ones the shortest: the fast body of a guarded shape, whose
redo pass repeats it with the special-value fix). `stack_traffic()` lists the instructions of a loop that read or
write the stack frame at a fixed offset (`0x40(%rsp)`, `-0x20(%rbp)`: spills
and reloads; the j buffers the kernel keeps on the stack are read with an
index register, `(%rsp,%rax,4)`, and are not counted). `mca()` runs llvm-mca
on a loop for a -mcpu and returns its block reciprocal throughput (cycles per
iteration). Used by bench/kernels/hot_loop.py, bench_kernels' documentation
and tests/compiler/test_hot_loop.py.
"""
from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

FMA = re.compile(r"^vf(n)?m(add|sub)")
STACK = re.compile(r"(^|[,\s])-?(0x[0-9a-f]+)?\(%(rsp|rbp)\)")


@dataclass
class Loop:
    instructions: list[tuple[str, str]]  # (mnemonic, operands), AT&T syntax
    U: int                               # i-vectors per block
    W: int                               # lanes per vector
    V: int = 1                           # j-particles per iteration (Simd.j_copies_rule)

    @property
    def per_interaction(self) -> float:
        return len(self.instructions) / (self.U * self.V * self.W)

    def text(self) -> str:
        return "\n".join(f"{op} {arg}" for op, arg in self.instructions)


def _structs(ck) -> list[str]:
    out = []
    for role in ("EPI", "EPJ", "FORCE"):
        fields = []
        for m in (m for m in ck.members if m.role == role):
            t = "double" if m.type.scalar.is_float else "long long"
            fields.append(f"{t} {m.name};" if m.type.lanes == 1 else
                          f"struct {{ {t} {', '.join('xyzw'[: m.type.lanes])}; }} {m.name};")
        out.append(f"struct {role} {{ {' '.join(fields)} }};")
    return out


def hot_loop(kernel: Path, isa: str, cxx: str = "g++", flags: str = "-O3 -march=native",
             unroll: int | None = None, cpu: str | None = None, j_copies: int | None = None) -> Loop:
    from pik_gen.backends import ISAS, Options
    from pik_gen.backends.emit import render_header
    from pik_gen.driver import frontend, lower
    from pik_gen.frontend import parse
    from pik_gen.pragmas import interpret

    source = Path(kernel).read_text()
    ck = frontend(source, str(kernel))
    k = lower(source, str(kernel), "K")
    cls = ISAS[isa]
    # the file's `#pragma unroll` (unless `unroll` overrides it) and `#pragma blend`, as pikg-gen
    pragma_unroll, blend = interpret(parse(source, str(kernel)), True, [])
    opts = Options(name="K", unroll=unroll if unroll is not None else pragma_unroll, cpu=cpu, blend=blend,
                   j_copies=j_copies)
    ctx = cls(opts).context(k, "probe")
    with tempfile.TemporaryDirectory() as d:
        hdr = Path(d) / "K.hpp"
        hdr.write_text(render_header(k, [cls], opts, source, str(kernel)))
        tu = Path(d) / "tu.cpp"
        tu.write_text("\n".join(_structs(ck)) + '\n#include "K.hpp"\n'
                      "__attribute__((noinline)) void run(const K& k, const EPI* a, int ni, const EPJ* b, int nj, "
                      "FORCE* f) { k(a, ni, b, nj, f); }\n")
        obj = Path(d) / "tu.o"
        subprocess.run([cxx, "-std=c++20", *flags.split(), "-c", str(tu), "-o", str(obj), f"-I{d}"],
                       check=True, capture_output=True, text=True)
        dis = subprocess.run(["objdump", "-d", "--no-show-raw-insn", str(obj)], check=True, capture_output=True,
                             text=True).stdout
    ins = []
    for line in dis.splitlines():
        m = re.match(r"\s+([0-9a-f]+):\s+(\S+)\s*(.*)", line)
        if m:
            ins.append((int(m.group(1), 16), m.group(2), m.group(3).split("#")[0].strip()))
    loops = []
    for a, op, arg in ins:
        m = re.match(r"([0-9a-f]+) <", arg)
        if op.startswith("j") and m and int(m.group(1), 16) < a:
            loops.append((int(m.group(1), 16), a))
    best: list = []
    nf = lambda body: sum(bool(FMA.match(x[1])) for x in body)  # noqa: E731
    for lo, hi in loops:
        if any(lo <= lo2 and hi2 <= hi and (lo2, hi2) != (lo, hi) for lo2, hi2 in loops):
            continue
        body = [x for x in ins if lo <= x[0] <= hi]
        if (nf(body), -len(body)) > (nf(best), -len(best)):  # ties: the shorter (a guarded fast body)
            best = body
    return Loop([(op, arg) for _a, op, arg in best], ctx["U"], ctx["W"], ctx["V"])


def stack_traffic(loop: Loop) -> list[str]:
    """Instructions of the loop that load or store at a fixed offset of the stack frame."""
    return [f"{op} {arg}" for op, arg in loop.instructions if STACK.search(arg)]


def spills(loop: Loop) -> list[str]:
    """The spills of the loop: stores to a fixed stack slot (AT&T: the slot is the last
    operand) and the loads of those slots. The other stack loads read loop-invariant
    values the compiler keeps in memory (hoisted constant broadcasts, i-values): a
    load per use, no store, as a memory operand from .rodata would be."""
    written = set()
    for op, arg in loop.instructions:
        parts = [p.strip() for p in re.split(r",(?![^(]*\))", arg)]
        if parts and STACK.search(parts[-1]) and not op.startswith(("cmp", "test", "vcmp", "vptest")):
            written.add(parts[-1])
    return [f"{op} {arg}" for op, arg in loop.instructions
            if any(w in [p.strip() for p in re.split(r",(?![^(]*\))", arg)] for w in written)]


def mca(loop: Loop, mcpu: str) -> float | None:
    """llvm-mca's block reciprocal throughput of the loop on -mcpu (None: no llvm-mca)."""
    tool = shutil.which("llvm-mca") or shutil.which("llvm-mca-14")
    if tool is None:
        return None
    asm = []
    for op, arg in loop.instructions:
        if op.startswith("j"):
            asm.append(f"{op} 0")  # the branch target does not matter to the throughput model
            continue
        asm.append(f"{op} {arg}".strip())
    r = subprocess.run([tool, f"-mcpu={mcpu}", "-iterations=200", "--skip-unsupported-instructions=lack-sched"],
                       input="\n".join(asm) + "\n", capture_output=True, text=True)
    if r.returncode != 0:
        r = subprocess.run([tool, f"-mcpu={mcpu}", "-iterations=200"], input="\n".join(asm) + "\n",
                           capture_output=True, text=True)
    m = re.search(r"Block RThroughput:\s*([0-9.]+)", r.stdout)
    tot = re.search(r"Total Cycles:\s*([0-9]+)", r.stdout)
    if tot:
        return int(tot.group(1)) / 200.0
    return float(m.group(1)) if m else None
