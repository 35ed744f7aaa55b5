"""What every SIMD backend shares (AVX2/AVX-512 in avx2.py, SVE in sve.py).

A SIMD backend runs the pair stage with particles in lanes and the rest of the
kernel as scalar C++ (printed by the reference). `Simd.plan` does the part of
that which does not depend on the ISA: it moves the pair stage's loads to the
i or j side, prints the scalar setup, i and j stages, finds which scalar values
the pair stage reads (each one kept in a lane buffer or broadcast), which pair
values differ between i-particles (one copy per unrolled i-vector), and the
accumulators. The ISA module keeps what really differs: lane counts, buffer
sizes, masks, reductions and the loop-shape template.

A backend subclasses `Simd` and provides `set_lane_bits` (what the widest
element of the pair stage means for its vectors), `lane_capacity`,
`lane_count` and `lane_arg` (for the lane-by-lane fallback), `vtype`, `bcast`,
`literal_vec`, `vload`/`vstore` and `vec_op`; see avx2.py or sve.py.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from pik_gen.backends.base import indexed_members
from pik_gen.backends.reference import Reference
from pik_gen.ir.nodes import Const, Kernel, MemberRef, Op, Reduce, Stage, fresh_name
from pik_gen.types import COMPONENTS, CXX_SCALAR, Scalar, Type

S = Scalar
WIDE = (S.F64, S.S64, S.U64)


def ebits(s: Scalar) -> int:
    """Bits of one lane of scalar kind s (F16 lives in F32 lanes, BOOL in 32-bit lanes or integers)."""
    return 64 if s in WIDE else 32


@dataclass
class PairPlan:
    """The ISA-independent split of a kernel for a SIMD loop (names are C++ identifiers)."""

    setup: list[str]           # scalar setup stage
    i_lines: list[str]         # scalar i stage, with the pair stage's EPI/FORCE loads
    j_lines: list[str]         # scalar j stage, with the pair stage's EPJ loads
    pair_ops: list[Op]         # the pair stage without its loads
    ivals: list[str]           # i values the pair stage reads (in lanes or broadcast)
    jvals: list[str]           # j values the pair stage reads
    svals: list[str]           # setup values the pair stage reads (broadcast once)
    idep: set[str]             # pair values that differ between i-particles
    nuse: dict[str, int]       # uses of each value in the pair stage
    defs: dict[str, Op]        # the pair op defining each value
    accs: dict[tuple, dict]    # (member, component, group) -> base, group, type, scale, target
    bufs_i: dict[str, str]     # i value -> its lane buffer
    bufs_j: dict[str, str]     # j value -> its buffer of one j block
    bytes_per_j: int           # bytes of j buffers per j-particle (sizes the j block)
    j_fill: list[str]          # scalar j stage + stores into the j buffers
    j_pad: list[str]           # copies of the last j-particle into a padding slot
    svec: dict[str, str]       # setup value -> its broadcast vector
    bcast_setup: list[str]     # the broadcasts of the setup values
    jvec: dict[str, str]       # j value -> its vector in the pair loop


class Simd(Reference):
    """The SIMD machinery shared by the vector ISAs; the scalar parts come from Reference."""

    reserved: ClassVar[frozenset[str]] = frozenset()  # names the ISA's loop skeleton declares
    j_block_bytes: ClassVar[int] = 16384  # j buffers per block: well inside L1

    def set_lane_bits(self, bits: int) -> None:
        """Set the vector shape for a pair stage whose widest element has `bits` bits (32 or 64)."""
        raise NotImplementedError

    # ------------------------------------------------------------ values
    def ctype(self, s: Scalar) -> str:
        """C++ element type of a lane buffer."""
        return "std::int32_t" if s == S.BOOL else "float" if s == S.F16 else CXX_SCALAR[s]

    def store_scalar(self, name: str) -> str:
        """Scalar value `name` as stored in its lane buffer (BOOL as 0 / -1)."""
        return f"-static_cast<std::int32_t>({name})" if self.types[name].scalar == S.BOOL else name

    def argv(self, name: str) -> str:
        """Value `name` as a vector expression (constants broadcast where used)."""
        if name in self.cvals:
            value, t = self.cvals[name]
            return self.literal_vec(value, t)
        return self.vmap.get(name, name)

    # ------------------------------------------------------------ lane by lane
    def lane_capacity(self) -> str:
        """Elements of a lane scratch buffer, as C++ (the most lanes a vector can have)."""
        raise NotImplementedError

    def lane_count(self) -> str:
        """Lanes of one vector, as C++."""
        raise NotImplementedError

    def lane_arg(self, x: str) -> tuple[Scalar, str]:
        """Argument x of a lane-by-lane op: the scalar kind it is stored as, and its vector."""
        raise NotImplementedError

    def lanewise(self, op: Op, r: str) -> list[str]:
        """Per-lane fallback for an op without a vector instruction (exp, log, pow...):
        store the arguments, apply the reference's scalar expression to every lane,
        load the result; exactly as accurate as the reference."""
        assert op.type is not None
        lines, elems = [], []
        for n, x in enumerate(op.args):
            xs, v = self.lane_arg(x)
            buf = fresh_name(self.used, f"{r}_a{n}")
            lines.append(f"alignas(64) {self.ctype(xs)} {buf}[{self.lane_capacity()}];")
            lines.append(self.vstore(buf, v, xs))
            elems.append(f"({buf}[lane] != 0)" if xs == S.BOOL else f"{buf}[lane]")
        s = op.type.scalar
        out = fresh_name(self.used, f"{r}_r")
        ref = self.scalar_printer
        ref.types.update({x: self.types[x] for x in op.args})
        e = Reference.expr(ref, op, elems)
        if s == S.BOOL:
            e = f"({e}) ? -1 : 0"
        elif s == S.F16:
            e = f"static_cast<float>({e})"
        lines.append(f"alignas(64) {self.ctype(s)} {out}[{self.lane_capacity()}];")
        lines.append(f"for (int lane = 0; lane < {self.lane_count()}; ++lane) {out}[lane] = {e};")
        lines.append(f"const {self.vtype(op.type)} {r} = {self.vload(out, s)};")
        return lines

    # ------------------------------------------------------------ accumulators
    def combine(self, group: str, target: str, v: str) -> str:
        return {"sum": f"{target} += {v};", "prod": f"{target} *= {v};",
                "max": f"if ({v} > {target}) {target} = {v};", "min": f"if ({v} < {target}) {target} = {v};"}[group]

    def scaled(self, acc: dict, v: str) -> str:
        """A finished sum times its pending power-of-two factor (defer_scale)."""
        if acc.get("scale", 1.0) == 1.0:
            return v
        return f"{Reference.literal(self, acc['scale'], Type(acc['type'].scalar))} * {v}"

    def acc_init(self, accs: dict[tuple, dict], U: int) -> list[str]:
        """Names the U copies of every accumulator (acc["names"]) and declares them at
        the identity of their group."""
        lines = []
        for acc in accs.values():
            acc["names"] = [fresh_name(self.used, acc["base"] + (f"_{u}" if U > 1 else "")) for u in range(U)]
            t = acc["type"]
            init = {"sum": 0, "prod": 1, "max": -math.inf, "min": math.inf}[acc["group"]]
            if not t.scalar.is_float and acc["group"] in ("max", "min"):
                lim = "lowest" if acc["group"] == "max" else "max"
                iv = self.bcast(f"std::numeric_limits<{CXX_SCALAR[t.scalar]}>::{lim}()", t.scalar)
            else:
                iv = self.literal_vec(init, t)
            lines += [f"{self.vtype(t)} {n} = {iv};" for n in acc["names"]]
        return lines

    def bind(self, plan: PairPlan, ivec: dict[str, list[str]], u: int, U: int) -> None:
        """Point the vector names at copy u of U of the i-dependent values."""
        self.cur_u, self.cur_U = u, U
        self.vmap = dict(plan.svec)
        self.vmap.update(plan.jvec)
        for a in plan.ivals:
            self.vmap[a] = ivec[a][u]
        for name in plan.idep - set(plan.ivals):
            self.vmap[name] = f"{name}_{u}" if U > 1 else name

    def jblock(self, min_lanes: int, bytes_per_j: int) -> int:
        """j-particles per buffered block: a power of two filling j_block_bytes, at
        least one vector of `min_lanes` and at most 4096."""
        return 1 << max(int(math.log2(min_lanes)), min(12, int(math.log2(self.j_block_bytes / bytes_per_j))))

    # ------------------------------------------------------------ plan
    def plan(self, k: Kernel) -> PairPlan:
        """Reset the per-kernel state and split kernel k for the SIMD loop shapes."""
        self.indexed = indexed_members(k)
        self.used = set(k.names()) | self.reserved
        self.types, self.consts, self.vmap = {}, {}, {}
        self.cvals: dict[str, tuple] = {}
        ref = Reference(self.options)
        ref.indexed = self.indexed
        self.scalar_printer = ref
        for op in k.all_ops():
            if op.opcode == "const":
                assert isinstance(op.attr, Const)
                self.cvals[op.result] = (op.attr.value, op.type)
            if op.result:
                self.types[op.result] = op.type  # type: ignore[assignment]
        pair_types = {op.type.scalar for op in k.pair if op.type is not None}
        pair_types |= {self.types[a].scalar for op in k.pair for a in op.args}
        self.set_lane_bits(max([ebits(s) for s in pair_types if s != S.BOOL] or [32]))

        # Loads in the pair stage read one particle: they belong to the i or j side.
        pair_loads = [op for op in k.pair if op.opcode == "load"]
        pair_ops = [op for op in k.pair if op.opcode != "load"]
        i_ops = list(k.i) + [op for op in pair_loads if op.attr.role != "EPJ"]  # type: ignore[union-attr]
        j_ops = list(k.j) + [op for op in pair_loads if op.attr.role == "EPJ"]  # type: ignore[union-attr]

        def scalar(ops: list[Op] | tuple[Op, ...], stage: Stage) -> list[str]:
            out = []
            for op in ops:
                if op.opcode == "load":
                    ref.types[op.result] = op.type  # type: ignore[assignment]
                    out.append(ref.load(op, stage))
                elif op.opcode != "accum":
                    st = ref.statement(op)
                    if st is not None:
                        out.append(st)
            return out

        setup = scalar(k.setup, Stage.SETUP)
        i_lines = scalar(i_ops, Stage.I)
        j_lines = scalar(j_ops, Stage.J)
        stage_of = {op.result: st for st, ops in (("setup", k.setup), ("i", i_ops), ("j", j_ops)) for op in ops}
        uses = list(dict.fromkeys(a for op in pair_ops for a in op.args if a in stage_of and a not in self.cvals))
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
        defs = {op.result: op for op in pair_ops if op.result}

        accs: dict[tuple, dict] = {}
        for op in pair_ops:
            if op.opcode != "accum":
                continue
            red = op.attr
            assert isinstance(red, Reduce)
            grp = self.GROUP[red.kind]
            key = (red.member, red.component, grp)
            if key not in accs:
                base = red.member + ("" if red.component is None else f"_{COMPONENTS[red.component]}")
                accs[key] = {"base": base if grp == "sum" else f"{base}_{grp}", "group": grp, "scale": red.scale,
                             "type": self.types[op.args[0]],
                             "target": self.member_access(MemberRef("FORCE", red.member, red.component))}

        bufs_i = {a: fresh_name(self.used, f"{a}_ib") for a in ivals}
        bufs_j = {a: fresh_name(self.used, f"{a}_jb") for a in jvals}
        svec = {a: fresh_name(self.used, f"{a}_v") for a in svals}
        jvec = {a: fresh_name(self.used, f"{a}_v") for a in jvals}
        return PairPlan(
            setup=setup, i_lines=i_lines, j_lines=j_lines, pair_ops=pair_ops,
            ivals=ivals, jvals=jvals, svals=svals, idep=idep, nuse=nuse, defs=defs, accs=accs,
            bufs_i=bufs_i, bufs_j=bufs_j,
            bytes_per_j=sum(ebits(self.types[a].scalar) // 8 for a in jvals) or 4,
            j_fill=j_lines + [f"{b}[jj] = {self.store_scalar(a)};" for a, b in bufs_j.items()],
            j_pad=[f"{b}[jj] = {b}[jn - 1];" for b in bufs_j.values()],
            svec=svec,
            bcast_setup=[f"const {self.vtype(self.types[a])} {v} = {self.bcast(a, self.types[a].scalar)};"
                         for a, v in svec.items()],
            jvec=jvec,
        )
