"""Lower a checked kernel (typed statements) to SSA IR.

Everything lands in the `pair` stage; the passes move ops to the stages where
they belong. `if/elsif/else` becomes straight-line code: both branches are
computed, each variable assigned differently in the two branches is merged
with a `select` named after it, and accumulations carry the branch mask as
their second argument. A variable assigned in only one branch, and never
before, keeps that branch's value after the `if` (it is computed anyway).

SSA names follow the .pik variables (`r2`, a second assignment `r2_2`),
intermediates are numbered after the statement's variable (`r2_1`), loads are
named after their binding (`xi`, `mj`) and constants `c`, `c_2`, ...
"""
from __future__ import annotations

import re
from dataclasses import replace

from pik_gen.ir.nodes import (
    Comp, Const, Kernel, LocalValue, MemberRef, Op, Param, ParamRef, Reduce, Stage, TableRef,
    fresh_name,
)
from pik_gen.typed import (
    CheckedKernel, TAccum, TAssign, TConst, TExpr, TIf, TLoad, TOp, TParam, TStmt, TVar,
)
from pik_gen.types import BOOL, Type


def _clean(name: str) -> str:
    name = re.sub(r"_+", "_", name).strip("_")
    return name or "v"


class Builder:
    def __init__(self, ck: CheckedKernel) -> None:
        self.ck = ck
        self.ops: list[Op] = []
        self.used: set[str] = set()
        self.env: dict[str, str] = {}
        self.locals: list[LocalValue] = []
        self.local_roles = {n: r for n, r, _t in ck.locals}
        self.counters: dict[str, int] = {}

    def emit(self, base: str, opcode: str, args: tuple[str, ...], type_: Type | None, attr=None, span=None) -> str:
        name = fresh_name(self.used, _clean(base)) if type_ is not None else ""
        self.ops.append(Op(name, opcode, args, type_, attr, span) if span else Op(name, opcode, args, type_, attr))
        return name

    def rename(self, value: str, base: str) -> str:
        """Give the op defining `value` a name after `base` (uses, env and locals follow)."""
        if not any(op.result == value for op in self.ops):
            return value  # not defined here (e.g. a constant bound elsewhere): keep
        new = fresh_name(self.used, _clean(base))
        m = {value: new}
        self.ops = [replace(op, result=m.get(op.result, op.result), args=tuple(m.get(a, a) for a in op.args))
                    for op in self.ops]
        self.env = {k: m.get(v, v) for k, v in self.env.items()}
        self.locals = [replace(lv, values=tuple(m.get(v, v) for v in lv.values)) for lv in self.locals]
        return new

    def temp_base(self, hint: str) -> str:
        k = self.counters.get(hint, 0) + 1
        self.counters[hint] = k
        return f"{hint}_{k}"

    # --- expressions: `hint` names the result, None = an intermediate of `owner`
    def expr(self, e: TExpr, owner: str, hint: str | None = None) -> str:
        base = hint if hint is not None else None
        match e:
            case TVar():
                return self.env[e.name]
            case TConst():
                return self.emit(base or "c", "const", (), e.type, Const(e.value), e.span)
            case TParam():
                return self.emit(base or e.name, "param", (), e.type, ParamRef(e.name), e.span)
            case TLoad():
                nm = e.name_hint or f"{e.role.lower()}_{e.member}"
                if e.component is not None:
                    nm = f"{nm}_{'xyzw'[e.component]}"
                return self.emit(base or nm, "load", (), e.type, MemberRef(e.role, e.member, e.component), e.span)
            case TOp():
                args = tuple(self.expr(a, owner) for a in e.args)
                attr = None
                if e.opcode == "comp":
                    attr = Comp(int(e.attr))  # type: ignore[arg-type]
                elif e.opcode == "table":
                    attr = TableRef(str(e.attr))
                return self.emit(base or self.temp_base(owner), e.opcode, args, e.type, attr, e.span)
        raise AssertionError(f"unexpected typed node {e!r}")  # pragma: no cover

    # --- statements
    def stmts(self, stmts: tuple[TStmt, ...], mask: str | None) -> None:
        for s in stmts:
            self.stmt(s, mask)

    def stmt(self, s: TStmt, mask: str | None) -> None:
        match s:
            case TAssign(component=None):
                if (isinstance(s.value, TVar) and s.value.returned
                        and self.env[s.value.name].startswith(_clean(s.value.name))):
                    # `dx = wrap(...)`: the value gets the caller's name, not the function's (wrap_w)
                    self.env[s.name] = self.rename(self.env[s.value.name], s.name)
                elif isinstance(s.value, TVar):
                    self.env[s.name] = self.env[s.value.name]
                else:
                    self.env[s.name] = self.expr(s.value, s.name, s.name)
                self.note_local(s.name)
            case TAssign():
                value = self.expr(s.value, s.name)
                old = self.env.get(s.name)
                t = self.vec_type(s.name)
                if old is None:
                    old = self.emit(f"{s.name}_0", "const", (), t, Const(0), s.span)
                self.env[s.name] = self.emit(s.name, "insert", (old, value), t, Comp(s.component), s.span)  # type: ignore[arg-type]
                self.note_local(s.name)
            case TAccum():
                owner = f"{s.member}" if s.component is None else f"{s.member}_{'xyzw'[s.component]}"
                value = self.expr(s.value, f"d{owner}")
                args = (value,) if mask is None else (value, mask)
                self.emit("", "accum", args, None, Reduce(s.kind, s.member, s.component), s.span)
            case TIf():
                cond = self.expr(s.cond, "cond", self.temp_base("cond"))
                inner = cond if mask is None else self.emit(self.temp_base("mask"), "and", (mask, cond), BOOL, None, s.span)
                before = dict(self.env)
                self.stmts(s.body, inner)
                after_then = self.env
                self.env = dict(before)
                if s.orelse:
                    not_cond = self.emit(self.temp_base("not_cond"), "not", (cond,), BOOL, None, s.span)
                    inner_else = not_cond if mask is None else self.emit(self.temp_base("mask"), "and", (mask, not_cond), BOOL, None, s.span)
                    self.stmts(s.orelse, inner_else)
                after_else = self.env
                merged: dict[str, str] = {}
                for name in list(after_then) + [n for n in after_else if n not in after_then]:
                    a, b = after_then.get(name), after_else.get(name)
                    if a is None or b is None:
                        merged[name] = a or b  # type: ignore[assignment]
                    elif a == b:
                        merged[name] = a
                    else:
                        t = self.type_of(a)
                        merged[name] = self.emit(name, "select", (cond, a, b), t, None, s.span)
                        self.note_local(name, merged[name])
                self.env = merged

    def note_local(self, name: str, value: str | None = None) -> None:
        role = self.local_roles.get(name)
        if role is not None:
            self.locals.append(LocalValue(name, role, (value or self.env[name],)))

    def type_of(self, value: str) -> Type:
        for op in reversed(self.ops):
            if op.result == value:
                assert op.type is not None
                return op.type
        raise AssertionError(value)  # pragma: no cover

    def vec_type(self, name: str) -> Type:
        if name in self.env:
            return self.type_of(self.env[name])
        for n, _r, t in self.ck.locals:
            if n == name:
                return t
        raise AssertionError(name)  # pragma: no cover


def build(ck: CheckedKernel, name: str) -> Kernel:
    """SSA IR of a checked kernel, all ops in the pair stage."""
    b = Builder(ck)
    b.used |= {p for p, _t in ck.params}  # parameter names stay readable in C++
    b.used.clear()
    b.stmts(ck.body, None)
    return Kernel(
        name=name,
        source=ck.file,
        params=tuple(Param(n, t) for n, t in ck.params),
        members=ck.members,
        tables=ck.tables,
        locals=tuple(b.locals),
        pair=tuple(b.ops),
        pragmas=ck.pragmas,
    )


__all__ = ["build", "Stage"]
