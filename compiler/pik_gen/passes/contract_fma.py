"""contract_fma: fuse a multiply feeding an add or subtract into one FMA op.

Rewrites, for floating-point scalars, when the product has no other use and
lives in the same stage:  a*b + c and c + a*b -> madd(a, b, c);  a*b - c ->
msub(a, b, c);  c - a*b -> nmadd(a, b, c). The fused op keeps the add's name;
the product disappears. Keeps: products used elsewhere (fusing would compute
them twice), integer arithmetic, and order. Backends may evaluate madd fused or
as a multiply and an add; both are within the accuracy contract.
"""
from __future__ import annotations

from collections import Counter

from pik_gen.ir.nodes import Kernel, Op


def contract_fma(k: Kernel) -> Kernel:
    uses: Counter[str] = Counter(a for op in k.all_ops() for a in op.args)
    uses.update(v for lv in k.locals for v in lv.values)
    blocks = {}
    for stage, ops in k.blocks():
        defs = {op.result: op for op in ops if op.result}
        fused: set[str] = set()
        out: list[Op] = []

        def product(name: str, t) -> Op | None:
            m = defs.get(name)
            if m is None or m.opcode != "mul" or uses[name] != 1 or m.type != t or name in fused:
                return None
            return m

        for op in ops:
            t = op.type
            if op.opcode in ("add", "sub") and t is not None and t.scalar.is_float and not t.is_vec:
                a, b = op.args
                new = None
                if (m := product(a, t)) is not None:
                    new = Op(op.result, "madd" if op.opcode == "add" else "msub", (m.args[0], m.args[1], b), t, None, op.span)
                    fused.add(a)
                elif (m := product(b, t)) is not None:
                    new = Op(op.result, "madd" if op.opcode == "add" else "nmadd", (m.args[0], m.args[1], a), t, None, op.span)
                    fused.add(b)
                if new is not None:
                    op = new
            out.append(op)
        blocks[stage] = tuple(o for o in out if o.result not in fused)
    return k.with_blocks(blocks)
