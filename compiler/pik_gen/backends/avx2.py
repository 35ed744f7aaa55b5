"""The AVX2 (+FMA) backend; AVX-512 (avx512.py) inherits it.

Lanes and register widths
-------------------------
One loop iteration handles W particles in lanes, W = 256 bits / the widest
element a kernel's pair stage uses (64-bit types: W = 4, otherwise W = 8).
Every value of the pair stage holds W lanes in a register of W x its element
width, so mixed precision needs no register pairs: in a kernel with F64, an F32
value is an `__m128` of 4 floats, an S32 index an `__m128i`. F16 is carried in
F32 lanes (more accurate than the reference, which rounds every F16 op).

Loop shapes (templates/simd.hpp.j2; the rule is also documented in docs/simd.md)
----------------------------------------------------------------------------------------
  i-parallel   i-particles in lanes, each j-particle broadcast from a small
               structure-of-arrays buffer the kernel fills with plain C++
               copies. Blocks of U*W i-particles (U independent register sets
               hide the FMA latency), then single vectors; a block's last lanes
               are padded with copies of a real particle and never stored.
  j-parallel   for ni <= W/2 (and nj >= W): one i-particle broadcast, W
               j-particles in lanes, a tail mask on the last vector, the
               accumulators reduced across lanes at the end.

Accuracy
--------
`rsqrt` and `inv` in F32 start from the hardware estimate (12 bits here, 14
bits on AVX-512) and are refined by Newton-Raphson or higher-order Householder
steps to a few ulp; `sqrt` and `/` are the IEEE instructions. On AVX2, F64
`rsqrt` is 1/sqrt and F64 `inv` 1/x with the IEEE instructions (AVX2 has no
F64 estimate), except that one unrolled i-vector in eight computes F64 `rsqrt`
from the F32 estimate of a power-of-four-scaled argument (_rsqrt_f64_scaled,
< 1e-13, every argument) so the FMA pipes share the divider's work. `--fast-math` keeps only the estimate (F32) or one refinement
step of the F32 estimate (F64, valid in the F32 range 1.2e-38 .. 3.4e38).
`exp` and `erfc` are vector code (vmath.py: F64 <= 1 / 4 ulp, F32 <= 1 / 5 ulp).
`log`, `pow` (and any op without a vector instruction, e.g. 64-bit
integer multiply on AVX2) run lane by lane through the C++ standard library,
so they are exactly as accurate as the reference.
"""
from __future__ import annotations

from pik_gen.backends.base import literal
from pik_gen.backends.simd import EmitState, Let, S, Simd, Uarch, ebits
from pik_gen.ir.nodes import Op, TableRef, fresh_name
from pik_gen.types import Scalar, Type

CMP = {"eq": "_CMP_EQ_OQ", "ne": "_CMP_NEQ_UQ", "lt": "_CMP_LT_OQ", "gt": "_CMP_GT_OQ",
       "le": "_CMP_LE_OQ", "ge": "_CMP_GE_OQ"}


