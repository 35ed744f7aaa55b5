"""The syntax tree of a .pik file, as the parser builds it (untyped, unresolved)."""
from __future__ import annotations

from dataclasses import dataclass

from pik_gen.diagnostics import Span


# ----- expressions -----
@dataclass(frozen=True)
class Number:
    text: str  # as written, e.g. "2.5e+4f"
    is_float: bool
    span: Span


@dataclass(frozen=True)
class Name:
    name: str
    span: Span


@dataclass(frozen=True)
class RoleMember:
    """`EPI.pos`: a member of the i-particle, j-particle or force struct."""

    role: str  # "EPI" | "EPJ" | "FORCE"
    member: str
    span: Span


@dataclass(frozen=True)
class Component:
    """`e.x`: component access on any vector expression."""

    base: "Expr"
    comp: str
    span: Span


@dataclass(frozen=True)
class Unary:
    op: str  # "-" | "!" | "+"
    operand: "Expr"
    span: Span


@dataclass(frozen=True)
class Binary:
    op: str
    left: "Expr"
    right: "Expr"
    span: Span


@dataclass(frozen=True)
class Call:
    func: str
    args: tuple["Expr", ...]
    span: Span


Expr = Number | Name | RoleMember | Component | Unary | Binary | Call


# ----- top-level items and statements -----
@dataclass(frozen=True)
class MemberDecl:
    """`EPI F64vec xi:pos` (binding) or `EPI local F32 h` (per-particle local)."""

    role: str
    local: bool
    type_name: str
    name: str
    member: str
    span: Span
    type_span: Span


@dataclass(frozen=True)
class ParamDecl:
    """`F64 eps2`: a kernel parameter (a constructor argument of the generated class)."""

    type_name: str
    name: str
    span: Span
    type_span: Span


@dataclass(frozen=True)
class TableDecl:
    """`tab0 = { 1.0f, 2.0f }`: coefficients for `table(tab0, index)`."""

    name: str
    values: tuple[Number, ...]
    span: Span


@dataclass(frozen=True)
class Assign:
    """`target op value`; op is one of `= += -= *= /=`."""

    target: Expr  # Name, RoleMember or Component of those
    op: str
    value: Expr
    span: Span


@dataclass(frozen=True)
class If:
    """`if c ... elsif c2 ... else ... endif`; elsif chains are nested Ifs in `orelse`."""

    cond: Expr
    body: tuple["Stmt", ...]
    orelse: tuple["Stmt", ...]
    span: Span


@dataclass(frozen=True)
class Pragma:
    text: str
    span: Span


Stmt = Assign | If | Pragma


@dataclass(frozen=True)
class Function:
    name: str
    params: tuple[str, ...]
    body: tuple[Stmt, ...]
    result: Expr
    span: Span


@dataclass(frozen=True)
class Module:
    file: str
    decls: tuple[MemberDecl | ParamDecl | TableDecl, ...]
    functions: tuple[Function, ...]
    body: tuple[Stmt, ...]
