"""The typed tree: what semantic analysis (sema/) hands to the IR builder (ir/build.py).

Statements are `T*` nodes with every name resolved and every expression typed;
`CheckedKernel` is a whole kernel with its declarations.
"""
from __future__ import annotations

from dataclasses import dataclass

from pik_gen.diagnostics import Span
from pik_gen.types import Type

@dataclass(frozen=True)
class TConst:
    value: float | int
    type: Type
    span: Span
    flex: bool = True  # a literal: may still take its type from context


@dataclass(frozen=True)
class TParam:
    name: str
    type: Type
    span: Span
    flex: bool = False


@dataclass(frozen=True)
class TLoad:
    """Read of a member of EPI / EPJ / FORCE (FORCE: its value on entry)."""

    role: str
    member: str
    component: int | None
    type: Type
    span: Span
    flex: bool = False
    name_hint: str = ""


@dataclass(frozen=True)
class TVar:
    name: str
    type: Type
    span: Span
    flex: bool = False
    returned: bool = False  # a function's own variable returned by an inlined call: renamed after its caller's


@dataclass(frozen=True)
class TOp:
    """An operation; opcode names are the IR's (see ir/ops.py). attr: component
    index for `comp`, table name for `table`, else None."""

    opcode: str
    args: tuple["TExpr", ...]
    type: Type
    span: Span
    flex: bool = False
    attr: int | str | None = None


TExpr = TConst | TParam | TLoad | TVar | TOp


@dataclass(frozen=True)
class TAssign:
    """`name = value` or, with component, `name.x = value`."""

    name: str
    value: TExpr
    component: int | None
    span: Span


@dataclass(frozen=True)
class TAccum:
    """Accumulation into FORCE: kind is add, sub, mul, div, max or min."""

    member: str
    component: int | None
    kind: str
    value: TExpr
    span: Span


@dataclass(frozen=True)
class TIf:
    cond: TExpr
    body: tuple["TStmt", ...]
    orelse: tuple["TStmt", ...]
    span: Span


TStmt = TAssign | TAccum | TIf


@dataclass(frozen=True)
class Member:
    role: str
    name: str  # the C++ member name
    type: Type
    indexed: bool = False  # components read as [0] [1] [2] (an array-like member per pikg-reflect), not .x .y .z


@dataclass(frozen=True)
class Table:
    name: str
    type: Type
    values: tuple[float | int, ...]


@dataclass(frozen=True)
class CheckedKernel:
    file: str
    params: tuple[tuple[str, Type], ...]
    members: tuple[Member, ...]
    locals: tuple[tuple[str, str, Type], ...]  # (name, role, type)
    tables: tuple[Table, ...]
    body: tuple[TStmt, ...]
    pragmas: tuple[str, ...]
