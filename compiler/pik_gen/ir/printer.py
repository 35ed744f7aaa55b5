"""Text form of the IR (what `--dump-ir-after=PASS` prints)."""
from __future__ import annotations

from pik_gen.ir.nodes import Comp, Const, Kernel, MemberRef, Op, ParamRef, Reduce, TableRef
from pik_gen.types import COMPONENTS


def format_attr(op: Op) -> str:
    a = op.attr
    match a:
        case Const():
            return repr(a.value)
        case ParamRef():
            return a.name
        case MemberRef():
            return f"{a.role}.{a.member}" + ("" if a.component is None else f".{COMPONENTS[a.component]}")
        case Comp():
            return f".{COMPONENTS[a.index]}"
        case TableRef():
            return a.name
        case Reduce():
            return f"FORCE.{a.member}" + ("" if a.component is None else f".{COMPONENTS[a.component]}")
    return ""


def format_op(op: Op) -> str:
    attr = format_attr(op)
    if op.opcode == "accum":
        assert isinstance(op.attr, Reduce)
        mask = f" if {op.args[1]}" if len(op.args) > 1 else ""
        scale = "" if op.attr.scale == 1.0 else f" * {op.attr.scale!r}"
        return f"accum.{op.attr.kind} {attr}, {op.args[0]}{scale}{mask}"
    parts = [p for p in (attr, ", ".join(op.args)) if p]
    return f"{op.result}: {op.type} = {op.opcode} {' '.join(parts)}".rstrip()


def format_kernel(k: Kernel) -> str:
    lines = [f"kernel {k.name}  ; {k.source}"]
    lines += [f"param {p.name}: {p.type}" for p in k.params]
    lines += [f"member {m.role}.{m.name}: {m.type}" for m in k.members]
    lines += [f"table {t.name}: {t.type}[{len(t.values)}]" for t in k.tables]
    lines += [f"local {lv.role} {lv.name} = {', '.join(lv.values)}" for lv in k.locals]
    for stage, ops in k.blocks():
        lines.append(f"{stage.value}:")
        lines += [f"  {format_op(op)}" for op in ops]
    return "\n".join(lines) + "\n"
