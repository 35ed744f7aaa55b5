"""How an ISA plugs into pikg-gen (docs/adding-a-target.md walks through it).

An ISA is ONE module in `backends/` defining a subclass of `Isa`, listed in
`backends/__init__.py:ISAS`; the driver, the command line and `pikg-gen verify`
derive their target lists from there. A SIMD ISA subclasses `simd.Simd`, which
assembles its loop shapes (templates/simd.hpp.j2, or its own template when its
loop shape really differs) from the hooks the ISA provides; the scalar stages
of every ISA are printed by the reference backend (`reference.ScalarPrinter`).

What a subclass provides
------------------------
Class attributes (the "typed table" part):

  name            target name on the command line (`avx2`)
  isa_label       what the generated `isa_name()` returns (`AVX2`)
  pikg_name       PIKG's --conversion-type spelling of the target ("" = none)
  summary         a few words for `pikg-gen --help`
  vector          True for a SIMD ISA (--fast-math and `#pragma unroll` apply)
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
  lane_counts     the lanes one vector can have (verify tests sizes around them)
  includes, gcc_ignores
                  headers the variant needs; GCC warnings the header silences
  template        the implementation template (default "impl.hpp.j2")
  OPS             {opcode or (opcode, Scalar): format string}. OPS MERGE DOWN THE
                  CLASS HIERARCHY (__init_subclass__): a subclass lists only the
                  entries that differ from its parent. What the arguments and
                  fields mean is the backend's (reference.py, simd.py).

and one method, `context(kernel, impl)`: every value the template needs,
printed; `interface_context()` gives the part every ISA shares.

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
from typing import Callable, ClassVar

from pik_gen.ir.nodes import Kernel, MemberRef, Op, Reduce
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
    blend: bool = False  # `#pragma blend`: never skip a vector of pairs outside an `if` (Simd.skip_region)
    cpu: str | None = None  # --cpu NAME: the microarchitecture family the loop shape is sized for (None: the ISA's default)
    j_copies: int | None = None  # j-particles per iteration of a SIMD i-parallel block (None: Simd.j_copies_rule; tests)


def indexed_members(k: Kernel) -> set[tuple[str, str]]:
    """(role, member) of the vector members whose components are m[0], m[1], ..."""
    return {(m.role, m.name) for m in k.members if m.indexed}


def literal(value: float | int | bool, t: Type) -> str:
    """A C++ constant of IR type t (scalar)."""
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


# The reduction group of each accumulation kind: the identity and the final combine.
GROUP = {"add": "sum", "sub": "sum", "mul": "prod", "div": "prod", "max": "max", "min": "min"}


@dataclass
class Accumulator:
    """One FORCE member component reduced over j, in one reduction group (the
    reference keeps one variable, a SIMD ISA one vector per unrolled i-vector)."""

    base: str       # stem of its C++ names: pot, acc_x, pot_max
    group: str      # sum (add/sub), prod (mul/div), max, min
    type: Type      # of the values accumulated
    target: str     # the FORCE component, as C++ (force[i].acc.x)
    scale: float    # defer_scale: a sum's pending power-of-two factor, applied once at the end
    names: list[str] = field(default_factory=list)  # its C++ variables, set by the backend


def accumulators(k: Kernel, types: dict[str, Type], target: Callable[[MemberRef], str]) -> dict[tuple, Accumulator]:
    """The accumulators of kernel k by (member, component, group), in order of
    first use; `target` prints a FORCE component."""
    accs: dict[tuple, Accumulator] = {}
    for op in k.pair:
        if op.opcode != "accum":
            continue
        r = op.attr
        assert isinstance(r, Reduce)
        group = GROUP[r.kind]
        key = (r.member, r.component, group)
        if key not in accs:
            base = r.member + ("" if r.component is None else f"_{COMPONENTS[r.component]}")
            accs[key] = Accumulator(base if group == "sum" else f"{base}_{group}", group, types[op.args[0]],
                                    target(MemberRef("FORCE", r.member, r.component)), r.scale)
    return accs


def accumulator_of(accs: dict[tuple, Accumulator], op: Op) -> Accumulator:
    """The accumulator an `accum` op updates."""
    r = op.attr
    assert isinstance(r, Reduce)
    return accs[(r.member, r.component, GROUP[r.kind])]


def combine(group: str, target: str, v: str) -> str:
    """The scalar statement folding v into target for a reduction group."""
    return {"sum": f"{target} += {v};", "prod": f"{target} *= {v};",
            "max": f"if ({v} > {target}) {target} = {v};", "min": f"if ({v} < {target}) {target} = {v};"}[group]


class Isa:
    name: ClassVar[str] = ""
    isa_label: ClassVar[str] = ""
    pikg_name: ClassVar[str] = ""
    summary: ClassVar[str] = ""
    vector: ClassVar[bool] = False
    in_auto: ClassVar[bool] = False
    preference: ClassVar[int] = 0
    cpu_check: ClassVar[str] = "true"
    function_attributes: ClassVar[str] = ""

    def variant_check(self) -> str:
        """The run-time test of this variant as configured (--cpu may ask for more than the ISA's cpu_check)."""
        return self.cpu_check

    def variant_attributes(self) -> str:
        """The function attributes of this variant as configured."""
        return self.function_attributes
    cxx_flags: ClassVar[tuple[str, ...]] = ()
    cxx: ClassVar[str] = ""
    runners: ClassVar[dict[str, tuple[str, ...]]] = {}
    lane_counts: ClassVar[tuple[int, ...]] = (1,)
    includes: ClassVar[tuple[str, ...]] = ()
    gcc_ignores: ClassVar[tuple[str, ...]] = ()
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

    def context(self, k: Kernel, impl: str) -> dict:
        """Everything the implementation template needs, printed."""
        raise NotImplementedError

    def interface_context(self, k: Kernel, impl: str) -> dict:
        """The template values every ISA shares: names, parameters (scalar class
        members, whatever the ISA's vectors), tables and whether EPJ is read."""
        o = self.options
        params = [{"type": CXX_SCALAR[p.type.scalar], "name": p.name, "member": f"{p.name}_"} for p in k.params]
        tables = [{"type": CXX_SCALAR[t.type.scalar], "name": t.name, "size": len(t.values),
                   "coefs": ", ".join(literal(v, t.type) for v in t.values)} for t in k.tables]
        return {
            "impl": impl, "isa": self.isa_label, "attrs": (self.variant_attributes() + " ") if self.variant_attributes() else "",
            "epi": o.epi, "epj": o.epj, "force": o.force, "params": params, "tables": tables,
            "uses_epj": any(isinstance(op.attr, MemberRef) and op.attr.role == "EPJ" for op in k.all_ops()),
        }
