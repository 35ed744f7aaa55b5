"""fold_constants: evaluate operations whose arguments are all constants.

Rewrites: an op with constant arguments into a `const` holding its value,
rounded to the op's type (F32 and F16 values are rounded as the hardware would);
`select` with a constant mask into its chosen argument; `x * 1`, `x / 1` and
`-(-x)` into `x`. Keeps: ops whose evaluation would fail or overflow (left for run
time, where IEEE rules apply), integer division by zero, and order.
"""
from __future__ import annotations

import math
import struct
from dataclasses import replace

from pik_gen.ir.nodes import Const, Kernel, Op, rename_args
from pik_gen.types import Type, round_to


def _cdiv(a: int, b: int) -> int:
    q = abs(a) // abs(b)
    return q if (a >= 0) == (b >= 0) else -q


def _eval(opcode: str, args: list, t: Type):
    f = t.scalar.is_float
    match opcode:
        case "neg": return -args[0]
        case "not": return not args[0]
        case "add": return args[0] + args[1]
        case "sub": return args[0] - args[1]
        case "mul": return args[0] * args[1]
        case "div": return args[0] / args[1] if f else _cdiv(args[0], args[1])
        case "eq": return args[0] == args[1]
        case "ne": return args[0] != args[1]
        case "lt": return args[0] < args[1]
        case "gt": return args[0] > args[1]
        case "le": return args[0] <= args[1]
        case "ge": return args[0] >= args[1]
        case "and": return bool(args[0]) and bool(args[1])
        case "or": return bool(args[0]) or bool(args[1])
        case "sqrt": return math.sqrt(args[0])
        case "rsqrt": return 1.0 / math.sqrt(args[0])
        case "rsqrt2": return 2.0 / math.sqrt(args[0])
        case "inv": return 1.0 / args[0]
        case "exp": return math.exp(args[0])
        case "erfc": return math.erfc(args[0])
        case "log": return math.log(args[0])
        case "floor": return float(math.floor(args[0]))
        case "abs": return abs(args[0])
        case "min": return min(args[0], args[1])
        case "max": return max(args[0], args[1])
        case "pow": return math.pow(args[0], args[1])
        case "madd": return args[0] * args[1] + args[2]
        case "msub": return args[0] * args[1] - args[2]
        case "nmadd": return -(args[0] * args[1]) + args[2]
        case "nmsub": return -(args[0] * args[1]) - args[2]
        case "cast": return float(args[0]) if f else int(args[0])
    raise ValueError(opcode)


def fold_constants(k: Kernel) -> Kernel:
    consts: dict[str, float | int | bool] = {}
    defs: dict[str, Op] = {}
    alias: dict[str, str] = {}
    blocks = {}
    for stage, ops in k.blocks():
        out: list[Op] = []
        for op in ops:
            op = replace(op, args=tuple(alias.get(a, a) for a in op.args))
            if op.opcode == "const" and op.type is not None and not op.type.is_vec:
                consts[op.result] = op.attr.value  # type: ignore[union-attr]
            elif op.opcode == "select" and op.args[0] in consts:
                alias[op.result] = op.args[1] if consts[op.args[0]] else op.args[2]
                continue
            elif op.opcode in ("mul", "div") and op.args[1] in consts and consts[op.args[1]] == 1 \
                    and op.type == _type(defs, op.args[0]):
                alias[op.result] = op.args[0]
                continue
            elif op.opcode == "neg" and op.args[0] in defs and defs[op.args[0]].opcode == "neg":
                alias[op.result] = defs[op.args[0]].args[0]
                continue
            elif op.result and op.args and op.type is not None and not op.type.is_vec \
                    and all(a in consts for a in op.args) and op.opcode not in ("table", "accum"):
                try:
                    value = round_to(_eval(op.opcode, [consts[a] for a in op.args], op.type), op.type)
                    if isinstance(value, float) and not math.isfinite(value):
                        raise OverflowError
                except (ArithmeticError, ValueError, OverflowError, struct.error):
                    pass
                else:
                    op = Op(op.result, "const", (), op.type, Const(value), op.span)
                    consts[op.result] = value
            if op.result:
                defs[op.result] = op
            out.append(op)
        blocks[stage] = out
    return rename_args(k.with_blocks(blocks), alias)


def _type(defs: dict[str, Op], name: str) -> Type | None:
    op = defs.get(name)
    return op.type if op else None
