"""The reference backend: portable scalar C++, the semantic definition of every op.

`ScalarPrinter` prints IR ops as scalar C++ statements from an op table; the
reference target is that printer plus the plain i x j loop (impl.hpp.j2), and
every SIMD ISA uses a ScalarPrinter with this table for its scalar stages
(setup, i, j) and for the ops it runs lane by lane.

OPS: {opcode or (opcode, Scalar): format string}. Arguments arrive already
printed as {0} {1} {2}; extra fields: {T} (C++ type of the result), {one}
(literal 1 of the result type), {table} (table name). Lookup order: (opcode,
scalar of the result, or of the first argument for comparisons), then opcode.
"""
from __future__ import annotations

import math

from pik_gen.backends.base import Accumulator, Isa, accumulator_of, accumulators, combine, indexed_members, literal
from pik_gen.ir.nodes import Const, Kernel, MemberRef, Op, ParamRef, Reduce, Stage, TableRef, fresh_name
from pik_gen.types import COMPONENTS, CXX_SCALAR, Scalar, Type

_F16 = Scalar.F16
CMP = ("eq", "ne", "lt", "gt", "le", "ge")


def _f16(fn: str) -> str:
    return f"static_cast<_Float16>({fn.format('static_cast<float>({0})', 'static_cast<float>({1})')})"


class ScalarPrinter:
    """Scalar C++ for the ops of one kernel: the values' types and the constants
    (printed inline where used) are recorded as the ops are printed."""

    def __init__(self, ops: dict, indexed: set[tuple[str, str]], isa: str = "reference") -> None:
        self.ops = ops
        self.indexed = indexed  # (role, member) read as m[0] m[1] ...
        self.isa = isa
        self.types: dict[str, Type] = {}
        self.consts: dict[str, str] = {}

    def member_access(self, ref: MemberRef) -> str:
        base = {"EPI": "epi[i]", "EPJ": "epj[j]", "FORCE": "force[i]"}[ref.role]
        if ref.component is None:
            comp = ""
        elif (ref.role, ref.member) in self.indexed:  # std::array / C-array member (pikg-reflect)
            comp = f"[{ref.component}]"
        else:
            comp = f".{COMPONENTS[ref.component]}"
        return f"{base}.{ref.member}{comp}"

    def arg(self, name: str) -> str:
        return self.consts.get(name, name)

    def lookup(self, opcode: str, scalar: Scalar) -> str:
        fmt = self.ops.get((opcode, scalar)) or self.ops.get(opcode)
        if fmt is None:
            raise KeyError(f"ISA {self.isa} has no implementation of '{opcode}' for {scalar.value}")
        return fmt

    def expr(self, op: Op, args: list[str]) -> str:
        """The right-hand side of op with its arguments printed as `args`."""
        assert op.type is not None
        scalar = self.types[op.args[0]].scalar if op.opcode in CMP else op.type.scalar
        fields = {"T": CXX_SCALAR[op.type.scalar], "one": literal(1, op.type)}
        if isinstance(op.attr, TableRef):
            fields["table"] = op.attr.name
        return self.lookup(op.opcode, scalar).format(*args, **fields)

    def statement(self, op: Op) -> str | None:
        """The C++ statement for one op; None for constants (printed inline) and accumulations."""
        assert op.type is not None or op.opcode == "accum"
        if op.opcode == "accum":
            return None
        self.types[op.result] = op.type
        t = CXX_SCALAR[op.type.scalar]
        if op.opcode == "const":
            assert isinstance(op.attr, Const)
            self.consts[op.result] = literal(op.attr.value, op.type)
            return None
        if op.opcode == "param":
            assert isinstance(op.attr, ParamRef)
            rhs = f"{op.attr.name}_"
        elif op.opcode == "load":
            assert isinstance(op.attr, MemberRef)
            rhs = f"static_cast<{t}>({self.member_access(op.attr)})"
        else:
            rhs = self.expr(op, [self.arg(a) for a in op.args])
        return f"const {t} {op.result} = {rhs};"

    def statements(self, ops) -> list[str]:
        return [s for s in (self.statement(op) for op in ops) if s is not None]

    def accumulate(self, op: Op, acc: Accumulator) -> str:
        """`acc op= value`, under the op's mask when it has one."""
        assert isinstance(op.attr, Reduce)
        v, n, kind = self.arg(op.args[0]), acc.names[0], op.attr.kind
        conds = [self.arg(op.args[1])] if len(op.args) > 1 else []
        if kind in ("max", "min"):  # as std::max/min, a NaN value keeps the accumulator
            conds.append(f"{v} {'>' if kind == 'max' else '<'} {n}")
            update = f"{n} = {v};"
        else:
            update = f"{n} {ARITH[kind]}= {v};"
        return f"if ({' && '.join(conds)}) {update}" if conds else update


