"""dce: dead-code elimination.

Rewrites: removes every op whose value no `accum` needs, directly or through
other ops (e.g. a variable computed but never used, a vector component that
does not contribute). Keeps: all `accum` ops and everything they depend on;
parameters stay in the kernel's interface even when unused.
"""
from __future__ import annotations

from pik_gen.ir.nodes import Kernel, Stage


def dce(k: Kernel) -> Kernel:
    live: set[str] = set()
    for stage in reversed(list(Stage)):
        for op in reversed(k.block(stage)):
            if op.opcode == "accum" or op.result in live:
                live.update(op.args)
    blocks = {s: tuple(op for op in ops if op.opcode == "accum" or op.result in live) for s, ops in k.blocks()}
    out = k.with_blocks(blocks)
    from dataclasses import replace

    locals_ = tuple(lv for lv in k.locals if all(v in live for v in lv.values))
    return replace(out, locals=locals_)
