"""cse: common-subexpression elimination.

Rewrites: an op computing the same opcode, arguments, type and attribute as an
earlier op visible from its stage (see nodes.VISIBLE) is removed and its uses
renamed to the earlier value. Repeated loads of one member and repeated reads
of one parameter therefore become one. Keeps: `accum` ops, the first
definition's name, and order.
"""
from __future__ import annotations

from dataclasses import replace

from pik_gen.ir.nodes import VISIBLE, Kernel, Op, Stage, rename_args


def cse(k: Kernel) -> Kernel:
    seen: dict[Stage, dict[tuple, str]] = {s: {} for s in Stage}
    alias: dict[str, str] = {}
    blocks = {}
    for stage, ops in k.blocks():
        out: list[Op] = []
        for op in ops:
            op = replace(op, args=tuple(alias.get(a, a) for a in op.args))
            if op.opcode != "accum":
                key = op.key()
                hit = next((seen[s][key] for s in VISIBLE[stage] if key in seen[s]), None)
                if hit is not None:
                    alias[op.result] = hit
                    continue
                seen[stage][key] = op.result
            out.append(op)
        blocks[stage] = out
    return rename_args(k.with_blocks(blocks), alias)
