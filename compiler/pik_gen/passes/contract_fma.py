"""contract_fma: fuse a multiply feeding an add or subtract into one FMA op.

Rewrites, for floating-point scalars, when the product has no other use and
lives in the same stage:  a*b + c and c + a*b -> madd(a, b, c);  a*b - c ->
msub(a, b, c);  c - a*b -> nmadd(a, b, c). The fused op keeps the add's name;
the product disappears. Then an addend joins a chain of fused products:
(a*b + (c*d + e*f)) + g -> a*b + (c*d + madd(e, f, g)) when every link has
no other use (e.g. the dot product of r2 = r*r + eps2 takes eps2 into its
first FMA: one add fewer per pair). This reassociates a sum, so the result
may differ in the last bit from the source's order; every backend gets the
same IR, so they all agree. Keeps: products used elsewhere (fusing would
compute them twice), integer arithmetic, and order. Backends may evaluate madd
fused or as a multiply and an add; both are within the accuracy contract.
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
        blocks[stage] = _absorb_addends([o for o in out if o.result not in fused], uses)
    return k.with_blocks(blocks)


def _absorb_addends(ops: list[Op], uses: Counter[str]) -> tuple[Op, ...]:
    """add(madd(a, b, madd(c, d, mul(e, f))), g) -> madd(a, b, madd(c, d, madd(e, f, g)))
    where each link of the chain has one use. The chain moves to the add's place
    (its links are used nowhere else), after the definition of g."""
    defs = {op.result: op for op in ops if op.result}
    moved: set[str] = set()
    out: list[Op] = []
    for op in ops:
        t = op.type
        if op.opcode == "add" and t is not None and t.scalar.is_float and not t.is_vec:
            for p, g in (op.args, op.args[::-1]):
                chain: list[Op] = []
                link = defs.get(p)
                while (link is not None and link.opcode == "madd" and link.type == t and uses[link.result] == 1
                       and link.result not in moved):
                    chain.append(link)
                    link = defs.get(link.args[2])
                if not chain or link is None or link.opcode != "mul" or link.type != t or uses[link.result] != 1:
                    continue
                bottom = Op(link.result, "madd", (link.args[0], link.args[1], g), t, None, link.span)
                rebuilt = [bottom] + chain[::-1]
                here = {x.result for x in rebuilt}
                moved |= here
                rebuilt[-1] = Op(op.result, "madd", rebuilt[-1].args, t, None, op.span)
                out = [x for x in out if x.result not in here]
                out.extend(rebuilt)
                break
            else:
                out.append(op)
            continue
        out.append(op)
    return tuple(out)
