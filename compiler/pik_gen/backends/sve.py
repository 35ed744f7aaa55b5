"""The ARM SVE backend: standard ACLE (`arm_sve.h`) code, vector-length agnostic.

The code builds with any SVE-capable GCC or Clang (`-march=armv8.2-a+sve`); it
uses no compiler-specific extension (PIKG's SVE output needed Fujitsu's
compiler for its member access to tuple types). SVE vectors are *sizeless*:
they cannot be class members or array elements, so every vector is a local
`const` value, and particles are staged in plain structure-of-arrays buffers
that `svld1` reads.

Lanes
-----
The lane count is read at run time (`svcntw()` or `svcntd()`), never fixed:
the same binary runs at every vector length from 128 to 2048 bits. A kernel
whose pair stage uses any 64-bit type runs on 64-bit lanes; its 32-bit values
(F32, S32) are then *unpacked*, one per 64-bit container (the layout `svcvt`
between F64 and F32 produces), so mixed precision needs no register pairs and
one governing predicate `pg` (`svptrue_b64()`) serves every type: a .S
operation under a .D predicate acts on the even elements, exactly the
unpacked values. F16 is carried in F32 lanes (more accurate than the
reference, which rounds every F16 op). Scratch buffers are sized for the
largest vector length (2048 bits), so no allocation happens in a kernel.

Loop shapes (templates/sve.hpp.j2; the same rule as the x86 backends)
---------------------------------------------------------------------
  i-parallel   i-particles in lanes, each j-particle broadcast (`svdup`, one
               `ld1rw`/`ld1rd`) from the structure-of-arrays buffer. Blocks of
               U vectors (U independent accumulator sets hide the FMA latency),
               then single vectors whose lanes past ni are governed by
               `ivalid = svwhilelt(ib, ni)`; padding lanes hold copies of a real
               particle, so every lane computes on valid data.
  j-parallel   for ni <= kW/2 and nj >= kW: one i-particle broadcast, kW
               j-particles in lanes, a predicated loop whose last vector is
               governed by `jvalid = svwhilelt(jj, jn)` (masked accumulation
               with the `_m` forms), reduced across lanes with `svaddv`.

Accuracy
--------
`rsqrt` and `inv` start from the 8-bit estimates `svrsqrte`/`svrecpe` and take
Newton-Raphson steps with the fused step instructions `svrsqrts` (3 - a b)/2
and `svrecps` 2 - a b: two steps for F32, three for F64 (8 -> 16 -> 32 -> 64
bits; every step squares the error, the last one leaves the rounding of the
final product, a few ulp). The steps keep the IEEE special cases:
rsqrt(0) = inf and inv(0) = inf (FRSQRTS/FRECPS return 1.5/2 for 0 x inf).
`--fast-math` takes one step fewer (F32 ~1e-5, F64 ~1e-9 relative). `sqrt` and
`/` are the IEEE instructions; `min`/`max` are a compare and a select, so NaN
and signed zeros behave as `std::min`/`std::max` in the reference.
`exp`, `log` and `pow` have no SVE instruction: they run lane by lane through
the C++ standard library (store, scalar loop over the kW lanes, load), exactly
as accurate as the reference and much slower than the rest of the kernel.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from pik_gen.backends.reference import Reference
from pik_gen.backends.simd_common import S, Simd, ebits
from pik_gen.ir.nodes import Kernel, Op, Reduce, TableRef, fresh_name
from pik_gen.types import Scalar, Type

PG = "pg"  # the governing all-true predicate of the generated kernel
CMP = {"eq": "svcmpeq", "ne": "svcmpne", "lt": "svcmplt", "gt": "svcmpgt", "le": "svcmple", "ge": "svcmpge"}

# QEMU user-mode emulation: the aarch64 libraries of the cross toolchain and
# the vector length in units of 128 bits (sve-max-vq).
QEMU = ("qemu-aarch64", "-L", "/usr/aarch64-linux-gnu")


def home(s: Scalar) -> Scalar:
    """The scalar kind whose vector type carries s."""
    return S.F32 if s == S.F16 else s


def sfx(s: Scalar) -> str:
    """ACLE type suffix of s (f32, s64, ...)."""
    s = home(s)
    return ("f" if s.is_float else "u" if s.is_unsigned else "s") + str(ebits(s))


def times(u: int, name: str) -> str:
    """`u * name` as C++ (`name` when u is 1)."""
    return name if u == 1 else f"{u} * {name}"


def _float_ops() -> dict:
    return {
        "add": "svadd_x({pg}, {0}, {1})", "sub": "svsub_x({pg}, {0}, {1})",
        "mul": "svmul_x({pg}, {0}, {1})", "div": "svdiv_x({pg}, {0}, {1})",
        "neg": "svneg_x({pg}, {0})", "abs": "svabs_x({pg}, {0})", "sqrt": "svsqrt_x({pg}, {0})",
        "floor": "svrintm_x({pg}, {0})",
        # std::min(a, b) = b < a ? b : a and std::max(a, b) = a < b ? b : a, NaN and -0 included
        "min": "svsel(svcmplt({pg}, {1}, {0}), {1}, {0})", "max": "svsel(svcmplt({pg}, {0}, {1}), {1}, {0})",
        # ACLE: mad = a*b + c, nmsb = a*b - c, msb = c - a*b, nmad = -a*b - c
        "madd": "svmad_x({pg}, {0}, {1}, {2})", "msub": "svnmsb_x({pg}, {0}, {1}, {2})",
        "nmadd": "svmsb_x({pg}, {0}, {1}, {2})", "nmsub": "svnmad_x({pg}, {0}, {1}, {2})",
    }


def _int_ops(unsigned: bool) -> dict:
    ops = {
        "add": "svadd_x({pg}, {0}, {1})", "sub": "svsub_x({pg}, {0}, {1})",
        "mul": "svmul_x({pg}, {0}, {1})", "div": "svdiv_x({pg}, {0}, {1})",
        "min": "svmin_x({pg}, {0}, {1})", "max": "svmax_x({pg}, {0}, {1})",
        "madd": "svmad_x({pg}, {0}, {1}, {2})", "nmadd": "svmsb_x({pg}, {0}, {1}, {2})",
        "msub": "svsub_x({pg}, svmul_x({pg}, {0}, {1}), {2})",
        "neg": "svneg_x({pg}, {0})", "abs": "svabs_x({pg}, {0})",
        "nmsub": "svneg_x({pg}, svmad_x({pg}, {0}, {1}, {2}))",
    }
    if unsigned:  # two's complement negation; |u| = u
        ops.update({"neg": "svsub_x({pg}, svdup_{t}(0), {0})", "abs": "{0}",
                    "nmsub": "svsub_x({pg}, svdup_{t}(0), svmad_x({pg}, {0}, {1}, {2}))"})
    return ops


# {(opcode, scalar kind): format}; {pg} the governing predicate, {t} the type suffix.
VEC: dict[tuple[str, Scalar], str] = {}
for _s in (S.F32, S.F64):
    VEC.update({(k, _s): v for k, v in _float_ops().items()})
for _s in (S.S32, S.S64, S.U32, S.U64):
    VEC.update({(k, _s): v for k, v in _int_ops(_s.is_unsigned).items()})
del _s


@dataclass
class Shape:
    """Printed lines of one loop shape (i-parallel block of U vectors, tail vector, or j-parallel)."""

    U: int
    lanes: str = "kW"  # i-particles per block, as C++
    i_fill: list[str] = field(default_factory=list)
    ibuf_decls: list[str] = field(default_factory=list)
    i_vec: list[str] = field(default_factory=list)
    acc_init: list[str] = field(default_factory=list)
    j_vec: list[str] = field(default_factory=list)
    pair: list[str] = field(default_factory=list)
    finish: list[str] = field(default_factory=list)


class Sve(Simd):
    name = "sve"
    isa_label = "SVE"
    in_auto = False  # `auto` dispatches between x86 variants only
    preference = 0
    # A header for this target is compiled for SVE (-march=...+sve); such a binary
    # runs only on SVE CPUs, so there is nothing left to check at run time.
    cpu_check = "true"
    function_attributes = ""
    cxx = "aarch64-linux-gnu-g++"  # builds the verification programs (a cross compiler on x86 hosts)
    cxx_flags = ("-march=armv8.2-a+sve",)
    # How a program built for SVE runs on a host without it: one configuration per vector length.
    runners = {f"VL{128 * vq}": QEMU + ("-cpu", f"max,sve-max-vq={vq}") for vq in (1, 2, 4)}
    lanes = {s: 0 for s in S}  # vector-length agnostic: read at run time (svcntw, svcntd)
    template = "sve.hpp.j2"
    includes = ("arm_sve.h",)
    registers = 32
    max_bits = 2048  # the largest SVE vector length: scratch buffers are sized for it
    reserved = frozenset({PG, "kMaxW", "ivalid"})  # declared by templates/sve.hpp.j2

    # ------------------------------------------------------------ types
    bits: int = 32  # lane width of the kernel being generated (32 or 64)

    def vtype(self, t: Type) -> str:
        s = home(t.scalar)
        if s == S.BOOL:
            return "svbool_t"
        kind = "float" if s.is_float else "uint" if s.is_unsigned else "int"
        return f"sv{kind}{ebits(s)}_t"

    def mask_type(self) -> str:
        return "svbool_t"

    def unpacked(self, s: Scalar) -> bool:
        """True for 32-bit values in a kernel on 64-bit lanes (one per 64-bit container)."""
        return self.bits == 64 and ebits(s) == 32

    # ------------------------------------------------------------ memory and broadcasts
    def vload(self, ptr: str, s: Scalar, pred: str = PG) -> str:
        if s == S.BOOL:
            return f"svcmpne({pred}, {self.vload(ptr, S.S32, pred)}, 0)"
        if self.unpacked(s):
            return (f"svreinterpret_{sfx(s)}_u64(svld1uw_u64({pred}, "
                    f"reinterpret_cast<const std::uint32_t*>({ptr})))")
        return f"svld1({pred}, {ptr})"

    def vstore(self, ptr: str, v: str, s: Scalar, pred: str = PG) -> str:
        if s == S.BOOL:
            return self.vstore(ptr, f"svsel({v}, svdup_s32(-1), svdup_s32(0))", S.S32, pred)
        if self.unpacked(s):
            return f"svst1w({pred}, reinterpret_cast<std::uint32_t*>({ptr}), svreinterpret_u64({v}));"
        return f"svst1({pred}, {ptr}, {v});"

    def bcast(self, expr: str, s: Scalar) -> str:
        """A vector with the scalar C++ expression `expr` (of kind s) in every lane."""
        if s == S.BOOL:
            return f"svdup_b{self.bits}({expr})"
        return f"svdup_{sfx(s)}(static_cast<{self.ctype(home(s))}>({expr}))"

    def literal_vec(self, value, t: Type) -> str:
        if t.scalar == S.BOOL:
            return self.bcast("true" if value else "false", S.BOOL)
        return f"svdup_{sfx(t.scalar)}({Reference.literal(self, value, Type(home(t.scalar)))})"

    # ------------------------------------------------------------ irregular ops
    def compare(self, opcode: str, s: Scalar, a: str, b: str) -> str:
        if s != S.BOOL:
            return f"{CMP[opcode]}({PG}, {a}, {b})"
        # on predicates (false < true): a < b is !a && b
        return {"eq": f"svnot_z({PG}, sveor_z({PG}, {a}, {b}))", "ne": f"sveor_z({PG}, {a}, {b})",
                "lt": f"svbic_z({PG}, {b}, {a})", "gt": f"svbic_z({PG}, {a}, {b})",
                "le": f"svnot_z({PG}, svbic_z({PG}, {a}, {b}))",
                "ge": f"svnot_z({PG}, svbic_z({PG}, {b}, {a}))"}[opcode]

    def logic(self, opcode: str, a: list[str]) -> str:
        if opcode == "not":
            return f"svnot_z({PG}, {a[0]})"
        return f"{'svand_z' if opcode == 'and' else 'svorr_z'}({PG}, {a[0]}, {a[1]})"

    def cast(self, src: Scalar, dst: Scalar, x: str) -> str | None:
        hs, hd = home(src), home(dst)
        if hs == hd:
            return x
        if S.BOOL in (hs, hd):
            return None
        if hs.is_float or hd.is_float:  # FCVT, FCVTZS/U (truncation, as static_cast), SCVTF/UCVTF
            return f"svcvt_{sfx(hd)}_{sfx(hs)}_x({PG}, {x})"
        if ebits(hs) == ebits(hd):  # S32 <-> U32, S64 <-> U64: the same bits
            return f"svreinterpret_{sfx(hd)}_{sfx(hs)}({x})"
        if ebits(hs) == 64:  # truncation: the low half of each container is the unpacked value
            return f"svreinterpret_{sfx(hd)}_{sfx(hs)}({x})"
        # widening: sign- or zero-extend the low 32 bits of each container, as static_cast does
        wide = "s64" if hs == S.S32 else "u64"
        e = f"svextw_{wide}_x({PG}, svreinterpret_{wide}_{sfx(hs)}({x}))"
        return e if wide == sfx(hd) else f"svreinterpret_{sfx(hd)}_{wide}({e})"

    def index64(self, idx: str, s: Scalar) -> tuple[str, str]:
        """A table index as 64-bit lanes and its ACLE gather suffix (s64index / u64index)."""
        if ebits(s) == 64:
            return idx, f"{sfx(s)}index"
        wide = "s64" if s == S.S32 else "u64"
        return f"svextw_{wide}_x({PG}, svreinterpret_{wide}_{sfx(s)}({idx}))", f"{wide}index"

    def gather(self, op: Op, idx: str) -> str | None:
        assert isinstance(op.attr, TableRef) and op.type is not None
        s, si = op.type.scalar, self.types[op.args[0]].scalar
        tab = op.attr.name
        if s not in (S.F32, S.F64) or not si.is_int:
            return None
        if self.bits == 32:  # F32 table, 32-bit indices
            return f"svld1_gather_{sfx(si)}index_f32({PG}, {tab}, {idx})"
        i64, kind = self.index64(idx, si)
        if s == S.F64:
            return f"svld1_gather_{kind}_f64({PG}, {tab}, {i64})"
        return (f"svreinterpret_f32_u64(svld1uw_gather_{kind}_u64({PG}, "
                f"reinterpret_cast<const std::uint32_t*>({tab}), {i64}))")

    def refine(self, opcode: str, x: str, s: Scalar, out: str) -> list[str]:
        """rsqrt/inv: the 8-bit estimate, then Newton-Raphson steps through the fused
        step instructions; y' = y (3 - x y^2)/2 as y * svrsqrts(x, y*y), y' = y (2 - x y)
        as y * svrecps(x, y). Each step squares the relative error."""
        T = self.vtype(Type(s))
        if opcode == "rsqrt2":  # 2/sqrt(x): the refined 1/sqrt doubled (exact)
            half = fresh_name(self.used, f"{out}_half")
            return self.refine("rsqrt", x, s, half) + [f"const {T} {out} = svadd_x({PG}, {half}, {half});"]
        est, step = ("svrsqrte", "svrsqrts") if opcode == "rsqrt" else ("svrecpe", "svrecps")
        n = (3 if s == S.F64 else 2) - (1 if self.options.fast_math else 0)
        y = fresh_name(self.used, f"{out}_y0")
        lines = [f"const {T} {y} = {est}({x});"]
        for k in range(1, n + 1):
            yn = out if k == n else fresh_name(self.used, f"{out}_y{k}")
            arg = f"svmul_x({PG}, {y}, {y})" if opcode == "rsqrt" else y
            lines.append(f"const {T} {yn} = svmul_x({PG}, {y}, {step}({x}, {arg}));")
            y = yn
        return lines

    def vec_op(self, op: Op) -> list[str]:
        """The statements computing pair op `op` on all lanes."""
        assert op.type is not None
        t, s = op.type, op.type.scalar
        r = self.vmap.get(op.result, op.result)
        a = [self.argv(x) for x in op.args]
        self.types[op.result] = t
        oc = op.opcode
        expr: str | None = None
        if oc in CMP:
            expr = self.compare(oc, home(self.types[op.args[0]].scalar), a[0], a[1])
        elif oc in ("and", "or", "not"):
            expr = self.logic(oc, a)
        elif oc == "select":
            expr = f"svsel({a[0]}, {a[1]}, {a[2]})"
        elif oc in ("rsqrt", "rsqrt2", "inv") and s.is_float:
            return self.refine(oc, a[0], home(s), r)
        elif oc == "cast":
            expr = self.cast(self.types[op.args[0]].scalar, s, a[0])
        elif oc == "table":
            expr = self.gather(op, a[0])
        elif s != S.BOOL:
            fmt = VEC.get((oc, home(s)))
            if fmt is not None:
                expr = fmt.format(*a, pg=PG, t=sfx(s))
        if expr is None:
            return self.lanewise(op, r)
        return [f"const {self.vtype(t)} {r} = {expr};"]

    def lane_capacity(self) -> str:
        return "kMaxW"

    def lane_count(self) -> str:
        return "kW"

    def lane_arg(self, x: str) -> tuple[Scalar, str]:
        return home(self.types[x].scalar), self.argv(x)

    # ------------------------------------------------------------ accumulation
    def acc_update(self, kind: str, acc: str, v: str, m: str | None, fused: tuple[str, str] | None) -> str:
        """acc op= v where mask m holds (merging `_m` forms keep acc elsewhere)."""
        p, sx = (m, "m") if m is not None else (PG, "x")
        if fused is not None:
            fn = "svmla" if kind == "add" else "svmls"  # acc + a b, acc - a b
            return f"{acc} = {fn}_{sx}({p}, {acc}, {fused[0]}, {fused[1]});"
        if kind in ("add", "sub", "mul", "div"):
            return f"{acc} = sv{kind}_{sx}({p}, {acc}, {v});"
        # max/min as the reference: if (v > acc) acc = v, so a NaN v keeps acc
        return f"{acc} = svsel({CMP['gt' if kind == 'max' else 'lt']}({p}, {v}, {acc}), {v}, {acc});"

    def unroll(self, n_acc: int) -> int:
        """Independent i-vectors per block: as many as keep the accumulators resident
        (or `#pragma unroll N`)."""
        if self.options.unroll:
            return self.options.unroll
        for u in (4, 2):
            if u * n_acc + 4 <= self.registers:
                return u
        return 1

    # ------------------------------------------------------------ context
    def set_lane_bits(self, bits: int) -> None:
        self.bits = bits

    def context(self, k: Kernel, impl: str) -> dict:
        plan = self.plan(k)
        ivals, jvals, pair_ops, accs = plan.ivals, plan.jvals, plan.pair_ops, plan.accs
        bufs_i, bufs_j, jvec = plan.bufs_i, plan.bufs_j, plan.jvec
        maxw = self.max_bits // self.bits

        def fusable(op: Op) -> bool:
            """A float product used once, by an add/sub accumulation: folded into svmla/svmls."""
            if op.opcode != "mul" or plan.nuse.get(op.result) != 1 or op.type is None or not op.type.scalar.is_float:
                return False
            return any(u.opcode == "accum" and u.args[0] == op.result and u.attr.kind in ("add", "sub")  # type: ignore[union-attr]
                       for u in pair_ops)

        # kMaxW more than a block: the j-parallel shape pads the last vector with copies
        jbuf_decls = [f"alignas(64) {self.ctype(self.types[a].scalar)} {b}[kJBlock + kMaxW];" for a, b in bufs_j.items()]
        ivec: dict[str, list[str]] = {}

        def pair_lines(U: int, jmask: str | None, sh: Shape) -> None:
            for u in range(U):
                self.bind(plan, ivec, u, U)
                for op in pair_ops:
                    if op.opcode == "accum":
                        red = op.attr
                        assert isinstance(red, Reduce)
                        acc = accs[(red.member, red.component, self.GROUP[red.kind])]
                        v = op.args[0]
                        m = op.args[1] if len(op.args) > 1 else None
                        mask = self.argv(m) if m is not None else None
                        if mask is not None and jmask is not None:
                            mask = f"svand_z({PG}, {mask}, {jmask})"
                        elif jmask is not None:
                            mask = jmask
                        dv = plan.defs.get(v)
                        fused = (self.argv(dv.args[0]), self.argv(dv.args[1])) if dv is not None and fusable(dv) else None
                        sh.pair.append(self.acc_update(red.kind, acc["names"][u], self.argv(v), mask, fused))
                        continue
                    if u > 0 and op.result not in plan.idep:
                        continue
                    if fusable(op):
                        continue
                    sh.pair.extend(self.vec_op(op))

        def make_shape(U: int, kind: str) -> Shape:
            """kind: 'block' (U full vectors), 'tail' (one vector, ivalid lanes), 'jpar'."""
            sh = Shape(U, times(U, "kW"))
            sh.acc_init = self.acc_init(accs, U)
            if kind == "jpar":
                sh.i_fill = list(plan.i_lines)
                for a in ivals:
                    ivec[a] = [fresh_name(self.used, f"{a}_v")]
                    sh.i_vec.append(f"const {self.vtype(self.types[a])} {ivec[a][0]} = {self.bcast(a, self.types[a].scalar)};")
                sh.j_vec.append(f"const svbool_t jvalid = svwhilelt_b{self.bits}(jj, jn);")
                for a in jvals:
                    sh.j_vec.append(f"const {self.vtype(self.types[a])} {jvec[a]} = "
                                    f"{self.vload(bufs_j[a] + ' + jj', self.types[a].scalar)};")
            else:
                sh.ibuf_decls = [f"alignas(64) {self.ctype(self.types[a].scalar)} {b}[{times(U, 'kMaxW')}];"
                                 for a, b in bufs_i.items()]
                sh.i_fill = list(plan.i_lines) + [f"{b}[l] = {self.store_scalar(a)};" for a, b in bufs_i.items()]
                for a in ivals:
                    ivec[a] = [fresh_name(self.used, f"{a}_{u}" if U > 1 else f"{a}_v") for u in range(U)]
                    for u in range(U):
                        off = "" if u == 0 else " + kW" if u == 1 else f" + {u} * kW"
                        sh.i_vec.append(f"const {self.vtype(self.types[a])} {ivec[a][u]} = "
                                        f"{self.vload(bufs_i[a] + off, self.types[a].scalar)};")
                for a in jvals:
                    s = self.types[a].scalar
                    src = f"{bufs_j[a]}[jj]" + (" != 0" if s == S.BOOL else "")
                    sh.j_vec.append(f"const {self.vtype(self.types[a])} {jvec[a]} = {self.bcast(src, s)};")
            pair_lines(U, "jvalid" if kind == "jpar" else None, sh)
            for acc in accs.values():
                t, target, grp = acc["type"], acc["target"], acc["group"]
                if kind == "jpar" and grp != "prod":
                    red = {"sum": "svaddv", "max": "svmaxv", "min": "svminv"}[grp]
                    sh.finish.append(self.combine(grp, target, self.scaled(acc, f"{red}({PG}, {acc['names'][0]})")))
                    continue
                tmp = fresh_name(self.used, acc["base"] + "_lanes")
                sh.finish.append(f"alignas(64) {self.ctype(t.scalar)} {tmp}[{times(U, 'kMaxW')}];")
                pred = "ivalid" if kind == "tail" else PG
                for u, nm in enumerate(acc["names"]):
                    off = "" if u == 0 else " + kW" if u == 1 else f" + {u} * kW"
                    sh.finish.append(self.vstore(tmp + off, nm, t.scalar, pred))
                if kind == "jpar":  # products: no SVE reduction instruction
                    sh.finish.append(f"for (int lane = 0; lane < kW; ++lane) {self.combine(grp, target, tmp + '[lane]')}")
                else:
                    sh.finish.append("for (int l = 0; l < n; ++l) {")
                    sh.finish.append("  const int i = ib + l;")
                    sh.finish.append("  " + self.combine(grp, target, self.scaled(acc, tmp + "[l]")))
                    sh.finish.append("}")
            return sh

        U = self.unroll(len(accs))
        main = make_shape(U, "block")
        tail = make_shape(1, "tail")
        jpar = make_shape(1, "jpar")
        return self.interface_context(k, impl) | {
            "bits": self.bits, "maxw": maxw, "cnt": "svcntw" if self.bits == 32 else "svcntd",
            "U": U, "jblock": self.jblock(maxw, plan.bytes_per_j), "setup": plan.setup,
            "bcast_setup": plan.bcast_setup, "jbuf_decls": jbuf_decls, "j_fill": plan.j_fill, "j_pad": plan.j_pad,
            "main": main, "tail": tail, "jpar": jpar, "has_pairs": bool(accs),
        }
