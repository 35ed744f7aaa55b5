"""The built-in functions (math, casts, `table`), the operator spellings and literals."""
from __future__ import annotations

from dataclasses import replace
from typing import Callable

from pik_gen.diagnostics import error, suggest
from pik_gen.frontend import ast
from pik_gen.sema.rules import retype, settle, span_of, unflex, unify
from pik_gen.typed import Table, TConst, TExpr, TOp
from pik_gen.types import Scalar, Type

CASTS: dict[str, Scalar] = {
    "to_f64": Scalar.F64, "to_f32": Scalar.F32, "to_f16": Scalar.F16,
    "to_s64": Scalar.S64, "to_s32": Scalar.S32, "to_u64": Scalar.U64, "to_u32": Scalar.U32,
    # PIKG's C-like spellings
    "to_double": Scalar.F64, "to_float": Scalar.F32, "to_int": Scalar.S32, "to_uint": Scalar.U32,
    "to_long": Scalar.S64, "to_ulong": Scalar.U64,
}
VEC_CASTS: dict[str, tuple[Scalar, int | None]] = {
    f"to_{s.lower()}vec{n}": (Scalar(s), int(n) if n else None)
    for s in ("F64", "F32", "F16") for n in ("", "2", "3", "4")
}
# name -> (number of arguments, float only?)
MATH = {
    "sqrt": (1, True), "rsqrt": (1, True), "inv": (1, True), "exp": (1, True), "erfc": (1, True), "log": (1, True),
    "floor": (1, True), "abs": (1, False), "min": (2, False), "max": (2, False), "pow": (2, True),
    "madd": (3, True), "msub": (3, True), "nmadd": (3, True), "nmsub": (3, True),
}
BUILTIN_NAMES = tuple(MATH) + tuple(CASTS) + tuple(VEC_CASTS) + ("table",)

BINARY = {"+": "add", "-": "sub", "*": "mul", "/": "div"}
COMPARE = {"==": "eq", "!=": "ne", "<": "lt", ">": "gt", "<=": "le", ">=": "ge"}
ACCUM = {"+=": "add", "-=": "sub", "*=": "mul", "/=": "div"}


def literal_value(num: ast.Number) -> tuple[float | int, Type]:
    """Value and suffix-given type of a numeric literal."""
    text = num.text.lower()
    stripped = text.rstrip("fhdlu")
    suffix = text[len(stripped):]
    if num.is_float:
        value: float | int = float(stripped)
        scalar = {"f": Scalar.F32, "h": Scalar.F16}.get(suffix, Scalar.F64)
    else:
        value = int(stripped, 10)
        scalar = Scalar.S32
        if "u" in suffix and "l" in suffix:
            scalar = Scalar.U64
        elif "u" in suffix:
            scalar = Scalar.U32
        elif "l" in suffix:
            scalar = Scalar.S64
    return value, Type(scalar)


def call(e: ast.Call, expr: Callable[[ast.Expr], TExpr], tables: dict[str, Table], functions) -> TExpr:
    """A call of a built-in function (`expr` checks an argument)."""
    f = e.func
    if f == "table":
        if len(e.args) != 2 or not isinstance(e.args[0], ast.Name):
            raise error(e.span, "table needs two arguments: table(TABLE_NAME, index)")
        tname = e.args[0].name
        if tname not in tables:
            raise error(e.args[0].span, f"unknown table '{tname}'" + suggest(tname, tables))
        idx = settle(expr(e.args[1]))
        if idx.type.is_vec or not idx.type.scalar.is_int:
            raise error(span_of(e.args[1]), f"a table index must be an integer (convert with to_s32(...)), not {idx.type}")
        return TOp("table", (idx,), tables[tname].type, e.span, attr=tname)
    args = [expr(a) for a in e.args]
    if f in CASTS or f in VEC_CASTS:
        return cast(f, args, e)
    if f not in MATH:
        raise error(e.span, f"unknown function '{f}'" + suggest(f, list(functions) + list(BUILTIN_NAMES)))
    nargs, float_only = MATH[f]
    if len(args) != nargs:
        raise error(e.span, f"{f} takes {nargs} argument{'s' if nargs > 1 else ''}, not {len(args)}")
    # Unify all arguments pairwise so literals take the others' type; twice, so that a
    # type found at the last argument reaches the literals before it.
    for _ in range(2):
        for k in range(1, nargs):
            args[0], args[k] = unify(args[0], args[k], e.span, f)
    lanes = {a.type.lanes for a in args}
    if len(lanes) > 1:
        raise error(e.span, f"{f}: arguments of different lengths ({', '.join(str(a.type) for a in args)})")
    t = args[0].type
    if t.scalar == Scalar.BOOL:
        raise error(e.span, f"{f} needs numbers, not logical values")
    flex = all(a.flex for a in args)
    if float_only and not t.scalar.is_float:
        if not flex:
            raise error(e.span, f"{f} needs floating-point arguments, not {t} (convert with to_f64(...) or to_f32(...))")
        args = [retype(a, Scalar.F64) for a in args]
        t = args[0].type
    return TOp(f, tuple(args), t, e.span, flex)


def cast(f: str, args: list[TExpr], e: ast.Call) -> TExpr:
    """to_f64(x), to_f32vec(v), ...: a conversion (none when x already has the type)."""
    if len(args) != 1:
        raise error(e.span, f"{f} takes one argument, not {len(args)}")
    x = args[0]
    if f in CASTS:
        target = Type(CASTS[f], x.type.lanes)
        if x.type.is_vec and not target.scalar.is_float:
            raise error(e.span, f"{f} of a vector; vectors convert to floating-point vectors only")
    else:
        s, lanes = VEC_CASTS[f]
        if not x.type.is_vec:
            raise error(e.span, f"{f} needs a vector argument, not {x.type} (use to_{s.value.lower()} for scalars)")
        if lanes is not None and lanes != x.type.lanes:
            raise error(e.span, f"{f} needs a {lanes}-component vector, not {x.type}")
        target = Type(s, x.type.lanes)
    if x.type.scalar == Scalar.BOOL:
        raise error(e.span, f"{f} of a logical value")
    if isinstance(x, TConst):
        return unflex(retype(replace(x, flex=True), target.scalar))
    x = settle(x)
    return x if x.type == target else TOp("cast", (x,), target, e.span)
