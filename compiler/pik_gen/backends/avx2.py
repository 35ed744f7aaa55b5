"""The AVX2 (+FMA) backend, and the SIMD machinery AVX-512 inherits.

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
`exp`, `log`, `pow` (and any op without a vector instruction, e.g. 64-bit
integer multiply on AVX2) run lane by lane through the C++ standard library,
so they are exactly as accurate as the reference.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from pik_gen.backends.reference import Reference
from pik_gen.backends.simd_common import S, Simd, ebits
from pik_gen.ir.nodes import Kernel, Op, Reduce, TableRef, fresh_name
from pik_gen.types import Scalar, Type

CMP = {"eq": "_CMP_EQ_OQ", "ne": "_CMP_NEQ_UQ", "lt": "_CMP_LT_OQ", "gt": "_CMP_GT_OQ",
       "le": "_CMP_LE_OQ", "ge": "_CMP_GE_OQ"}


def home(s: Scalar) -> Scalar:
    """The scalar kind whose vector instructions implement s."""
    return {S.F16: S.F32, S.U32: S.S32, S.U64: S.S64}.get(s, s)


@dataclass
class Shape:
    """Printed lines of one loop shape (i-parallel block of U vectors, or j-parallel)."""

    U: int
    i_fill: list[str] = field(default_factory=list)      # scalar i stage + stores into i buffers
    ibuf_decls: list[str] = field(default_factory=list)
    i_vec: list[str] = field(default_factory=list)       # i values as vectors
    acc_init: list[str] = field(default_factory=list)
    j_vec: list[str] = field(default_factory=list)       # j values as vectors (top of the j loop)
    pair: list[str] = field(default_factory=list)
    finish: list[str] = field(default_factory=list)      # accumulators into FORCE


class Avx2(Simd):
    name = "avx2"
    mix_rsqrt = False  # set per kernel in context(): F64 rsqrt in the pair stage
    MIX_EVERY = 8
    cur_u = 0
    cur_U = 1
    isa_label = "AVX2"
    in_auto = True
    preference = 10
    cpu_check = '__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")'
    function_attributes = '__attribute__((target("avx2,fma")))'
    cxx_flags = ("-mavx2", "-mfma")
    reg_bits = 256
    lanes = {S.F64: 4, S.F32: 8, S.F16: 8, S.S64: 4, S.U64: 4, S.S32: 8, S.U32: 8}
    template = "simd.hpp.j2"
    includes = ("immintrin.h",)
    # GCC 12 reports the deliberately undefined vectors inside its own intrinsics as
    # maybe-uninitialized once inlined into a target("...") function (GCC PR 105593).
    gcc_ignores = ("-Wmaybe-uninitialized",)
    registers = 16
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
    W: int = 8

    def vbits(self, s: Scalar) -> int:
        return self.W * ebits(s)

    def pre(self, s: Scalar) -> str:
        # wider than a register only for kinds the kernel does not have (never printed)
        return {128: "_mm", 256: "_mm256", 512: "_mm512"}.get(self.vbits(s), "_mm_unavailable")

    def suf(self, s: Scalar) -> str:
        return {S.F64: "pd", S.F32: "ps", S.F16: "ps", S.S32: "epi32", S.U32: "epi32", S.S64: "epi64",
                S.U64: "epi64"}[s]

    def vtype(self, t: Type) -> str:
        s = t.scalar
        if s == S.BOOL:
            return self.mask_type()
        b = self.vbits(s)
        return f"__m{b}d" if s == S.F64 else f"__m{b}" if s.is_float else f"__m{b}i"

    def fields(self, s: Scalar) -> dict:
        b = self.vbits(s)
        return {"p": self.pre(s), "s": self.suf(s), "si": f"si{b}",
                "u": ("epu" if s.is_unsigned else "epi") + str(ebits(s)), "W": self.W,
                "m0": "-0.0" if s == S.F64 else "-0.0f"}

    # ------------------------------------------------------------ masks
    # AVX2 masks are float vectors with all bits of a lane set (what cmp_ps and
    # blendv use), of 32-bit lanes or, in kernels with 64-bit values, 64-bit lanes.
    def mask_type(self, bits: int = 32) -> str:
        return self.vtype(Type(S.F64 if bits == 64 else S.F32))

    def mb(self, name: str) -> int:
        """Lane width (32 or 64 bits) of mask value `name`."""
        return self.mbits.get(self.vmap.get(name, name), 32)

    def mask_of(self, name: str, bits: int) -> str:
        """Mask value `name` converted to lanes of `bits` bits."""
        have = self.mb(name)
        expr = self.argv(name)
        if have == bits:
            return expr
        if bits == 32:  # 4 x 64 -> 4 x 32: keep the low half of every lane
            return ("_mm_castsi128_ps(_mm256_castsi256_si128(_mm256_permutevar8x32_epi32(_mm256_castpd_si256("
                    f"{expr}), _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7))))")
        return f"_mm256_castsi256_pd(_mm256_cvtepi32_epi64(_mm_castps_si128({expr})))"

    def mask_from_i32(self, vec: str) -> str:
        """A mask from a vector of S32 lanes that are 0 or -1."""
        return f"{self.pre(S.F32)}_castsi{self.vbits(S.F32)}_ps({vec})"

    def mask_to_i32(self, m: str) -> str:
        return f"{self.pre(S.F32)}_castps_si{self.vbits(S.F32)}({m})"

    def mask_logic(self, opcode: str, a: str, b: str | None) -> str:
        bits = self.mb(a)
        ft = S.F64 if bits == 64 else S.F32
        p, s = self.pre(ft), self.suf(ft)
        if opcode == "not":
            ones = f"{p}_castsi{self.vbits(ft)}_{s}({p}_set1_epi32(-1))"
            return f"{p}_xor_{s}({self.argv(a)}, {ones})"
        assert b is not None
        return f"{p}_{opcode}_{s}({self.argv(a)}, {self.mask_of(b, bits)})"

    def tail_mask(self, remaining: str) -> str:
        p = self.pre(S.S32)
        idx = ", ".join(str(x) for x in range(self.W))
        return f"{p}_castsi{self.vbits(S.S32)}_ps({p}_cmpgt_epi32({p}_set1_epi32({remaining}), {p}_setr_epi32({idx})))"

    def compare(self, op: Op, a: str, b: str) -> str | None:
        s = self.types[op.args[0]].scalar
        f = self.fields(s)
        if s.is_float:
            return f"{f['p']}_cmp_{f['s']}({a}, {b}, {CMP[op.opcode]})"
        if s.is_unsigned or s == S.BOOL:
            return None
        cast = f"{f['p']}_castsi{self.vbits(s)}_{'pd' if ebits(s) == 64 else 'ps'}"
        e = f"{f['p']}_cmpeq_{f['s']}"
        g = f"{f['p']}_cmpgt_{f['s']}"
        raw = {"eq": f"{e}({a}, {b})", "gt": f"{g}({a}, {b})", "lt": f"{g}({b}, {a})",
               "ne": f"{e}({a}, {b})", "le": f"{g}({a}, {b})", "ge": f"{g}({b}, {a})"}[op.opcode]
        if op.opcode in ("ne", "le", "ge"):  # the complement of eq, gt, lt
            raw = f"{f['p']}_xor_{f['si']}({raw}, {f['p']}_set1_epi32(-1))"
        return f"{cast}({raw})"

    def select(self, m: str, a: str, b: str, t: Type) -> str:
        s = t.scalar
        if s == S.BOOL:
            bits = self.mb(m)
            ft = S.F64 if bits == 64 else S.F32
            return f"{self.pre(ft)}_blendv_{self.suf(ft)}({b}, {a}, {self.argv(m)})"
        f = self.fields(s)
        mask = self.mask_of(m, ebits(s))
        if s.is_float:
            return f"{f['p']}_blendv_{f['s']}({b}, {a}, {mask})"
        mt = "pd" if ebits(s) == 64 else "ps"
        return f"{f['p']}_blendv_epi8({b}, {a}, {f['p']}_cast{mt}_{f['si']}({mask}))"

    # ------------------------------------------------------------ values
    def bcast(self, expr: str, s: Scalar) -> str:
        """A vector with `expr` (a scalar C++ expression of kind s) in every lane."""
        if s == S.BOOL:
            return self.mask_from_i32(f"{self.pre(S.S32)}_set1_epi32(-static_cast<std::int32_t>({expr}))")
        f = self.fields(s)
        if s.is_float:
            return f"{f['p']}_set1_{f['s']}({expr})"
        if ebits(s) == 32:
            return f"{f['p']}_set1_epi32(static_cast<std::int32_t>({expr}))"
        return f"{f['p']}_set1_epi64x(static_cast<long long>({expr}))"

    def vload(self, ptr: str, s: Scalar) -> str:
        if s == S.BOOL:
            return self.mask_from_i32(self.vload(ptr, S.S32))
        f = self.fields(s)
        if s.is_float:
            return f"{f['p']}_load_{f['s']}({ptr})"
        return f"{f['p']}_load_{f['si']}(reinterpret_cast<const __m{self.vbits(s)}i*>({ptr}))"

    def vstore(self, ptr: str, v: str, s: Scalar) -> str:
        if s == S.BOOL:
            return self.vstore(ptr, self.mask_to_i32(v), S.S32)
        f = self.fields(s)
        if s.is_float:
            return f"{f['p']}_store_{f['s']}({ptr}, {v});"
        return f"{f['p']}_store_{f['si']}(reinterpret_cast<__m{self.vbits(s)}i*>({ptr}), {v});"

    def literal_vec(self, value, t: Type) -> str:
        if t.scalar == S.BOOL:
            return self.bcast("true" if value else "false", S.BOOL)
        return self.bcast(Reference.literal(self, value, t), t.scalar)

    # ------------------------------------------------------------ refinement
    def refine_rsqrt(self, x: str, s: Scalar, out: str, twice: bool = False) -> list[str]:
        """1/sqrt(x), or 2/sqrt(x) for `rsqrt2` (twice). F32: the 12-bit estimate
        (relative error < 1.5 * 2^-12) and one Newton-Raphson step (1.5 e^2 <
        2^-22.4, about 2 ulp). F64: the IEEE square root and division (each
        correctly rounded, any argument); on the Zen 5 host they measured faster
        than the F32 estimate plus a fifth-order step, but one i-vector copy in
        eight through _rsqrt_f64_scaled is faster than none (_estimate_copy).
        --fast-math: F64 from the F32 estimate (F32 range only) plus one NR step."""
        f = self.fields(s)
        p, sf, T = f["p"], f["s"], self.vtype(Type(s))
        if s == S.F64 and not self.options.fast_math and self._estimate_copy():
            return self._rsqrt_f64_scaled(x, out, twice)
        if s == S.F64 and not self.options.fast_math:
            return [f"const {T} {out} = {p}_div_pd({p}_set1_pd({2.0 if twice else 1.0}), {p}_sqrt_pd({x}));"]
        y0 = fresh_name(self.used, f"{out}_y0")
        if s == S.F64:
            est = f"_mm256_cvtps_pd(_mm_rsqrt_ps(_mm256_cvtpd_ps({x})))"
        else:
            est = f"{p}_rsqrt_ps({x})"
        lines = [f"const {T} {y0} = {est};"]
        if self.options.fast_math and s != S.F64:
            two = f"{p}_add_{sf}({y0}, {y0})"
            return lines + [f"const {T} {out} = {two if twice else y0};"]
        return lines + self._rsqrt_steps(x, y0, out, s, ["nr"], twice)

    def _estimate_copy(self) -> bool:
        """Whether the F64 rsqrt of the i-vector copy being printed takes the
        estimate path (_rsqrt_f64_scaled) instead of the divider: the last of a
        block of MIX_EVERY copies when mix_rsqrt is on, so the FMA pipes take a
        share of the work the square-root/divide unit would otherwise serialise.
        Measured on the Zen 5 host (gravity F64, docs/bench-kernels.md): 1 in 8
        +8 %, 1 in 5 or 6 +6 %, 1 in 4 +4 %, 1 in 2 slower (the estimate path's
        ~16 ops per vector then saturate the FMA pipes); U = 8 without any
        estimate copy is no faster than U = 2."""
        n = self.MIX_EVERY
        return self.mix_rsqrt and self.cur_U >= n and self.cur_u % n == n - 1

    def _rsqrt_f64_scaled(self, x: str, out: str, twice: bool) -> list[str]:
        """1/sqrt(x) in F64 without the divider, for every x. x = x' 4^j with
        s = 2^-j read from the exponent bits (s = 2^(511 - floor(E/2)), E the biased
        exponent, always a normal power of two in 2^-512 .. 2^511): x' = (x s) s
        is exact and in [0.5, 2) for normal x, in [2^-52, 1) for subnormal x, and
        keeps 0, inf, NaN and the sign, so the F32 estimate of x' is in range and
        its special results are those of the reference. One fourth-order step
        (error < 35/128 h^4 + rounding, h < 7.4e-4: < 1e-13) and the scale s."""
        p, T = "_mm256", "__m256d"
        sc = fresh_name(self.used, f"{out}_s")
        xs = fresh_name(self.used, f"{out}_x")
        y0 = fresh_name(self.used, f"{out}_y0")
        r = fresh_name(self.used, f"{out}_r")
        lines = [
            f"const {T} {sc} = {p}_castsi256_pd({p}_sub_epi64({p}_set1_epi64x(0x5FE0000000000000LL), "
            f"{p}_and_si256({p}_srli_epi64({p}_castpd_si256({x}), 1), {p}_set1_epi64x(0x3FF0000000000000LL))));",
            f"const {T} {xs} = {p}_mul_pd({p}_mul_pd({x}, {sc}), {sc});",
            f"const {T} {y0} = _mm256_cvtps_pd(_mm_rsqrt_ps(_mm256_cvtpd_ps({xs})));",
        ]
        lines += self._rsqrt_steps(xs, y0, r, S.F64, ["h4"], True)
        if twice:
            return lines + [f"const {T} {out} = {p}_mul_pd({r}, {sc});"]
        return lines + [f"const {T} {out} = {p}_mul_pd({r}, {p}_mul_pd({sc}, {p}_set1_pd(0.5)));"]

    def _rsqrt_steps(self, x: str, y: str, out: str, s: Scalar, steps: list[str], twice: bool = False) -> list[str]:
        """Refinement of the estimate y ~ 1/sqrt(x) with h = 1 - x y^2. Every step
        but the last: nr: y + y h/2 (squares the error); h3: y + y h (1/2 + 3/8 h)
        (cubes it); h4: y + y h (1/2 + h (3/8 + 5/16 h)) (fourth power). The last
        step computes twice its value, y * P2(h) with P2 = 2 + h (nr, as 3 - x y^2),
        2 + h + 3/4 h^2 (h3), 2 + h + 3/4 h^2 + 5/8 h^3 (h4), one multiply cheaper
        (rsqrt2 keeps it; rsqrt halves it). The result is then max(y P2, y0): equal
        to y P2 for every positive finite x (y P2 ~ 2 y0 > y0), and y0 where x y0^2
        is 0 * inf (x = 0: inf; x = inf: 0) so rsqrt(0) = inf and rsqrt(inf) = 0 as
        in the reference; NaN stays NaN."""
        f = self.fields(s)
        p, sf, T = f["p"], f["s"], self.vtype(Type(s))
        c = lambda v: f"{p}_set1_{sf}({Reference.literal(self, v, Type(s))})"  # noqa: E731
        y0 = y
        lines = []
        for n, step in enumerate(steps[:-1]):
            h = fresh_name(self.used, f"{out}_h")
            yn = fresh_name(self.used, f"{out}_y{n + 1}")
            lines.append(f"const {T} {h} = {p}_fnmadd_{sf}({p}_mul_{sf}({x}, {y}), {y}, {c(1.0)});")
            yh = f"{p}_mul_{sf}({y}, {h})"
            poly = {"nr": c(0.5), "h3": f"{p}_fmadd_{sf}({h}, {c(0.375)}, {c(0.5)})",
                    "h4": f"{p}_fmadd_{sf}({p}_fmadd_{sf}({h}, {c(0.3125)}, {c(0.375)}), {h}, {c(0.5)})"}[step]
            lines.append(f"const {T} {yn} = {p}_fmadd_{sf}({yh}, {poly}, {y});")
            y = yn
        last = steps[-1]
        h = fresh_name(self.used, f"{out}_h")
        two = fresh_name(self.used, f"{out}_2") if not twice else out
        if last == "nr":
            lines.append(f"const {T} {h} = {p}_fnmadd_{sf}({p}_mul_{sf}({x}, {y}), {y}, {c(3.0)});")
            p2 = h
        else:
            lines.append(f"const {T} {h} = {p}_fnmadd_{sf}({p}_mul_{sf}({x}, {y}), {y}, {c(1.0)});")
            p2 = f"{p}_fmadd_{sf}({h}, {c(0.75)}, {c(1.0)})"
            if last == "h4":
                p2 = f"{p}_fmadd_{sf}({p}_fmadd_{sf}({h}, {c(0.625)}, {c(0.75)}), {h}, {c(1.0)})"
            p2 = f"{p}_fmadd_{sf}({p2}, {h}, {c(2.0)})"
        lines.append(f"const {T} {two} = {p}_max_{sf}({p}_mul_{sf}({y}, {p2}), {y0});")
        if not twice:
            lines.append(f"const {T} {out} = {p}_mul_{sf}({two}, {c(0.5)});")
        return lines

    def refine_inv(self, x: str, s: Scalar, out: str) -> list[str]:
        """1/x: F64 the IEEE division; F32 the 12-bit estimate and one third-order step."""
        f = self.fields(s)
        p, T = f["p"], self.vtype(Type(s))
        if s == S.F64:
            return [f"const {T} {out} = {p}_div_pd({p}_set1_pd(1.0), {x});"]
        y0 = fresh_name(self.used, f"{out}_y0")
        lines = [f"const {T} {y0} = {p}_rcp_ps({x});"]
        if self.options.fast_math:
            return lines + [f"const {T} {out} = {y0};"]
        return lines + self._inv_steps(x, y0, out, s, ["h3"])

    def _inv_steps(self, x: str, y: str, out: str, s: Scalar, steps: list[str]) -> list[str]:
        """Refinement of y ~ 1/x with h = 1 - x y: nr: y + y h; h3: y + y (h + h^2)."""
        f = self.fields(s)
        p, sf, T = f["p"], f["s"], self.vtype(Type(s))
        lines = []
        for n, step in enumerate(steps):
            last = n == len(steps) - 1
            h = fresh_name(self.used, f"{out}_h")
            yn = out if last else fresh_name(self.used, f"{out}_y{n + 1}")
            lines.append(f"const {T} {h} = {p}_fnmadd_{sf}({x}, {y}, {p}_set1_{sf}({Reference.literal(self, 1, Type(s))}));")
            e = h if step == "nr" else f"{p}_fmadd_{sf}({h}, {h}, {h})"
            lines.append(f"const {T} {yn} = {p}_fmadd_{sf}({y}, {e}, {y});")
            y = yn
        return lines

    # ------------------------------------------------------------ casts, tables
    def cast(self, src: Scalar, dst: Scalar, x: str) -> str | None:
        hs, hd = home(src), home(dst)
        if hs == hd:
            return x
        key = (hs, hd)
        p64, p32 = self.pre(S.F64), self.pre(S.F32)
        table = {
            (S.F64, S.F32): f"{p64}_cvtpd_ps({x})", (S.F32, S.F64): f"{p64}_cvtps_pd({x})",
            (S.F32, S.S32): f"{p32}_cvttps_epi32({x})", (S.F64, S.S32): f"{p64}_cvttpd_epi32({x})",
            (S.S32, S.F32): f"{p32}_cvtepi32_ps({x})", (S.S32, S.F64): f"{p64}_cvtepi32_pd({x})",
            (S.S32, S.S64): f"{p64}_cvtepi32_epi64({x})",
        }
        if src.is_unsigned or dst.is_unsigned:
            # F <-> U and widening U32 need unsigned conversions AVX2 lacks
            return x if (src.is_int and dst.is_int and ebits(src) == ebits(dst)) else None
        return table.get(key)

    def gather(self, op: Op, idx: str) -> str | None:
        assert isinstance(op.attr, TableRef) and op.type is not None
        if home(self.types[op.args[0]].scalar) != S.S32 or op.type.scalar not in (S.F32, S.F64):
            return None
        f = self.fields(op.type.scalar)
        p, sf = f["p"], f["s"]
        # the masked form: GCC 12 warns about the undefined source of the plain one
        ones = f"{p}_castsi{self.vbits(op.type.scalar)}_{sf}({p}_set1_epi32(-1))"
        return (f"{p}_mask_i32gather_{sf}({p}_setzero_{sf}(), {op.attr.name}, {idx}, {ones}, "
                f"{ebits(op.type.scalar) // 8})")

    # ------------------------------------------------------------ one op
    def lookup_vec(self, opcode: str, s: Scalar) -> str | None:
        return self.OPS.get((opcode, home(s)))

    def vec_op(self, op: Op) -> list[str]:
        """The statements computing pair op `op` on W lanes."""
        assert op.type is not None
        t, s, r = op.type, op.type.scalar, self.vmap.get(op.result, op.result)
        a = [self.argv(x) for x in op.args]
        self.types[op.result] = t
        expr: str | None = None
        oc = op.opcode
        bits = 32
        if oc in CMP:
            expr = self.compare(op, *a)
            if expr is not None:
                bits = ebits(self.types[op.args[0]].scalar)
        elif oc in ("and", "or", "not"):
            expr = self.mask_logic(oc, op.args[0], op.args[1] if len(op.args) > 1 else None)
            bits = self.mb(op.args[0])
        elif oc == "select":
            expr = self.select(op.args[0], a[1], a[2], t)
            if s == S.BOOL:
                bits = self.mb(op.args[0])
        elif oc in ("rsqrt", "rsqrt2") and s in (S.F32, S.F64, S.F16):
            return self.refine_rsqrt(a[0], home(s), r, oc == "rsqrt2")
        elif oc == "inv" and s in (S.F32, S.F64, S.F16):
            return self.refine_inv(a[0], home(s), r)
        elif oc == "cast":
            expr = self.cast(self.types[op.args[0]].scalar, s, a[0])
        elif oc == "table":
            expr = self.gather(op, a[0])
        elif s != S.BOOL:
            fmt = self.lookup_vec(oc, s)
            if fmt is not None:
                expr = fmt.format(*a, **self.fields(s))
        if expr is None:
            return self.lanewise(op, r)
        T = self.vtype(t)
        if s == S.BOOL:
            self.mbits[r] = bits
            T = self.mask_type(bits)
        return [f"const {T} {r} = {expr};"]

    def lane_capacity(self) -> str:
        return str(self.W)

    def lane_count(self) -> str:
        return str(self.W)

    def lane_arg(self, x: str) -> tuple[Scalar, str]:
        s = self.types[x].scalar
        return s, self.mask_of(x, 32) if s == S.BOOL else self.argv(x)

    def lanewise(self, op: Op, r: str) -> list[str]:
        lines = super().lanewise(op, r)
        if op.type is not None and op.type.scalar == S.BOOL:
            self.mbits[r] = 32
        return lines

    # ------------------------------------------------------------ accumulation
    def acc_update(self, kind: str, acc: str, v: str, m: str | None, t: Type, fused: tuple[str, str] | None) -> str:
        s = home(t.scalar)
        f = self.fields(s)
        p, sf = f["p"], f["s"]
        if fused is not None and m is None:
            fn = "fmadd" if kind == "add" else "fnmadd"
            return f"{acc} = {p}_{fn}_{sf}({fused[0]}, {fused[1]}, {acc});"
        if fused is not None:
            v = f"{p}_mul_{sf}({fused[0]}, {fused[1]})"
        if kind in ("add", "sub"):
            if m is not None:
                mask = self.mask_of(m, ebits(s))
                v = (f"{p}_and_{sf}({v}, {mask})" if s.is_float else
                     f"{p}_and_{f['si']}({v}, {p}_cast{'pd' if ebits(s) == 64 else 'ps'}_{f['si']}({mask}))")
            fmt = self.OPS[(kind, s)]
            return f"{acc} = {fmt.format(acc, v, **f)};"
        opc = {"mul": "mul", "div": "div", "max": "max", "min": "min"}[kind]
        fmt = self.OPS.get((opc, s))
        if fmt is None:
            raise KeyError(f"ISA {self.name} cannot accumulate '{kind}' on {t.scalar.value}")
        new = fmt.format(acc, v, **f)  # max/min: the table's operand order keeps acc where v is NaN
        if m is None:
            return f"{acc} = {new};"
        return f"{acc} = {self.select(m, new, acc, t)};"

    # ------------------------------------------------------------ shapes
    def unroll(self, n_acc: int, n_ivals: int) -> int:
        """i-vectors per block (U): two independent chains per broadcast j-particle,
        which with out-of-order overlap of loop iterations keeps both FMA pipes
        busy; one when two sets of accumulators would not stay in registers. Four
        measured no faster on AVX-512 (gravity, LJ) and spills accumulators
        (hot-loop instruction counts in docs/bench-kernels.md). An i-dependent F64
        rsqrt gets MIX_EVERY = 8 (one copy off the divider, _estimate_copy) when
        the accumulators are few (gravity: 4)."""
        if self.options.unroll:
            return self.options.unroll
        if self.mix_rsqrt and 2 * n_acc + 8 <= self.registers:
            return self.MIX_EVERY  # one F64 rsqrt in MIX_EVERY off the divider (_estimate_copy)
        return 2 if 2 * n_acc + 4 <= self.registers else 1

    def set_lane_bits(self, bits: int) -> None:
        self.W = self.reg_bits // bits

    def context(self, k: Kernel, impl: str) -> dict:
        self.mbits = {}
        plan = self.plan(k)
        ivals, jvals, svals, pair_ops, accs = plan.ivals, plan.jvals, plan.svals, plan.pair_ops, plan.accs
        bufs_i, bufs_j, jvec, svec = plan.bufs_i, plan.bufs_j, plan.jvec, plan.svec
        jbuf_decls = [f"alignas(64) {self.ctype(self.types[a].scalar)} {b}[kJBlock];" for a, b in bufs_j.items()]
        self.mix_rsqrt = (self.name == "avx2" and not self.options.fast_math
                          and any(op.opcode in ("rsqrt", "rsqrt2") and op.type is not None and op.type.scalar == S.F64
                                  and op.result in plan.idep for op in pair_ops))
        U = self.unroll(len(accs), len(ivals))
        ivec: dict[str, list[str]] = {}

        def pair_lines(U: int, jpar: bool, shape: Shape) -> None:
            jmask = "jvalid" if jpar else None
            for u in range(U):
                self.bind(plan, ivec, u, U)
                for op in pair_ops:
                    if op.opcode == "accum":
                        red = op.attr
                        assert isinstance(red, Reduce)
                        acc = accs[(red.member, red.component, self.GROUP[red.kind])]
                        v = op.args[0]
                        user_m = op.args[1] if len(op.args) > 1 else None
                        m = self.combine_masks(user_m, jmask)
                        fused = None
                        dv = plan.defs.get(v)
                        if (dv is not None and dv.opcode == "mul" and plan.nuse.get(v) == 1 and red.kind in ("add", "sub")
                                and self.can_fuse(m) and dv.type is not None and dv.type.scalar.is_float):
                            fused = (self.argv(dv.args[0]), self.argv(dv.args[1]))
                        shape.pair.append(self.acc_update(red.kind, acc["names"][u], self.argv(v), m, acc["type"], fused))
                        continue
                    if u > 0 and op.result not in plan.idep:
                        continue
                    if (op.opcode == "mul" and plan.nuse.get(op.result) == 1 and self.fused_away(op, pair_ops, accs, jmask)):
                        continue
                    shape.pair.extend(self.vec_op(op))

        def make_shape(U: int, jpar: bool) -> Shape:
            sh = Shape(U)
            sh.acc_init = self.acc_init(accs, U)
            if jpar:
                sh.i_fill = list(plan.i_lines)
                for a in ivals:
                    ivec[a] = [fresh_name(self.used, f"{a}_v")]
                    sh.i_vec.append(f"const {self.vtype(self.types[a])} {ivec[a][0]} = {self.bcast(a, self.types[a].scalar)};")
                for a in jvals:
                    sh.j_vec.append(f"const {self.vtype(self.types[a])} {jvec[a]} = {self.vload(bufs_j[a] + ' + jj', self.types[a].scalar)};")
                sh.j_vec.insert(0, f"const {self.mask_type()} jvalid = {self.tail_mask('jn - jj')};")
            else:
                sh.ibuf_decls = [f"alignas(64) {self.ctype(self.types[a].scalar)} {b}[{U * self.W}];" for a, b in bufs_i.items()]
                sh.i_fill = list(plan.i_lines) + [f"{b}[l] = {self.store_scalar(a)};" for a, b in bufs_i.items()]
                for a in ivals:
                    ivec[a] = [fresh_name(self.used, f"{a}_{u}" if U > 1 else f"{a}_v") for u in range(U)]
                    for u in range(U):
                        off = f" + {u * self.W}" if u else ""
                        sh.i_vec.append(f"const {self.vtype(self.types[a])} {ivec[a][u]} = {self.vload(bufs_i[a] + off, self.types[a].scalar)};")
                for a in jvals:
                    sh.j_vec.append(f"const {self.vtype(self.types[a])} {jvec[a]} = {self.bcast(bufs_j[a] + '[jj]', self.types[a].scalar)};")
            self.mbits = {}
            for a in ivals + jvals + svals:
                if self.types[a].scalar == S.BOOL:
                    for n in ivec.get(a, []) + [jvec.get(a, ""), svec.get(a, "")]:
                        self.mbits[n] = 32
            pair_lines(U, jpar, sh)
            # accumulators into FORCE
            for acc in accs.values():
                t = acc["type"]
                tmp = fresh_name(self.used, acc["base"] + "_lanes")
                sh.finish.append(f"alignas(64) {self.ctype(t.scalar)} {tmp}[{U * self.W}];")
                for u, n in enumerate(acc["names"]):
                    sh.finish.append(self.vstore(tmp + (f" + {u * self.W}" if u else ""), n, t.scalar))
                target = acc["target"]
                if jpar:
                    tot = fresh_name(self.used, acc["base"] + "_sum")
                    sh.finish.append(f"{self.ctype(t.scalar)} {tot} = {tmp}[0];")
                    sh.finish.append(f"for (int lane = 1; lane < kW; ++lane) {self.combine(acc['group'], tot, tmp + '[lane]')}")
                    sh.finish.append(self.combine(acc["group"], target, self.scaled(acc, tot)))
                else:
                    sh.finish.append("for (int l = 0; l < n; ++l) {")
                    sh.finish.append("  const int i = ib + l;")
                    sh.finish.append("  " + self.combine(acc["group"], target, self.scaled(acc, tmp + "[l]")))
                    sh.finish.append("}")
            return sh

        main = make_shape(U, False)
        tail = make_shape(1, False)
        jpar = make_shape(1, True)
        return self.interface_context(k, impl) | {
            "W": self.W, "U": U, "jblock": self.jblock(self.W, plan.bytes_per_j), "setup": plan.setup,
            "bcast_setup": plan.bcast_setup, "jbuf_decls": jbuf_decls, "j_fill": plan.j_fill, "j_pad": plan.j_pad,
            "main": main, "tail": tail, "jpar": jpar, "has_pairs": bool(accs),
        }

    def combine_masks(self, user: str | None, jmask: str | None) -> str | None:
        """The mask `user && jmask` as a value name (printed inline where used)."""
        if user is None or jmask is None:
            return user or jmask
        name = f"{user}&&{jmask}"
        expr = self.mask_logic("and", user, jmask)
        self.vmap[name] = expr
        self.mbits[expr] = self.mb(user)
        return name

    def can_fuse(self, m: str | None) -> bool:
        return m is None

    def fused_away(self, op: Op, pair_ops: list[Op], accs: dict, jmask: str | None) -> bool:
        """True when the product `op` is folded into its (only) accumulation as an FMA."""
        for use in pair_ops:
            if use.opcode == "accum" and use.args[0] == op.result:
                red = use.attr
                assert isinstance(red, Reduce)
                if red.kind not in ("add", "sub") or op.type is None or not op.type.scalar.is_float:
                    return False
                m = (use.args[1] if len(use.args) > 1 else None) or jmask
                return self.can_fuse(m)
        return False
