"""How an ISA plugs into pikg-gen (read this before adding a backend).

An ISA is ONE module in `backends/` defining a subclass of `Isa` and listing it
in `backends/__init__.py:ISAS`. Adding an ISA touches about three files: its
module, `ISAS`, and (only when its loop shape differs) a template that
`{% extends "impl.hpp.j2" %}` and overrides a block.

What a subclass provides
------------------------
Class attributes (the "typed table" part):

  name            target name on the command line (`avx2`)
  isa_label       what the generated `isa_name()` returns (`AVX2`)
  in_auto         True: part of `--target auto` (x86 variants)
  preference      larger = preferred by `auto` when the CPU supports it
  cpu_check       C++ expression true when the running CPU can execute this
                  variant, e.g. `__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")`
  function_attributes
                  put before every generated function of the variant, e.g.
                  `__attribute__((target("avx2,fma")))`, so a header compiled
                  without -mavx2 can still contain (and dispatch to) AVX2 code
  cxx_flags       flags a standalone test needs to compile this variant
  cxx             the compiler that builds programs for this variant when it is
                  not the host's (a cross compiler, e.g. `aarch64-linux-gnu-g++`);
                  "" = the host compiler
  runners         {label: argv prefix} for an ISA the host cannot execute: how
                  `pikg-gen verify` and the tests run such a program (an emulator),
                  one entry per configuration, e.g. {"VL256": ("qemu-aarch64",
                  "-cpu", "max,sve-max-vq=2")}; {} = run natively after `cpu_check`
  lanes           {Scalar: SIMD lanes}; the reference has 1 everywhere
  template        the implementation template (default "impl.hpp.j2")
  OPS             {opcode or (opcode, Scalar): format string}. Arguments arrive
                  already printed as {0} {1} {2}; extra fields: {T} (C++ type of
                  the result), {one} (literal 1 of the result type), {table}
                  (table name). OPS MERGE DOWN THE CLASS HIERARCHY
                  (__init_subclass__): a subclass lists only the entries that
                  differ from its parent; `Reference` supplies every default.
                  Lookup order: (opcode, scalar of the result or first argument),
                  then opcode.

Methods for the irregular cases (override as needed; the defaults are scalar C++):

  vtype(t)                  C++ type of a value of IR type t (e.g. __m512 for F32)
  mask_type()               C++ type of a BOOL value
  literal(value, t)         a constant (SIMD: a broadcast, emitted once in setup)
  load(op, stage)           statement reading one member component of EPI/EPJ/FORCE
  param(op)                 statement reading a parameter (class member `<name>_`)
  expr(op, args)            right-hand side of one op (table lookup, then the
                            irregular helpers: select, cast, table, rsqrt/inv
                            refinement...)
  statement(op, args)       `const T name = expr;`
  accumulators(kernel)      the Accumulator list: declaration, update, and the final
                            combine into FORCE (SIMD: horizontal reduction here)
  context(kernel, impl)     the full template context: interface_context() plus
                            the ISA's loop-shape values; a SIMD backend subclasses
                            simd_common.Simd, whose plan() splits the kernel for
                            SIMD loops (i/j sides, lane buffers, accumulators)

The IR a backend receives (see ir/nodes.py, ir/ops.py) is fully scalar (no
vector ops: verify(kernel, expanded=True) holds), in four stages: setup (once
per call), i (per i-particle), j (per j-particle, only EPJ locals: the values
of `j` used in `pair` must be kept per j, e.g. in a buffer), pair (per i×j pair;
ends with `accum` ops whose optional second argument is a mask). Value names are
valid, unique C++ identifiers that never clash with the skeleton's names.

Loads: the generated code copies each member component with a plain C++
assignment (`static_cast<float>(epi[i].pos.x)`), so a member declared F32 on a
double struct converts correctly and a SIMD backend can first copy a block of
particles into its own aligned structure-of-arrays buffers and load lanes from there.

The implementation class of an ISA is `pik_kernels::<Name>_<isa>_<hash>`; the
public class `<Name>` (from --name, possibly qualified) forwards to it, so two
ISAs or two kernels never collide at link time. `--target auto` puts every
`in_auto` variant into one header; the public class picks the available variant
with the highest `preference` once, on first use (`cpu_check`), never by timing.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

from pik_gen.ir.nodes import Const, Kernel, MemberRef, Op, ParamRef, Reduce, Stage, TableRef, fresh_name
from pik_gen.types import COMPONENTS, CXX_SCALAR, Scalar, Type


@dataclass(frozen=True)
class Options:
    """Code-generation options from the command line."""

    name: str  # public class name, possibly qualified (sim::Gravity)
    epi: str = "EPI"
    epj: str = "EPJ"
    force: str = "FORCE"
    fast_math: bool = False
    emit_c: bool = False
    constants: tuple[tuple[str, str], ...] = ()  # --const NAME=VALUE: parameters bound at compile time
    unroll: int | None = None  # `#pragma unroll N`: i-vectors per SIMD block (None: the backend's rule)


def indexed_members(k: Kernel) -> set[tuple[str, str]]:
    """(role, member) of the vector members whose components are m[0], m[1], ..."""
    return {(m.role, m.name) for m in k.members if m.indexed}


@dataclass(frozen=True)
class Accumulator:
    """One FORCE member component being reduced over j."""

    decl: str     # before the j loop
    update: dict = field(default_factory=dict)  # unused by the reference; free for backends
    final: str = ""  # after the j loop
    name: str = ""
    member: str = ""
    component: int | None = None
    group: str = "sum"  # sum (add/sub), prod (mul/div), max, min
    type: Type | None = None


class Isa:
    name: ClassVar[str] = ""
    isa_label: ClassVar[str] = ""
    in_auto: ClassVar[bool] = False
    preference: ClassVar[int] = 0
    cpu_check: ClassVar[str] = "true"
    function_attributes: ClassVar[str] = ""
    cxx_flags: ClassVar[tuple[str, ...]] = ()
    cxx: ClassVar[str] = ""
    runners: ClassVar[dict[str, tuple[str, ...]]] = {}
    lanes: ClassVar[dict[Scalar, int]] = {}
    template: ClassVar[str] = "impl.hpp.j2"
    OPS: ClassVar[dict] = {}

    def __init_subclass__(cls, **kw) -> None:
        super().__init_subclass__(**kw)
        merged: dict = {}
        for base in reversed(cls.__mro__[1:]):
            merged.update(getattr(base, "OPS", {}))
        merged.update(cls.__dict__.get("OPS", {}))
        cls.OPS = merged

    def __init__(self, options: Options) -> None:
        self.options = options
        self.indexed: set[tuple[str, str]] = set()  # (role, member) read as m[0] m[1] ...; set per kernel
        self.types: dict[str, Type] = {}
        self.consts: dict[str, str] = {}

    # ----------------------------------------------------------------- types
    def vtype(self, t: Type) -> str:
        return CXX_SCALAR[t.scalar]

    def mask_type(self) -> str:
        return "bool"

    # -------------------------------------------------------------- literals
    def literal(self, value: float | int | bool, t: Type) -> str:
        s = t.scalar
        if s == Scalar.BOOL:
            return "true" if value else "false"
        if s.is_int:
            v = int(value)
            text = {Scalar.S32: f"{v}", Scalar.U32: f"{v}u", Scalar.S64: f"std::int64_t{{{v}}}",
                    Scalar.U64: f"std::uint64_t{{{v}}}"}[s]
            if s == Scalar.S32 and v == -(2**31):
                text = "std::numeric_limits<std::int32_t>::min()"
            return f"({text})" if v < 0 else text
        fv = float(value)
        if math.isnan(fv):
            return f"std::numeric_limits<{CXX_SCALAR[s]}>::quiet_NaN()"
        if math.isinf(fv):
            return ("-" if fv < 0 else "") + f"std::numeric_limits<{CXX_SCALAR[s]}>::infinity()"
        text = repr(abs(fv))
        if "e" not in text and "." not in text:
            text += ".0"
        if s == Scalar.F32:
            text += "f"
        elif s == Scalar.F16:
            text = f"static_cast<_Float16>({text})"
        return f"(-{text})" if math.copysign(1.0, fv) < 0 else text

    # ----------------------------------------------------------- statements
    def member_access(self, ref: MemberRef) -> str:
        base = {"EPI": "epi[i]", "EPJ": "epj[j]", "FORCE": "force[i]"}[ref.role]
        if ref.component is None:
            comp = ""
        elif (ref.role, ref.member) in self.indexed:  # std::array / C-array member (pikg-reflect)
            comp = f"[{ref.component}]"
        else:
            comp = f".{COMPONENTS[ref.component]}"
        return f"{base}.{ref.member}{comp}"

    def load(self, op: Op, stage: Stage) -> str:
        assert isinstance(op.attr, MemberRef) and op.type is not None
        return f"const {self.vtype(op.type)} {op.result} = static_cast<{self.vtype(op.type)}>({self.member_access(op.attr)});"

    def param(self, op: Op) -> str:
        assert isinstance(op.attr, ParamRef) and op.type is not None
        return f"const {self.vtype(op.type)} {op.result} = {op.attr.name}_;"

    def arg(self, name: str) -> str:
        return self.consts.get(name, name)

    def lookup(self, opcode: str, scalar: Scalar) -> str:
        fmt = self.OPS.get((opcode, scalar)) or self.OPS.get(opcode)
        if fmt is None:
            raise KeyError(f"ISA {self.name} has no implementation of '{opcode}' for {scalar.value}")
        return fmt

    def expr(self, op: Op, args: list[str]) -> str:
        assert op.type is not None
        scalar = op.type.scalar
        if op.opcode in ("eq", "ne", "lt", "gt", "le", "ge", "cast") and op.args:
            scalar = self.types[op.args[0]].scalar if op.opcode != "cast" else op.type.scalar
        fields = {"T": self.vtype(op.type), "one": self.literal(1, op.type)}
        if isinstance(op.attr, TableRef):
            fields["table"] = op.attr.name
        return self.lookup(op.opcode, scalar).format(*args, **fields)

    def statement(self, op: Op) -> str | None:
        """The C++ statement for one op; None for ops printed inline (constants)."""
        assert op.type is not None
        self.types[op.result] = op.type
        if op.opcode == "const":
            assert isinstance(op.attr, Const)
            self.consts[op.result] = self.literal(op.attr.value, op.type)
            return None
        if op.opcode == "param":
            return self.param(op)
        if op.opcode == "load":
            raise AssertionError("loads are printed by load()")
        t = self.mask_type() if op.type.scalar == Scalar.BOOL else self.vtype(op.type)
        return f"const {t} {op.result} = {self.expr(op, [self.arg(a) for a in op.args])};"

    # --------------------------------------------------------- accumulation
    GROUP = {"add": "sum", "sub": "sum", "mul": "prod", "div": "prod", "max": "max", "min": "min"}

    def accumulators(self, k: Kernel, used: set[str]) -> tuple[list[Accumulator], dict[tuple, Accumulator]]:
        accs: dict[tuple, Accumulator] = {}
        for op in k.pair:
            if op.opcode != "accum":
                continue
            r = op.attr
            assert isinstance(r, Reduce)
            group = self.GROUP[r.kind]
            key = (r.member, r.component, group)
            if key in accs:
                continue
            t = self.types[op.args[0]]
            base = r.member + ("" if r.component is None else f"_{COMPONENTS[r.component]}")
            name = fresh_name(used, base if group == "sum" else f"{base}_{group}")
            target = self.member_access(MemberRef("FORCE", r.member, r.component))
            vt = self.vtype(t)
            init = {"sum": self.literal(0, t), "prod": self.literal(1, t),
                    "max": self.literal(-math.inf, t) if t.scalar.is_float else f"std::numeric_limits<{vt}>::lowest()",
                    "min": self.literal(math.inf, t) if t.scalar.is_float else f"std::numeric_limits<{vt}>::max()"}[group]
            # defer_scale: the sum's pending power-of-two factor, applied once here
            scaled = name if r.scale == 1.0 else f"{self.literal(r.scale, t)} * {name}"
            final = {"sum": f"{target} += {scaled};", "prod": f"{target} *= {name};",
                     "max": f"if ({name} > {target}) {target} = {name};",
                     "min": f"if ({name} < {target}) {target} = {name};"}[group]
            accs[key] = Accumulator(f"{vt} {name} = {init};", {}, final, name, r.member, r.component, group, t)
        return list(accs.values()), accs

    def accumulate(self, op: Op, acc: Accumulator) -> str:
        assert isinstance(op.attr, Reduce)
        v = self.arg(op.args[0])
        kind = op.attr.kind
        stmt = {"add": f"{acc.name} += {v};", "sub": f"{acc.name} -= {v};", "mul": f"{acc.name} *= {v};",
                "div": f"{acc.name} /= {v};", "max": f"if ({v} > {acc.name}) {acc.name} = {v};",
                "min": f"if ({v} < {acc.name}) {acc.name} = {v};"}[kind]
        if len(op.args) > 1:
            stmt = f"if ({self.arg(op.args[1])}) {stmt}" if not stmt.startswith("if") else f"if ({self.arg(op.args[1])} && {stmt[4:]}"
        return stmt

    # ------------------------------------------------------------- context
    def context(self, k: Kernel, impl: str) -> dict:
        """Everything the implementation template needs, printed."""
        self.indexed = indexed_members(k)
        used = set(k.names())
        self.types = {}
        self.consts = {}
        stmts: dict[Stage, list[str]] = {s: [] for s in Stage}
        for stage, ops in k.blocks():
            for op in ops:
                if op.opcode == "accum":
                    continue
                if op.opcode == "load":
                    self.types[op.result] = op.type  # type: ignore[assignment]
                    stmts[stage].append(self.load(op, stage))
                    continue
                s = self.statement(op)
                if s is not None:
                    stmts[stage].append(s)
        accs, by_key = self.accumulators(k, used)
        # j values used in pair are kept per j-particle in a buffer.
        j_defs = {op.result: op for op in k.j if op.result and op.result not in self.consts}
        pair_uses = {a for op in k.pair for a in op.args}
        buffers = []
        for name, op in j_defs.items():
            if name in pair_uses:
                buf = fresh_name(used, f"{name}_buf")
                t = self.mask_type() if op.type.scalar == Scalar.BOOL else self.vtype(op.type)  # type: ignore[union-attr]
                buffers.append({"decl": f"{t} {buf}[kJBlock];", "store": f"{buf}[j - jb] = {name};",
                                "load": f"const {t} {name} = {buf}[j - jb];"})
        pair = list(stmts[Stage.PAIR])
        for op in k.pair:
            if op.opcode == "accum":
                r = op.attr
                assert isinstance(r, Reduce)
                pair.append(self.accumulate(op, by_key[(r.member, r.component, self.GROUP[r.kind])]))
        return self.interface_context(k, impl) | {
            "setup": stmts[Stage.SETUP], "i_stmts": stmts[Stage.I], "j_stmts": stmts[Stage.J],
            "pair": pair, "accumulators": accs, "buffers": buffers,
        }

    def interface_context(self, k: Kernel, impl: str) -> dict:
        """The template values every ISA shares: names, parameters (scalar class
        members, whatever the ISA's vectors), tables and whether EPJ is read."""
        o = self.options
        params = [{"type": CXX_SCALAR[p.type.scalar], "name": p.name, "member": f"{p.name}_"} for p in k.params]
        tables = [{"type": CXX_SCALAR[t.type.scalar], "name": t.name, "size": len(t.values),
                   "coefs": ", ".join(Isa.literal(self, v, t.type) for v in t.values)} for t in k.tables]
        return {
            "impl": impl, "isa": self.isa_label, "attrs": (self.function_attributes + " ") if self.function_attributes else "",
            "epi": o.epi, "epj": o.epj, "force": o.force, "params": params, "tables": tables,
            "uses_epj": any(isinstance(op.attr, MemberRef) and op.attr.role == "EPJ" for op in k.all_ops()),
        }
