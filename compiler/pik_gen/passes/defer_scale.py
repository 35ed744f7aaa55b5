"""defer_scale: carry constant power-of-two factors to the accumulations.

Rewrites, in the pair stage, for F32/F64 scalars:
  rsqrt(x) -> rsqrt2(x) with a pending factor 1/2. 2/sqrt(x) is one operation
      cheaper than 1/sqrt(x) wherever 1/sqrt comes from a Newton step,
      y (3 - x y^2) / 2: the step without its 1/2.
  x * c, c * x (c a positive power of two, a literal) -> x with a pending factor c.
A pending factor travels through `mul` (factors multiply), `div` (divide),
`neg`, and `add`/`sub`/`min`/`max`/`select` whose operands carry the same
factor, and ends in an `add`/`sub` accumulation as its `scale`: the backend
multiplies the finished sum once, when it adds it to FORCE. Anywhere else (a
comparison, sqrt, a cast, operands with different factors) the factor is
applied by one `mul` just before the use; a second accumulation into the same
FORCE sum with another factor is multiplied by the ratio of the two. Scaling by a power of two is exact in binary floating
point, so every value is the same as without the pass (barring overflow or
underflow at the extremes of the range), e.g. gravity's

    rinv = rsqrt(r2); mr = mj * rinv; acc -= mr * rinv * rinv * rij; pot -= mr

becomes R = rsqrt2(r2), mj * R, ..., `acc -= ... * 0.125` and `pot -= ... * 0.5`
with one multiply fewer per pair. Keeps: everything when the rewrite would
add more multiplies than it removes; other stages (they run once per particle);
integer arithmetic.
"""
from __future__ import annotations

import math
from dataclasses import replace

from pik_gen.ir.nodes import Const, Kernel, Op, Reduce, Stage, fresh_name
from pik_gen.types import Scalar


def _pow2(v: float) -> bool:
    return v > 0 and math.isfinite(v) and math.frexp(v)[0] == 0.5


def defer_scale(k: Kernel) -> Kernel:
    consts = {op.result: op.attr.value for op in k.all_ops() if op.opcode == "const" and isinstance(op.attr, Const)}
    used = set(k.names())
    # every pair value v is (base, c): v = c * base, base the name computed in the output
    val: dict[str, tuple[str, float]] = {}
    acc_scale: dict[tuple, float] = {}
    fixed: dict[tuple[str, float], str] = {}   # (base, factor) -> its materialised name
    const_ops: dict[tuple, Op] = {}
    out: list[Op] = []
    saved = added = 0

    def base(a: str) -> str:
        return val.get(a, (a, 1.0))[0]

    def sc(a: str) -> float:
        return val.get(a, (a, 1.0))[1]

    def apply(a: str, op: Op, keep: float = 1.0) -> str:
        """`a` with its pending factor applied but `keep` (one mul, shared by later uses)."""
        nonlocal added
        b, c = val.get(a, (a, 1.0))
        c /= keep
        if c == 1.0:
            return b
        if (b, c) not in fixed:
            t = op_types[a]
            key = (c, t)
            if key not in const_ops:
                const_ops[key] = Op(fresh_name(used, "scale"), "const", (), t, Const(c), op.span)
            r = fresh_name(used, f"{b}_s")
            out.append(Op(r, "mul", (b, const_ops[key].result), t, None, op.span))
            fixed[(b, c)] = r
            added += 1
        return fixed[(b, c)]

    op_types = {op.result: op.type for op in k.all_ops() if op.result}
    for op in k.pair:
        args = tuple(base(a) for a in op.args)
        t = op.type
        flt = t is not None and not t.is_vec and t.scalar in (Scalar.F32, Scalar.F64)
        oc = op.opcode
        new: float | None = None  # the result's pending factor when op is kept with unscaled args
        if oc == "rsqrt" and flt and sc(op.args[0]) == 1.0:
            out.append(replace(op, opcode="rsqrt2", args=args))
            val[op.result] = (op.result, 0.5)
            saved += 1
            continue
        if oc == "mul" and flt:
            a, b = op.args
            if b in consts and _pow2(float(consts[b])) and a not in consts:
                a, b = b, a
            if a in consts and _pow2(float(consts[a])) and op_types.get(b) == t:
                val[op.result] = (base(b), float(consts[a]) * sc(b))
                saved += 1
                continue
            new = sc(a) * sc(b)
        elif oc == "div" and flt:
            new = sc(op.args[0]) / sc(op.args[1])
        elif oc == "neg" and flt:
            new = sc(op.args[0])
        elif oc in ("add", "sub", "min", "max") and flt and sc(op.args[0]) == sc(op.args[1]):
            new = sc(op.args[0])
        elif oc == "select" and flt and sc(op.args[1]) == sc(op.args[2]):
            new = sc(op.args[1])
        elif oc == "accum" and isinstance(op.attr, Reduce) and op.attr.kind in ("add", "sub"):
            key = (op.attr.member, op.attr.component)
            c = acc_scale.setdefault(key, sc(op.args[0]))  # one factor per FORCE sum
            v = apply(op.args[0], op, keep=c)
            out.append(replace(op, args=(v,) + args[1:], attr=replace(op.attr, scale=op.attr.scale * c)))
            continue
        if new is not None:
            out.append(replace(op, args=args))
            val[op.result] = (op.result, new)
            continue
        out.append(replace(op, args=tuple(apply(a, op) for a in op.args)))
        if op.result:
            val[op.result] = (op.result, 1.0)
    if added >= saved:
        return k
    return k.with_blocks({Stage.PAIR: tuple(const_ops.values()) + tuple(out)})
