"""The AVX-512 backend (F, DQ, VL): only what differs from AVX2 (see avx2.py).

512-bit registers (W = 16 lanes for 32-bit kernels, 8 with 64-bit values; an F32
value of a mixed kernel is then a 256-bit vector, with the VL forms of every
instruction), 32 registers (blocks of 4 i-vectors), and `__mmask` registers for
every BOOL whatever its element width, so masks need no conversions; masked
accumulation is one instruction (`mask_add`, `mask3_fmadd`).

Accuracy: the 14-bit `rsqrt14`/`rcp14` estimates, refined by one Newton-Raphson
step for F32 (error ~2^-28 before rounding), for F64 `rsqrt` by one fourth-order
Householder step (14 -> 56 bits); F64 `inv` is the IEEE division.
"""
from __future__ import annotations

from pik_gen.backends.avx2 import CMP, Avx2
from pik_gen.backends.simd import EmitState, Let, S, Uarch, ebits
from pik_gen.ir.nodes import Op, TableRef, fresh_name
from pik_gen.types import Scalar, Type

ICMP = {"eq": "_MM_CMPINT_EQ", "ne": "_MM_CMPINT_NE", "lt": "_MM_CMPINT_LT", "le": "_MM_CMPINT_LE",
        "gt": "_MM_CMPINT_NLE", "ge": "_MM_CMPINT_NLT"}


