"""expand_vectors: rewrite vec2/3/4 values as their scalar components.

Rewrites: a vector op into one op per component named `<value>_x`, `_y`, ...;
`dot` into a multiply/add chain, `cross` into its six products, `comp` and
`insert` into renamings, a vector load into component loads, a vector `accum`
into one accumulation per component. Keeps: scalar ops (with arguments
renamed), stages and order. After this pass the IR has no vector types
(verify(..., expanded=True)).
"""
from __future__ import annotations

from dataclasses import replace

from pik_gen.ir import ops as O
from pik_gen.ir.nodes import Comp, Const, Kernel, MemberRef, Op, Reduce, fresh_name
from pik_gen.types import COMPONENTS


def expand_vectors(k: Kernel) -> Kernel:
    used = set(k.names())
    comps: dict[str, tuple[str, ...]] = {}  # vector value -> component values
    alias: dict[str, str] = {}  # scalar value -> the value it is now

    def sc(a: str) -> str:
        return alias.get(a, a)

    def part(a: str, c: int) -> str:
        return comps[a][c] if a in comps else sc(a)

    def expand(op: Op, out: list[Op]) -> None:
        t = op.type
        vec_args = [a for a in op.args if a in comps]
        if op.opcode == "comp":
            alias[op.result] = comps[op.args[0]][op.attr.index]  # type: ignore[union-attr]
            return
        if op.opcode == "insert":
            parts = list(comps[op.args[0]])
            parts[op.attr.index] = sc(op.args[1])  # type: ignore[union-attr]
            comps[op.result] = tuple(parts)
            return
        if op.opcode == "dot":
            a, b = op.args
            n = len(comps[a])
            acc = None
            for c in range(n):
                last = c == n - 1
                prod_name = fresh_name(used, f"{op.result}_{COMPONENTS[c]}")
                out.append(Op(prod_name, "mul", (comps[a][c], comps[b][c]), t, None, op.span))
                if acc is None:
                    acc = prod_name
                else:
                    sum_name = op.result if last else fresh_name(used, f"{op.result}_s{c}")
                    out.append(Op(sum_name, "add", (acc, prod_name), t, None, op.span))
                    acc = sum_name
            if acc != op.result:
                alias[op.result] = acc  # type: ignore[assignment]
            return
        if op.opcode == "cross":
            a, b = comps[op.args[0]], comps[op.args[1]]
            e = t.element  # type: ignore[union-attr]
            names = []
            for c, (p, q) in enumerate(((1, 2), (2, 0), (0, 1))):
                base = f"{op.result}_{COMPONENTS[c]}"
                l_ = fresh_name(used, base + "_l")
                r_ = fresh_name(used, base + "_r")
                nm = fresh_name(used, base)
                out.append(Op(l_, "mul", (a[p], b[q]), e, None, op.span))
                out.append(Op(r_, "mul", (a[q], b[p]), e, None, op.span))
                out.append(Op(nm, "sub", (l_, r_), e, None, op.span))
                names.append(nm)
            comps[op.result] = tuple(names)
            return
        if op.opcode == "accum" and vec_args and vec_args[0] == op.args[0]:
            red = op.attr
            assert isinstance(red, Reduce)
            for c, v in enumerate(comps[op.args[0]]):
                out.append(Op("", "accum", (v,) + tuple(sc(x) for x in op.args[1:]), None,
                              Reduce(red.kind, red.member, c), op.span))
            return
        if t is not None and t.is_vec:
            names = []
            for c in range(t.lanes):
                nm = fresh_name(used, f"{op.result}_{COMPONENTS[c]}")
                attr = op.attr
                if op.opcode == "load":
                    assert isinstance(attr, MemberRef)
                    attr = MemberRef(attr.role, attr.member, c)
                out.append(Op(nm, op.opcode, tuple(part(a, c) for a in op.args), t.element, attr, op.span))
                names.append(nm)
            comps[op.result] = tuple(names)
            return
        assert op.opcode in O.ARITY
        out.append(replace(op, args=tuple(sc(a) for a in op.args)))

    blocks = {}
    for stage, ops in k.blocks():
        out: list[Op] = []
        for op in ops:
            expand(op, out)
        blocks[stage] = out
    locals_ = tuple(
        replace(lv, values=tuple(x for v in lv.values for x in (comps[v] if v in comps else (sc(v),))))
        for lv in k.locals
    )
    return replace(k.with_blocks(blocks), locals=locals_)


__all__ = ["expand_vectors", "Const", "Comp"]
