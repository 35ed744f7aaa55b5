"""What every SIMD backend shares: the split of a kernel for SIMD loops and the
assembly of the loop shapes (AVX2 and AVX-512 in avx2.py/avx512.py, SVE in sve.py).

A SIMD backend runs the pair stage with particles in lanes and the rest of the
kernel as scalar C++ (printed by a `reference.ScalarPrinter`). `Simd.context`
does everything that does not depend on the ISA:

  split       the pair stage's loads go to the i or j side; the scalar setup,
              i and j stages are printed; the scalar values the pair stage reads
              are each kept in a lane buffer or broadcast; the pair values that
              differ between i-particles get one copy per unrolled i-vector
  shapes      i-parallel blocks of U vectors, the single-vector tail, and the
              j-parallel shape (few i-particles: j-particles in lanes, a mask on
              the last vector, reduced across lanes), each with its buffers,
              accumulators, pair statements (products folded into fused
              accumulations) and the combine into FORCE
  j-blocking  j-particles are staged a block at a time (j_block_bytes)

The ISA module provides the operation table OPS ({(opcode, Scalar): format},
formatted with `fields()`) and the hooks below, each given the kernel's
`EmitState` and returning a C++ expression (or, for multi-step refinements, a
list of `Let`); this module writes every declaration and assignment.

  vtype, mask_type, home, fields     types and table fields
  bcast, buffered, vload, vstore, literal_vec, lane_arg
                                     memory, broadcasts, lane-by-lane arguments
  compare, logic, select, cast, gather, refine, vector_op
                                     the ops (None: run it lane by lane)
  vround, vpow2, select_negative     the pieces of exp and erfc (vmath.py)
  acc_update, can_fuse, reduce_jpar  accumulation
  j_tail_mask, lane_offset, lane_buffer, block_lanes, lane_count, lane_capacity,
  min_lanes, unroll, shape_context   loop-shape sizes (and its template's values)

Class attributes: registers (sizes the unroll), reserved (names the ISA's
template declares), jbuf_pad and tail_predicate (see below), template.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar, NamedTuple

from pik_gen.backends import vmath
from pik_gen.backends.base import Accumulator, Isa, accumulator_of, accumulators, combine, indexed_members, literal
from pik_gen.backends.reference import CMP, Reference, ScalarPrinter
from pik_gen.ir.nodes import Const, Kernel, MemberRef, Op, Reduce, Stage, fresh_name
from pik_gen.types import CXX_SCALAR, Scalar, Type

S = Scalar
WIDE = (S.F64, S.S64, S.U64)
REFINED = ("rsqrt", "rsqrt2", "inv")  # float ops built from an estimate and refinement steps


def ebits(s: Scalar) -> int:
    """Bits of one lane of scalar kind s (F16 lives in F32 lanes, BOOL in 32-bit lanes or integers)."""
    return 64 if s in WIDE else 32


@dataclass(frozen=True)
class Let:
    """`const type name = expr;`: one step of a multi-statement op."""

    type: str
    name: str
    expr: str

    def __str__(self) -> str:
        return f"const {self.type} {self.name} = {self.expr};"


@dataclass
class PairPlan:
    """The ISA-independent split of a kernel for a SIMD loop (names are C++ identifiers)."""

    setup: list[str]           # scalar setup stage
    i_lines: list[str]         # scalar i stage, with the pair stage's EPI/FORCE loads
    pair_ops: list[Op]         # the pair stage without its loads
    ivals: list[str]           # i values the pair stage reads (in lanes or broadcast)
    jvals: list[str]           # j values the pair stage reads
    idep: set[str]             # pair values that differ between i-particles
    nuse: dict[str, int]       # uses of each value in the pair stage
    defs: dict[str, Op]        # the pair op defining each value
    accs: dict[tuple, Accumulator]
    bufs_i: dict[str, str]     # i value -> its lane buffer
    bufs_j: dict[str, str]     # j value -> its buffer of one j block
    bytes_per_j: int           # bytes of j buffers per j-particle (sizes the j block)
    j_fill: list[str]          # scalar j stage + stores into the j buffers
    j_pad: list[str]           # copies of the last j-particle into a padding slot
    svec: dict[str, str]       # setup value -> its broadcast vector
    bcast_setup: list[str]     # the broadcasts of the setup values
    jvec: dict[str, str]       # j value -> its vector in the pair loop
    jdirect: dict[str, str]    # j value -> its member of epj[jb + jj], where every j value is a load (Simd.direct_j)


@dataclass(frozen=True)
class Uarch:
    """One row of an ISA's microarchitecture table (UARCH): what sizes its loop shape."""

    registers: int        # architectural vector registers (ymm/zmm/z)
    fma_pipes: int        # FMA instructions issued per cycle at this width
    fma_latency: int      # cycles
    rsqrt_per_cycle: float  # estimate instructions (rsqrt/rcp) per cycle at this width
    gather_cycles: int    # reciprocal throughput of one full-width gather
    mca: str = ""         # the llvm-mca -mcpu name that models it
    note: str = ""
    f64_divider: bool = False  # AVX2: F64 rsqrt by vsqrtpd/vdivpd even where guarded (a fast divider)
    evex: bool = False    # AVX2 on an AVX-512 CPU: the code may use AVX-512VL's EVEX encoding (ymm16-31),
                          # so `registers` is 32; the variant then requires avx512vl (Isa.variant_check)
    f64_rsqrt14: bool = False  # AVX2 with evex: F64 rsqrt from AVX-512VL's vrsqrt14pd ymm and one
                               # fourth-order step (as the AVX-512 variant), not the F32 estimate/divider
    f64_div_every: int = 0  # F64 rsqrt: copy n-1 of every n unrolled i-vectors by the IEEE divider
                            # (sqrt + div) instead of the estimate, so the divide unit takes a share
                            # of the FMA pipes' work (AVX2 with f64_rsqrt14, AVX-512); 0: never
    split_sums: bool = False  # a chain of three fused products and an addend, a*b + (c*d + (e*f + g)),
                              # as (e*f + g) + (a*b + c*d): one add more (on pipes of their own on AMD
                              # cores) for one FMA latency less on the chain (Simd.split_fma_chains)
    j_copies: tuple[int, int] = (1, 1)  # (F32, F64) kernels: j-particles per iteration of the i-parallel
                                        # block's j loop (V), their copies printed op by op, with one
                                        # i-vector per block (U = 1) where that fits (Simd.j_copies_rule)


class SkipNames(NamedTuple):
    """C++ names of a skipped branch's state (Simd.skip_state, Simd.compacted)."""

    n: str       # vectors tested
    flips: str   # direction changes among them
    last: str    # the last direction
    dense: str   # the branch is unpredictable: run every vector, or compacted
    t: str       # the lanes in the branch
    run: str     # whether the vector runs (the value hidden from g++)
    idx: str     # compacted: the listed j-particles
    na: str      # compacted: how many
    k: str       # compacted: the index into the list


@dataclass
class EmitState:
    """Everything that changes while one kernel is printed, passed to every hook."""

    scalar: ScalarPrinter               # the scalar stages and the lane-by-lane ops
    used: set[str]                      # C++ names taken (fresh_name)
    types: dict[str, Type]              # IR type of every value
    cvals: dict[str, tuple]             # constant -> (value, type), broadcast where used
    lane_bits: int = 32                 # 64 when the pair stage has a 64-bit element
    plan: PairPlan = field(init=False)  # set by Simd.begin once the kernel is split
    vmap: dict[str, str] = field(default_factory=dict)       # value -> its vector in the copy printed
    masks: dict[str, tuple[str, int]] = field(default_factory=dict)  # combined mask -> (expr, lane bits)
    mask_bits: dict[str, int] = field(default_factory=dict)  # mask vector -> its lane bits (AVX2)
    copy: int = 0                       # which of `copies` unrolled i-vectors is printed
    copies: int = 1
    jmask: str | None = None            # "jvalid" while the j-parallel shape is printed
    guard: frozenset[str] = frozenset()  # rsqrt results whose special values the fast body leaves out (guarded)
    fast: bool = False                  # the fast body of a guarded shape is printed
    refining: str = ""                  # the result of the refined op being printed
    region: tuple[str, frozenset[str]] | None = None  # the skipped branch (Simd.skip_region), set by begin
    skip: SkipNames | None = None       # C++ names of its state (Simd.skip_state)
    interleave: bool = False            # the U copies printed op by op (Simd.interleaved), where that fits