class Avx512(Avx2):
    name = "avx512"
    isa_label = "AVX-512"
    pikg_name = "AVX-512"
    summary = "512-bit AVX-512 F/DQ/VL"
    preference = 20
    cpu_check = ('__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") && '
                 '__builtin_cpu_supports("avx512vl")')
    function_attributes = '__attribute__((target("avx512f,avx512dq,avx512vl,avx2,fma")))'
    cxx_flags = ("-mavx512f", "-mavx512dq", "-mavx512vl", "-mavx2", "-mfma")
    lane_counts = (8, 16)
    reg_bits = 512
    registers = 32
    masks_in_vregs = False
    # 512-bit: zmm registers, FMA pipes at 512 bits (Zen 4 splits a zmm FMA in two
    # 256-bit halves), latency, rsqrt14ps zmm per cycle, vgatherdps zmm throughput.
    UARCH = {
        "generic": Uarch(32, 2, 4, 0.5, 8, "skylake-avx512", "any AVX-512 F/DQ/VL CPU"),
        "skylake-avx512": Uarch(32, 2, 4, 0.5, 8, "skylake-avx512", "Skylake-SP, Cascade Lake (2 FMA units)"),
        "icelake-server": Uarch(32, 2, 4, 0.5, 8, "icelake-server", "Ice Lake-SP"),
        "sapphirerapids": Uarch(32, 2, 4, 0.5, 8, "sapphirerapids", "Sapphire/Emerald Rapids (this host)"),
        # Zen 4 issues one zmm FMA and one zmm add per cycle (measured), but the two-copy block
        # (fma_pipes 2 in the rule) with one F64 rsqrt copy in two by the divider is what measured
        # fastest on a Zen 4 host: gravity F64 0.88-0.89x -> 0.95-0.97x PIKG; U = 3, 4 and other divider
        # shares were slower (docs/bench-kernels.md, Zen 4)
        # Four j-particles per iteration beside one i-vector for F64 (Simd.j_copies_rule): gravity
        # F64 +3.8 % against two i-vectors; F32 +0.3 % with V = 3 or 4, so it keeps U = 2
        # (docs/bench-kernels.md, 2026-12-07 fourth session)
        "znver4": Uarch(32, 2, 4, 0.5, 12, "znver3", "AMD Zen 4 (llvm-mca 14 has no znver4)", f64_div_every=2,
                        split_sums=True, j_copies=(1, 4)),
        # Zen 5: one F64 rsqrt copy in two by the divider (gravity F64 +9-11 %, docs/bench-kernels.md)
        "znver5": Uarch(32, 2, 4, 1.0, 8, "znver3", "AMD Zen 5 (llvm-mca 14 has no znver5)", f64_div_every=2),
    }
    default_cpu = "generic"
    mix_f64_rsqrt = False  # rsqrt14 + one fourth-order step: no divider to relieve
    premask_ok = False  # masked FMA into the sum is one instruction (mask3_fmadd)
    OPS = {
        ("mul", S.S64): "{p}_mullo_epi64({0}, {1})", ("abs", S.S64): "{p}_abs_epi64({0})",
        ("min", S.S64): "{p}_min_{u}({0}, {1})", ("max", S.S64): "{p}_max_{u}({0}, {1})",
    }

    # ------------------------------------------------------------ masks
    def mask_type(self, st: EmitState, bits: int = 32) -> str:
        return f"__mmask{self.W(st)}"

    def mask_of(self, st: EmitState, name: str, bits: int) -> str:
        return self.argv(st, name)

    def mask_from_i32(self, st: EmitState, vec: str) -> str:
        return f"{self.pre(st, S.S32)}_movepi32_mask({vec})"

    def mask_to_i32(self, st: EmitState, m: str) -> str:
        return f"{self.pre(st, S.S32)}_movm_epi32({m})"

    def logic(self, st: EmitState, opcode: str, a: str, b: str | None) -> str:
        M = self.mask_type(st)
        if opcode == "not":
            return f"static_cast<{M}>(~{self.argv(st, a)})"
        assert b is not None
        return f"static_cast<{M}>({self.argv(st, a)} {'&' if opcode == 'and' else '|'} {self.argv(st, b)})"

    def any_lane(self, st: EmitState, m: str) -> str:
        return f"static_cast<unsigned>({self.argv(st, m)})"

    def any_nonfinite(self, st: EmitState, vecs: list[tuple[str, Type]]) -> str:
        tests = []
        for name, t in vecs:
            s = self.home(t.scalar)
            if self.vbits(st, s) != 512:
                tests.append(super().any_nonfinite(st, [(name, t)]))
                continue
            e = "_mm512_set1_epi64(0x7FF0000000000000LL)" if s == S.F64 else "_mm512_set1_epi32(0x7F800000)"
            eq, sf = ("epi64", "pd") if s == S.F64 else ("epi32", "ps")
            tests.append(f"static_cast<int>(_mm512_cmpeq_{eq}_mask(_mm512_and_si512(_mm512_cast{sf}_si512({name}), {e}), {e}))")
        return " | ".join(tests)

    def j_tail_mask(self, st: EmitState) -> str:
        return f"static_cast<{self.mask_type(st)}>(jn - jj >= kW ? ~0u : (1u << (jn - jj)) - 1u)"

    def bcast(self, st: EmitState, expr: str, s: Scalar) -> str:
        if s == S.BOOL:
            return f"static_cast<{self.mask_type(st)}>(-static_cast<int>({expr}))"
        if s.is_int and ebits(s) == 64 and self.vbits(st, s) == 512:
            return f"_mm512_set1_epi64(static_cast<long long>({expr}))"
        return super().bcast(st, expr, s)

    def compare(self, st: EmitState, op: Op, a: str, b: str) -> str | None:
        s = st.types[op.args[0]].scalar
        if s == S.BOOL:
            return None
        f = self.fields(st, s)
        if s.is_float:
            return f"{f['p']}_cmp_{f['s']}_mask({a}, {b}, {CMP[op.opcode]})"
        return f"{f['p']}_cmp_{f['u']}_mask({a}, {b}, {ICMP[op.opcode]})"

    def masked_arith(self, st: EmitState, kind: str, m: str, x: str, y: str, t: Type) -> str:
        """One masked add/sub that keeps x where m is clear (mask_add, mask_sub)."""
        f = self.fields(st, self.home(t.scalar))
        return f"{f['p']}_mask_{kind}_{f['s']}({x}, {self.argv(st, m)}, {x}, {y})"

    def select(self, st: EmitState, m: str, a: str, b: str, t: Type) -> str:
        s = t.scalar
        mv = self.argv(st, m)
        if s == S.BOOL:
            M = self.mask_type(st)
            return f"static_cast<{M}>(({mv} & {a}) | (~{mv} & {b}))"
        f = self.fields(st, s)
        return f"{f['p']}_mask_blend_{f['s']}({mv}, {b}, {a})"

    # ------------------------------------------------------------ refinement
    def refine_rsqrt(self, st: EmitState, x: str, s: Scalar, out: str, twice: bool = False) -> list[Let]:
        f = self.fields(st, s)
        T = self.vtype(st, Type(s))
        if s == S.F64 and not self.options.fast_math and self.divider_copy(st):
            p = f["p"]
            return [Let(T, out, f"{p}_div_pd({p}_set1_pd({2.0 if twice else 1.0}), {p}_sqrt_pd({x}))")]
        y0 = fresh_name(st.used, f"{out}_y0")
        lets = [Let(T, y0, f"{f['p']}_rsqrt14_{f['s']}({x})")]
        if self.options.fast_math and s != S.F64:
            return lets + [Let(T, out, f"{f['p']}_add_{f['s']}({y0}, {y0})" if twice else y0)]
        steps = ["nr"] if (s != S.F64 or self.options.fast_math) else ["h4"]
        return lets + self._rsqrt_steps(st, x, y0, out, s, steps, twice)

    def refine_inv(self, st: EmitState, x: str, s: Scalar, out: str) -> list[Let]:
        """F32: rcp14 and one NR step. F64: the IEEE division, which measured faster
        than rcp14 and two NR steps on the Zen 5 host (Lennard-Jones 1.58 vs 1.30 G
        pairs/s: its divider keeps up, the FMA pipes were the bottleneck)."""
        if s == S.F64 and not self.options.fast_math:
            return super().refine_inv(st, x, s, out)
        f = self.fields(st, s)
        T = self.vtype(st, Type(s))
        y0 = fresh_name(st.used, f"{out}_y0")
        lets = [Let(T, y0, f"{f['p']}_rcp14_{f['s']}({x})")]
        if self.options.fast_math and s != S.F64:
            return lets + [Let(T, out, y0)]
        return lets + self._inv_steps(st, x, y0, out, s, ["nr"])

    # ------------------------------------------------------------ exp, erfc (vmath.py)
    def vround(self, st: EmitState, s: Scalar, x: str) -> str:
        if self.vbits(st, s) != 512:
            return super().vround(st, s, x)
        return f"_mm512_roundscale_{self.suf(self.home(s))}({x}, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC)"

    def select_negative(self, st: EmitState, s: Scalar, x: str, a: str, b: str) -> str:
        if self.vbits(st, s) != 512:
            return super().select_negative(st, s, x, a, b)
        sf, e = self.suf(self.home(s)), ebits(s)
        return f"_mm512_mask_blend_{sf}(_mm512_movepi{e}_mask(_mm512_cast{sf}_si512({x})), {b}, {a})"

    # ------------------------------------------------------------ other irregular ops
    def vector_op(self, st: EmitState, op: Op, a: list[str]) -> str | None:
        assert op.type is not None
        s = self.home(op.type.scalar)
        if op.opcode in ("floor", "abs") and s.is_float and self.vbits(st, s) == 512:
            sf = self.suf(s)
            return (f"_mm512_roundscale_{sf}({a[0]}, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC)"
                    if op.opcode == "floor" else f"_mm512_abs_{sf}({a[0]})")
        return super().vector_op(st, op, a)

    def cast(self, st: EmitState, src: Scalar, dst: Scalar, x: str) -> str | None:
        got = super().cast(st, src, dst, x)
        if got is not None or src.is_unsigned or dst.is_unsigned:
            return got
        p = "_mm512"  # 64-bit integers only occur with W = 8, i.e. in 512-bit registers
        return {(S.F64, S.S64): f"{p}_cvttpd_epi64({x})", (S.S64, S.F64): f"{p}_cvtepi64_pd({x})",
                (S.F32, S.S64): f"{p}_cvttps_epi64({x})", (S.S64, S.F32): f"{p}_cvtepi64_ps({x})",
                (S.S64, S.S32): f"{p}_cvtepi64_epi32({x})"}.get((self.home(src), self.home(dst)))

    def gather(self, st: EmitState, op: Op, idx: str) -> str | None:
        assert isinstance(op.attr, TableRef) and op.type is not None
        s = op.type.scalar
        if (self.home(st.types[op.args[0]].scalar) != S.S32 or s not in (S.F32, S.F64)
                or self.vbits(st, s) != 512):
            return super().gather(st, op, idx)
        sf = self.suf(s)
        return (f"_mm512_mask_i32gather_{sf}(_mm512_setzero_{sf}(), static_cast<{self.mask_type(st)}>(-1), {idx}, "
                f"{op.attr.name}, {ebits(s) // 8})")

    # ------------------------------------------------------------ accumulation
    def can_fuse(self, masked: bool) -> bool:
        return True

    def acc_update(self, st: EmitState, kind: str, acc: str, v: str, m: str | None, t: Type,
                   fused: tuple[str, str] | None) -> str:
        if m is None:
            return super().acc_update(st, kind, acc, v, None, t, fused)
        s = self.home(t.scalar)
        f = self.fields(st, s)
        p, sf = f["p"], f["s"]
        mv = self.argv(st, m)
        if fused is not None:
            fn = "fmadd" if kind == "add" else "fnmadd"
            return f"{p}_mask3_{fn}_{sf}({fused[0]}, {fused[1]}, {acc}, {mv})"
        if s.is_float:
            a, b = (v, acc) if kind in ("max", "min") else (acc, v)  # max/min keep acc where v is NaN
            return f"{p}_mask_{kind}_{sf}({acc}, {mv}, {a}, {b})"
        return f"{p}_mask_blend_{sf}({mv}, {acc}, {super().acc_update(st, kind, acc, v, None, t, None)})"