ARITH = {"add": "+", "sub": "-", "mul": "*", "div": "/"}


def identity(acc: Accumulator) -> str:
    """The scalar start value of an accumulator."""
    t = acc.type
    if not t.scalar.is_float and acc.group in ("max", "min"):
        return f"std::numeric_limits<{CXX_SCALAR[t.scalar]}>::{'lowest' if acc.group == 'max' else 'max'}()"
    return literal({"sum": 0, "prod": 1, "max": -math.inf, "min": math.inf}[acc.group], t)


class Reference(Isa):
    name = "reference"
    isa_label = "reference"
    pikg_name = "reference"
    summary = "portable scalar C++"
    in_auto = True
    preference = 0
    cpu_check = "true"
    lane_counts = (1,)
    OPS = {
        "neg": "-{0}", "not": "!{0}",
        "add": "{0} + {1}", "sub": "{0} - {1}", "mul": "{0} * {1}", "div": "{0} / {1}",
        "eq": "{0} == {1}", "ne": "{0} != {1}", "lt": "{0} < {1}", "gt": "{0} > {1}",
        "le": "{0} <= {1}", "ge": "{0} >= {1}",
        "and": "{0} && {1}", "or": "{0} || {1}",
        "select": "{0} ? {1} : {2}",
        "sqrt": "std::sqrt({0})", "rsqrt": "{one} / std::sqrt({0})",
        "rsqrt2": "static_cast<{T}>(2) / std::sqrt({0})", "inv": "{one} / {0}",
        "exp": "std::exp({0})", "erfc": "std::erfc({0})", "log": "std::log({0})", "floor": "std::floor({0})",
        "abs": "std::abs({0})", "min": "std::min({0}, {1})", "max": "std::max({0}, {1})",
        "pow": "std::pow({0}, {1})",
        # The reference leaves fusing to the C++ compiler (both are within a few ulp).
        "madd": "{0} * {1} + {2}", "msub": "{0} * {1} - {2}",
        "nmadd": "{2} - {0} * {1}", "nmsub": "-({0} * {1}) - {2}",
        "cast": "static_cast<{T}>({0})",
        "table": "{table}[{0}]",
        ("abs", Scalar.U32): "{0}", ("abs", Scalar.U64): "{0}",
        ("sqrt", _F16): _f16("std::sqrt({0})"), ("rsqrt", _F16): _f16("1.0f / std::sqrt({0})"),
        ("rsqrt2", _F16): _f16("2.0f / std::sqrt({0})"),
        ("exp", _F16): _f16("std::exp({0})"), ("erfc", _F16): _f16("std::erfc({0})"), ("log", _F16): _f16("std::log({0})"),
        ("floor", _F16): _f16("std::floor({0})"), ("abs", _F16): _f16("std::abs({0})"),
        ("pow", _F16): _f16("std::pow({0}, {1})"),
    }

    def context(self, k: Kernel, impl: str) -> dict:
        p = ScalarPrinter(self.OPS, indexed_members(k), self.name)
        used = set(k.names())
        stmts = {stage: p.statements(ops) for stage, ops in k.blocks()}
        accs = accumulators(k, p.types, p.member_access)
        acc_rows = []
        for acc in accs.values():
            name = fresh_name(used, acc.base)
            acc.names = [name]
            scaled = name if acc.scale == 1.0 or acc.group != "sum" else f"{literal(acc.scale, acc.type)} * {name}"
            acc_rows.append({"decl": f"{CXX_SCALAR[acc.type.scalar]} {name} = {identity(acc)};",
                             "final": combine(acc.group, acc.target, scaled)})
        # j values used in pair are kept per j-particle in a buffer.
        pair_uses = {a for op in k.pair for a in op.args}
        buffers = []
        for op in k.j:
            if op.result and op.result not in p.consts and op.result in pair_uses:
                buf = fresh_name(used, f"{op.result}_buf")
                t = CXX_SCALAR[op.type.scalar]  # type: ignore[union-attr]
                buffers.append({"decl": f"{t} {buf}[kJBlock];", "store": f"{buf}[j - jb] = {op.result};",
                                "load": f"const {t} {op.result} = {buf}[j - jb];"})
        pair = stmts[Stage.PAIR] + [p.accumulate(op, accumulator_of(accs, op)) for op in k.pair if op.opcode == "accum"]
        return self.interface_context(k, impl) | {
            "setup": stmts[Stage.SETUP], "i_stmts": stmts[Stage.I], "j_stmts": stmts[Stage.J],
            "pair": pair, "accumulators": acc_rows, "buffers": buffers,
        }
