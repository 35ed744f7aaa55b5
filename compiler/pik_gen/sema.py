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

Every mistake is reported as a located Diagnostic with a suggestion where one
is obvious; checking continues with the next statement so that several
independent errors are reported at once.
"""
from __future__ import annotations

from typing import Callable
from dataclasses import dataclass, field, replace

from pik_gen.diagnostics import CompileError, Diagnostic, Span, error, suggest
from pik_gen.frontend import ast
from pik_gen.reflect import Reflection
from pik_gen.types import BOOL, COMPONENTS, Scalar, Type, parse_type_name

ROLES = ("EPI", "EPJ", "FORCE")


# ----------------------------------------------------------------- typed tree
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


# ------------------------------------------------------------------ built-ins
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
    "sqrt": (1, True), "rsqrt": (1, True), "inv": (1, True), "exp": (1, True), "log": (1, True),
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


@dataclass
class _FuncScope:
    name: str
    bindings: dict[str, TExpr]
    renames: dict[str, str] = field(default_factory=dict)
    branches: list[tuple[set[str], set[str]]] = field(default_factory=list)  # see Checker.branches


class Checker:
    def __init__(self, module: ast.Module, reflection: Reflection | None = None) -> None:
        self.m = module
        self.reflection = reflection  # member types from the user's C++ header (pikg-reflect)
        self.diags: list[Diagnostic] = []
        self.params: dict[str, Type] = {}
        self.param_order: list[str] = []
        self.bindings: dict[str, dict[str, tuple[str, Type]]] = {r: {} for r in ROLES}  # role -> name -> (member, type)
        self.members: dict[str, dict[str, Type]] = {r: {} for r in ROLES}
        self.locals: dict[str, tuple[str, Type]] = {}
        self.tables: dict[str, Table] = {}
        self.functions: dict[str, ast.Function] = {}
        self.vars: dict[str, Type] = {}
        self.deps: dict[str, frozenset[str]] = {}  # variable -> roles it depends on
        self.used_names: set[str] = set()
        self.out: list[TStmt] = []
        self.func_stack: list[_FuncScope] = []
        # One frame per enclosing if-branch being checked: (names hidden in it, names
        # assigned in it). A name first assigned in the 'then' branch is hidden in the
        # 'else' branch until assigned there; after the if, both branches' names are
        # defined. The top level's frames; a function's are in its _FuncScope.
        self.branches: list[tuple[set[str], set[str]]] = []
        self.cond_deps: list[frozenset[str]] = []
        self.pragmas: list[str] = []

    # ----------------------------------------------------------- declarations
    def declare(self) -> None:
        seen: dict[str, Span] = {}

        def claim(name: str, span: Span, what: str) -> bool:
            if name in seen:
                prev = seen[name]
                self.diags.append(Diagnostic(span, f"'{name}' is already declared", notes=(f"previous declaration at {prev}",)))
                return False
            if name in BUILTIN_NAMES:
                self.diags.append(Diagnostic(span, f"{what} '{name}' has the name of a built-in function"))
                return False
            seen[name] = span
            return True

        for d in self.m.decls:
            match d:
                case ast.ParamDecl():
                    t = parse_type_name(d.type_name)
                    assert t is not None
                    if claim(d.name, d.span, "parameter"):
                        self.params[d.name] = t
                        self.param_order.append(d.name)
                case ast.MemberDecl(local=True):
                    t = parse_type_name(d.type_name)
                    assert t is not None
                    if claim(d.name, d.span, "local"):
                        self.locals[d.name] = (d.role, t)
                case ast.MemberDecl():
                    t = parse_type_name(d.type_name)
                    assert t is not None
                    if self.reflection is not None:
                        try:
                            self.reflection.check_declaration(d.role, d.member, t, d.type_span, d.span)
                        except CompileError as e:
                            self.diags.extend(e.diagnostics)
                            continue
                    prev = self.members[d.role].get(d.member)
                    if prev is not None and prev != t:
                        self.diags.append(Diagnostic(d.type_span, f"{d.role} member '{d.member}' declared as {t} here but as {prev} before"))
                        continue
                    if d.name in self.bindings[d.role]:
                        self.diags.append(Diagnostic(d.span, f"'{d.name}' is already declared for {d.role}"))
                        continue
                    if d.name in self.params or d.name in self.locals:
                        self.diags.append(Diagnostic(d.span, f"'{d.name}' is already declared"))
                        continue
                    self.members[d.role][d.member] = t
                    self.bindings[d.role][d.name] = (d.member, t)
                case ast.TableDecl():
                    if claim(d.name, d.span, "table"):
                        self.tables[d.name] = self.table(d)
        for f in self.m.functions:
            if f.name in self.functions or f.name in BUILTIN_NAMES:
                self.diags.append(Diagnostic(f.span, f"function '{f.name}' is already defined" if f.name in self.functions else f"function '{f.name}' has the name of a built-in function"))
                continue
            self.functions[f.name] = f
        self.used_names |= set(self.params) | set(self.locals) | set(self.tables)
        for r in ROLES:
            self.used_names |= set(self.bindings[r])

    def table(self, d: ast.TableDecl) -> Table:
        vals: list[float | int] = []
        types: set[Scalar] = set()
        for num in d.values:
            text = num.text.lstrip("-")
            v, t = literal_value(ast.Number(text, num.is_float, num.span))
            vals.append(-v if num.text.startswith("-") else v)
            if num.is_float:
                types.add(t.scalar)
        scalar = Scalar.F64
        if types == {Scalar.F32}:
            scalar = Scalar.F32
        elif types == {Scalar.F16}:
            scalar = Scalar.F16
        elif not types:
            scalar = Scalar.F64
        if len(types) > 1:
            raise error(d.span, f"table '{d.name}' mixes literal types ({', '.join(sorted(s.value for s in types))})")
        return Table(d.name, Type(scalar), tuple(float(v) for v in vals))

    # ------------------------------------------------------------- statements
    def run(self) -> CheckedKernel:
        self.declare()
        for s in self.m.body:
            try:
                self.statement(s)
            except CompileError as e:
                self.diags.extend(e.diagnostics)
        for name, (role, _t) in self.locals.items():
            if name not in self.vars and not self.diags:
                pass  # a declared but unused local is harmless
        if not any(isinstance(s, (TAccum,)) or self._has_accum(s) for s in self.out) and not self.diags:
            span = Span(self.m.file, 1, 1, 1)
            self.diags.append(Diagnostic(span, "the kernel never accumulates into FORCE (add e.g. 'FORCE.acc += ...')"))
        if self.diags:
            raise CompileError(self.diags)
        refl = self.reflection
        members = tuple(Member(r, n, t, refl is not None and refl.indexed(r, n))
                        for r in ROLES for n, t in self.members[r].items())
        return CheckedKernel(
            self.m.file,
            tuple((p, self.params[p]) for p in self.param_order),
            members,
            tuple((n, r, t) for n, (r, t) in self.locals.items()),
            tuple(self.tables.values()),
            tuple(self.out),
            tuple(self.pragmas),
        )

    def _has_accum(self, s: TStmt) -> bool:
        if isinstance(s, TIf):
            return any(isinstance(x, TAccum) or self._has_accum(x) for x in s.body + s.orelse)
        return isinstance(s, TAccum)

    def statement(self, s: ast.Stmt) -> None:
        match s:
            case ast.Pragma():
                self.pragmas.append(s.text)
            case ast.If():
                cond = self.expr(s.cond)
                if cond.type != BOOL:
                    raise error(self._span(s.cond), f"an 'if' condition must be a comparison or logical expression, not {cond.type}")
                saved = self.out
                self.cond_deps.append(self.expr_deps(cond))
                try:
                    body, orelse = self.branches_of(s, self.branches, set(self.vars), self.statement)
                finally:
                    self.out = saved
                    self.cond_deps.pop()
                self.out.append(TIf(cond, body, orelse, s.span))
            case ast.Assign():
                self.assign(s)

    def assign(self, s: ast.Assign) -> None:
        target = s.target
        comp: int | None = None
        comp_span = None
        if isinstance(target, ast.Component):
            comp_span = target.span
            comp = self.component_index(target.comp, target.span)
            target = target.base
            if isinstance(target, ast.Component):
                raise error(comp_span, "only one component may be assigned (e.g. 'v.x = ...')")
        # --- FORCE targets
        force_member = self.force_target(target, s.op)
        if force_member is not None:
            self.accumulate(s, force_member, comp, comp_span)
            return
        if isinstance(target, ast.RoleMember):
            raise error(target.span, f"{target.role} members are read-only; only FORCE members can be accumulated")
        assert isinstance(target, ast.Name)
        name = target.name
        if name in self.params:
            raise error(target.span, f"parameter '{name}' is read-only inside the kernel")
        if name in self.tables:
            raise error(target.span, f"table '{name}' is read-only")
        for r in ("EPI", "EPJ"):
            if name in self.bindings[r] and name not in self.vars:
                raise error(target.span, f"'{name}' is bound to {r}.{self.bindings[r][name][0]}, which is read-only")
        value = self.expr(s.value)
        if s.op != "=" or comp is not None:
            self.check_not_hidden(name, self.branches, target.span)
        if self.branches:
            self.branches[-1][1].add(name)
        if s.op != "=":
            if name not in self.vars:
                raise error(target.span, f"'{name}' is not defined before '{s.op}'" + suggest(name, self.visible_names()))
            old: TExpr = TVar(name, self.vars[name], target.span)
            if comp is not None:
                old = self.component(old, comp, target.span)
            value = self.binary(BINARY[s.op[0]], old, value, s.span)
        declared = self.locals.get(name)
        if comp is not None:
            base_t = self.vars.get(name) or (declared[1] if declared else None)
            if base_t is None:
                raise error(target.span, f"'{name}' must be defined (or declared 'EPI local') before assigning '{name}.{COMPONENTS[comp]}'")
            if not base_t.is_vec or comp >= base_t.lanes:
                raise error(comp_span or target.span, f"'{name}' of type {base_t} has no component '{COMPONENTS[comp]}'")
            value = self.coerce(value, base_t.element, s.value)
            self.vars[name] = base_t
        else:
            want = declared[1] if declared else self.vars.get(name)
            if want is not None:
                value = self.coerce(value, want, s.value)
            else:
                value = self.settle(value)
            self.vars[name] = value.type
        deps = self.expr_deps(value).union(*self.cond_deps) if self.cond_deps else self.expr_deps(value)
        if comp is not None and name in self.deps:
            deps = deps | self.deps[name]
        if declared is not None:
            role = declared[0]
            bad = deps - {role}
            if bad:
                other = sorted(bad)[0]
                raise error(self._span(s.value), f"{role} local '{name}' depends on {other}; an {role} local may use only {role} members, parameters and other {role} locals")
        self.deps[name] = deps
        self.used_names.add(name)
        self.out.append(TAssign(name, value, comp, s.span))

    def force_target(self, target: ast.Expr, op: str) -> str | None:
        """The FORCE member an assignment target refers to, or None."""
        if isinstance(target, ast.RoleMember):
            return target.member if target.role == "FORCE" else None
        if isinstance(target, ast.Name):
            n = target.name
            if n in self.vars or n in self.locals or n in self.params:
                return None
            if n in self.bindings["FORCE"]:
                return self.bindings["FORCE"][n][0]
            if op != "=":
                if n in self.members["FORCE"]:
                    return n
                if self.reflection is not None and self.reflection.field("FORCE", n) is not None:
                    return n
                cands = set(self.bindings["FORCE"]) | set(self.members["FORCE"]) | set(self.vars)
                raise error(target.span, f"unknown FORCE member or variable '{n}' on the left of '{op}'" + suggest(n, cands))
        return None

    def accumulate(self, s: ast.Assign, member: str, comp: int | None, comp_span: Span | None) -> None:
        known = self.members["FORCE"].get(member)
        if known is None and self.reflection is not None:
            known = self.reflection.member_type("FORCE", member, self._span(s.target))
            self.members["FORCE"][member] = known
        if s.op == "=":
            kind, value_ast = self.reduction_pattern(s, member, comp)
        else:
            kind, value_ast = ACCUM[s.op], s.value
        value = self.expr(value_ast)
        if known is None:
            # A member used only through FORCE.m: its type follows the value.
            value = self.settle(value)
            known = value.type if comp is None else None
            if known is None:
                raise error(s.target.span if not isinstance(s.target, ast.Component) else s.target.span,
                            f"the type of FORCE member '{member}' is unknown; declare it, e.g. 'FORCE F64vec {member}'")
            self.members["FORCE"][member] = known
        t = known
        if comp is not None:
            if not t.is_vec or comp >= t.lanes:
                raise error(comp_span or s.span, f"FORCE member '{member}' of type {t} has no component '{COMPONENTS[comp]}'")
            t = t.element
        value = self.coerce(value, t, value_ast)
        if kind in ("max", "min") and t.is_vec:
            raise error(s.span, f"'{kind}' reductions need a scalar FORCE member, '{member}' is {t}")
        if kind in ("mul", "div") and t.is_vec:
            pass  # component-wise
        if self.cond_deps and "FORCE" in frozenset().union(*self.cond_deps):
            raise error(s.span, "an accumulation may not be conditional on a FORCE value")
        self.out.append(TAccum(member, comp, kind, value, s.span))

    def reduction_pattern(self, s: ast.Assign, member: str, comp: int | None) -> tuple[str, ast.Expr]:
        """`FORCE.m = max(FORCE.m, v)` (or min, arguments either way) -> ("max", v)."""
        v = s.value
        if isinstance(v, ast.Call) and v.func in ("max", "min") and len(v.args) == 2:
            for k in (0, 1):
                if self.refers_to_force(v.args[k], member, comp):
                    return v.func, v.args[1 - k]
        shown = f"FORCE.{member}" + (f".{COMPONENTS[comp]}" if comp is not None else "")
        raise error(s.span, f"{shown} can only be accumulated ('+=', '-=', '*=', '/=') or reduced as '{shown} = max({shown}, value)' (or min)")

    def refers_to_force(self, e: ast.Expr, member: str, comp: int | None) -> bool:
        c = None
        if isinstance(e, ast.Component):
            c = COMPONENTS.index(e.comp) if e.comp in COMPONENTS else -1
            e = e.base
        if c != comp:
            return False
        if isinstance(e, ast.RoleMember):
            return e.role == "FORCE" and e.member == member
        if isinstance(e, ast.Name) and e.name not in self.vars and e.name not in self.params:
            b = self.bindings["FORCE"].get(e.name)
            return (b is not None and b[0] == member) or e.name == member
        return False

    # ------------------------------------------------------------ expressions
    def expr(self, e: ast.Expr) -> TExpr:
        match e:
            case ast.Number():
                v, t = literal_value(e)
                return TConst(v, t, e.span, True)
            case ast.Name():
                return self.name(e)
            case ast.RoleMember():
                return self.role_member(e.role, e.member, e.span)
            case ast.Component():
                base = self.expr(e.base)
                return self.component(base, self.component_index(e.comp, e.span), e.span)
            case ast.Unary():
                x = self.expr(e.operand)
                if e.op == "+":
                    return x
                if e.op == "!":
                    if x.type != BOOL:
                        raise error(e.span, f"'!' needs a logical operand, not {x.type}")
                    return TOp("not", (x,), BOOL, e.span)
                if x.type.scalar == Scalar.BOOL:
                    raise error(e.span, "unary '-' needs a number, not a logical value")
                if isinstance(x, TConst):
                    return replace(x, value=-x.value)
                return TOp("neg", (x,), x.type, e.span, x.flex)
            case ast.Binary():
                left, right = self.expr(e.left), self.expr(e.right)
                if e.op in ("&&", "||"):
                    for side in (left, right):
                        if side.type != BOOL:
                            raise error(e.span, f"'{e.op}' needs logical operands (comparisons), not {side.type}")
                    return TOp("and" if e.op == "&&" else "or", (left, right), BOOL, e.span)
                if e.op in COMPARE:
                    left, right = self.unify(left, right, e.span, e.op)
                    if left.type.is_vec:
                        raise error(e.span, f"'{e.op}' compares scalars, not {left.type}")
                    if left.type.scalar == Scalar.BOOL and e.op not in ("==", "!="):
                        raise error(e.span, f"'{e.op}' needs numbers, not logical values")
                    left, right = self.settle(left), self.settle(right)
                    return TOp(COMPARE[e.op], (left, right), BOOL, e.span)
                if e.op == "^":
                    return self.cross(left, right, e.span)
                return self.binary(BINARY[e.op], left, right, e.span)
            case ast.Call():
                return self.call(e)
        raise error(self._span(e), "unsupported expression")  # pragma: no cover

    def _span(self, e: ast.Expr) -> Span:
        if isinstance(e, ast.Binary):
            return self._span(e.left)
        if isinstance(e, ast.Component):
            return self._span(e.base)
        return e.span

    def component_index(self, comp: str, span: Span) -> int:
        if comp not in COMPONENTS:
            raise error(span, f"unknown component '{comp}'; vectors have components x, y, z, w")
        return COMPONENTS.index(comp)

    def component(self, base: TExpr, idx: int, span: Span) -> TExpr:
        if not base.type.is_vec:
            raise error(span, f"component '.{COMPONENTS[idx]}' of a scalar ({base.type})")
        if idx >= base.type.lanes:
            raise error(span, f"{base.type} has no component '{COMPONENTS[idx]}'")
        if isinstance(base, TLoad) and base.component is None:
            return TLoad(base.role, base.member, idx, base.type.element, base.span, name_hint=base.name_hint)
        return TOp("comp", (base,), base.type.element, span, attr=idx)

    def branches_of(self, s: ast.If, frames: list[tuple[set[str], set[str]]], before: set[str],
                    check: Callable[[ast.Stmt], None]) -> tuple[tuple[TStmt, ...], tuple[TStmt, ...]]:
        """Checks both branches of an if (see `branches`); returns their statements."""
        out = []
        hidden: set[str] = set()
        for stmts in (s.body, s.orelse):
            self.out = []
            frames.append((hidden, set()))
            try:
                for b in stmts:
                    check(b)
            finally:
                _h, assigned = frames.pop()
            hidden = assigned - before
            out.append((tuple(self.out), assigned))
        if frames:
            frames[-1][1].update(out[0][1] | out[1][1])
        return out[0][0], out[1][0]

    def check_not_hidden(self, n: str, frames: list[tuple[set[str], set[str]]], span) -> None:
        """A name first assigned in the other branch of an enclosing if is not defined here."""
        assigned: set[str] = set()
        for hidden, a in reversed(frames):
            assigned |= a
            if n in hidden and n not in assigned:
                raise error(span, f"'{n}' is assigned only in another branch of an 'if', not before it")

    def visible_names(self) -> set[str]:
        names = set(self.vars) | set(self.params) | set(self.tables) | set(self.locals)
        for r in ROLES:
            names |= set(self.bindings[r]) | set(self.members[r])
        if self.func_stack:
            names |= set(self.func_stack[-1].bindings) | set(self.func_stack[-1].renames)
        return names

    def name(self, e: ast.Name) -> TExpr:
        n = e.name
        self.check_not_hidden(n, self.func_stack[-1].branches if self.func_stack else self.branches, e.span)
        if self.func_stack:
            scope = self.func_stack[-1]
            if n in scope.renames:
                real = scope.renames[n]
                return TVar(real, self.vars[real], e.span)
            if n in scope.bindings:
                b = scope.bindings[n]
                return replace(b, span=e.span) if not isinstance(b, TOp) else b
            if n in self.params:
                return TParam(n, self.params[n], e.span)
            raise error(e.span, f"unknown name '{n}' in function '{scope.name}' (functions see their arguments and the kernel parameters)" + suggest(n, set(scope.bindings) | set(scope.renames) | set(self.params)))
        if n in self.vars:
            return TVar(n, self.vars[n], e.span)
        if n in self.locals:
            raise error(e.span, f"{self.locals[n][0]} local '{n}' is used before it is assigned")
        if n in self.params:
            return TParam(n, self.params[n], e.span)
        if n in self.tables:
            raise error(e.span, f"table '{n}' can only be used as table({n}, index)")
        for r in ROLES:
            if n in self.bindings[r]:
                member, t = self.bindings[r][n]
                return TLoad(r, member, None, t, e.span, name_hint=n)
        # a plain name on the right: a member of EPI, then EPJ, then FORCE (declared in the
        # file, or a member of the user's struct when the header was reflected)
        for r in ROLES:
            if n in self.members[r]:
                return TLoad(r, n, None, self.members[r][n], e.span, name_hint=n)
            if self.reflection is not None and self.reflection.field(r, n) is not None:
                t = self.reflection.member_type(r, n, e.span)
                self.members[r][n] = t
                return TLoad(r, n, None, t, e.span, name_hint=n)
        if n in self.functions or n in BUILTIN_NAMES:
            raise error(e.span, f"'{n}' is a function; call it as {n}(...)")
        raise error(e.span, f"unknown name '{n}'" + suggest(n, self.visible_names()))

    def role_member(self, role: str, member: str, span: Span) -> TExpr:
        t = self.members[role].get(member)
        if t is None and self.reflection is not None:
            t = self.reflection.member_type(role, member, span)
            self.members[role][member] = t
        if t is None:
            hint = suggest(member, self.members[role])
            if hint:
                raise error(span, f"unknown member '{member}' of {role}{hint}")
            raise error(span, f"the type of {role} member '{member}' is unknown; declare it, e.g. '{role} F64 {member}'" + ("" if role != "FORCE" else " (FORCE members also take the type of what is accumulated)"))
        return TLoad(role, member, None, t, span, name_hint=f"{role.lower()}_{member}")

    # ------------------------------------------------------------ type rules
    def retype(self, e: TExpr, scalar: Scalar, span: Span) -> TExpr:
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
            args = tuple(self.retype(a, scalar, span) for a in e.args)
            return TOp(e.opcode, args, e.type.with_scalar(scalar), e.span, True, e.attr)
        return e

    def settle(self, e: TExpr) -> TExpr:
        """Fix a literal expression to its own (suffix) type: it has no context."""
        if not e.flex:
            return e
        fixed = self.retype(e, e.type.scalar, e.span)
        return _unflex(fixed)

    def coerce(self, e: TExpr, want: Type, where: ast.Expr) -> TExpr:
        if e.flex and e.type.lanes == want.lanes:
            e = _unflex(self.retype(e, want.scalar, e.span))
        if e.type != want:
            raise error(self._span(where), f"type mismatch: expected {want}, found {e.type}" + self.cast_hint(want))
        return e

    def cast_hint(self, want: Type) -> str:
        if want.is_vec:
            return f" (convert with to_{want.scalar.value.lower()}vec(...))" if want.scalar.is_float else ""
        return f" (convert with to_{want.scalar.value.lower()}(...))"

    def unify(self, a: TExpr, b: TExpr, span: Span, op: str) -> tuple[TExpr, TExpr]:
        if a.flex and not b.flex:
            a = self.retype(a, b.type.scalar, span)
        elif b.flex and not a.flex:
            b = self.retype(b, a.type.scalar, span)
        elif a.flex and b.flex:
            sa, sb = a.type.scalar, b.type.scalar
            if sa.is_float != sb.is_float:
                s = sa if sa.is_float else sb
            else:
                s = sa if sa.bits >= sb.bits else sb
            a, b = self.retype(a, s, span), self.retype(b, s, span)
        if a.type.scalar != b.type.scalar:
            raise error(span, f"type mismatch in '{op}': {a.type} and {b.type}" + self.cast_hint(Type(a.type.scalar if a.type.scalar.bits >= b.type.scalar.bits else b.type.scalar)))
        return a, b

    def binary(self, opcode: str, a: TExpr, b: TExpr, span: Span) -> TExpr:
        sym = {"add": "+", "sub": "-", "mul": "*", "div": "/"}[opcode]
        for side in (a, b):
            if side.type.scalar == Scalar.BOOL:
                raise error(span, f"'{sym}' needs numbers, not logical values")
        a, b = self.unify(a, b, span, sym)
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

    def cross(self, a: TExpr, b: TExpr, span: Span) -> TExpr:
        a, b = self.unify(a, b, span, "^")
        if not (a.type.is_vec and b.type.is_vec and a.type.lanes == b.type.lanes == 3):
            raise error(span, f"'^' is the cross product of two 3-vectors, not {a.type} ^ {b.type}")
        if not a.type.scalar.is_float:
            raise error(span, "'^' needs floating-point vectors")
        return TOp("cross", (a, b), a.type, span, a.flex and b.flex)

    def call(self, e: ast.Call) -> TExpr:
        f = e.func
        if f in self.functions:
            return self.inline(self.functions[f], e)
        if f == "table":
            if len(e.args) != 2 or not isinstance(e.args[0], ast.Name):
                raise error(e.span, "table needs two arguments: table(TABLE_NAME, index)")
            tname = e.args[0].name
            if tname not in self.tables:
                raise error(e.args[0].span, f"unknown table '{tname}'" + suggest(tname, self.tables))
            idx = self.expr(e.args[1])
            if idx.flex:
                idx = self.settle(idx)
            if idx.type.is_vec or not idx.type.scalar.is_int:
                raise error(self._span(e.args[1]), f"a table index must be an integer (convert with to_s32(...)), not {idx.type}")
            return TOp("table", (idx,), self.tables[tname].type, e.span, attr=tname)
        args = [self.expr(a) for a in e.args]
        if f in CASTS or f in VEC_CASTS:
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
                return _unflex(self.retype(replace(x, flex=True), target.scalar, e.span))
            x = self.settle(x)
            if x.type == target:
                return x
            return TOp("cast", (x,), target, e.span)
        if f not in MATH:
            raise error(e.span, f"unknown function '{f}'" + suggest(f, list(self.functions) + list(BUILTIN_NAMES)))
        nargs, float_only = MATH[f]
        if len(args) != nargs:
            raise error(e.span, f"{f} takes {nargs} argument{'s' if nargs > 1 else ''}, not {len(args)}")
        # Unify all arguments pairwise so literals take the others' type.
        for k in range(1, nargs):
            args[0], args[k] = self.unify(args[0], args[k], e.span, f)
        for k in range(1, nargs):
            args[0], args[k] = self.unify(args[0], args[k], e.span, f)
        lanes = {a.type.lanes for a in args}
        if len(lanes) > 1:
            raise error(e.span, f"{f}: arguments of different lengths ({', '.join(str(a.type) for a in args)})")
        t = args[0].type
        if t.scalar == Scalar.BOOL:
            raise error(e.span, f"{f} needs numbers, not logical values")
        flex = all(a.flex for a in args)
        if float_only and not t.scalar.is_float:
            if flex:
                args = [self.retype(a, Scalar.F64, e.span) for a in args]
                t = args[0].type
            else:
                raise error(e.span, f"{f} needs floating-point arguments, not {t} (convert with to_f64(...) or to_f32(...))")
        return TOp(f, tuple(args), t, e.span, flex)

    def inline(self, fn: ast.Function, call: ast.Call) -> TExpr:
        if any(s.name == fn.name for s in self.func_stack):
            raise error(call.span, f"function '{fn.name}' calls itself; recursion is not supported")
        if len(call.args) != len(fn.params):
            raise error(call.span, f"function '{fn.name}' takes {len(fn.params)} argument{'s' if len(fn.params) != 1 else ''}, not {len(call.args)}")
        args = [self.expr(a) for a in call.args]
        scope = _FuncScope(fn.name, dict(zip(fn.params, args)))
        self.func_stack.append(scope)
        try:
            for s in fn.body:
                self.function_statement(fn, s, scope)
            result = self.expr(fn.result)
        finally:
            self.func_stack.pop()
        if isinstance(result, TVar) and result.name in scope.renames.values():
            result = replace(result, returned=True)
        return result

    def function_statement(self, fn: ast.Function, s: ast.Stmt, scope: _FuncScope) -> None:
        match s:
            case ast.Pragma():
                return
            case ast.If():
                cond = self.expr(s.cond)
                if cond.type != BOOL:
                    raise error(self._span(s.cond), f"an 'if' condition must be a comparison or logical expression, not {cond.type}")
                saved = self.out
                try:
                    body, orelse = self.branches_of(s, scope.branches, set(scope.renames),
                                                    lambda b: self.function_statement(fn, b, scope))
                finally:
                    self.out = saved
                self.out.append(TIf(cond, body, orelse, s.span))
            case ast.Assign():
                if not isinstance(s.target, ast.Name):
                    raise error(s.target.span if not isinstance(s.target, ast.Component) else s.target.span,
                                f"inside function '{fn.name}' only local variables can be assigned")
                n = s.target.name
                value = self.expr(s.value)
                if s.op != "=":
                    self.check_not_hidden(n, scope.branches, s.target.span)
                if scope.branches:
                    scope.branches[-1][1].add(n)
                if s.op != "=":
                    if n not in scope.renames and n not in scope.bindings:
                        raise error(s.target.span, f"'{n}' is not defined before '{s.op}'")
                    value = self.binary(BINARY[s.op[0]], self.name(s.target), value, s.span)
                if n in scope.renames:
                    real = scope.renames[n]
                    value = self.coerce(value, self.vars[real], s.value)
                else:
                    value = self.settle(value)
                    real = self.fresh(f"{fn.name}_{n}")
                    scope.renames[n] = real
                    scope.bindings.pop(n, None)
                self.vars[real] = value.type
                self.deps[real] = self.expr_deps(value)
                self.out.append(TAssign(real, value, None, s.span))

    def fresh(self, base: str) -> str:
        name, k = base, 1
        while name in self.used_names or name in self.vars:
            k += 1
            name = f"{base}_{k}"
        self.used_names.add(name)
        return name

    def expr_deps(self, e: TExpr) -> frozenset[str]:
        match e:
            case TLoad():
                return frozenset({e.role})
            case TVar():
                return self.deps.get(e.name, frozenset())
            case TOp():
                return frozenset().union(*(self.expr_deps(a) for a in e.args))
        return frozenset()


def _unflex(e: TExpr) -> TExpr:
    if not e.flex:
        return e
    if isinstance(e, TOp):
        return TOp(e.opcode, tuple(_unflex(a) for a in e.args), e.type, e.span, False, e.attr)
    return replace(e, flex=False)


def check(module: ast.Module, reflection: Reflection | None = None) -> CheckedKernel:
    """Resolve names and types of a parsed module; raises CompileError on mistakes.
    With `reflection`, members not declared in the file take their types from the
    user's C++ struct and declarations are checked against it."""
    return Checker(module, reflection).run()
