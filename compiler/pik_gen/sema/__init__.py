"""Semantic analysis: names, types and the checks that need them.

Input: the parser's `ast.Module`. Output: a `CheckedKernel` whose statements are
typed trees (`T*` nodes) with every name resolved:

* an unprefixed name on the left of an accumulation means a FORCE member; on the
  right it is a variable, a parameter, a table, or a member binding looked up in
  EPI, then EPJ, then FORCE;
* literals take their type from context (`F32 * 2.0` is F32); alone they take the
  type of their suffix (`2.0` F64, `2.0f` F32, `2.0h` F16, `2` S32, `2l` S64,
  `2u` U32, `2ul` U64);
* mixing two different non-literal types is an error that names the cast to use;
* user functions are inlined here: their local variables become kernel
  variables with unique names, emitted before the statement that calls them.

The parts: scopes.py (declarations, branch frames), rules.py (type rules),
builtins.py (built-in functions), inline.py (user functions), checker.py
(statements, expressions and names). The typed tree is pik_gen/typed.py.

Every mistake is reported as a located Diagnostic with a suggestion where one
is obvious; checking continues with the next statement so that several
independent errors are reported at once.
"""
from __future__ import annotations

from pik_gen.frontend import ast
from pik_gen.reflect import Reflection
from pik_gen.sema.builtins import literal_value
from pik_gen.sema.checker import Checker
from pik_gen.typed import CheckedKernel


def check(module: ast.Module, reflection: Reflection | None = None) -> CheckedKernel:
    """Resolve names and types of a parsed module; raises CompileError on mistakes.
    With `reflection`, members not declared in the file take their types from the
    user's C++ struct and declarations are checked against it."""
    return Checker(module, reflection).run()


__all__ = ["CheckedKernel", "check", "literal_value"]
