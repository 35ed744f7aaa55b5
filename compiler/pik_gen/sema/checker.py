"""The checker: statements, expressions and names of one kernel, in order.

The type rules are in rules.py, the built-ins in builtins.py, the declarations
and branch frames in scopes.py, function inlining in inline.py.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Callable

from pik_gen.diagnostics import CompileError, Diagnostic, Span, error, suggest
from pik_gen.frontend import ast
from pik_gen.reflect import Reflection
from pik_gen.sema import builtins, inline
from pik_gen.sema.builtins import ACCUM, BINARY, BUILTIN_NAMES, COMPARE, literal_value
from pik_gen.sema.rules import binary, coerce, cross, settle, span_of, unify
from pik_gen.sema.scopes import ROLES, Frames, FuncScope, check_not_hidden, declare
from pik_gen.typed import (
    CheckedKernel, Member, TAccum, TAssign, TConst, TExpr, TIf, TLoad, TOp, TParam, TStmt, TVar,
)
from pik_gen.types import BOOL, COMPONENTS, Scalar, Type


def assigned_names(s: ast.Stmt) -> set[str]:
    """The plain names a statement (and the statements inside an `if`) assigns."""
    out: set[str] = set()
    stack = [s]
    while stack:
        x = stack.pop()
        if isinstance(x, ast.Assign):
            t = x.target
            while isinstance(t, ast.Component):  # `v.x = ...` defines v too
                t = t.base
            if isinstance(t, ast.Name):
                out.add(t.name)
        elif isinstance(x, ast.If):
            stack.extend(x.body)
            stack.extend(x.orelse)
    return out


def has_accum(s: TStmt) -> bool:
    if isinstance(s, TIf):
        return any(has_accum(x) for x in s.body + s.orelse)
    return isinstance(s, TAccum)


class Checker:
    def __init__(self, module: ast.Module, reflection: Reflection | None = None) -> None:
        self.m = module
        self.reflection = reflection  # member types from the user's C++ header (pikg-reflect)
        self.diags: list[Diagnostic] = []
        self.decl = declare(module, reflection, self.diags)
        self.vars: dict[str, Type] = {}  # variables assigned so far
        self.deps: dict[str, frozenset[str]] = {}  # variable -> roles it depends on
        self.used_names: set[str] = self.decl.names()
        self.out: list[TStmt] = []  # the statements of the block being checked
        self.func_stack: list[FuncScope] = []
        self.branches: Frames = []  # the kernel body's if frames (a function's are in its FuncScope)
        self.cond_deps: list[frozenset[str]] = []  # roles the enclosing if conditions depend on
        self.pragmas: list[str] = []
        # names whose definition failed (already reported): using them reports nothing more
        self.poisoned: set[str] = {
            x.name for x in module.decls
            if isinstance(x, ast.MemberDecl) and not x.local and x.name not in self.decl.bindings[x.role]
            and x.name not in self.decl.params and x.name not in self.decl.locals}

    # the declarations, by their short names
    params = property(lambda self: self.decl.params)
    bindings = property(lambda self: self.decl.bindings)
    members = property(lambda self: self.decl.members)
    locals = property(lambda self: self.decl.locals)
    tables = property(lambda self: self.decl.tables)
    functions = property(lambda self: self.decl.functions)

    # ------------------------------------------------------------- statements
    def run(self) -> CheckedKernel:
        for s in self.m.body:
            try:
                self.statement(s)
            except CompileError as e:
                self.diags.extend(e.diagnostics)
                self.poisoned |= assigned_names(s)
        if not any(has_accum(s) for s in self.out) and not self.diags:
            span = Span(self.m.file, 1, 1, 1)
            self.diags.append(Diagnostic(span, "the kernel never accumulates into FORCE (add e.g. 'FORCE.acc += ...')"))
        if self.diags:
            raise CompileError(self.diags)
        refl = self.reflection
        members = tuple(Member(r, n, t, refl is not None and refl.indexed(r, n))
                        for r in ROLES for n, t in self.members[r].items())
        return CheckedKernel(
            self.m.file,
            tuple(self.params.items()),
            members,
            tuple((n, r, t) for n, (r, t) in self.locals.items()),
            tuple(self.tables.values()),
            tuple(self.out),
            tuple(self.pragmas),
        )

    def statement(self, s: ast.Stmt) -> None:
        match s:
            case ast.Pragma():
                self.pragmas.append(s.text)
            case ast.If():
                self.if_statement(s, self.branches, set(self.vars), self.statement)
            case ast.Assign():
                self.assign(s)

    def if_statement(self, s: ast.If, frames: Frames, before: set[str], check: Callable[[ast.Stmt], None]) -> None:
        """An if in the kernel body or in a function (`check` checks one statement
        of a branch, `frames` are the enclosing branches, `before` the names defined before it)."""
        cond = self.expr(s.cond)
        if cond.type != BOOL:
            raise error(span_of(s.cond), f"an 'if' condition must be a comparison or logical expression, not {cond.type}")
        saved = self.out
        self.cond_deps.append(self.expr_deps(cond))
        try:
            branches = []
            hidden: set[str] = set()
            for stmts in (s.body, s.orelse):
                self.out = []
                frames.append((hidden, set()))
                try:
                    for b in stmts:
                        check(b)
                finally:
                    _h, assigned = frames.pop()
                hidden = assigned - before  # names first assigned in 'then' are hidden in 'else'
                branches.append((tuple(self.out), assigned))
            if frames:
                frames[-1][1].update(branches[0][1] | branches[1][1])
        finally:
            self.out = saved
            self.cond_deps.pop()
        self.out.append(TIf(cond, branches[0][0], branches[1][0], s.span))

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
            check_not_hidden(name, self.branches, target.span)
        if self.branches:
            self.branches[-1][1].add(name)
        if s.op != "=":
            if name not in self.vars:
                raise error(target.span, f"'{name}' is not defined before '{s.op}'" + suggest(name, self.visible_names()))
            old: TExpr = TVar(name, self.vars[name], target.span)
            if comp is not None:
                old = self.component(old, comp, target.span)
            value = binary(BINARY[s.op[0]], old, value, s.span)
        declared = self.locals.get(name)
        if comp is not None:
            base_t = self.vars.get(name) or (declared[1] if declared else None)
            if base_t is None and s.op == "=" and declared is None:
                # PIKG: `v.x = 0.0f` on a new name defines a vector of the value's type (3
                # components, 4 when .w is assigned), here starting from zero
                elem = settle(value).type
                if elem.lanes == 1 and elem.scalar in (Scalar.F64, Scalar.F32, Scalar.F16):
                    base_t = Type(elem.scalar, 4 if comp == 3 else 3)
                    self.vars[name] = base_t
                    self.deps[name] = frozenset()
                    zero = TConst(0.0, base_t, target.span, False)
                    self.out.append(TAssign(name, zero, None, s.span))
            if base_t is None:
                raise error(target.span, f"'{name}' must be defined (or declared 'EPI local') before assigning '{name}.{COMPONENTS[comp]}'")
            if not base_t.is_vec or comp >= base_t.lanes:
                raise error(comp_span or target.span, f"'{name}' of type {base_t} has no component '{COMPONENTS[comp]}'")
            value = coerce(value, base_t.element, s.value)
            self.vars[name] = base_t
        else:
            want = declared[1] if declared else self.vars.get(name)
            if want is not None:
                value = coerce(value, want, s.value)
            else:
                value = settle(value)
            self.vars[name] = value.type
        deps = self.expr_deps(value).union(*self.cond_deps) if self.cond_deps else self.expr_deps(value)
        if comp is not None and name in self.deps:
            deps = deps | self.deps[name]
        if declared is not None:
            role = declared[0]
            bad = deps - {role}
            if bad:
                other = sorted(bad)[0]
                raise error(span_of(s.value), f"{role} local '{name}' depends on {other}; an {role} local may use only {role} members, parameters and other {role} locals")
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
            known = self.reflection.member_type("FORCE", member, span_of(s.target))
            self.members["FORCE"][member] = known
        if s.op == "=":
            kind, value_ast = self.reduction_pattern(s, member, comp)
        else:
            kind, value_ast = ACCUM[s.op], s.value
        value = self.expr(value_ast)
        if known is None:
            # A member used only through FORCE.m: its type follows the value.
            value = settle(value)
            known = value.type if comp is None else None
            if known is None:
                raise error(s.target.span, f"the type of FORCE member '{member}' is unknown; declare it, e.g. 'FORCE F64vec {member}'")
            self.members["FORCE"][member] = known
        t = known
        if comp is not None:
            if not t.is_vec or comp >= t.lanes:
                raise error(comp_span or s.span, f"FORCE member '{member}' of type {t} has no component '{COMPONENTS[comp]}'")
            t = t.element
        value = coerce(value, t, value_ast)
        if kind in ("max", "min") and t.is_vec:
            raise error(s.span, f"'{kind}' reductions need a scalar FORCE member, '{member}' is {t}")
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
                    left, right = unify(left, right, e.span, e.op)
                    if left.type.is_vec:
                        raise error(e.span, f"'{e.op}' compares scalars, not {left.type}")
                    if left.type.scalar == Scalar.BOOL and e.op not in ("==", "!="):
                        raise error(e.span, f"'{e.op}' needs numbers, not logical values")
                    left, right = settle(left), settle(right)
                    return TOp(COMPARE[e.op], (left, right), BOOL, e.span)
                if e.op == "^":
                    return cross(left, right, e.span)
                return binary(BINARY[e.op], left, right, e.span)
            case ast.Call():
                return self.call(e)
        raise error(span_of(e), "unsupported expression")  # pragma: no cover

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

    def visible_names(self) -> set[str]:
        names = set(self.vars) | set(self.params) | set(self.tables) | set(self.locals)
        for r in ROLES:
            names |= set(self.bindings[r]) | set(self.members[r])
        if self.func_stack:
            names |= set(self.func_stack[-1].bindings) | set(self.func_stack[-1].renames)
        return names

    def name(self, e: ast.Name) -> TExpr:
        n = e.name
        check_not_hidden(n, self.func_stack[-1].branches if self.func_stack else self.branches, e.span)
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
        if n in self.poisoned:
            raise CompileError([])  # its definition failed and was reported: no second error
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

    # ------------------------------------------------------------ calls
    def call(self, e: ast.Call) -> TExpr:
        if e.func in self.functions:
            return inline.inline(self, self.functions[e.func], e)
        return builtins.call(e, self.expr, self.tables, self.functions)

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