@dataclass
class Shape:
    """Printed lines of one loop shape (i-parallel block of U vectors, tail vector, or j-parallel)."""

    U: int
    lanes: str  # i-particles per block, as C++
    i_fill: list[str] = field(default_factory=list)      # scalar i stage + stores into i buffers
    ibuf_decls: list[str] = field(default_factory=list)
    i_vec: list[str] = field(default_factory=list)       # i values as vectors
    acc_init: list[str] = field(default_factory=list)
    j_vec: list[str] = field(default_factory=list)       # j values as vectors (top of the j loop)
    pair: list[str] = field(default_factory=list)
    finish: list[str] = field(default_factory=list)      # accumulators into FORCE
    redo: str = ""                                       # guarded: the C++ test that a sum is not finite
    acc_reset: list[str] = field(default_factory=list)   # guarded: the accumulators back to their identity
    pair_safe: list[str] = field(default_factory=list)   # guarded: the pair body with IEEE special values
    V: int = 1                                           # j-particles per iteration of the main j loop
    compact: SkipNames | None = None                     # skipped branch, compacted passes: their names
    compact_jvec: list[str] = field(default_factory=list)  # Simd.compacted: the j values the first pass reads
    compact_test: list[str] = field(default_factory=list)  # Simd.compacted: the first pass (test, append)
    compact_pair: list[str] = field(default_factory=list)  # Simd.compacted: the second pass (the whole body)
    pair_V: list[str] = field(default_factory=list)      # V > 1: the V copies of the pair body (and their j
                                                         # broadcasts), op by op


def all_cpus() -> list[str]:
    """Every --cpu family of every SIMD ISA."""
    from pik_gen.backends import ISAS
    return sorted({c for cls in ISAS.values() for c in getattr(cls, "UARCH", {})})


def native_cpu(cpuinfo: str | None = None) -> str | None:
    """The --cpu family of the machine pikg-gen runs on, from /proc/cpuinfo (vendor,
    family, model); None (generic) when unknown. Read when the header is generated,
    never by the generated code."""
    if cpuinfo is None:
        try:
            cpuinfo = Path("/proc/cpuinfo").read_text()
        except OSError:
            return None
    field = lambda k: next((ln.split(":", 1)[1].strip() for ln in cpuinfo.splitlines()  # noqa: E731
                            if ln.split(":", 1)[0].strip() == k), "")
    vendor, fam = field("vendor_id"), int(field("cpu family") or 0)
    model = int(field("model") or 0)
    if vendor == "GenuineIntel" and fam == 6:
        return {0x8F: "sapphirerapids", 0xCF: "sapphirerapids", 0xAD: "sapphirerapids", 0x6A: "icelake-server",
                0x6C: "icelake-server", 0x55: "skylake-avx512", 0x3C: "haswell", 0x3F: "haswell", 0x45: "haswell",
                0x46: "haswell", 0x4E: "skylake", 0x5E: "skylake", 0x8E: "skylake", 0x9E: "skylake",
                0xA5: "skylake"}.get(model)
    if vendor == "AuthenticAMD":
        if fam == 0x17:
            return "znver2" if model >= 0x30 else None
        if fam == 0x19:
            return "znver4" if (0x10 <= model < 0x20 or 0x60 <= model < 0x80 or model >= 0xA0) else "znver3"
        if fam == 0x1A:
            return "znver5"
    return None


def const(T: str, name: str, expr: str) -> str:
    return f"const {T} {name} = {expr};"


