"""IR verifier: the invariants every pass must keep.

* every value is defined once and used only after its definition, in a stage
  that can see it (see nodes.VISIBLE);
* opcodes are known, arities and attribute kinds match;
* types are consistent (see ops.py for the rules);
* loads respect stages: EPI is not read in `j`, EPJ not in `setup`/`i`, FORCE
  (value on entry) not in `setup`/`j`; `accum` only in `pair`;
* with `expanded=True` (after expand_vectors) no vector type remains.
"""
from __future__ import annotations

import math

from pik_gen.ir import ops as O
from pik_gen.ir.nodes import VISIBLE, Comp, Const, Kernel, MemberRef, Op, ParamRef, Reduce, Stage, TableRef
from pik_gen.types import BOOL, Scalar


class VerifyError(Exception):
    """An IR invariant is broken: a compiler bug, never a user error."""


def verify(k: Kernel, expanded: bool = False) -> None:
    problems = check(k, expanded)
    if problems:
        raise VerifyError(f"IR of kernel {k.name} is invalid:\n  " + "\n  ".join(problems))


def check(k: Kernel, expanded: bool = False) -> list[str]:
    out: list[str] = []
    where: dict[str, Stage] = {}
    types = {}
    params = {p.name for p in k.params}
    tables = {t.name for t in k.tables}
    for stage, ops in k.blocks():
        for op in ops:
            out += [f"{stage.value}: {op.result or op.opcode}: {m}" for m in _check_op(op, stage, where, types, params, tables, expanded)]
            if op.result:
                if op.result in where:
                    out.append(f"{stage.value}: '{op.result}' defined twice")
                where[op.result] = stage
                types[op.result] = op.type
    for lv in k.locals:
        for v in lv.values:
            if v not in where:
                out.append(f"local {lv.name}: value '{v}' is not defined")
    return out


def _check_op(op: Op, stage: Stage, where, types, params, tables, expanded: bool) -> list[str]:
    p: list[str] = []
    ar = O.ARITY.get(op.opcode)
    if ar is None:
        return [f"unknown opcode '{op.opcode}'"]
    lo, hi = (ar, ar) if isinstance(ar, int) else ar
    if not lo <= len(op.args) <= hi:
        p.append(f"{op.opcode} takes {ar} arguments, has {len(op.args)}")
    for a in op.args:
        if a not in where:
            p.append(f"uses '{a}' before its definition")
        elif where[a] not in VISIBLE[stage]:
            p.append(f"uses '{a}' of stage {where[a].value}, invisible in {stage.value}")
    if p:
        return p
    if (op.opcode == "accum") != (op.result == ""):
        p.append("only accum has no result")
    if op.opcode != "accum" and op.type is None:
        p.append("no type")
    if expanded and op.type is not None and op.type.is_vec:
        p.append(f"vector type {op.type} after expansion")
    if expanded and op.opcode in O.VECTOR_ONLY:
        p.append(f"vector op '{op.opcode}' after expansion")
    at = [types[a] for a in op.args]
    t = op.type
    attr_kind = {"const": Const, "param": ParamRef, "load": MemberRef, "table": TableRef, "comp": Comp,
                 "insert": Comp, "accum": Reduce}.get(op.opcode, type(None))
    if not isinstance(op.attr, attr_kind):
        p.append(f"attribute {op.attr!r} is not a {attr_kind.__name__}")
        return p
    match op.opcode:
        case "param":
            if op.attr.name not in params:  # type: ignore[union-attr]
                p.append(f"unknown parameter {op.attr.name}")  # type: ignore[union-attr]
        case "table":
            if op.attr.name not in tables or at[0].is_vec or not at[0].scalar.is_int:  # type: ignore[union-attr]
                p.append("bad table reference or index")
        case "load":
            role = op.attr.role  # type: ignore[union-attr]
            bad = {"EPI": (Stage.J, Stage.SETUP), "EPJ": (Stage.SETUP, Stage.I), "FORCE": (Stage.SETUP, Stage.J)}[role]
            if stage in bad:
                p.append(f"{role} load in stage {stage.value}")
        case "accum":
            if stage != Stage.PAIR:
                p.append("accum outside the pair stage")
            if len(at) > 1 and at[1] != BOOL:
                p.append("accum mask is not BOOL")
            if op.attr.kind not in O.REDUCE_KINDS:  # type: ignore[union-attr]
                p.append(f"unknown reduction {op.attr.kind}")  # type: ignore[union-attr]
            sc = op.attr.scale  # type: ignore[union-attr]
            if sc != 1.0 and (op.attr.kind not in ("add", "sub") or not (sc > 0 and math.frexp(sc)[0] == 0.5)):  # type: ignore[union-attr]
                p.append(f"accum scale {sc} is not a power of two on a sum")
        case "select":
            if at[0] != BOOL or at[1] != at[2] or t != at[1]:
                p.append(f"select types {at[0]}, {at[1]}, {at[2]} -> {t}")
        case "and" | "or" | "not":
            if any(x != BOOL for x in at) or t != BOOL:
                p.append("logical op on non-BOOL")
        case "eq" | "ne" | "lt" | "gt" | "le" | "ge":
            if at[0] != at[1] or t != BOOL or at[0].is_vec:
                p.append(f"comparison of {at[0]} and {at[1]}")
        case "mul" | "div":
            a, b = at
            if a.scalar != b.scalar or t is None or t.scalar != a.scalar:
                p.append(f"{op.opcode} of {a} and {b} -> {t}")
            elif (a.is_vec and b.is_vec) or (op.opcode == "div" and b.is_vec) or t.lanes != max(a.lanes, b.lanes):
                p.append(f"{op.opcode} of {a} and {b} -> {t}")
        case "dot":
            if at[0] != at[1] or not at[0].is_vec or t != at[0].element:
                p.append(f"dot of {at[0]} and {at[1]} -> {t}")
        case "cross":
            if at[0] != at[1] or at[0].lanes != 3 or t != at[0]:
                p.append(f"cross of {at[0]} and {at[1]} -> {t}")
        case "comp":
            if not at[0].is_vec or op.attr.index >= at[0].lanes or t != at[0].element:  # type: ignore[union-attr]
                p.append(f"component of {at[0]}")
        case "insert":
            if not at[0].is_vec or at[1] != at[0].element or t != at[0]:
                p.append(f"insert of {at[1]} into {at[0]}")
        case "cast":
            if at[0].lanes != t.lanes:  # type: ignore[union-attr]
                p.append("cast changes the length")
        case "const" | "load":
            pass
        case _:
            if any(x != t for x in at):
                p.append(f"{op.opcode} of {', '.join(map(str, at))} -> {t}")
            if t is not None and t.scalar == Scalar.BOOL:
                p.append(f"{op.opcode} on BOOL")
    return p
