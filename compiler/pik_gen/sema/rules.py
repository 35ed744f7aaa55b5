"""The type rules: how literals take their type from context, which types mix,
and the types of the arithmetic, vector and comparison operators. Pure
functions of typed expressions; mistakes raise located errors."""
from __future__ import annotations

from dataclasses import replace

from pik_gen.diagnostics import Span, error
from pik_gen.frontend import ast
from pik_gen.typed import TConst, TExpr, TOp
from pik_gen.types import Scalar, Type

SYMBOL = {"add": "+", "sub": "-", "mul": "*", "div": "/"}


def span_of(e: ast.Expr) -> Span:
    """Where an expression starts (its leftmost operand)."""
    if isinstance(e, ast.Binary):
        return span_of(e.left)
    if isinstance(e, ast.Component):
        return span_of(e.base)
    return e.span


def retype(e: TExpr, scalar: Scalar) -> TExpr:
    """Give a literal (sub)expression the scalar type its context asks for."""
    if not e.flex:
        return e
    if isinstance(e, TConst):
        if isinstance(e.value, float) and not scalar.is_float:
            if scalar == Scalar.BOOL:
                raise error(e.span, f"number {e.value} used as a logical value")
            if not float(e.value).is_integer():
                raise error(e.span, f"floating-point literal {e.value:g} used as {scalar.value}")
        if scalar == Scalar.BOOL:
            raise error(e.span, "number used as a logical value")
        v: float | int = float(e.value) if scalar.is_float else int(e.value)
        return TConst(v, Type(scalar), e.span, True)
    if isinstance(e, TOp):
        args = tuple(retype(a, scalar) for a in e.args)
        return TOp(e.opcode, args, e.type.with_scalar(scalar), e.span, True, e.attr)
    return e


def unflex(e: TExpr) -> TExpr:
    """The expression with its type fixed (no longer taken from context)."""
    if not e.flex:
        return e
    if isinstance(e, TOp):
        return TOp(e.opcode, tuple(unflex(a) for a in e.args), e.type, e.span, False, e.attr)
    return replace(e, flex=False)


def settle(e: TExpr) -> TExpr:
    """Fix a literal expression to its own (suffix) type: it has no context."""
    return unflex(retype(e, e.type.scalar)) if e.flex else e


def cast_hint(want: Type) -> str:
    if want.is_vec:
        return f" (convert with to_{want.scalar.value.lower()}vec(...))" if want.scalar.is_float else ""
    return f" (convert with to_{want.scalar.value.lower()}(...))"


def coerce(e: TExpr, want: Type, where: ast.Expr) -> TExpr:
    """e as a value of type want (a literal takes it), else a located mismatch."""
    if e.flex and e.type.lanes == want.lanes:
        e = unflex(retype(e, want.scalar))
    if e.type != want:
        raise error(span_of(where), f"type mismatch: expected {want}, found {e.type}" + cast_hint(want))
    return e


def unify(a: TExpr, b: TExpr, span: Span, op: str) -> tuple[TExpr, TExpr]:
    """The two operands of op with one scalar kind (literals follow the other side)."""
    if a.flex and not b.flex:
        a = retype(a, b.type.scalar)
    elif b.flex and not a.flex:
        b = retype(b, a.type.scalar)
    elif a.flex and b.flex:
        sa, sb = a.type.scalar, b.type.scalar
        if sa.is_float != sb.is_float:
            s = sa if sa.is_float else sb
        else:
            s = sa if sa.bits >= sb.bits else sb
        a, b = retype(a, s), retype(b, s)
    if a.type.scalar != b.type.scalar:
        wider = a.type.scalar if a.type.scalar.bits >= b.type.scalar.bits else b.type.scalar
        raise error(span, f"type mismatch in '{op}': {a.type} and {b.type}" + cast_hint(Type(wider)))
    return a, b


def binary(opcode: str, a: TExpr, b: TExpr, span: Span) -> TExpr:
    """a + b, a - b, a * b (vector * vector: the dot product), a / b."""
    sym = SYMBOL[opcode]
    for side in (a, b):
        if side.type.scalar == Scalar.BOOL:
            raise error(span, f"'{sym}' needs numbers, not logical values")
    a, b = unify(a, b, span, sym)
    flex = a.flex and b.flex
    ta, tb = a.type, b.type
    if opcode == "mul" and ta.is_vec and tb.is_vec:
        if ta.lanes != tb.lanes:
            raise error(span, f"dot product of {ta} and {tb}: lengths differ")
        return TOp("dot", (a, b), ta.element, span, flex)
    if ta.is_vec and tb.is_vec and ta.lanes != tb.lanes:
        raise error(span, f"'{sym}' of {ta} and {tb}: lengths differ")
    if opcode in ("add", "sub") and ta.is_vec != tb.is_vec:
        raise error(span, f"'{sym}' of a vector and a scalar ({ta} {sym} {tb}); did you mean a component, e.g. v.x?")
    if opcode == "div" and tb.is_vec:
        raise error(span, f"division by a vector ({tb})")
    t = ta if ta.is_vec else tb
    return TOp(opcode, (a, b), t, span, flex)


def cross(a: TExpr, b: TExpr, span: Span) -> TExpr:
    """a ^ b: the cross product of two float 3-vectors."""
    a, b = unify(a, b, span, "^")
    if not (a.type.is_vec and b.type.is_vec and a.type.lanes == b.type.lanes == 3):
        raise error(span, f"'^' is the cross product of two 3-vectors, not {a.type} ^ {b.type}")
    if not a.type.scalar.is_float:
        raise error(span, "'^' needs floating-point vectors")
    return TOp("cross", (a, b), a.type, span, a.flex and b.flex)