class Simd(Isa):
    """The SIMD machinery shared by the vector ISAs (see the module docstring)."""

    vector = True
    template = "simd.hpp.j2"
    registers: ClassVar[int] = 16
    reserved: ClassVar[frozenset[str]] = frozenset()  # names the ISA's loop skeleton declares
    j_block_bytes: ClassVar[int] = 16384  # j buffers per block: well inside L1
    jbuf_pad: ClassVar[str] = ""  # extra elements of a j buffer past kJBlock, as C++
    tail_predicate: ClassVar[str | None] = None  # governs the stores of the tail vector
    guard_special: ClassVar[bool] = False  # the ISA has any_nonfinite: guarded rsqrt (see `guarded`)
    direct_j_ok: ClassVar[bool] = False  # the template can broadcast j values straight from epj (see `direct_j`)

    # ------------------------------------------------------------ hooks (see the module docstring)
    def vtype(self, st: EmitState, t: Type) -> str:
        raise NotImplementedError

    def mask_type(self, st: EmitState, bits: int = 32) -> str:
        raise NotImplementedError

    def home(self, s: Scalar) -> Scalar:
        """The scalar kind whose vector instructions (and OPS entries) implement s."""
        return S.F32 if s == S.F16 else s

    def fields(self, st: EmitState, s: Scalar) -> dict:
        """The extra fields of the OPS formats for kind s."""
        return {}

    def bcast(self, st: EmitState, expr: str, s: Scalar) -> str:
        raise NotImplementedError

    def buffered(self, elem: str, s: Scalar) -> str:
        """A lane-buffer element as the scalar `bcast` takes (BOOL is stored as 0 / -1)."""
        return elem

    def literal_vec(self, st: EmitState, value, t: Type) -> str:
        if t.scalar == S.BOOL:
            return self.bcast(st, "true" if value else "false", S.BOOL)
        return self.bcast(st, literal(value, t), t.scalar)

    def vload(self, st: EmitState, ptr: str, s: Scalar) -> str:
        raise NotImplementedError

    def vstore(self, st: EmitState, ptr: str, v: str, s: Scalar, pred: str | None = None) -> str:
        """The store of vector v (of kind s) at ptr, as a C++ expression."""
        raise NotImplementedError

    def compare(self, st: EmitState, op: Op, a: str, b: str) -> str | None:
        raise NotImplementedError

    def logic(self, st: EmitState, opcode: str, a: str, b: str | None) -> str:
        """and/or/not of the mask values a and b (names)."""
        raise NotImplementedError

    def select(self, st: EmitState, m: str, a: str, b: str, t: Type) -> str:
        """m ? a : b, m a mask value name, a and b printed."""
        raise NotImplementedError

    def cast(self, st: EmitState, src: Scalar, dst: Scalar, x: str) -> str | None:
        raise NotImplementedError

    def gather(self, st: EmitState, op: Op, idx: str) -> str | None:
        raise NotImplementedError

    def refine(self, st: EmitState, opcode: str, x: str, s: Scalar, out: str) -> list[Let]:
        """rsqrt, rsqrt2 or inv of float kind s (home) from an estimate: the steps, the last named out."""
        raise NotImplementedError

    def vround(self, st: EmitState, s: Scalar, x: str) -> str:
        """x rounded to the nearest integer (ties to even), float kind s (vmath)."""
        raise NotImplementedError

    def vpow2(self, st: EmitState, s: Scalar, n: str) -> str:
        """2^n for a float vector n of integers with a normal result (vmath: |n| <= 600 F64, 75 F32)."""
        raise NotImplementedError

    def select_negative(self, st: EmitState, s: Scalar, x: str, a: str, b: str) -> str:
        """a where x < 0 (or -0, or a NaN with the sign bit: a and b agree there in vmath), else b."""
        raise NotImplementedError

    def vector_op(self, st: EmitState, op: Op, a: list[str]) -> str | None:
        """An op of the table (None: none, run it lane by lane)."""
        assert op.type is not None
        fmt = self.OPS.get((op.opcode, self.home(op.type.scalar)))
        return None if fmt is None else fmt.format(*a, **self.fields(st, op.type.scalar))

    def acc_update(self, st: EmitState, kind: str, acc: str, v: str, m: str | None, t: Type,
                   fused: tuple[str, str] | None) -> str:
        """The new value of accumulator acc: acc `kind` v (or the product `fused`)
        where mask value m holds."""
        raise NotImplementedError

    def can_fuse(self, masked: bool) -> bool:
        """Whether a product can fold into a (masked) accumulation."""
        return True

    def reduce_jpar(self, st: EmitState, acc: Accumulator) -> list[str]:
        """The j-parallel accumulator (one vector) combined into FORCE: across lanes."""
        t = acc.type
        tmp = fresh_name(st.used, acc.base + "_lanes")
        tot = fresh_name(st.used, acc.base + "_sum")
        return [f"alignas(64) {self.ctype(t.scalar)} {tmp}[{self.lane_buffer(st, 1)}];",
                self.vstore(st, tmp, acc.names[0], t.scalar) + ";",
                f"{self.ctype(t.scalar)} {tot} = {tmp}[0];",
                f"for (int lane = 1; lane < kW; ++lane) {combine(acc.group, tot, tmp + '[lane]')}",
                combine(acc.group, acc.target, self.scaled(acc, tot))]

    def j_tail_mask(self, st: EmitState) -> str:
        """The lanes of the j-parallel vector at jj that hold real j-particles."""
        raise NotImplementedError

    def any_nonfinite(self, st: EmitState, vecs: list[tuple[str, Type]]) -> str:
        """A C++ condition: some lane of some vector (name, type) is inf or NaN (guarded rsqrt)."""
        raise NotImplementedError

    def lane_offset(self, st: EmitState, u: int) -> str:
        """` + <offset of vector u in a lane buffer>` ("" for u = 0)."""
        raise NotImplementedError

    def lane_buffer(self, st: EmitState, U: int) -> str:
        """Elements of a lane buffer for U vectors, as C++."""
        raise NotImplementedError

    def block_lanes(self, U: int) -> str:
        """i-particles of a block of U vectors, as C++ (the template's copy loop)."""
        return f"{U} * kW"

    def lane_capacity(self, st: EmitState) -> str:
        """Elements of a lane scratch buffer, as C++ (the most lanes a vector can have)."""
        raise NotImplementedError

    def lane_count(self, st: EmitState) -> str:
        """Lanes of one vector, as C++."""
        raise NotImplementedError

    def min_lanes(self, st: EmitState) -> int:
        """The lanes a j block holds at least (the most lanes of one vector)."""
        raise NotImplementedError

    def unroll(self, st: EmitState, n_acc: int) -> int:
        """i-vectors per block."""
        raise NotImplementedError

    def shape_context(self, st: EmitState) -> dict:
        """The template values of the ISA's loop shape (lane counts...)."""
        return {}

    # ------------------------------------------------------------ register-pressure model
    UARCH: ClassVar[dict[str, Uarch]] = {}
    default_cpu: ClassVar[str] = ""
    masks_in_vregs: ClassVar[bool] = False  # AVX2: a BOOL is a vector register (AVX-512, SVE: mask/predicate registers)
    max_unroll: ClassVar[int] = 4
    # extra vector temporaries an op needs beyond its result while it is computed
    OP_TEMPS: ClassVar[dict[str, int]] = {"rsqrt": 2, "rsqrt2": 2, "inv": 2, "exp": 3, "erfc": 4}

    def uarch(self) -> tuple[str, Uarch]:
        """The microarchitecture family the code is sized for: --cpu, else the ISA's default."""
        name = self.options.cpu or self.default_cpu
        if name not in self.UARCH:
            if name in all_cpus():  # a family of another ISA (--target auto --cpu znver5): this ISA's generic row
                name = self.default_cpu
            else:
                raise ValueError(f"unknown --cpu '{name}'; choose one of {', '.join(all_cpus())}")
        return name, self.UARCH[name]

    def live_vectors(self, st: EmitState, U: int, interleaved: bool = False, V: int = 1) -> int:
        """Vector registers the j loop of a block of U i-vectors needs at its peak: the
        loop invariants (U copies of the i values and of the accumulators, the
        broadcast setup values) plus the most temporaries live at once when the body
        runs in the order it is printed (the j broadcasts first, then copy 0, 1, ...;
        interleaved: the values that do not depend on i, then op by op for copy 0, 1,
        ..., as Simd.interleaved prints them; a value lives from its definition to its
        last use; a refined or vmath op needs OP_TEMPS more while it runs). Constants
        are not counted: the compiler takes them as memory operands from .rodata, which
        is no stack traffic. V > 1 (with U = 1): V j-particles per iteration, op by op
        for j-copy 0, 1, ..., V-1, each j value broadcast just before the first op that
        reads it, as Simd.pair_lines_j prints them; every pair value has V copies."""
        plan = st.plan
        invariant = U * (len(plan.ivals) + len(plan.accs)) + len(plan.svec)
        inv = set(plan.ivals) | set(plan.svec)
        vreg = lambda x: (x not in st.cvals and x not in inv  # noqa: E731
                          and (self.masks_in_vregs or st.types[x].scalar != S.BOOL))
        seq: list[tuple[tuple | None, list[tuple], int]] = [(("j", a), [], 0) for a in plan.jvals if vreg(a)]
        shared = lambda op: op.opcode != "accum" and op.result not in plan.idep  # noqa: E731
        if V > 1:
            assert U == 1
            seq = []
            order = [(v, op) for op in plan.pair_ops for v in range(V)]
            first = self.j_first_use(st)
            index = {id(op): n for n, op in enumerate(plan.pair_ops)}
        elif interleaved:
            order = [(0, op) for op in plan.pair_ops if shared(op)] + \
                    [(u, op) for op in plan.pair_ops if not shared(op) for u in range(U)]
        else:
            order = [(u, op) for u in range(U) for op in plan.pair_ops if u == 0 or not shared(op)]
        for u, op in order:
            if V > 1:
                name = lambda x: ("j", u, x) if x in plan.jvals else (u, x)  # noqa: E731
                n = index[id(op)]
                seq += [(("j", u, a), [], 0) for a in plan.jvals if vreg(a) and first.get(a) == n]
            else:
                name = lambda x: ("j", x) if x in plan.jvals else (u if x in plan.idep else 0, x)  # noqa: E731
            uses = [name(x) for x in op.args if vreg(x)]
            d = None if op.opcode == "accum" or not vreg(op.result) else name(op.result)
            seq.append((d, uses, self.OP_TEMPS.get(op.opcode, 0)))
        last: dict[tuple, int] = {}
        for n, (_d, uses, _t) in enumerate(seq):
            for x in uses:
                last[x] = n
        live: set[tuple] = set()
        peak = 0
        for n, (d, uses, extra) in enumerate(seq):
            if d is not None:
                live.add(d)
            peak = max(peak, len(live) + extra)
            live -= {x for x in uses if last.get(x) == n}
            if d is not None and d not in last:
                live.discard(d)
        return invariant + peak

    def ops_per_copy(self, st: EmitState) -> int:
        """Vector instructions of one i-vector copy of the pair stage (refinements as 4)."""
        plan = st.plan
        return sum(4 if op.opcode in self.OP_TEMPS else 1 for op in plan.pair_ops
                   if op.result in plan.idep or op.opcode == "accum")

    def unroll_rule(self, st: EmitState) -> int:
        """i-vectors per block (U), from the typed IR and the microarchitecture table:
          U_fit  the largest U (powers of two up to max_unroll) whose live_vectors fit
                 the family's registers: no spill in the j loop;
          U_lat  the smallest U whose U x ops_per_copy vector instructions cover four
                 FMA latencies of all FMA pipes (4 x fma_latency x fma_pipes): the
                 independent work per j-particle that keeps the pipes busy behind the
                 loop-carried accumulator chains (calibrated with llvm-mca on the hot
                 loops, docs/simd.md: gravity, 20 instructions per copy, runs 11 %
                 fewer cycles per interaction at U = 2 than at U = 1 on Skylake-SP,
                 Ice Lake-SP and Sapphire Rapids when both fit; Lennard-Jones, 50, gains
                 nothing from U = 2);
          U = min(U_fit, U_lat), at least 1. Nothing is timed."""
        _name, ua = self.uarch()
        fit = 1
        u = 2
        while u <= self.max_unroll:
            if self.live_vectors(st, u) <= ua.registers:
                fit = u
            u *= 2
        need = 4 * ua.fma_latency * ua.fma_pipes
        lat = 1
        while lat < self.max_unroll and lat * self.ops_per_copy(st) < need:
            lat *= 2
        return max(1, min(fit, lat))

    def j_copies_rule(self, st: EmitState) -> int:
        """j-particles per iteration of the i-parallel block's j loop (V), printed op by
        op as V copies of the pair body beside one i-vector (U = 1): the row's j_copies
        for the kernel's precision (F64 where the pair stage has a 64-bit element), where
        it is above 1, no `#pragma unroll` fixes U, the kernel has no skipped branch
        (its state is per j-particle) and live_vectors(st, 1, V=V) fits the registers;
        else 1. The i-vector copies share the j broadcasts, the j copies share the i
        values: where a broadcast is a memory operand at no cost (EVEX embedded
        broadcast) and the copies' long chains (r^2, rsqrt, its refinement, the sums)
        need independent work beside them, j copies buy it with fewer registers. The
        rows that ask are measured (docs/bench-kernels.md, 2026-12-07 fourth session);
        nothing is timed. Options.j_copies overrides it (tests)."""
        if self.options.j_copies is not None:
            return self.options.j_copies
        if self.options.unroll is not None or st.region is not None:
            return 1
        V = self.uarch()[1].j_copies[1 if st.lane_bits == 64 else 0]
        if V > 1 and self.live_vectors(st, 1, V=V) > self.uarch()[1].registers:
            return 1
        return V

    # ------------------------------------------------------------ values
    def ctype(self, s: Scalar) -> str:
        """C++ element type of a lane buffer."""
        return "std::int32_t" if s == S.BOOL else "float" if s == S.F16 else CXX_SCALAR[s]

    def store_scalar(self, st: EmitState, name: str) -> str:
        """Scalar value `name` as stored in its lane buffer (BOOL as 0 / -1)."""
        return f"-static_cast<std::int32_t>({name})" if st.types[name].scalar == S.BOOL else name

    def argv(self, st: EmitState, name: str) -> str:
        """Value `name` as a vector expression (constants broadcast where used)."""
        if name in st.cvals:
            value, t = st.cvals[name]
            return self.literal_vec(st, value, t)
        if name in st.masks:
            return st.masks[name][0]
        return st.vmap.get(name, name)

    def mb(self, st: EmitState, name: str) -> int:
        """Lane width (32 or 64 bits) of mask value `name`."""
        if name in st.masks:
            return st.masks[name][1]
        return st.mask_bits.get(st.vmap.get(name, name), 32)

    def scaled(self, acc: Accumulator, v: str) -> str:
        """A finished sum times its pending power-of-two factor (defer_scale)."""
        return v if acc.scale == 1.0 else f"{literal(acc.scale, Type(acc.type.scalar))} * {v}"

    def jblock(self, min_lanes: int, bytes_per_j: int) -> int:
        """j-particles per buffered block: a power of two filling j_block_bytes, at
        least one vector of `min_lanes` and at most 4096."""
        return 1 << max(int(math.log2(min_lanes)), min(12, int(math.log2(self.j_block_bytes / bytes_per_j))))

    # ------------------------------------------------------------ one op
    def vec_op(self, st: EmitState, op: Op) -> list[str]:
        """The statements computing pair op `op` on all lanes."""
        assert op.type is not None
        t, s, oc = op.type, op.type.scalar, op.opcode
        r = st.vmap.get(op.result, op.result)
        a = [self.argv(st, x) for x in op.args]
        st.types[op.result] = t
        expr: str | None = None
        bits = 32
        if oc in CMP:
            expr = self.compare(st, op, a[0], a[1])
            if expr is not None:
                bits = ebits(st.types[op.args[0]].scalar)
        elif oc in ("and", "or", "not"):
            expr = self.logic(st, oc, op.args[0], op.args[1] if len(op.args) > 1 else None)
            bits = self.mb(st, op.args[0])
        elif oc == "select" and self.masked_pattern(st, op) is not None:
            kind, x, y = self.masked_pattern(st, op)  # type: ignore[misc]
            expr = self.masked_arith(st, kind, op.args[0], self.argv(st, x), self.argv(st, y), t)
        elif oc == "select":
            expr = self.select(st, op.args[0], a[1], a[2], t)
            if s == S.BOOL:
                bits = self.mb(st, op.args[0])
        elif oc in REFINED and s.is_float:
            st.refining = op.result
            return [str(x) for x in self.refine(st, oc, a[0], self.home(s), r)]
        elif oc in vmath.FUNCTIONS and s.is_float:
            return [str(x) for x in vmath.FUNCTIONS[oc](self, st, a[0], self.home(s), r)]
        elif oc == "cast":
            expr = self.cast(st, st.types[op.args[0]].scalar, s, a[0])
        elif oc == "table":
            expr = self.gather(st, op, a[0])
        elif s != S.BOOL:
            expr = self.vector_op(st, op, a)
        if expr is None:
            return self.lanewise(st, op, r)
        if s == S.BOOL:
            st.mask_bits[r] = bits
            return [const(self.mask_type(st, bits), r, expr)]
        return [const(self.vtype(st, t), r, expr)]

    def lanewise(self, st: EmitState, op: Op, r: str) -> list[str]:
        """Per-lane fallback for an op without a vector instruction (exp, log, pow...):
        store the arguments, apply the reference's scalar expression to every lane,
        load the result; exactly as accurate as the reference."""
        assert op.type is not None
        lines, elems = [], []
        cap = self.lane_capacity(st)
        for n, x in enumerate(op.args):
            xs, v = self.lane_arg(st, x)
            buf = fresh_name(st.used, f"{r}_a{n}")
            lines.append(f"alignas(64) {self.ctype(xs)} {buf}[{cap}];")
            lines.append(self.vstore(st, buf, v, xs) + ";")
            elems.append(f"({buf}[lane] != 0)" if xs == S.BOOL else f"{buf}[lane]")
        s = op.type.scalar
        out = fresh_name(st.used, f"{r}_r")
        st.scalar.types.update({x: st.types[x] for x in op.args})
        e = st.scalar.expr(op, elems)
        if s == S.BOOL:
            e = f"({e}) ? -1 : 0"
            st.mask_bits[r] = 32
        elif s == S.F16:
            e = f"static_cast<float>({e})"
        lines.append(f"alignas(64) {self.ctype(s)} {out}[{cap}];")
        lines.append(f"for (int lane = 0; lane < {self.lane_count(st)}; ++lane) {out}[lane] = {e};")
        lines.append(const(self.vtype(st, op.type), r, self.vload(st, out, s)))
        return lines

    def lane_arg(self, st: EmitState, x: str) -> tuple[Scalar, str]:
        """Argument x of a lane-by-lane op: the scalar kind it is stored as, and its vector."""
        return self.home(st.types[x].scalar), self.argv(st, x)

    # ------------------------------------------------------------ split
    def begin(self, k: Kernel) -> EmitState:
        """The emit state of kernel k, with its SIMD split (st.plan)."""
        if self.uarch()[1].split_sums:
            k = split_fma_chains(k)
        indexed = indexed_members(k)
        ref = ScalarPrinter(Reference.OPS, indexed)
        st = EmitState(scalar=ref, used=set(k.names()) | self.reserved, types={}, cvals={})
        for op in k.all_ops():
            if op.opcode == "const":
                assert isinstance(op.attr, Const)
                st.cvals[op.result] = (op.attr.value, op.type)
            if op.result:
                st.types[op.result] = op.type  # type: ignore[assignment]
        pair_types = {op.type.scalar for op in k.pair if op.type is not None}
        pair_types |= {st.types[a].scalar for op in k.pair for a in op.args}
        st.lane_bits = max([ebits(s) for s in pair_types if s != S.BOOL] or [32])

        # Loads in the pair stage read one particle: they belong to the i or j side.
        pair_loads = [op for op in k.pair if op.opcode == "load"]
        pair_ops = [op for op in k.pair if op.opcode != "load"]
        i_ops = list(k.i) + [op for op in pair_loads if op.attr.role != "EPJ"]  # type: ignore[union-attr]
        j_ops = list(k.j) + [op for op in pair_loads if op.attr.role == "EPJ"]  # type: ignore[union-attr]
        setup = ref.statements(k.setup)
        i_lines = ref.statements(i_ops)
        j_lines = ref.statements(j_ops)
        stage_of = {op.result: stg for stg, ops in (("setup", k.setup), ("i", i_ops), ("j", j_ops)) for op in ops}
        uses = list(dict.fromkeys(a for op in pair_ops for a in op.args if a in stage_of and a not in st.cvals))
        ivals = [a for a in uses if stage_of[a] == "i"]
        jvals = [a for a in uses if stage_of[a] == "j"]
        svals = [a for a in uses if stage_of[a] == "setup"]

        # pair values that differ between i-particles get one copy per unrolled vector
        idep = set(ivals)
        for op in pair_ops:
            if op.result and any(x in idep for x in op.args):
                idep.add(op.result)
        nuse: dict[str, int] = {}
        for op in pair_ops:
            for x in op.args:
                nuse[x] = nuse.get(x, 0) + 1

        accs = accumulators(k, st.types, ref.member_access)
        bufs_i = {a: fresh_name(st.used, f"{a}_ib") for a in ivals}
        bufs_j = {a: fresh_name(st.used, f"{a}_jb") for a in jvals}
        svec = {a: fresh_name(st.used, f"{a}_v") for a in svals}
        jvec = {a: fresh_name(st.used, f"{a}_v") for a in jvals}
        st.plan = PairPlan(
            setup=setup, i_lines=i_lines, pair_ops=pair_ops,
            ivals=ivals, jvals=jvals, idep=idep, nuse=nuse,
            defs={op.result: op for op in pair_ops if op.result}, accs=accs,
            bufs_i=bufs_i, bufs_j=bufs_j,
            bytes_per_j=sum(ebits(st.types[a].scalar) // 8 for a in jvals) or 4,
            j_fill=j_lines + [f"{b}[jj] = {self.store_scalar(st, a)};" for a, b in bufs_j.items()],
            j_pad=[f"{b}[jj] = {b}[jn - 1];" for b in bufs_j.values()],
            svec=svec,
            bcast_setup=[const(self.vtype(st, st.types[a]), v, self.bcast(st, a, st.types[a].scalar))
                         for a, v in svec.items()],
            jvec=jvec, jdirect={},
        )
        st.region = self.skip_region(st)
        st.plan.jdirect = self.direct_j(st, j_ops, ref)
        if st.region is not None:
            st.skip = SkipNames(*(fresh_name(st.used, f"skip_{n}") for n in SkipNames._fields))
        return st

    def direct_j(self, st: EmitState, j_ops: list[Op], ref: ScalarPrinter) -> dict[str, str]:
        """The j values an i-parallel block may broadcast straight from the particles.

        The j buffers turn the j side into a structure of arrays once per j block: the
        j-parallel shape loads whole vectors of it, and an EPJ local is computed there
        once per j-particle. An i-parallel block broadcasts one j value at a time, which
        a load from the particle array does as well, so where every j value the pair
        stage reads is a member load (no EPJ local) the block reads `epj[jb + jj]` and
        the fill runs only for the j-parallel shape. Whether a member has the kernel's
        type is known only to the compiler: the template declares `kJDirect`
        (`direct_j_check`, in C++11's type traits, as the rest of the header keeps to),
        and a member of another type (a double position for an F32 kernel) keeps the
        buffer, whose fill converts it once per j-particle. The values and their order
        of operations are the same either way. Not with skipped branches (their state
        sits beside the buffers), BOOL or F16 values."""
        plan = st.plan
        if not self.direct_j_ok or st.region is not None or not plan.jvals:
            return {}
        defs = {op.result: op for op in j_ops if op.result}
        out: dict[str, str] = {}
        for a in plan.jvals:
            op = defs.get(a)
            if op is None or op.opcode != "load" or st.types[a].scalar in (S.BOOL, S.F16):
                return {}
            assert isinstance(op.attr, MemberRef)
            access = ref.member_access(op.attr)
            assert access.startswith("epj[j]")
            out[a] = access[len("epj[j]"):]
        return out

    def direct_j_check(self, st: EmitState) -> str:
        """The C++ constant expression: every member of `jdirect` has its value's type."""
        tests = dict.fromkeys(
            f"std::is_same<std::decay<decltype(epj[0]{m})>::type, {CXX_SCALAR[st.types[a].scalar]}>::value"
            for a, m in st.plan.jdirect.items())
        return " &&\n        ".join(tests)

    def bind(self, st: EmitState, ivec: dict[str, list[str]], u: int, U: int) -> None:
        """Point the vector names at copy u of U of the i-dependent values."""
        plan = st.plan
        st.copy, st.copies = u, U
        st.masks = {}
        st.vmap = dict(plan.svec)
        st.vmap.update(plan.jvec)
        for a in plan.ivals:
            st.vmap[a] = ivec[a][u]
        # Names printed as they are beside the copies: the broadcast, j and i vectors and
        # the pair values that do not depend on i.
        taken = set(st.vmap.values()) | {op.result for op in plan.pair_ops if op.result and op.result not in plan.idep}
        for name in plan.idep - set(plan.ivals):
            st.vmap[name] = self.copy_name(name, u, taken) if U > 1 else name

    @staticmethod
    def copy_name(name: str, u: int, taken: set[str]) -> str:
        """The C++ name of copy u of an i-dependent value: name_u, unless that is another
        value's name (the CSE temporary heat_1 beside copy 1 of heat), then name_u_2, ..."""
        cand, k = f"{name}_{u}", 1
        while cand in taken:
            k += 1
            cand = f"{name}_{u}_{k}"
        return cand

    # ------------------------------------------------------------ guarded rsqrt
    # Ops through which an inf or NaN operand always gives an inf or NaN result
    # (IEEE 754: NaN in -> NaN out; inf in -> inf or NaN: inf * 0, inf - inf), for
    # every value of the other operands. `div` only through its dividend (x / inf = 0).
    PROPAGATES: ClassVar[frozenset[str]] = frozenset(
        {"add", "sub", "mul", "madd", "msub", "nmadd", "nmsub", "neg", "abs", "sqrt", "cast"})

    def guarded(self, st: EmitState) -> tuple[frozenset[str], list[tuple]]:
        """The rsqrt/rsqrt2 of the pair stage whose IEEE special-value fix, the
        `max(y P2, y0)` of _rsqrt_steps (one instruction per pair), the common case
        can skip, and the accumulators that guard them.

        Without the fix the refined value is y P2 = y0 P2(1 - x y0^2), which equals
        the fixed one for every x whose estimate y0 is finite and nonzero and x y0^2
        finite (a positive normal x), and is NaN or -inf otherwise (x = 0, subnormal,
        inf: 0 * inf in h). An rsqrt qualifies when every use of its result, and of
        every value computed from it, is an op of PROPAGATES (float results), the
        dividend of a `div`, or the value (not the mask) of an add/sub accumulation
        into a float sum, and at least one such accumulation exists. Then a pair where
        the unfixed value differs from the fixed one makes every sum it reaches inf or
        NaN (and a sum that is inf or NaN stays so under further +/-), while a pair
        masked out of every sum does not matter either way. So the shape runs the fast
        body over a j block, tests those sums once (`any_nonfinite`), and only where
        one is not finite runs the block again from the identity with the fix: the
        result is the fixed kernel's for every input, at the cost of the test per
        i-vector and j block (and the second pass where inputs are special)."""
        plan = st.plan
        if not self.guard_special:
            return frozenset(), []
        guard: set[str] = set()
        reached: dict[int, Accumulator] = {}
        for r in plan.pair_ops:
            if r.opcode not in ("rsqrt", "rsqrt2") or r.type is None or not r.type.scalar.is_float:
                continue
            taint, accs, ok = {r.result}, {}, True
            for op in plan.pair_ops:
                hit = [x in taint for x in op.args]
                if not any(hit):
                    continue
                if op.opcode == "accum":
                    assert isinstance(op.attr, Reduce)
                    acc = accumulator_of(plan.accs, op)
                    if op.attr.kind not in ("add", "sub") or any(hit[1:]) or not acc.type.scalar.is_float:
                        ok = False
                        break
                    accs[id(acc)] = acc
                    continue
                flt = op.type is not None and op.type.scalar.is_float
                if flt and (op.opcode in self.PROPAGATES or (op.opcode == "div" and not hit[1])):
                    taint.add(op.result)
                    continue
                ok = False
                break
            if ok and accs:
                guard.add(r.result)
                reached.update(accs)
        return frozenset(guard), list(reached.values())

    premask_ok: ClassVar[bool] = False  # masked sums of products as fma(a & m, b, acc) in a guarded fast body

    def premasked(self, st: EmitState, jmask: str | None) -> list[Accumulator]:
        """The sums that a guarded fast body updates as fma(a & m, b, acc) (AVX2):
        masked add/sub accumulations of a float product a * b with no other use
        (`fuses`). Where m is clear, (a & m) b = 0 * b is 0, the sum unchanged, unless
        b is inf or NaN: then the sum turns NaN, which the guard's test after the j
        block catches and the redo pass computes with the exact masked form
        (and(a * b, m) then add). Where m holds it is a * b with one rounding (FMA)."""
        if not (self.premask_ok and self.guard_special):
            return []
        plan = st.plan
        safe = self.finite_values(st)
        out: dict[int, Accumulator] = {}
        for op in plan.pair_ops:
            if op.opcode != "accum" or not (len(op.args) > 1 or jmask is not None):
                continue
            assert isinstance(op.attr, Reduce)
            dv = plan.defs.get(op.args[0])
            if (op.attr.kind in ("add", "sub") and dv is not None and dv.opcode == "mul"
                    and plan.nuse.get(dv.result) == 1 and dv.type is not None and dv.type.scalar.is_float
                    and any(a in safe for a in dv.args)):
                acc = accumulator_of(plan.accs, op)
                out[id(acc)] = acc
        return list(out.values())

    SAFE_OPS: ClassVar[frozenset[str]] = frozenset(
        {"add", "sub", "mul", "madd", "msub", "nmadd", "nmsub", "neg", "abs", "select", "min", "max", "floor", "cast",
         "eq", "ne", "lt", "gt", "le", "ge", "and", "or", "not"})

    def finite_values(self, st: EmitState) -> set[str]:
        """Pair values that are finite whenever the particles and parameters are (no
        division, rsqrt, inv, sqrt, exp, ...; overflow aside): the operand b of a
        premasked fma(a & m, b, acc) is taken from them, so that a masked-out pair (the
        self pair's 1/r^2 = inf) does not send every block to the redo pass. Only a
        matter of speed: the guard's test keeps every result right whatever b is."""
        plan = st.plan
        safe = set(plan.ivals) | set(plan.jvals) | set(plan.svec) | set(st.cvals)
        for op in plan.pair_ops:
            if op.result and op.opcode in self.SAFE_OPS and all(a in safe for a in op.args):
                safe.add(op.result)
        return safe

    # ------------------------------------------------------------ shapes
    def acc_identity(self, st: EmitState, acc: Accumulator) -> str:
        """The identity of an accumulator's group, as a vector."""
        t = acc.type
        if not t.scalar.is_float and acc.group in ("max", "min"):
            lim = "lowest" if acc.group == "max" else "max"
            return self.bcast(st, f"std::numeric_limits<{CXX_SCALAR[t.scalar]}>::{lim}()", t.scalar)
        return self.literal_vec(st, {"sum": 0, "prod": 1, "max": -math.inf, "min": math.inf}[acc.group], t)

    def acc_init(self, st: EmitState, U: int) -> list[str]:
        """Names the U copies of every accumulator and declares them at the identity of their group."""
        lines = []
        for acc in st.plan.accs.values():
            acc.names = [fresh_name(st.used, acc.base + (f"_{u}" if U > 1 else "")) for u in range(U)]
            iv = self.acc_identity(st, acc)
            lines += [f"{self.vtype(st, acc.type)} {n} = {iv};" for n in acc.names]
        return lines

    def combined_mask(self, st: EmitState, user: str | None, jmask: str | None) -> str | None:
        """The mask `user && jmask` as a value name (printed where used)."""
        if user is None or jmask is None:
            return user or jmask
        name = f"{user}&&{jmask}"
        st.masks[name] = (self.logic(st, "and", user, jmask), self.mb(st, user))
        return name

    masked_arith_ok: ClassVar[bool] = False  # the ISA has masked_arith (select of x +- y and x in one step)

    def masked_pattern(self, st: EmitState, op: Op) -> tuple[str, str, str] | None:
        """(kind, x, y) when `op` is select(m, x + y, x) or select(m, x - y, x) (also
        y + x) of floats whose sum is used only there: `if c: w = w + l` in the source
        (the minimum image). The ISA then adds y only where m holds, one instruction
        (AVX-512 mask_add) or two (AVX2 and + sub) instead of the op and a blend."""
        plan = st.plan
        if not self.masked_arith_ok or op.opcode != "select" or op.type is None or not op.type.scalar.is_float:
            return None
        _m, a, b = op.args
        d = plan.defs.get(a)
        if d is None or d.opcode not in ("add", "sub") or plan.nuse.get(a) != 1 or d.type != op.type:
            return None
        if d.args[0] == b:
            return d.opcode, b, d.args[1]
        if d.opcode == "add" and d.args[1] == b:
            return "add", b, d.args[0]
        return None

    def folded_into_select(self, st: EmitState, op: Op) -> bool:
        """True when the add/sub `op` is printed by its only use, a masked_pattern select."""
        plan = st.plan
        if op.opcode not in ("add", "sub") or plan.nuse.get(op.result) != 1:
            return False
        return any(use.opcode == "select" and use.args[1] == op.result and self.masked_pattern(st, use) is not None
                   for use in plan.pair_ops)

    def masked_arith(self, st: EmitState, kind: str, m: str, x: str, y: str, t: Type) -> str:
        """x kind y where mask value m holds, else x (x, y printed; exactly select's result)."""
        raise NotImplementedError

    def fuses(self, st: EmitState, op: Op) -> bool:
        """True when the product `op` folds into its only use, an add/sub accumulation."""
        plan = st.plan
        if op.opcode != "mul" or plan.nuse.get(op.result) != 1 or op.type is None or not op.type.scalar.is_float:
            return False
        for use in plan.pair_ops:
            if use.opcode == "accum" and use.args[0] == op.result:
                assert isinstance(use.attr, Reduce)
                masked = len(use.args) > 1 or st.jmask is not None
                pre = st.fast and self.premask_ok and any(a in self.finite_values(st) for a in op.args)
                return use.attr.kind in ("add", "sub") and (self.can_fuse(masked) or pre)
        return False

    # ------------------------------------------------------------ skipped branches
    skip_ok: ClassVar[bool] = False  # the ISA has any_lane (skipped branches)
    skip_min_ops: ClassVar[int] = 8  # ops a skipped branch must hold (0: never skip); see skip_region

    def any_lane(self, st: EmitState, m: str) -> str:
        """An int-valued C++ expression, nonzero when mask value m holds in some lane."""
        raise NotImplementedError

    def skip_region(self, st: EmitState) -> tuple[str, frozenset[str]] | None:
        """(m, inner) when the pair body can be skipped for a vector of pairs where the
        mask value m holds in no lane: every accumulation is masked by m (directly or
        by an `and` with m, an `if` around them in the source), so such a vector
        changes no sum. `inner` is the pair values computed only for those
        accumulations (every use is an accumulation or another inner value), which
        the shape prints under `if (any lane of m)`; m and what it is computed from
        stay outside. The results are those of the blended body bit for bit: a lane
        outside m keeps its sum either way.

        Cost and rule: the test is one mask test and a branch per vector (AVX-512
        `kortest`, AVX2 `vmovmskps`), no FP-pipe work. The branch is printed when
        `inner` holds at least skip_min_ops ops. Where lanes are coherent (particles in
        tree order: a j beyond the cut-off of a whole i-vector, a candidate beyond the
        support of a whole group) vectors skip or run in long runs and the branch is
        predicted; in random order its direction changes at random and every
        misprediction costs more than the skip saves (Lennard-Jones at 7 % of the pairs
        within the cut-off: 0.53x the blended loop, Zen 4). So the loop counts how often
        the direction changes (skip_state): an i-vector whose predecessors changed it in
        more than 1 of skip_flip_limit vectors runs every vector (the test stays, always
        true, so predicted), and the counts keep being taken; where compact_ok (AVX2,
        AVX-512) it runs the compacted passes instead, from 1 in compact_flip_limit
        (Simd.compacted)."""
        plan = st.plan
        if self.options.blend or self.skip_min_ops <= 0 or not self.skip_ok:
            return None
        accs = [op for op in plan.pair_ops if op.opcode == "accum"]
        if not accs or any(len(op.args) < 2 for op in accs):
            return None

        def implied(m: str) -> list[str]:  # m, and every mask m is an `and` of, recursively
            out, todo = [], [m]
            while todo:
                x = todo.pop(0)
                if x not in out:
                    out.append(x)
                    d = plan.defs.get(x)
                    if d is not None and d.opcode == "and":
                        todo += list(d.args)
            return out

        common: list[str] | None = None
        for op in accs:
            imp = implied(op.args[1])
            common = imp if common is None else [x for x in common if x in imp]
        common = [x for x in common or [] if x in plan.defs]
        if not common:
            return None
        m = next((x for x in common if all(y in implied(x) for y in common)), common[0])
        outer = self.computed_from(st, m)
        users: dict[str, list[Op]] = {}
        for op in plan.pair_ops:
            for x in op.args:
                users.setdefault(x, []).append(op)
        inner: set[str] = set()
        for op in reversed(plan.pair_ops):
            if op.opcode == "accum" or not op.result or op.result in outer:
                continue
            us = users.get(op.result, [])
            if us and all(u.opcode == "accum" or u.result in inner for u in us):
                inner.add(op.result)
        if len(inner) < self.skip_min_ops:
            return None
        return m, frozenset(inner)

    @staticmethod
    def computed_from(st: EmitState, m: str) -> set[str]:
        """The pair values m is computed from, m included."""
        out, todo = set(), [m]
        while todo:
            x = todo.pop()
            if x in st.plan.defs and x not in out:
                out.add(x)
                todo += list(st.plan.defs[x].args)
        return out

    skip_flip_limit: ClassVar[int] = 3  # run every vector where over 1/limit of the recent tests changed direction
    compact_ok: ClassVar[bool] = True  # the unpredictable mode runs compacted (Simd.compacted)
    compact_flip_limit: ClassVar[int] = 8  # ... compacted where over 1/limit changed direction (compact_ok)

    def set_compacted(self, st: EmitState, sh: Shape, ivec: dict[str, list[str]], U: int, kind: str) -> None:
        """The compacted passes of an i-parallel shape with a skipped branch (Simd.compacted)."""
        if st.region is None or not self.compact_ok or kind == "jpar":
            return
        sh.compact = st.skip
        sh.compact_test, sh.compact_pair = self.compacted(st, ivec, U)
        # the first pass broadcasts only the j values its test reads
        need = self.computed_from(st, st.region[0])
        read = {x for op in st.plan.pair_ops if op.result in need for x in op.args}
        sh.compact_jvec = [line for a, line in zip(st.plan.jvals, sh.j_vec) if a in read]

    def compacted(self, st: EmitState, ivec: dict[str, list[str]], U: int) -> tuple[list[str], list[str]]:
        """The two passes a block with a skipped branch runs where the branch is
        unpredictable (skip_state's count: over 1 in compact_flip_limit tests changed
        direction), instead of every vector: the first computes the test for every
        j-particle and appends its index to a list (no branch: the index is written
        and the count advances by the test); the second runs the whole pair body, the
        branch's inner part blended by its mask as without the branch, for the listed
        j-particles in order. A j-particle with no lane in the branch changes no sum, so
        the sums are those of every vector, bit for bit. It pays where the branch holds
        few of the vectors and they come in random order (Lennard-Jones with the atoms
        shuffled: about 1 in 6 of the AVX2 vectors, 1 in 3 of the AVX-512 ones); the
        first pass repeats the ops the test needs, which costs where most vectors are
        in the branch, but then its direction changes seldom and the branch is taken.
        Returns (first pass, second pass) lines; the second pass reads `jj` as usual."""
        plan = st.plan
        test = self.pair_lines(st, ivec, U, None, test_only=True)
        full = self.interleaved(st, ivec, U, None, plan.pair_ops)
        return test, full

    def skip_state(self, st: EmitState) -> tuple[list[str], list[str]]:
        """The skipped branch's bookkeeping: declarations once per call (vectors tested
        and direction changes, halved at every i-vector so that recent ones weigh most;
        the last direction; the compacted passes' index list) and the lines at the top of
        an i-vector's j loop (whether it runs every vector or, where compact_ok, compacted). The results do not depend on it: both ways give the blended
        sums bit for bit. Only where st.region is set (its names come from begin)."""
        assert st.skip is not None
        n, flips, last, dense, idx = st.skip.n, st.skip.flips, st.skip.last, st.skip.dense, st.skip.idx
        decls = [f"int {n} = 0, {flips} = 0;  // vectors tested, direction changes of the skipped branch (skip_state)",
                 f"unsigned {last} = 1u;"]
        if self.compact_ok:
            decls.append(f"int {idx}[kJBlock];  // the j-particles in the branch (Simd.compacted)")
        limit, mode = (self.compact_flip_limit, "compacted") if self.compact_ok else (self.skip_flip_limit, "run every vector")
        top = [f"const unsigned {dense} = {limit} * {flips} > {n} ? ~0u : 0u;  // unpredictable: {mode}",
               f"{n} >>= 1;", f"{flips} >>= 1;"]
        return decls, top

    def pair_lines(self, st: EmitState, ivec: dict[str, list[str]], U: int, jmask: str | None,
                   test_only: bool = False) -> list[str]:
        """The pair body of a block; with a skipped branch, the test and `if` around its
        inner part. test_only: the first pass of Simd.compacted instead, the test and the
        index of the j-particle appended where some lane is in the branch."""
        plan = st.plan
        st.jmask = jmask
        out: list[str] = []
        skip = st.region
        if skip is None:
            out += self.interleaved(st, ivec, U, jmask, plan.pair_ops)
        else:
            m, inner = skip
            tests: list[str] = []
            if test_only:  # only m and what it is computed from
                need = self.computed_from(st, m)
                first = [op for op in plan.pair_ops if op.opcode != "accum" and op.result in need]
            else:
                first = [op for op in plan.pair_ops if op.opcode != "accum" and op.result not in inner]
            out += self.interleaved(st, ivec, U, jmask, first)
            for u in range(U):
                self.bind(st, ivec, u, U)
                tests.append(self.any_lane(st, m))
            assert st.skip is not None
            n, flips, last, dense, t, run, idx, na, _ = st.skip
            # one branch on (lanes | dense): g++ 12 splits a visible `(t | dense) != 0` into a
            # branch on the lanes and one on dense, and the first mispredicts as often in the
            # dense mode; the empty asm hides the value from that rewriting
            out.append(f"const unsigned {t} = {' | '.join(dict.fromkeys(tests))};  // the lanes in the branch")
            if test_only:
                # the test as a value, hidden from g++, which would otherwise branch on it
                out.append(f"unsigned {run} = {t} != 0 ? 1u : 0u;")
                out.append(f'__asm__("" : "+r"({run}));')
                out.append(f"{flips} += {run} ^ {last};")
                out.append(f"{last} = {run};")
                out.append(f"++{n};")
                out.append(f"{idx}[{na}] = jj;")
                out.append(f"{na} += static_cast<int>({run});")
                st.jmask = None
                return out
            out.append(f"{flips} += ({t} != 0 ? 1u : 0u) ^ {last};")
            out.append(f"{last} = {t} != 0 ? 1u : 0u;")
            out.append(f"++{n};")
            out.append(f"unsigned {run} = {t} | {dense};")
            out.append(f'__asm__("" : "+r"({run}));')
            out.append(f"if ({run} != 0) {{  // skip_region")
            out += ["  " + line for line in self.interleaved(
                st, ivec, U, jmask, [op for op in plan.pair_ops if op.opcode == "accum" or op.result in inner])]
            out.append("}")
        st.jmask = None
        return out

    def interleaved(self, st: EmitState, ivec: dict[str, list[str]], U: int, jmask: str | None,
                    ops: list[Op]) -> list[str]:
        """The statements of `ops` for the U unrolled copies. Where st.interleave (the
        register-pressure model says it fits): op by op, first the values that do not
        depend on i (printed once, with copy 0), then every other op for copy 0, 1, ...,
        U-1 in turn; else copy after copy. Copy after copy, g++ keeps much of that order
        and the out-of-order core has one copy's long dependency chain (r^2, rsqrt, its
        refinement, the sums) in its window at a time (docs/simd.md, "Copies op by op")."""
        if not st.interleave:
            out: list[str] = []
            for u in range(U):
                self.bind(st, ivec, u, U)
                out += [line for _op, lines in self.copy_groups(st, u, jmask, ops) for line in lines]
            return out
        groups: list[dict[int, list[str]]] = []
        for u in range(U):
            self.bind(st, ivec, u, U)
            groups.append({id(op): lines for op, lines in self.copy_groups(st, u, jmask, ops)})
        idep = st.plan.idep
        shared = [op for op in ops if op.opcode != "accum" and op.result not in idep]
        out = [line for op in shared for line in groups[0].get(id(op), [])]
        for op in ops:
            if op.opcode == "accum" or op.result in idep:
                for g in groups:
                    out += g.get(id(op), [])
        return out

    def j_copy_names(self, st: EmitState, V: int) -> list[dict[str, str]]:
        """The C++ names of j-copy v of V of every j value and pair value: name_j<v>."""
        plan = st.plan
        values = list(plan.jvals) + [op.result for op in plan.pair_ops if op.result and op.opcode != "accum"]
        return [{a: fresh_name(st.used, f"{a}_j{v}") for a in dict.fromkeys(values)} for v in range(V)]

    @staticmethod
    def j_first_use(st: EmitState) -> dict[str, int]:
        """j value -> the index in the pair ops of the first op that reads it."""
        first: dict[str, int] = {}
        for n, op in enumerate(st.plan.pair_ops):
            for x in op.args:
                if x in st.plan.jvals:
                    first.setdefault(x, n)
        return first

    def pair_lines_j(self, st: EmitState, ivec: dict[str, list[str]], names: list[dict[str, str]],
                     loads: list[dict[str, str]]) -> list[str]:
        """The pair body for V = len(names) j-particles (jj, jj + 1, ...) of a one-vector
        block, op by op: copy 0, 1, ..., V-1 of each op in turn, each j value's broadcast
        (loads[v]) printed just before the first op that reads it. Every accumulator
        takes j-copy 0's term, then 1's, ...: the sums are those of V iterations of the
        plain loop, bit for bit. The F64 divider mix (Uarch.f64_div_every) alternates
        over the j copies as it does over i-vector copies."""
        plan = st.plan
        V = len(names)
        first = self.j_first_use(st)
        groups: list[dict[int, list[str]]] = []
        for v in range(V):
            self.bind(st, ivec, 0, 1)
            st.copy, st.copies = v, V
            st.vmap.update(names[v])
            groups.append({id(op): lines for op, lines in self.copy_groups(st, 0, None, plan.pair_ops)})
        st.copy, st.copies = 0, 1
        out: list[str] = []
        for n, op in enumerate(plan.pair_ops):
            for v, g in enumerate(groups):
                out += [loads[v][a] for a in plan.jvals if first[a] == n]
                out += g.get(id(op), [])
        return out

    def copy_groups(self, st: EmitState, u: int, jmask: str | None, ops: list[Op]) -> list[tuple[Op, list[str]]]:
        """The statements of `ops` (pair ops, in order) for unrolled copy u (bound), by op."""
        plan = st.plan
        out: list[tuple[Op, list[str]]] = []
        for op in ops:
            if op.opcode == "accum":
                assert isinstance(op.attr, Reduce)
                acc = accumulator_of(plan.accs, op)
                v = op.args[0]
                m = self.combined_mask(st, op.args[1] if len(op.args) > 1 else None, jmask)
                dv = plan.defs.get(v)
                fused = (self.argv(st, dv.args[0]), self.argv(st, dv.args[1])) if dv is not None and self.fuses(st, dv) else None
                if fused is not None and m is not None and st.fast and self.premask_ok and dv is not None \
                        and dv.args[0] in self.finite_values(st):
                    fused = (fused[1], fused[0])  # the premask goes on the operand that may be inf
                name = acc.names[u]
                out.append((op, [f"{name} = {self.acc_update(st, op.attr.kind, name, self.argv(st, v), m, acc.type, fused)};"]))
                continue
            if u > 0 and op.result not in plan.idep:
                continue
            if self.fuses(st, op) or self.folded_into_select(st, op):
                continue
            out.append((op, self.vec_op(st, op)))
        return out

    def shape(self, st: EmitState, U: int, kind: str, V: int = 1) -> Shape:
        """kind: 'block' (U full vectors; with V > 1, U = 1 and V j-particles per
        iteration of its main j loop), 'tail' (one vector, the last i-particles), 'jpar'."""
        plan = st.plan
        T = lambda a: self.vtype(st, st.types[a])  # noqa: E731
        sh = Shape(U, self.block_lanes(U))
        sh.acc_init = self.acc_init(st, U)
        if st.region is not None:
            sh.acc_init += self.skip_state(st)[1]
        ivec: dict[str, list[str]] = {}
        if kind == "jpar":
            sh.i_fill = list(plan.i_lines)
            for a in plan.ivals:
                ivec[a] = [fresh_name(st.used, f"{a}_v")]
                sh.i_vec.append(const(T(a), ivec[a][0], self.bcast(st, a, st.types[a].scalar)))
            sh.j_vec.append(const(self.mask_type(st), "jvalid", self.j_tail_mask(st)))
            for a in plan.jvals:
                sh.j_vec.append(const(T(a), plan.jvec[a], self.vload(st, plan.bufs_j[a] + " + jj", st.types[a].scalar)))
        else:
            sh.ibuf_decls = [f"alignas(64) {self.ctype(st.types[a].scalar)} {b}[{self.lane_buffer(st, U)}];"
                             for a, b in plan.bufs_i.items()]
            sh.i_fill = list(plan.i_lines) + [f"{b}[l] = {self.store_scalar(st, a)};" for a, b in plan.bufs_i.items()]
            for a in plan.ivals:
                ivec[a] = [fresh_name(st.used, f"{a}_{u}" if U > 1 else f"{a}_v") for u in range(U)]
                for u in range(U):
                    ptr = plan.bufs_i[a] + self.lane_offset(st, u)
                    sh.i_vec.append(const(T(a), ivec[a][u], self.vload(st, ptr, st.types[a].scalar)))
            for a in plan.jvals:
                s = st.types[a].scalar
                elem = self.buffered(f"{plan.bufs_j[a]}[jj]", s)
                if a in plan.jdirect:
                    elem = f"kJDirect ? static_cast<{CXX_SCALAR[s]}>(epj[jb + jj]{plan.jdirect[a]}) : {elem}"
                sh.j_vec.append(const(T(a), plan.jvec[a], self.bcast(st, elem, s)))
        jnames: list[dict[str, str]] = []
        if V > 1:
            assert kind == "block" and U == 1 and st.region is None
            sh.V = V
            jnames = self.j_copy_names(st, V)
            jloads: list[dict[str, str]] = [{} for _ in range(V)]
            for v in range(V):
                at = f"jj + {v}" if v else "jj"
                for a in plan.jvals:
                    s = st.types[a].scalar
                    elem = self.buffered(f"{plan.bufs_j[a]}[{at}]", s)
                    if a in plan.jdirect:
                        elem = f"kJDirect ? static_cast<{CXX_SCALAR[s]}>(epj[jb + {at}]{plan.jdirect[a]}) : {elem}"
                    jloads[v][a] = const(T(a), jnames[v][a], self.bcast(st, elem, s))
        st.mask_bits = {}
        for a in plan.ivals + plan.jvals + list(plan.svec):
            if st.types[a].scalar == S.BOOL:
                for n in ivec.get(a, []) + [plan.jvec.get(a, ""), plan.svec.get(a, "")]:
                    st.mask_bits[n] = 32
        jm = "jvalid" if kind == "jpar" else None
        guard, reached = self.guarded(st)
        pre = self.premasked(st, jm)
        if guard or pre:
            st.guard, st.fast = guard, True
            sh.pair = self.pair_lines(st, ivec, U, jm)
            if jnames:
                sh.pair_V = self.pair_lines_j(st, ivec, jnames, jloads)
            self.set_compacted(st, sh, ivec, U, kind)
            st.fast = False
            sh.pair_safe = self.pair_lines(st, ivec, U, jm)
            checked = list({id(a): a for a in reached + pre}.values())
            sh.redo = self.any_nonfinite(st, [(n, acc.type) for acc in checked for n in acc.names])
            sh.acc_reset = [f"{n} = {self.acc_identity(st, acc)};" for acc in plan.accs.values() for n in acc.names]
        else:
            sh.pair = self.pair_lines(st, ivec, U, jm)
            if jnames:
                sh.pair_V = self.pair_lines_j(st, ivec, jnames, jloads)
            self.set_compacted(st, sh, ivec, U, kind)
        for acc in plan.accs.values():
            if kind == "jpar":
                sh.finish += self.reduce_jpar(st, acc)
                continue
            t = acc.type
            tmp = fresh_name(st.used, acc.base + "_lanes")
            sh.finish.append(f"alignas(64) {self.ctype(t.scalar)} {tmp}[{self.lane_buffer(st, U)}];")
            pred = self.tail_predicate if kind == "tail" else None
            for u, n in enumerate(acc.names):
                sh.finish.append(self.vstore(st, tmp + self.lane_offset(st, u), n, t.scalar, pred) + ";")
            sh.finish += ["for (int l = 0; l < n; ++l) {", "  const int i = ib + l;",
                          "  " + combine(acc.group, acc.target, self.scaled(acc, tmp + "[l]")), "}"]
        return sh

    def context(self, k: Kernel, impl: str) -> dict:
        st = self.begin(k)
        plan = st.plan
        jbuf_decls = [f"alignas(64) {self.ctype(st.types[a].scalar)} {b}[kJBlock{self.jbuf_pad}];"
                      for a, b in plan.bufs_j.items()]
        if st.region is not None:
            jbuf_decls += self.skip_state(st)[0]
        V = self.j_copies_rule(st)
        U = 1 if V > 1 else self.unroll(st, len(plan.accs))
        st.interleave = U > 1 and self.live_vectors(st, U, interleaved=True) <= self.uarch()[1].registers
        main = self.shape(st, U, "block", V)
        st.interleave = False
        tail = self.shape(st, 1, "tail")
        jpar = self.shape(st, 1, "jpar")
        return self.interface_context(k, impl) | self.shape_context(st) | {
            "U": U, "V": V, "jblock": self.jblock(self.min_lanes(st), plan.bytes_per_j), "setup": plan.setup,
            "bcast_setup": plan.bcast_setup, "jbuf_decls": jbuf_decls, "j_fill": plan.j_fill, "j_pad": plan.j_pad,
            "main": main, "tail": tail, "jpar": jpar, "has_pairs": bool(plan.accs),
            "jdirect": self.direct_j_check(st) if plan.jdirect else "",
        }


def split_fma_chains(k: Kernel) -> Kernel:
    """The pair stage's chains of three fused products and an addend, as contract_fma
    leaves r^2 + eps^2: madd(a, b, madd(c, d, madd(e, f, g))) with every link used once,
    rewritten as add(madd(e, f, g), madd(a, b, mul(c, d))). One add more, and the chain's
    latency falls from three FMA latencies to an FMA after a multiply and an add (on Zen 4,
    4 + 4 + 4 = 12 cycles against 3 + 4 + 3 = 10). The sum is reassociated, so the result
    may differ in the last bit from the other families' (as the F64 rsqrt's divider copies
    already do); only the rows with Uarch.split_sums ask for it (docs/simd.md)."""
    uses: dict[str, int] = {}
    for op in k.all_ops():
        for a in op.args:
            uses[a] = uses.get(a, 0) + 1
    for lv in k.locals:
        for v in lv.values:
            uses[v] = uses.get(v, 0) + 1
    ops = list(k.pair)
    defs = {op.result: op for op in ops if op.result}
    taken = set(k.names())

    def link(name: str, t) -> Op | None:
        op = defs.get(name)
        return op if op is not None and op.opcode == "madd" and op.type == t and uses.get(name) == 1 else None

    out: list[Op] = []
    gone: set[str] = set()
    for op in ops:
        t = op.type
        mid = link(op.args[2], t) if op.opcode == "madd" and t is not None and not t.is_vec else None
        low = link(mid.args[2], t) if mid is not None else None
        if mid is None or low is None or mid.result in gone or low.result in gone:
            out.append(op)
            continue
        prod = Op(fresh_name(taken, mid.result + "_p"), "mul", (mid.args[0], mid.args[1]), t, None, mid.span)
        top = Op(fresh_name(taken, op.result + "_q"), "madd", (op.args[0], op.args[1], prod.result), t, None, op.span)
        gone.add(mid.result)
        out = [x for x in out if x.result != mid.result]
        out += [prod, top, Op(op.result, "add", (low.result, top.result), t, None, op.span)]
    return k.with_blocks({Stage.PAIR: tuple(out)})
