"""What names mean: the kernel's declarations (parameters, members and their
bindings, locals, tables, functions), the scope of an inlined function, and the
branch frames of `if` statements (a name first assigned in one branch is not
defined in the other)."""
from __future__ import annotations

from dataclasses import dataclass, field

from pik_gen.diagnostics import CompileError, Diagnostic, Span, error
from pik_gen.frontend import ast
from pik_gen.reflect import Reflection
from pik_gen.sema.builtins import BUILTIN_NAMES, literal_value
from pik_gen.typed import Table, TExpr
from pik_gen.types import Scalar, Type, parse_type_name

ROLES = ("EPI", "EPJ", "FORCE")

# One frame per enclosing if-branch being checked: (names hidden in it, names
# assigned in it). A name first assigned in the 'then' branch is hidden in the
# 'else' branch until assigned there; after the if, both branches' names are defined.
Frames = list[tuple[set[str], set[str]]]


def check_not_hidden(n: str, frames: Frames, span: Span) -> None:
    """A name first assigned in the other branch of an enclosing if is not defined here."""
    assigned: set[str] = set()
    for hidden, a in reversed(frames):
        assigned |= a
        if n in hidden and n not in assigned:
            raise error(span, f"'{n}' is assigned only in another branch of an 'if', not before it")


@dataclass
class FuncScope:
    """An inlined call: the function's arguments and its variables' kernel names."""

    name: str
    bindings: dict[str, TExpr]
    renames: dict[str, str] = field(default_factory=dict)
    branches: Frames = field(default_factory=list)


@dataclass
class Declarations:
    """The declarations of a kernel file, checked (mistakes go to `diags`)."""

    params: dict[str, Type] = field(default_factory=dict)  # in declaration order
    bindings: dict[str, dict[str, tuple[str, Type]]] = field(default_factory=lambda: {r: {} for r in ROLES})
    members: dict[str, dict[str, Type]] = field(default_factory=lambda: {r: {} for r in ROLES})
    locals: dict[str, tuple[str, Type]] = field(default_factory=dict)  # name -> (role, type)
    tables: dict[str, Table] = field(default_factory=dict)
    functions: dict[str, ast.Function] = field(default_factory=dict)

    def names(self) -> set[str]:
        """Every name the declarations take."""
        out = set(self.params) | set(self.locals) | set(self.tables)
        for r in ROLES:
            out |= set(self.bindings[r])
        return out


def declare(m: ast.Module, reflection: Reflection | None, diags: list[Diagnostic]) -> Declarations:
    d = Declarations()
    seen: dict[str, Span] = {}

    def claim(name: str, span: Span, what: str) -> bool:
        if name in seen:
            prev = seen[name]
            diags.append(Diagnostic(span, f"'{name}' is already declared", notes=(f"previous declaration at {prev}",)))
            return False
        if name in BUILTIN_NAMES:
            diags.append(Diagnostic(span, f"{what} '{name}' has the name of a built-in function"))
            return False
        seen[name] = span
        return True

    for x in m.decls:
        match x:
            case ast.ParamDecl():
                t = parse_type_name(x.type_name)
                assert t is not None
                if claim(x.name, x.span, "parameter"):
                    d.params[x.name] = t
            case ast.MemberDecl(local=True):
                t = parse_type_name(x.type_name)
                assert t is not None
                if claim(x.name, x.span, "local"):
                    d.locals[x.name] = (x.role, t)
            case ast.MemberDecl():
                t = parse_type_name(x.type_name)
                assert t is not None
                if reflection is not None:
                    try:
                        reflection.check_declaration(x.role, x.member, t, x.type_span, x.span)
                    except CompileError as e:
                        diags.extend(e.diagnostics)
                        continue
                prev = d.members[x.role].get(x.member)
                if prev is not None and prev != t:
                    diags.append(Diagnostic(x.type_span, f"{x.role} member '{x.member}' declared as {t} here but as {prev} before"))
                    continue
                if x.name in d.bindings[x.role]:
                    diags.append(Diagnostic(x.span, f"'{x.name}' is already declared for {x.role}"))
                    continue
                if x.name in d.params or x.name in d.locals:
                    diags.append(Diagnostic(x.span, f"'{x.name}' is already declared"))
                    continue
                d.members[x.role][x.member] = t
                d.bindings[x.role][x.name] = (x.member, t)
            case ast.TableDecl():
                if claim(x.name, x.span, "table"):
                    d.tables[x.name] = table(x)
    for f in m.functions:
        if f.name in d.functions:
            diags.append(Diagnostic(f.span, f"function '{f.name}' is already defined"))
        elif f.name in BUILTIN_NAMES:
            diags.append(Diagnostic(f.span, f"function '{f.name}' has the name of a built-in function"))
        else:
            d.functions[f.name] = f
    return d


def table(d: ast.TableDecl) -> Table:
    """A table's values and type: F64 unless every literal is F32 (or F16)."""
    vals: list[float | int] = []
    types: set[Scalar] = set()
    for num in d.values:
        text = num.text.lstrip("-")
        v, t = literal_value(ast.Number(text, num.is_float, num.span))
        vals.append(-v if num.text.startswith("-") else v)
        if num.is_float:
            types.add(t.scalar)
    if len(types) > 1:
        raise error(d.span, f"table '{d.name}' mixes literal types ({', '.join(sorted(s.value for s in types))})")
    scalar = types.pop() if types and types <= {Scalar.F32, Scalar.F16} else Scalar.F64
    return Table(d.name, Type(scalar), tuple(float(v) for v in vals))
