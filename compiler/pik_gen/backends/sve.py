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
`exp` and `erfc` are vector code (vmath.py, the x86 algorithm on `svrintn`
and an exponent shift). `log` and `pow` have no SVE instruction: they run lane
by lane through the C++ standard library (store, scalar loop over the kW lanes,
load), exactly as accurate as the reference and much slower than the rest.
"""
from __future__ import annotations

from pik_gen.backends.base import Accumulator, combine, literal
from pik_gen.backends.simd import EmitState, Let, S, Simd, Uarch, ebits
from pik_gen.ir.nodes import Op, TableRef, fresh_name
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


class Sve(Simd):
    name = "sve"
    isa_label = "SVE"
    pikg_name = "A64FX"
    summary = "Arm SVE, vector-length agnostic"
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
    lane_counts = (2, 4, 8, 16)  # vector-length agnostic: read at run time; these at VL 128..512
    template = "sve.hpp.j2"
    includes = ("arm_sve.h",)
    registers = 32
    UARCH = {
        "generic": Uarch(32, 2, 4, 1.0, 8, "neoverse-v1", "any SVE CPU"),
        "a64fx": Uarch(32, 2, 9, 0.5, 16, "a64fx", "Fujitsu A64FX (FMA latency 9)"),
        "neoverse-v1": Uarch(32, 2, 4, 1.0, 8, "neoverse-v1", "Arm Neoverse V1 (Graviton 3)"),
    }
    default_cpu = "generic"
    max_bits = 2048  # the largest SVE vector length: scratch buffers are sized for it
    reserved = frozenset({PG, "kMaxW", "ivalid"})  # declared by templates/sve.hpp.j2
    jbuf_pad = " + kMaxW"  # the j-parallel shape pads the last vector with copies
    tail_predicate = "ivalid"
    # {(opcode, scalar kind): format}; {pg} the governing predicate, {t} the type suffix.
    OPS = {(k, s): v for s in (S.F32, S.F64) for k, v in _float_ops().items()}
    OPS.update({(k, s): v for s in (S.S32, S.S64, S.U32, S.U64) for k, v in _int_ops(s.is_unsigned).items()})

    # ------------------------------------------------------------ types
    def vtype(self, st: EmitState, t: Type) -> str:
        s = home(t.scalar)
        if s == S.BOOL:
            return "svbool_t"
        kind = "float" if s.is_float else "uint" if s.is_unsigned else "int"
        return f"sv{kind}{ebits(s)}_t"

    def mask_type(self, st: EmitState, bits: int = 32) -> str:
        return "svbool_t"

    def fields(self, st: EmitState, s: Scalar) -> dict:
        return {"pg": PG, "t": sfx(s)}

    def unpacked(self, st: EmitState, s: Scalar) -> bool:
        """True for 32-bit values in a kernel on 64-bit lanes (one per 64-bit container)."""
        return st.lane_bits == 64 and ebits(s) == 32

    # ------------------------------------------------------------ memory and broadcasts
    def vload(self, st: EmitState, ptr: str, s: Scalar, pred: str = PG) -> str:
        if s == S.BOOL:
            return f"svcmpne({pred}, {self.vload(st, ptr, S.S32, pred)}, 0)"
        if self.unpacked(st, s):
            return (f"svreinterpret_{sfx(s)}_u64(svld1uw_u64({pred}, "
                    f"reinterpret_cast<const std::uint32_t*>({ptr})))")
        return f"svld1({pred}, {ptr})"

    def vstore(self, st: EmitState, ptr: str, v: str, s: Scalar, pred: str | None = None) -> str:
        pred = pred or PG
        if s == S.BOOL:
            return self.vstore(st, ptr, f"svsel({v}, svdup_s32(-1), svdup_s32(0))", S.S32, pred)
        if self.unpacked(st, s):
            return f"svst1w({pred}, reinterpret_cast<std::uint32_t*>({ptr}), svreinterpret_u64({v}))"
        return f"svst1({pred}, {ptr}, {v})"

    def bcast(self, st: EmitState, expr: str, s: Scalar) -> str:
        """A vector with the scalar C++ expression `expr` (of kind s) in every lane."""
        if s == S.BOOL:
            return f"svdup_b{st.lane_bits}({expr})"
        return f"svdup_{sfx(s)}(static_cast<{self.ctype(home(s))}>({expr}))"

    def buffered(self, elem: str, s: Scalar) -> str:
        return elem + (" != 0" if s == S.BOOL else "")

    def literal_vec(self, st: EmitState, value, t: Type) -> str:
        if t.scalar == S.BOOL:
            return self.bcast(st, "true" if value else "false", S.BOOL)
        return f"svdup_{sfx(t.scalar)}({literal(value, Type(home(t.scalar)))})"

    # ------------------------------------------------------------ irregular ops
    def compare(self, st: EmitState, op: Op, a: str, b: str) -> str:
        if home(st.types[op.args[0]].scalar) != S.BOOL:
            return f"{CMP[op.opcode]}({PG}, {a}, {b})"
        # on predicates (false < true): a < b is !a && b
        return {"eq": f"svnot_z({PG}, sveor_z({PG}, {a}, {b}))", "ne": f"sveor_z({PG}, {a}, {b})",
                "lt": f"svbic_z({PG}, {b}, {a})", "gt": f"svbic_z({PG}, {a}, {b})",
                "le": f"svnot_z({PG}, svbic_z({PG}, {a}, {b}))",
                "ge": f"svnot_z({PG}, svbic_z({PG}, {b}, {a}))"}[op.opcode]

    skip_ok = True
    compact_ok = False  # the compacted passes (Simd.compacted) are measured on x86 only

    def any_lane(self, st: EmitState, m: str) -> str:
        return f"static_cast<int>(svptest_any({PG}, {self.argv(st, m)}))"

    def logic(self, st: EmitState, opcode: str, a: str, b: str | None) -> str:
        if opcode == "not":
            return f"svnot_z({PG}, {self.argv(st, a)})"
        assert b is not None
        return f"{'svand_z' if opcode == 'and' else 'svorr_z'}({PG}, {self.argv(st, a)}, {self.argv(st, b)})"

    def select(self, st: EmitState, m: str, a: str, b: str, t: Type) -> str:
        return f"svsel({self.argv(st, m)}, {a}, {b})"

    def cast(self, st: EmitState, src: Scalar, dst: Scalar, x: str) -> str | None:
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

    def gather(self, st: EmitState, op: Op, idx: str) -> str | None:
        assert isinstance(op.attr, TableRef) and op.type is not None
        s, si = op.type.scalar, st.types[op.args[0]].scalar
        tab = op.attr.name
        if s not in (S.F32, S.F64) or not si.is_int:
            return None
        if st.lane_bits == 32:  # F32 table, 32-bit indices
            return f"svld1_gather_{sfx(si)}index_f32({PG}, {tab}, {idx})"
        i64, kind = self.index64(idx, si)
        if s == S.F64:
            return f"svld1_gather_{kind}_f64({PG}, {tab}, {i64})"
        return (f"svreinterpret_f32_u64(svld1uw_gather_{kind}_u64({PG}, "
                f"reinterpret_cast<const std::uint32_t*>({tab}), {i64}))")

    def refine(self, st: EmitState, opcode: str, x: str, s: Scalar, out: str) -> list[Let]:
        """rsqrt/inv: the 8-bit estimate, then Newton-Raphson steps through the fused
        step instructions; y' = y (3 - x y^2)/2 as y * svrsqrts(x, y*y), y' = y (2 - x y)
        as y * svrecps(x, y). Each step squares the relative error."""
        T = self.vtype(st, Type(s))
        if opcode == "rsqrt2":  # 2/sqrt(x): the refined 1/sqrt doubled (exact)
            half = fresh_name(st.used, f"{out}_half")
            return self.refine(st, "rsqrt", x, s, half) + [Let(T, out, f"svadd_x({PG}, {half}, {half})")]
        est, step = ("svrsqrte", "svrsqrts") if opcode == "rsqrt" else ("svrecpe", "svrecps")
        n = (3 if s == S.F64 else 2) - (1 if self.options.fast_math else 0)
        y = fresh_name(st.used, f"{out}_y0")
        lets = [Let(T, y, f"{est}({x})")]
        for k in range(1, n + 1):
            yn = out if k == n else fresh_name(st.used, f"{out}_y{k}")
            arg = f"svmul_x({PG}, {y}, {y})" if opcode == "rsqrt" else y
            lets.append(Let(T, yn, f"svmul_x({PG}, {y}, {step}({x}, {arg}))"))
            y = yn
        return lets

    # ------------------------------------------------------------ exp, erfc (vmath.py)
    def vround(self, st: EmitState, s: Scalar, x: str) -> str:
        return f"svrintn_x({PG}, {x})"

    def vpow2(self, st: EmitState, s: Scalar, n: str) -> str:
        """As on x86: n + 1.5 * 2^52 + 1023 shifted into the exponent field (F32: 2^23, 127)."""
        if home(s) == S.F64:
            bias, u, shift = "6755399441056767.0", "u64", 52
        else:
            bias, u, shift = "12583039.0f", "u32", 23
        t = sfx(s)
        return (f"svreinterpret_{t}_{u}(svlsl_n_{u}_x({PG}, svreinterpret_{u}_{t}(svadd_x({PG}, {n}, "
                f"svdup_{t}({bias}))), {shift}))")

    def select_negative(self, st: EmitState, s: Scalar, x: str, a: str, b: str) -> str:
        return f"svsel(svcmplt({PG}, {x}, {self.literal_vec(st, 0.0, Type(home(s)))}), {a}, {b})"

    # ------------------------------------------------------------ accumulation
    def acc_update(self, st: EmitState, kind: str, acc: str, v: str, m: str | None, t: Type,
                   fused: tuple[str, str] | None) -> str:
        """acc op= v where mask m holds (merging `_m` forms keep acc elsewhere)."""
        p, sx = (self.argv(st, m), "m") if m is not None else (PG, "x")
        if fused is not None:
            fn = "svmla" if kind == "add" else "svmls"  # acc + a b, acc - a b
            return f"{fn}_{sx}({p}, {acc}, {fused[0]}, {fused[1]})"
        if kind in ("add", "sub", "mul", "div"):
            return f"sv{kind}_{sx}({p}, {acc}, {v})"
        # max/min as the reference: if (v > acc) acc = v, so a NaN v keeps acc
        return f"svsel({CMP['gt' if kind == 'max' else 'lt']}({p}, {v}, {acc}), {v}, {acc})"

    def reduce_jpar(self, st: EmitState, acc: Accumulator) -> list[str]:
        if acc.group != "prod":
            red = {"sum": "svaddv", "max": "svmaxv", "min": "svminv"}[acc.group]
            return [combine(acc.group, acc.target, self.scaled(acc, f"{red}({PG}, {acc.names[0]})"))]
        # products: no SVE reduction instruction
        tmp = fresh_name(st.used, acc.base + "_lanes")
        return [f"alignas(64) {self.ctype(acc.type.scalar)} {tmp}[kMaxW];",
                self.vstore(st, tmp, acc.names[0], acc.type.scalar) + ";",
                f"for (int lane = 0; lane < kW; ++lane) {combine(acc.group, acc.target, tmp + '[lane]')}"]

    # ------------------------------------------------------------ shapes
    def unroll(self, st: EmitState, n_acc: int) -> int:
        """Independent i-vectors per block: as many as keep the accumulators resident
        (or `#pragma unroll N`)."""
        if self.options.unroll:
            return self.options.unroll
        return self.unroll_rule(st)

    def j_tail_mask(self, st: EmitState) -> str:
        return f"svwhilelt_b{st.lane_bits}(jj, jn)"

    def lane_offset(self, st: EmitState, u: int) -> str:
        return "" if u == 0 else " + kW" if u == 1 else f" + {u} * kW"

    def lane_buffer(self, st: EmitState, U: int) -> str:
        return times(U, "kMaxW")

    def block_lanes(self, U: int) -> str:
        return times(U, "kW")

    def lane_capacity(self, st: EmitState) -> str:
        return "kMaxW"

    def lane_count(self, st: EmitState) -> str:
        return "kW"

    def min_lanes(self, st: EmitState) -> int:
        return self.max_bits // st.lane_bits

    def shape_context(self, st: EmitState) -> dict:
        bits = st.lane_bits
        return {"bits": bits, "maxw": self.max_bits // bits, "cnt": "svcntw" if bits == 32 else "svcntd"}