class Avx2(Simd):
    name = "avx2"
    isa_label = "AVX2"
    pikg_name = "AVX2"
    summary = "256-bit AVX2 + FMA"
    in_auto = True
    preference = 10
    cpu_check = '__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")'
    function_attributes = '__attribute__((target("avx2,fma")))'
    cxx_flags = ("-mavx2", "-mfma")
    lane_counts = (4, 8)
    includes = ("immintrin.h", "type_traits")
    direct_j_ok = True  # simd.hpp.j2 declares kJDirect (Simd.direct_j)
    # GCC 12 reports the deliberately undefined vectors inside its own intrinsics as
    # maybe-uninitialized (or, at -O2 in some loop shapes, uninitialized) once inlined
    # into a target("...") function (GCC PR 105593).
    gcc_ignores = ("-Wmaybe-uninitialized", "-Wuninitialized")
    reg_bits = 256
    registers = 16
    masks_in_vregs = True
    # Microarchitecture families (--cpu): 256-bit registers, FMA pipes and latency,
    # rsqrtps/rcpps per cycle and the reciprocal throughput of vgatherdps ymm, from
    # the vendors' optimisation manuals and uops.info; `mca` is llvm-mca's -mcpu.
    # f64_divider: the guarded F64 rsqrt stays on vsqrtpd/vdivpd (AMD's divider:
    # llvm-mca -mcpu=znver3 puts gravity F64 at 3.82 cycles per interaction with it
    # against 4.53 with the estimate path; on the Intel host the estimate measured
    # 1.25-1.3x faster, docs/bench-kernels.md).
    UARCH = {
        "generic": Uarch(16, 2, 4, 1.0, 8, "x86-64-v3", "any AVX2 + FMA CPU"),
        "haswell": Uarch(16, 2, 5, 1.0, 12, "haswell", "Haswell, Broadwell"),
        "skylake": Uarch(16, 2, 4, 1.0, 5, "skylake", "Skylake to Comet Lake clients"),
        "znver2": Uarch(16, 2, 5, 1.0, 9, "znver2", "AMD Zen 2", f64_divider=True),
        "znver3": Uarch(16, 2, 4, 1.0, 8, "znver3", "AMD Zen 3 (the issue-15 host)", f64_divider=True),
        # AVX2 code for Zen 4 (AVX-512VL): the Zen 5 row's choices, measured on a Zen 4 host
        # (family 25 model 17) against the 16-register row: gravity F64 AVX2 0.65x -> 0.91-0.93x PIKG;
        # U = 3 or 4 and a divider copy in 3 or 4 were slower (docs/bench-kernels.md, Zen 4).
        # Four j-particles per iteration beside one i-vector (j_copies, Simd.j_copies_rule), the
        # divider taking j-copies 1 and 3: gravity F32 +7.8 %, F64 +8.3 % against two i-vectors,
        # no spill (V = 2, 3: +1-4 %; V = 5 spills; docs/bench-kernels.md, 2026-12-07 fourth session)
        "znver4": Uarch(32, 2, 4, 1.0, 8, "znver3", "AMD Zen 4 running AVX2 code (EVEX: needs AVX-512VL)",
                        f64_divider=True, evex=True, f64_rsqrt14=True, f64_div_every=2, j_copies=(4, 4)),
        # AVX2 code for Zen 5 (AVX-512VL, full-width FP): EVEX encodings, so 32 ymm (gravity U = 2),
        # and the F64 rsqrt by vrsqrt14pd ymm + one fourth-order step (7 instructions, no divider):
        # gravity F64 AVX2 0.60x -> ~0.99x PIKG on the Zen 5 host (docs/bench-kernels.md)
        "znver5": Uarch(32, 2, 4, 1.0, 8, "znver3", "AMD Zen 5 running AVX2 code (EVEX: needs AVX-512VL)",
                        f64_divider=True, evex=True, f64_rsqrt14=True, f64_div_every=2),
        # AVX2 code for an AVX-512 Xeon: EVEX-encoded (target avx512vl), 32 ymm registers, so
        # the register-pressure model admits two gravity i-vectors without a spill (U = 2):
        # gravity F32 1.04x PIKG against 0.96-1.0x at U = 1 with 16 (docs/bench-kernels.md)
        "sapphirerapids": Uarch(32, 2, 4, 1.0, 5, "sapphirerapids",
                                "Intel Xeon 4th/5th gen running AVX2 code (EVEX: needs AVX-512VL)", evex=True),
    }
    default_cpu = "generic"

    def variant_check(self) -> str:
        return self.cpu_check + (' && __builtin_cpu_supports("avx512vl")' if self.uarch()[1].evex else "")

    def variant_attributes(self) -> str:
        return '__attribute__((target("avx2,fma,avx512vl")))' if self.uarch()[1].evex else self.function_attributes

    mix_f64_rsqrt = True  # one unrolled i-vector in MIX_EVERY computes F64 rsqrt off the divider
    guard_special = True  # rsqrt's special-value fix only where a sum turns inf/NaN (Simd.guarded)
    MIX_EVERY = 8
    OPS = {
        # float: {p} prefix (_mm, _mm256, _mm512), {s} suffix (ps, pd)
        ("add", S.F32): "{p}_add_{s}({0}, {1})", ("sub", S.F32): "{p}_sub_{s}({0}, {1})",
        ("mul", S.F32): "{p}_mul_{s}({0}, {1})", ("div", S.F32): "{p}_div_{s}({0}, {1})",
        ("sqrt", S.F32): "{p}_sqrt_{s}({0})",
        # std::min(a, b) = b < a ? b : a = min_ps(b, a), also for NaN and signed zeros
        ("min", S.F32): "{p}_min_{s}({1}, {0})", ("max", S.F32): "{p}_max_{s}({1}, {0})",
        ("neg", S.F32): "{p}_xor_{s}({0}, {p}_set1_{s}({m0}))",
        ("abs", S.F32): "{p}_andnot_{s}({p}_set1_{s}({m0}), {0})",
        ("floor", S.F32): "{p}_floor_{s}({0})",
        ("madd", S.F32): "{p}_fmadd_{s}({0}, {1}, {2})", ("msub", S.F32): "{p}_fmsub_{s}({0}, {1}, {2})",
        ("nmadd", S.F32): "{p}_fnmadd_{s}({0}, {1}, {2})", ("nmsub", S.F32): "{p}_fnmsub_{s}({0}, {1}, {2})",
        # 32-bit integers ({s} = epi32, {u} = epu32 for unsigned kinds)
        ("add", S.S32): "{p}_add_epi32({0}, {1})", ("sub", S.S32): "{p}_sub_epi32({0}, {1})",
        ("mul", S.S32): "{p}_mullo_epi32({0}, {1})", ("neg", S.S32): "{p}_sub_epi32({p}_setzero_{si}(), {0})",
        ("min", S.S32): "{p}_min_{u}({0}, {1})", ("max", S.S32): "{p}_max_{u}({0}, {1})",
        ("abs", S.S32): "{p}_abs_epi32({0})",
        # 64-bit integers: only what AVX2 has; the rest runs lane by lane
        ("add", S.S64): "{p}_add_epi64({0}, {1})", ("sub", S.S64): "{p}_sub_epi64({0}, {1})",
        ("neg", S.S64): "{p}_sub_epi64({p}_setzero_{si}(), {0})",
    }
    for _op in ("add", "sub", "mul", "div", "sqrt", "min", "max", "neg", "abs", "floor", "madd", "msub", "nmadd", "nmsub"):
        OPS[(_op, S.F64)] = OPS[(_op, S.F32)]
    del _op

    # ------------------------------------------------------------ widths
    def W(self, st: EmitState) -> int:
        """Lanes per vector: the register width over the widest element of the pair stage."""
        return self.reg_bits // st.lane_bits

    def vbits(self, st: EmitState, s: Scalar) -> int:
        return self.W(st) * ebits(s)

    def pre(self, st: EmitState, s: Scalar) -> str:
        # wider than a register only for kinds the kernel does not have (never printed)
        return {128: "_mm", 256: "_mm256", 512: "_mm512"}.get(self.vbits(st, s), "_mm_unavailable")

    def suf(self, s: Scalar) -> str:
        return {S.F64: "pd", S.F32: "ps", S.F16: "ps", S.S32: "epi32", S.U32: "epi32", S.S64: "epi64",
                S.U64: "epi64"}[s]

    def home(self, s: Scalar) -> Scalar:
        return {S.F16: S.F32, S.U32: S.S32, S.U64: S.S64}.get(s, s)

    def vtype(self, st: EmitState, t: Type) -> str:
        s = t.scalar
        if s == S.BOOL:
            return self.mask_type(st)
        b = self.vbits(st, s)
        return f"__m{b}d" if s == S.F64 else f"__m{b}" if s.is_float else f"__m{b}i"

    def fields(self, st: EmitState, s: Scalar) -> dict:
        b = self.vbits(st, s)
        return {"p": self.pre(st, s), "s": self.suf(s), "si": f"si{b}",
                "u": ("epu" if s.is_unsigned else "epi") + str(ebits(s)), "W": self.W(st),
                "m0": "-0.0" if s == S.F64 else "-0.0f"}

    # ------------------------------------------------------------ masks
    # AVX2 masks are float vectors with all bits of a lane set (what cmp_ps and
    # blendv use), of 32-bit lanes or, in kernels with 64-bit values, 64-bit lanes.
    def mask_type(self, st: EmitState, bits: int = 32) -> str:
        return self.vtype(st, Type(S.F64 if bits == 64 else S.F32))

    def mask_of(self, st: EmitState, name: str, bits: int) -> str:
        """Mask value `name` converted to lanes of `bits` bits."""
        have = self.mb(st, name)
        expr = self.argv(st, name)
        if have == bits:
            return expr
        if bits == 32:  # 4 x 64 -> 4 x 32: keep the low half of every lane
            return ("_mm_castsi128_ps(_mm256_castsi256_si128(_mm256_permutevar8x32_epi32(_mm256_castpd_si256("
                    f"{expr}), _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7))))")
        return f"_mm256_castsi256_pd(_mm256_cvtepi32_epi64(_mm_castps_si128({expr})))"

    def mask_from_i32(self, st: EmitState, vec: str) -> str:
        """A mask from a vector of S32 lanes that are 0 or -1."""
        return f"{self.pre(st, S.F32)}_castsi{self.vbits(st, S.F32)}_ps({vec})"

    def mask_to_i32(self, st: EmitState, m: str) -> str:
        return f"{self.pre(st, S.F32)}_castps_si{self.vbits(st, S.F32)}({m})"

    def logic(self, st: EmitState, opcode: str, a: str, b: str | None) -> str:
        bits = self.mb(st, a)
        ft = S.F64 if bits == 64 else S.F32
        p, s = self.pre(st, ft), self.suf(ft)
        if opcode == "not":
            ones = f"{p}_castsi{self.vbits(st, ft)}_{s}({p}_set1_epi32(-1))"
            return f"{p}_xor_{s}({self.argv(st, a)}, {ones})"
        assert b is not None
        return f"{p}_{opcode}_{s}({self.argv(st, a)}, {self.mask_of(st, b, bits)})"

    skip_ok = True

    def any_lane(self, st: EmitState, m: str) -> str:
        ft = S.F64 if self.mb(st, m) == 64 else S.F32
        f = self.fields(st, ft)
        return f"{f['p']}_movemask_{f['s']}({self.argv(st, m)})"

    def any_nonfinite(self, st: EmitState, vecs: list[tuple[str, Type]]) -> str:
        """Some lane has all exponent bits set (inf or NaN), tested on the integer bits
        so that no -ffast-math build can fold it away."""
        tests = []
        for name, t in vecs:
            s = self.home(t.scalar)
            f = self.fields(st, s)
            p, b, sf = f["p"], self.vbits(st, s), f["s"]
            e = (f"{p}_set1_epi64x(0x7FF0000000000000LL)" if s == S.F64 else f"{p}_set1_epi32(0x7F800000)")
            eq = "epi64" if s == S.F64 else "epi32"
            tests.append(f"{p}_movemask_{sf}({p}_castsi{b}_{sf}({p}_cmpeq_{eq}({p}_and_si{b}({p}_cast{sf}_si{b}({name}), "
                         f"{e}), {e})))")
        return " | ".join(tests)

    def j_tail_mask(self, st: EmitState) -> str:
        p = self.pre(st, S.S32)
        idx = ", ".join(str(x) for x in range(self.W(st)))
        return f"{p}_castsi{self.vbits(st, S.S32)}_ps({p}_cmpgt_epi32({p}_set1_epi32(jn - jj), {p}_setr_epi32({idx})))"

    def compare(self, st: EmitState, op: Op, a: str, b: str) -> str | None:
        s = st.types[op.args[0]].scalar
        f = self.fields(st, s)
        if s.is_float:
            return f"{f['p']}_cmp_{f['s']}({a}, {b}, {CMP[op.opcode]})"
        if s.is_unsigned or s == S.BOOL:
            return None
        cast = f"{f['p']}_castsi{self.vbits(st, s)}_{'pd' if ebits(s) == 64 else 'ps'}"
        e = f"{f['p']}_cmpeq_{f['s']}"
        g = f"{f['p']}_cmpgt_{f['s']}"
        raw = {"eq": f"{e}({a}, {b})", "gt": f"{g}({a}, {b})", "lt": f"{g}({b}, {a})",
               "ne": f"{e}({a}, {b})", "le": f"{g}({a}, {b})", "ge": f"{g}({b}, {a})"}[op.opcode]
        if op.opcode in ("ne", "le", "ge"):  # the complement of eq, gt, lt
            raw = f"{f['p']}_xor_{f['si']}({raw}, {f['p']}_set1_epi32(-1))"
        return f"{cast}({raw})"

    def select(self, st: EmitState, m: str, a: str, b: str, t: Type) -> str:
        s = t.scalar
        if s == S.BOOL:
            bits = self.mb(st, m)
            ft = S.F64 if bits == 64 else S.F32
            return f"{self.pre(st, ft)}_blendv_{self.suf(ft)}({b}, {a}, {self.argv(st, m)})"
        f = self.fields(st, s)
        mask = self.mask_of(st, m, ebits(s))
        if s.is_float:
            return f"{f['p']}_blendv_{f['s']}({b}, {a}, {mask})"
        mt = "pd" if ebits(s) == 64 else "ps"
        return f"{f['p']}_blendv_epi8({b}, {a}, {f['p']}_cast{mt}_{f['si']}({mask}))"

    masked_arith_ok = True
    premask_ok = True  # masked sums of products: fma(a & m, b, acc) in the guarded fast body (Simd.premasked)

    def masked_arith(self, st: EmitState, kind: str, m: str, x: str, y: str, t: Type) -> str:
        """x - (y & m) for sub, x - (-y & m) for add: where m is clear, x - (+0) = x,
        also for x = -0 and whatever y is (x + 0 would turn -0 into +0); where it
        holds, x - y or x - (-y) = x + y exactly. Two instructions (the negation of a
        loop-invariant y is hoisted) against the op and a blendv (2-3 uops on Intel)."""
        s = self.home(t.scalar)
        f = self.fields(st, s)
        p, sf = f["p"], f["s"]
        mask = self.mask_of(st, m, ebits(s))
        yy = y if kind == "sub" else f"{p}_xor_{sf}({y}, {p}_set1_{sf}({f['m0']}))"
        return f"{p}_sub_{sf}({x}, {p}_and_{sf}({yy}, {mask}))"

    # ------------------------------------------------------------ values
    def bcast(self, st: EmitState, expr: str, s: Scalar) -> str:
        """A vector with `expr` (a scalar C++ expression of kind s) in every lane."""
        if s == S.BOOL:
            return self.mask_from_i32(st, f"{self.pre(st, S.S32)}_set1_epi32(-static_cast<std::int32_t>({expr}))")
        f = self.fields(st, s)
        if s.is_float:
            return f"{f['p']}_set1_{f['s']}({expr})"
        if ebits(s) == 32:
            return f"{f['p']}_set1_epi32(static_cast<std::int32_t>({expr}))"
        return f"{f['p']}_set1_epi64x(static_cast<long long>({expr}))"

    def vload(self, st: EmitState, ptr: str, s: Scalar) -> str:
        if s == S.BOOL:
            return self.mask_from_i32(st, self.vload(st, ptr, S.S32))
        f = self.fields(st, s)
        if s.is_float:
            return f"{f['p']}_load_{f['s']}({ptr})"
        return f"{f['p']}_load_{f['si']}(reinterpret_cast<const __m{self.vbits(st, s)}i*>({ptr}))"

    def vstore(self, st: EmitState, ptr: str, v: str, s: Scalar, pred: str | None = None) -> str:
        if s == S.BOOL:
            return self.vstore(st, ptr, self.mask_to_i32(st, v), S.S32)
        f = self.fields(st, s)
        if s.is_float:
            return f"{f['p']}_store_{f['s']}({ptr}, {v})"
        return f"{f['p']}_store_{f['si']}(reinterpret_cast<__m{self.vbits(st, s)}i*>({ptr}), {v})"

    # ------------------------------------------------------------ refinement
    def refine(self, st: EmitState, opcode: str, x: str, s: Scalar, out: str) -> list[Let]:
        if opcode == "inv":
            return self.refine_inv(st, x, s, out)
        return self.refine_rsqrt(st, x, s, out, opcode == "rsqrt2")

    def refine_rsqrt(self, st: EmitState, x: str, s: Scalar, out: str, twice: bool = False) -> list[Let]:
        """1/sqrt(x), or 2/sqrt(x) for `rsqrt2` (twice). F32: the 12-bit estimate
        (relative error < 1.5 * 2^-12) and one Newton-Raphson step (1.5 e^2 <
        2^-22.4, about 2 ulp). F64: the IEEE square root and division (each
        correctly rounded, any argument); on the Zen 5 host they measured faster
        than the F32 estimate plus a fifth-order step, but one i-vector copy in
        eight through _rsqrt_f64_scaled is faster than none (_estimate_copy).
        --fast-math: F64 from the F32 estimate (F32 range only) plus one NR step."""
        f = self.fields(st, s)
        p, sf, T = f["p"], f["s"], self.vtype(st, Type(s))
        if s == S.F64 and not self.options.fast_math and self.divider_copy(st):
            return [Let(T, out, f"{p}_div_pd({p}_set1_pd({2.0 if twice else 1.0}), {p}_sqrt_pd({x}))")]
        if s == S.F64 and not self.options.fast_math and self.uarch()[1].f64_rsqrt14:
            # AVX-512VL (evex rows): 14-bit estimate of every double (0, subnormals, inf
            # included) and one fourth-order step, exactly as the AVX-512 variant
            y0 = fresh_name(st.used, f"{out}_y0")
            return [Let(T, y0, f"{p}_rsqrt14_pd({x})")] + self._rsqrt_steps(st, x, y0, out, s, ["h4"], twice)
        if (s == S.F64 and not self.options.fast_math and st.fast and st.refining in st.guard
                and not self.uarch()[1].f64_divider):
            return self._rsqrt_f64_guarded(st, x, out, twice)
        if s == S.F64 and not self.options.fast_math and self._estimate_copy(st):
            return self._rsqrt_f64_scaled(st, x, out, twice)
        if s == S.F64 and not self.options.fast_math:
            return [Let(T, out, f"{p}_div_pd({p}_set1_pd({2.0 if twice else 1.0}), {p}_sqrt_pd({x}))")]
        y0 = fresh_name(st.used, f"{out}_y0")
        if s == S.F64:
            est = f"_mm256_cvtps_pd(_mm_rsqrt_ps(_mm256_cvtpd_ps({x})))"
        else:
            est = f"{p}_rsqrt_ps({x})"
        lets = [Let(T, y0, est)]
        if self.options.fast_math and s != S.F64:
            return lets + [Let(T, out, f"{p}_add_{sf}({y0}, {y0})" if twice else y0)]
        return lets + self._rsqrt_steps(st, x, y0, out, s, ["nr"], twice)

    def divider_copy(self, st: EmitState) -> bool:
        """Whether the F64 rsqrt of the i-vector copy being printed is the IEEE divider
        (sqrt + div, exact) instead of the row's estimate path: copy n-1 of every n of a
        block of U >= n copies, n = the row's f64_div_every (0: never). On Zen 5 the
        estimate paths (vrsqrt14pd + a fourth-order step) keep both FMA pipes busy while
        the divide unit idles; one copy in two through it measured gravity F64 +5-8 % on
        AVX2 and +9-11 % on AVX-512 (docs/bench-kernels.md). Tail vectors and the
        j-parallel shape (one copy) keep the estimate."""
        n = self.uarch()[1].f64_div_every
        return n > 0 and st.copies >= n and st.copy % n == n - 1

    def mixes_rsqrt(self, st: EmitState) -> bool:
        """Whether the kernel's F64 rsqrt differs between i-particles (and the ISA mixes in the estimate path)."""
        plan = st.plan
        return (self.mix_f64_rsqrt and not self.options.fast_math
                and any(op.opcode in ("rsqrt", "rsqrt2") and op.type is not None and op.type.scalar == S.F64
                        and op.result in plan.idep for op in plan.pair_ops))

    def _estimate_copy(self, st: EmitState) -> bool:
        """Whether the F64 rsqrt of the i-vector copy being printed takes the
        estimate path (_rsqrt_f64_scaled) instead of the divider: the last of a
        block of MIX_EVERY copies when mixes_rsqrt, so the FMA pipes take a
        share of the work the square-root/divide unit would otherwise serialise.
        Measured on the Zen 5 host (gravity F64, docs/bench-kernels.md): 1 in 8
        +8 %, 1 in 5 or 6 +6 %, 1 in 4 +4 %, 1 in 2 slower (the estimate path's
        ~16 ops per vector then saturate the FMA pipes); U = 8 without any
        estimate copy is no faster than U = 2."""
        n = self.MIX_EVERY
        return st.copies >= n and st.copy % n == n - 1 and self.mixes_rsqrt(st)

    def _rsqrt_f64_guarded(self, st: EmitState, x: str, out: str, twice: bool) -> list[Let]:
        """1/sqrt(x) in F64 without the divider, in the fast body of a guarded shape
        (Simd.guarded): the F32 estimate of x rounded to F32, y0 (relative error
        < 1.5 * 2^-12 + 2^-24), one third-order step y1 = y0 + y0 h (1/2 + 3/8 h),
        h = 1 - x y0^2 (error 5/16 |h|^3 < 1.3e-10), then one Newton step (error
        3/2 e^2 < 3e-20: the result is the rounding of a few F64 operations, 1-2 ulp).
        14 instructions, no sqrt/div. Correct wherever x rounds to a normal F32; every
        other x leaves the result inf or NaN, which the guard's redo pass catches:
        x = 0, or below the F32 range: the estimate is inf; x above it (x rounds to
        inf): y0 is made NaN by xf * 0 + y0 (inf * 0), which would otherwise be a
        silent 0; x = inf, NaN or negative: NaN. The redo computes it with the IEEE
        divider. (Needs IEEE semantics: not for -ffinite-math-only builds, as every
        special value of the kernel.)"""
        p, T = "_mm256", "__m256d"
        xf = fresh_name(st.used, f"{out}_xf")
        y0 = fresh_name(st.used, f"{out}_y0")
        lets = [Let("__m128", xf, f"{p}_cvtpd_ps({x})"),
                Let(T, y0, f"{p}_cvtps_pd(_mm_fmadd_ps({xf}, _mm_setzero_ps(), _mm_rsqrt_ps({xf})))")]
        return lets + self._rsqrt_steps(st, x, y0, out, S.F64, ["h3", "nr"], twice)

    def _rsqrt_f64_scaled(self, st: EmitState, x: str, out: str, twice: bool) -> list[Let]:
        """1/sqrt(x) in F64 without the divider, for every x. x = x' 4^j with
        s = 2^-j read from the exponent bits (s = 2^(511 - floor(E/2)), E the biased
        exponent, always a normal power of two in 2^-512 .. 2^511): x' = (x s) s
        is exact and in [0.5, 2) for normal x, in [2^-52, 1) for subnormal x, and
        keeps 0, inf, NaN and the sign, so the F32 estimate of x' is in range and
        its special results are those of the reference. One fourth-order step
        (error < 35/128 h^4 + rounding, h < 7.4e-4: < 1e-13) and the scale s."""
        p, T = "_mm256", "__m256d"
        sc = fresh_name(st.used, f"{out}_s")
        xs = fresh_name(st.used, f"{out}_x")
        y0 = fresh_name(st.used, f"{out}_y0")
        r = fresh_name(st.used, f"{out}_r")
        lets = [
            Let(T, sc, f"{p}_castsi256_pd({p}_sub_epi64({p}_set1_epi64x(0x5FE0000000000000LL), "
                       f"{p}_and_si256({p}_srli_epi64({p}_castpd_si256({x}), 1), {p}_set1_epi64x(0x3FF0000000000000LL))))"),
            Let(T, xs, f"{p}_mul_pd({p}_mul_pd({x}, {sc}), {sc})"),
            Let(T, y0, f"_mm256_cvtps_pd(_mm_rsqrt_ps(_mm256_cvtpd_ps({xs})))"),
        ]
        lets += self._rsqrt_steps(st, xs, y0, r, S.F64, ["h4"], True)
        if twice:
            return lets + [Let(T, out, f"{p}_mul_pd({r}, {sc})")]
        return lets + [Let(T, out, f"{p}_mul_pd({r}, {p}_mul_pd({sc}, {p}_set1_pd(0.5)))")]

    def _rsqrt_steps(self, st: EmitState, x: str, y: str, out: str, s: Scalar, steps: list[str],
                     twice: bool = False) -> list[Let]:
        """Refinement of the estimate y ~ 1/sqrt(x) with h = 1 - x y^2. Every step
        but the last: nr: y + y h/2 (squares the error); h3: y + y h (1/2 + 3/8 h)
        (cubes it); h4: y + y h (1/2 + h (3/8 + 5/16 h)) (fourth power). The last
        step computes twice its value, y * P2(h) with P2 = 2 + h (nr, as 3 - x y^2),
        2 + h + 3/4 h^2 (h3), 2 + h + 3/4 h^2 + 5/8 h^3 (h4), one multiply cheaper
        (rsqrt2 keeps it; rsqrt halves it). The result is then max(y P2, y0): equal
        to y P2 for every positive finite x (y P2 ~ 2 y0 > y0), and y0 where x y0^2
        is 0 * inf (x = 0: inf; x = inf: 0) so rsqrt(0) = inf and rsqrt(inf) = 0 as
        in the reference; NaN stays NaN. In the fast body of a guarded shape
        (Simd.guarded) the max is left out: there y P2 is used as it is, and a block
        where it is not finite runs again with the max."""
        f = self.fields(st, s)
        p, sf, T = f["p"], f["s"], self.vtype(st, Type(s))
        c = lambda v: f"{p}_set1_{sf}({literal(v, Type(s))})"  # noqa: E731
        y0 = y
        lets = []
        for n, step in enumerate(steps[:-1]):
            h = fresh_name(st.used, f"{out}_h")
            yn = fresh_name(st.used, f"{out}_y{n + 1}")
            lets.append(Let(T, h, f"{p}_fnmadd_{sf}({p}_mul_{sf}({x}, {y}), {y}, {c(1.0)})"))
            yh = f"{p}_mul_{sf}({y}, {h})"
            poly = {"nr": c(0.5), "h3": f"{p}_fmadd_{sf}({h}, {c(0.375)}, {c(0.5)})",
                    "h4": f"{p}_fmadd_{sf}({p}_fmadd_{sf}({h}, {c(0.3125)}, {c(0.375)}), {h}, {c(0.5)})"}[step]
            lets.append(Let(T, yn, f"{p}_fmadd_{sf}({yh}, {poly}, {y})"))
            y = yn
        last = steps[-1]
        h = fresh_name(st.used, f"{out}_h")
        two = fresh_name(st.used, f"{out}_2") if not twice else out
        if last == "nr":
            lets.append(Let(T, h, f"{p}_fnmadd_{sf}({p}_mul_{sf}({x}, {y}), {y}, {c(3.0)})"))
            p2 = h
        else:
            lets.append(Let(T, h, f"{p}_fnmadd_{sf}({p}_mul_{sf}({x}, {y}), {y}, {c(1.0)})"))
            p2 = f"{p}_fmadd_{sf}({h}, {c(0.75)}, {c(1.0)})"
            if last == "h4":
                p2 = f"{p}_fmadd_{sf}({p}_fmadd_{sf}({h}, {c(0.625)}, {c(0.75)}), {h}, {c(1.0)})"
            p2 = f"{p}_fmadd_{sf}({p2}, {h}, {c(2.0)})"
        if st.fast and st.refining in st.guard:
            lets.append(Let(T, two, f"{p}_mul_{sf}({y}, {p2})"))
        else:
            lets.append(Let(T, two, f"{p}_max_{sf}({p}_mul_{sf}({y}, {p2}), {y0})"))
        if not twice:
            lets.append(Let(T, out, f"{p}_mul_{sf}({two}, {c(0.5)})"))
        return lets

    def refine_inv(self, st: EmitState, x: str, s: Scalar, out: str) -> list[Let]:
        """1/x: F64 the IEEE division; F32 the 12-bit estimate and one third-order step."""
        f = self.fields(st, s)
        p, T = f["p"], self.vtype(st, Type(s))
        if s == S.F64:
            return [Let(T, out, f"{p}_div_pd({p}_set1_pd(1.0), {x})")]
        y0 = fresh_name(st.used, f"{out}_y0")
        lets = [Let(T, y0, f"{p}_rcp_ps({x})")]
        if self.options.fast_math:
            return lets + [Let(T, out, y0)]
        return lets + self._inv_steps(st, x, y0, out, s, ["h3"])

    def _inv_steps(self, st: EmitState, x: str, y: str, out: str, s: Scalar, steps: list[str]) -> list[Let]:
        """Refinement of y ~ 1/x with h = 1 - x y: nr: y + y h; h3: y + y (h + h^2)."""
        f = self.fields(st, s)
        p, sf, T = f["p"], f["s"], self.vtype(st, Type(s))
        lets = []
        for n, step in enumerate(steps):
            last = n == len(steps) - 1
            h = fresh_name(st.used, f"{out}_h")
            yn = out if last else fresh_name(st.used, f"{out}_y{n + 1}")
            lets.append(Let(T, h, f"{p}_fnmadd_{sf}({x}, {y}, {p}_set1_{sf}({literal(1, Type(s))}))"))
            e = h if step == "nr" else f"{p}_fmadd_{sf}({h}, {h}, {h})"
            lets.append(Let(T, yn, f"{p}_fmadd_{sf}({y}, {e}, {y})"))
            y = yn
        return lets

    # ------------------------------------------------------------ exp, erfc (vmath.py)
    def vround(self, st: EmitState, s: Scalar, x: str) -> str:
        f = self.fields(st, s)
        return f"{f['p']}_round_{f['s']}({x}, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC)"

    def vpow2(self, st: EmitState, s: Scalar, n: str) -> str:
        """n + 1.5 * 2^52 + 1023 (F64) has n + 1023 in its low mantissa bits; shifted
        into the exponent field it is 2^n (the 1.5 * 2^52 bits leave the register)."""
        f = self.fields(st, s)
        p, sf, b = f["p"], f["s"], self.vbits(st, s)
        if self.home(s) == S.F64:
            bias, bits, shift = "6755399441056767.0", "epi64", 52
        else:
            bias, bits, shift = "12583039.0f", "epi32", 23
        return (f"{p}_castsi{b}_{sf}({p}_slli_{bits}({p}_cast{sf}_si{b}({p}_add_{sf}({n}, "
                f"{p}_set1_{sf}({bias}))), {shift}))")

    def select_negative(self, st: EmitState, s: Scalar, x: str, a: str, b: str) -> str:
        f = self.fields(st, s)
        return f"{f['p']}_blendv_{f['s']}({b}, {a}, {x})"  # by the sign bit of each lane of x

    # ------------------------------------------------------------ casts, tables
    def cast(self, st: EmitState, src: Scalar, dst: Scalar, x: str) -> str | None:
        hs, hd = self.home(src), self.home(dst)
        if hs == hd:
            return x
        p64, p32 = self.pre(st, S.F64), self.pre(st, S.F32)
        table = {
            (S.F64, S.F32): f"{p64}_cvtpd_ps({x})", (S.F32, S.F64): f"{p64}_cvtps_pd({x})",
            (S.F32, S.S32): f"{p32}_cvttps_epi32({x})", (S.F64, S.S32): f"{p64}_cvttpd_epi32({x})",
            (S.S32, S.F32): f"{p32}_cvtepi32_ps({x})", (S.S32, S.F64): f"{p64}_cvtepi32_pd({x})",
            (S.S32, S.S64): f"{p64}_cvtepi32_epi64({x})",
        }
        if src.is_unsigned or dst.is_unsigned:
            # F <-> U and widening U32 need unsigned conversions AVX2 lacks
            return x if (src.is_int and dst.is_int and ebits(src) == ebits(dst)) else None
        return table.get((hs, hd))

    def gather(self, st: EmitState, op: Op, idx: str) -> str | None:
        assert isinstance(op.attr, TableRef) and op.type is not None
        if self.home(st.types[op.args[0]].scalar) != S.S32 or op.type.scalar not in (S.F32, S.F64):
            return None
        f = self.fields(st, op.type.scalar)
        p, sf = f["p"], f["s"]
        # the masked form: GCC 12 warns about the undefined source of the plain one
        ones = f"{p}_castsi{self.vbits(st, op.type.scalar)}_{sf}({p}_set1_epi32(-1))"
        return (f"{p}_mask_i32gather_{sf}({p}_setzero_{sf}(), {op.attr.name}, {idx}, {ones}, "
                f"{ebits(op.type.scalar) // 8})")

    def lane_arg(self, st: EmitState, x: str) -> tuple[Scalar, str]:
        s = st.types[x].scalar
        return s, self.mask_of(st, x, 32) if s == S.BOOL else self.argv(st, x)

    # ------------------------------------------------------------ accumulation
    def can_fuse(self, masked: bool) -> bool:
        return not masked

    def acc_update(self, st: EmitState, kind: str, acc: str, v: str, m: str | None, t: Type,
                   fused: tuple[str, str] | None) -> str:
        s = self.home(t.scalar)
        f = self.fields(st, s)
        p, sf = f["p"], f["s"]
        if fused is not None and m is None:
            fn = "fmadd" if kind == "add" else "fnmadd"
            return f"{p}_{fn}_{sf}({fused[0]}, {fused[1]}, {acc})"
        if fused is not None and st.fast and self.premask_ok and kind in ("add", "sub"):  # Simd.premasked
            fn = "fmadd" if kind == "add" else "fnmadd"
            return f"{p}_{fn}_{sf}({p}_and_{sf}({fused[0]}, {self.mask_of(st, m, ebits(s))}), {fused[1]}, {acc})"
        if fused is not None:
            v = f"{p}_mul_{sf}({fused[0]}, {fused[1]})"
        if kind in ("add", "sub"):
            if m is not None:
                mask = self.mask_of(st, m, ebits(s))
                v = (f"{p}_and_{sf}({v}, {mask})" if s.is_float else
                     f"{p}_and_{f['si']}({v}, {p}_cast{'pd' if ebits(s) == 64 else 'ps'}_{f['si']}({mask}))")
            return self.OPS[(kind, s)].format(acc, v, **f)
        fmt = self.OPS.get((kind, s))
        if fmt is None:
            raise KeyError(f"ISA {self.name} cannot accumulate '{kind}' on {t.scalar.value}")
        new = fmt.format(acc, v, **f)  # max/min: the table's operand order keeps acc where v is NaN
        return new if m is None else self.select(st, m, new, acc, t)

    # ------------------------------------------------------------ shapes
    def unroll(self, st: EmitState, n_acc: int) -> int:
        """i-vectors per block (U): `Simd.unroll_rule`, the register-pressure model on
        the --cpu family's row of UARCH (docs/simd.md), or `#pragma unroll N` /
        --unroll N. The F64 rsqrt mix (_estimate_copy) needs U = 8, which spills on
        every family (16 ymm): it is used only when asked for with unroll 8."""
        if self.options.unroll:
            return self.options.unroll
        return self.unroll_rule(st)

    def lane_offset(self, st: EmitState, u: int) -> str:
        return f" + {u * self.W(st)}" if u else ""

    def lane_buffer(self, st: EmitState, U: int) -> str:
        return str(U * self.W(st))

    def lane_capacity(self, st: EmitState) -> str:
        return str(self.W(st))

    def lane_count(self, st: EmitState) -> str:
        return str(self.W(st))

    def min_lanes(self, st: EmitState) -> int:
        return self.W(st)

    def shape_context(self, st: EmitState) -> dict:
        return {"W": self.W(st)}
