"""User functions, inlined at the call: the function's variables become kernel
variables with unique names (`<function>_<name>`), assigned before the statement
that calls it; the call's value is the function's result expression."""
from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

from pik_gen.diagnostics import error
from pik_gen.frontend import ast
from pik_gen.sema.builtins import BINARY
from pik_gen.sema.rules import binary, coerce, settle
from pik_gen.sema.scopes import FuncScope, check_not_hidden
from pik_gen.typed import TAssign, TExpr, TVar

if TYPE_CHECKING:
    from pik_gen.sema.checker import Checker


def inline(chk: Checker, fn: ast.Function, call: ast.Call) -> TExpr:
    if any(s.name == fn.name for s in chk.func_stack):
        raise error(call.span, f"function '{fn.name}' calls itself; recursion is not supported")
    if len(call.args) != len(fn.params):
        raise error(call.span, f"function '{fn.name}' takes {len(fn.params)} argument{'s' if len(fn.params) != 1 else ''}, not {len(call.args)}")
    args = [chk.expr(a) for a in call.args]
    scope = FuncScope(fn.name, dict(zip(fn.params, args)))
    chk.func_stack.append(scope)
    try:
        for s in fn.body:
            statement(chk, fn, s, scope)
        result = chk.expr(fn.result)
    finally:
        chk.func_stack.pop()
    if isinstance(result, TVar) and result.name in scope.renames.values():
        result = replace(result, returned=True)
    return result


def statement(chk: Checker, fn: ast.Function, s: ast.Stmt, scope: FuncScope) -> None:
    """One statement of a function body (pragmas there are ignored)."""
    match s:
        case ast.If():
            chk.if_statement(s, scope.branches, set(scope.renames), lambda b: statement(chk, fn, b, scope))
        case ast.Assign():
            assign(chk, fn, s, scope)


def assign(chk: Checker, fn: ast.Function, s: ast.Assign, scope: FuncScope) -> None:
    if not isinstance(s.target, ast.Name):
        raise error(s.target.span, f"inside function '{fn.name}' only local variables can be assigned")
    n = s.target.name
    value = chk.expr(s.value)
    if s.op != "=":
        check_not_hidden(n, scope.branches, s.target.span)
    if scope.branches:
        scope.branches[-1][1].add(n)
    if s.op != "=":
        if n not in scope.renames and n not in scope.bindings:
            raise error(s.target.span, f"'{n}' is not defined before '{s.op}'")
        value = binary(BINARY[s.op[0]], chk.name(s.target), value, s.span)
    if n in scope.renames:
        real = scope.renames[n]
        value = coerce(value, chk.vars[real], s.value)
    else:
        value = settle(value)
        real = chk.fresh(f"{fn.name}_{n}")
        scope.renames[n] = real
        scope.bindings.pop(n, None)
    chk.vars[real] = value.type
    chk.deps[real] = chk.expr_deps(value)
    chk.out.append(TAssign(real, value, None, s.span))
