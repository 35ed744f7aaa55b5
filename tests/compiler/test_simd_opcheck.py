"""Op-check tables for the SIMD backends: for a kernel and an ISA, the intrinsics
the generated code must (and must not) contain. Generation only, no compiler:
these pin the instruction choices (refined estimates, masks, gathers, fused
accumulation, mixed-precision register widths) that the run tests cannot see."""
from __future__ import annotations

import re

import pytest

from conftest import ROOT

GRAVITY = (ROOT / "kernels/gravity.pik").read_text()
GRAVITY_F64 = (ROOT / "kernels/gravity_f64.pik").read_text()
LJ = (ROOT / "kernels/lj.pik").read_text()
# Lennard-Jones with the minimum image as two ifs (kernels/lj.pik before session 5): pins the
# compare-mask, masked add/sub and premasked-sum patterns, which the nint form no longer uses.
LJ_IFS = """
EPI   F64vec xi:pos
EPJ   F64vec xj:pos
FORCE F64vec acc:acc
FORCE F64    pot:pot
FORCE F64    vir:vir
F64 box
F64 rcut2
F64 eps
F64 sigma2
function wrap(d, l)
  w = d
  if w < -0.5 * l
    w = w + l
  endif
  if w >= 0.5 * l
    w = w - l
  endif
  return w
end
dx = wrap(xi.x - xj.x, box)
dy = wrap(xi.y - xj.y, box)
dz = wrap(xi.z - xj.z, box)
r2 = dx * dx + dy * dy + dz * dz
if r2 < rcut2 && r2 > 0.0
  ir2 = inv(r2)
  i6  = ir2 * ir2 * ir2
  s6  = sigma2 * sigma2 * sigma2
  w   = i6 * (48.0 * eps * s6 * s6 * i6 - 24.0 * eps * s6)
  f   = w * ir2
  FORCE.acc.x += f * dx
  FORCE.acc.y += f * dy
  FORCE.acc.z += f * dz
  pot += i6 * (4.0 * eps * s6 * s6 * i6 - 4.0 * eps * s6)
  vir += w
endif
"""

MIXED = """
EPI F64vec xi:pos
EPJ F64vec xj:pos
EPJ F32 mj:mass
FORCE F64vec acc:acc
FORCE F32 pot:pot
dr = xi - xj
r2 = dr * dr + 0.01
rinv = rsqrt(to_f32(r2))
acc -= to_f64(mj * rinv * rinv * rinv) * dr
pot -= mj * rinv
"""

TABLE = """
EPI F32vec xi:pos
EPJ F32vec xj:pos
FORCE F32 dens:dens
tab = { 1.0f, 0.5f, 0.25f, 0.125f }
dr = xi - xj
q = sqrt(dr * dr)
k = min(max(to_s32(floor(q * 2.0)), 0), 3)
dens += table(tab, k) * abs(q - 1.0)
"""

TRANSCENDENTAL = """
EPI F64 a:a
EPJ F64 b:b
FORCE F64 s:s
FORCE F64 m:m
s += exp(-a * b) + log(a + b) + pow(a, b)
FORCE.m = max(FORCE.m, a - b)
"""

CASES = [
    # gravity F32: AVX-512 refines rsqrt14 (one NR step), FMA into the accumulators, 16 lanes
    (GRAVITY, "avx512", ["_mm512_rsqrt14_ps(", "_mm512_fnmadd_ps(", "__m512 ", "__mmask16", "constexpr int kW = 16;",
                         "_mm512_cmpeq_epi32_mask(_mm512_and_si512(",
                         '__attribute__((target("avx512f,avx512dq,avx512vl'], ["_mm256_", "std::sqrt"]),
    # gravity F32 on AVX2: 12-bit estimate plus a refinement step (2/sqrt: y (3 - x y^2), max
    # keeps rsqrt(0) = inf), the factors 1/8 and 1/2 applied once per sum, 8 lanes
    # (the max only in the redo pass of the guard: the sums tested for inf/NaN by their exponent bits)
    (GRAVITY, "avx2", ["_mm256_rsqrt_ps(", "_mm256_fnmadd_ps(", "_mm256_set1_ps(3.0f)", "_mm256_max_ps(",
                       "_mm256_set1_epi32(0x7F800000)", "__builtin_expect(",
                       "0.125f * acc_x", "0.5f * pot", "constexpr int kW = 8;",
                       '__attribute__((target("avx2,fma")))'], ["_mm512", "__mmask"]),
    # gravity F64: rsqrt14_pd refined (fourth order), 8 lanes of double
    (GRAVITY_F64, "avx512", ["_mm512_rsqrt14_pd(", "__m512d", "constexpr int kW = 8;"], ["_mm512_sqrt_pd"]),
    # gravity F64 on AVX2: no F64 estimate (PIKG used the 12-bit F32 one unrefined). The guarded
    # fast body: the F32 estimate, NaN where x is above the F32 range (xf * 0 + y0), a third-order
    # and a Newton step; the sums tested for inf/NaN once per block; the redo pass the IEEE sqrt
    # and division...
    (GRAVITY_F64, "avx2", ["_mm256_div_pd(_mm256_set1_pd(2.0), _mm256_sqrt_pd(", "__m256d",
                           "_mm_fmadd_ps(rinv_xf", "_mm_rsqrt_ps(rinv_xf", "_mm256_set1_pd(0.375)",
                           "_mm256_set1_epi64x(0x7FF0000000000000LL)", "__builtin_expect("], ["_mm512"]),
    # ... and with `#pragma unroll 8` one i-vector in eight through the F32 estimate of x scaled by
    # a power of four, refined to fourth order, scaled back
    ("#pragma unroll 8\n" + GRAVITY_F64, "avx2", ["_mm256_div_pd(_mm256_set1_pd(2.0), _mm256_sqrt_pd(", "__m256d", "_7 = _mm256_sub_pd(",
                           "_mm256_set1_epi64x(0x5FE0000000000000LL)", "_mm_rsqrt_ps(_mm256_cvtpd_ps(",
                           "_mm256_set1_pd(0.625)"], ["_mm512"]),
    # LJ: compare masks, one masked add/sub per side of the minimum image (`if w < -l/2: w = w + l`),
    # masked FMA accumulation, F64 inv an IEEE division
    (LJ_IFS, "avx512", ["_mm512_cmp_pd_mask(", "_CMP_LT_OQ", "_CMP_GE_OQ", "_mm512_mask_add_pd(", "_mm512_mask_sub_pd(",
                    "_mm512_div_pd(_mm512_set1_pd(1.0)", "_mm512_mask3_fmadd_pd(", "static_cast<__mmask8>("],
     ["_mm512_rcp14_pd(", "_mm512_mask_blend_pd("]),
    # LJ on AVX2: vector masks, the minimum image as x - (y & m) (no blendv), IEEE division for
    # F64 inv, masks as and-ed values in sums
    (LJ_IFS, "avx2", ["_mm256_cmp_pd(", "_mm256_sub_pd(wrap_w, _mm256_and_pd(_mm256_xor_pd(box_v",
                  "_mm256_div_pd(_mm256_set1_pd(1.0)", "_mm256_and_pd("], ["_mm256_rcp", "_mm256_blendv_pd("]),
    # kernels/lj.pik: the minimum image d - l nint(d / l) as fma(d, 1/l, 1.5 * 2^52) - 1.5 * 2^52 (not
    # folded: IEEE rounding) and one FMA, 1/l once per call and kept normal; compares only for the cutoff and r2 > 0
    (LJ, "avx512", ["_mm512_fmadd_pd(wrap_n_1, ibox_v, _mm512_set1_pd(6755399441056768.0))",
                    "_mm512_sub_pd(wrap_n_3, _mm512_set1_pd(6755399441056768.0))", "std::max(ibox_1, 1e-290)",
                    "_mm512_div_pd(_mm512_set1_pd(1.0)", "_mm512_mask3_fmadd_pd("],
     ["_CMP_GE_OQ", "_CMP_LT_OQ, box", "_mm512_mask_sub_pd("]),
    (LJ, "avx2", ["_mm256_set1_pd(6755399441056768.0)", "_mm256_fnmadd_pd(wrap_n", "_mm256_div_pd(_mm256_set1_pd(1.0)"],
     ["_CMP_GE_OQ", "_mm256_blendv_pd("]),
    # every sum under the cut-off's `if`: a vector of pairs with no lane inside skips the division and
    # the sums, by one mask test (kortest / vmovmskpd) and a branch (Simd.skip_region), unless the
    # branch has been unpredictable (skip_state), where the i-vector runs the compacted passes: the
    # j-particles in the branch listed without a branch, then only those (Simd.compacted); not with
    # `#pragma blend`
    (LJ, "avx512", ["const unsigned skip_t = static_cast<unsigned>(cond_1);", "unsigned skip_run = skip_t | skip_dense;",
                    "if (skip_run != 0) {", "8 * skip_flips > skip_n ? ~0u : 0u", "if (skip_dense != 0) {",
                    "skip_idx[skip_na] = jj;", "skip_na += static_cast<int>(skip_run);",
                    "const int jj = skip_idx[skip_k];"], []),
    (LJ, "avx2", ["const unsigned skip_t = _mm256_movemask_pd(cond_1);", "if (skip_run != 0) {"], []),
    ("#pragma blend\n" + LJ, "avx512", ["_mm512_mask3_fmadd_pd("], ["static_cast<unsigned>(cond_1)", "skip_"]),
    # mixed precision: W from the F64 values, F32 values in half-width registers
    (MIXED, "avx512", ["__m256 ", "__m512d", "_mm512_cvtpd_ps(", "_mm512_cvtps_pd(", "_mm256_rsqrt14_ps(", "kW = 8;"],
     []),
    (MIXED, "avx2", ["__m128 ", "__m256d", "_mm256_cvtpd_ps(", "_mm256_cvtps_pd(", "kW = 4;"], []),
    # tables are gathers, floor/abs/min/max/casts vector instructions
    # F32 inv: rcp14 and a Newton step
    ("EPI F32 a:a\nEPJ F32 b:b\nFORCE F32 s:s\ns += inv(a + b)\n", "avx512", ["_mm512_rcp14_ps("], ["_div_ps"]),
    (TABLE, "avx512", ["_mm512_mask_i32gather_ps(", "_mm512_roundscale_ps(", "_MM_FROUND_TO_NEG_INF",
                       "_mm512_cvttps_epi32(", "_mm512_max_epi32(", "_mm512_min_epi32(", "_mm512_abs_ps(",
                       "_mm512_sqrt_ps("], ["_r[lane] ="]),
    (TABLE, "avx2", ["_mm256_mask_i32gather_ps(", "_mm256_floor_ps(", "_mm256_cvttps_epi32(", "_mm256_andnot_ps("],
     ["_r[lane] ="]),
    # exp is a vector function (vmath.py: round, polynomial, 2^n by an exponent shift); log
    # and pow run lane by lane through the standard library; max reductions stay vector ops
    (TRANSCENDENTAL, "avx512", ["std::log(", "std::pow(", "for (int lane = 0; lane < 8; ++lane)",
                                "_mm512_roundscale_pd(", "_mm512_slli_epi64(", "_mm512_max_pd("], ["std::exp("]),
    (TRANSCENDENTAL, "avx2", ["_mm256_round_pd(", "_mm256_slli_epi64(", "for (int lane = 0; lane < 4; ++lane)",
                              "_mm256_max_pd("], ["std::exp("]),
    # erfc: one division, the polynomial, exp(-x^2) with the FMA correction, the sign blend
    ("EPI F32 a:a\nEPJ F32 b:b\nFORCE F32 s:s\ns += erfc(a - b)\n", "avx2",
     ["_mm256_div_ps(", "_mm256_fmsub_ps(", "_mm256_blendv_ps(", "_mm256_slli_epi32("], ["std::erfc(", "_r[lane] ="]),
    ("EPI F64 a:a\nEPJ F64 b:b\nFORCE F64 s:s\ns += erfc(a - b)\n", "avx512",
     ["_mm512_div_pd(", "_mm512_movepi64_mask(", "_mm512_mask_blend_pd(", "_mm512_roundscale_pd("],
     ["std::erfc(", "_r[lane] ="]),
]


@pytest.mark.parametrize("source,isa,present,absent", CASES,
                         ids=[f"{i}-{c[1]}" for i, c in enumerate(CASES)])
def test_intrinsics(source: str, isa: str, present: list[str], absent: list[str], tmp_path) -> None:
    from pik_gen.backends import Options
    from pik_gen.driver import generate

    code = generate(source, "k.pik", isa, Options(name="K"))
    for s in present:
        assert s in code, f"expected '{s}' in the {isa} code"
    for s in absent:
        assert s not in code, f"did not expect '{s}' in the {isa} code"


def test_fast_math_keeps_the_estimate_and_says_so() -> None:
    from pik_gen.backends import Options
    from pik_gen.driver import generate

    exact = generate(GRAVITY, "g.pik", "avx512", Options(name="K"))
    fast = generate(GRAVITY, "g.pik", "avx512", Options(name="K", fast_math=True))
    assert "--fast-math" in fast.splitlines()[1] and "--fast-math" not in exact
    assert "rinv_h" in exact and "rinv_h" not in fast  # no refinement step left


def test_fast_math_is_a_noted_no_op_on_reference() -> None:
    # The reference is the semantic definition: --fast-math leaves its code unchanged
    # and the banner says so (in `auto`, for the reference variant).
    from pik_gen.backends import Options
    from pik_gen.driver import generate

    exact = generate(GRAVITY, "g.pik", "reference", Options(name="K"))
    fast = generate(GRAVITY, "g.pik", "reference", Options(name="K", fast_math=True))
    assert "--fast-math: no effect on the reference target" in fast.splitlines()[1]
    def body(code: str) -> list[str]:  # the implementation class name hashes the options
        return re.sub(r"_reference_[0-9a-f]+", "_reference_H", code).splitlines()[2:]

    assert body(exact) == body(fast)
    auto = generate(GRAVITY, "g.pik", "auto", Options(name="K", fast_math=True)).splitlines()[1]
    assert "no effect on the reference variant" in auto


def test_auto_dispatches_to_every_x86_variant() -> None:
    from pik_gen.backends import Options
    from pik_gen.driver import generate

    code = generate(GRAVITY, "g.pik", "auto", Options(name="K"))
    for impl in ("K_avx512_", "K_avx2_", "K_reference_"):
        assert impl in code
    # AVX-512 is tried first, the reference is the fallback
    assert code.index('__builtin_cpu_supports("avx512f")') < code.index('__builtin_cpu_supports("avx2")')
    assert "#include <immintrin.h>" in code


def test_avx2_for_an_avx512_xeon_uses_evex_registers() -> None:
    # --cpu sapphirerapids: AVX2-width code with EVEX encodings (32 ymm), so gravity gets two
    # i-vectors per block; the variant carries avx512vl in its target attribute and checks it
    # at run time, so `auto` never runs it on an AVX2-only CPU. The generic row is unchanged.
    from pik_gen.backends import Options
    from pik_gen.driver import generate

    xeon = generate(GRAVITY, "g.pik", "avx2", Options(name="K", cpu="sapphirerapids"))
    assert "2 vectors per block" in xeon and '__attribute__((target("avx2,fma,avx512vl")))' in xeon
    generic = generate(GRAVITY, "g.pik", "avx2", Options(name="K"))
    assert "1 vector per block" in generic and "avx512vl" not in generic
    auto = generate(GRAVITY, "g.pik", "auto", Options(name="K", cpu="sapphirerapids"))
    assert ('__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && '
            '__builtin_cpu_supports("avx512vl")') in auto
    auto_generic = generate(GRAVITY, "g.pik", "auto", Options(name="K"))
    avx2_check = [ln for ln in auto_generic.splitlines() if '__builtin_cpu_supports("avx2")' in ln]
    assert avx2_check and all("avx512vl" not in ln for ln in avx2_check)


@pytest.mark.parametrize("zen", ["znver4", "znver5"])
def test_avx2_for_zen4_zen5_uses_evex_and_rsqrt14(zen: str) -> None:
    # --cpu znver4/znver5 (and --cpu native on a family-25 model-0x10+ or family-26 AMD host):
    # AVX2 code with EVEX encodings as for the Xeon, and the F64 rsqrt from AVX-512VL's
    # vrsqrt14pd ymm plus one fourth-order step (no F32 estimate, no divider in the fast
    # body); F32 keeps rsqrtps. Other rows unchanged.
    from pik_gen.backends import Options
    from pik_gen.backends.simd import native_cpu
    from pik_gen.driver import generate

    g64 = generate(GRAVITY_F64, "g.pik", "avx2", Options(name="K", cpu=zen))
    # znver4: one i-vector and four j-particles per iteration (Uarch.j_copies), the divider
    # taking j-copies 1 and 3; znver5: two i-vectors, the divider taking copy 1
    shape, div, est = (("1 vector per block, j broadcast, 4 j-particles per iteration", ("r2_j1", "r2_j3"),
                        ("r2_j0", "r2_j2")) if zen == "znver4" else ("2 vectors per block", ("r2_1",), ("r2_0",)))
    assert shape in g64 and '__attribute__((target("avx2,fma,avx512vl")))' in g64
    assert "_mm256_rsqrt14_pd" in g64 and "_mm_rsqrt_ps" not in g64
    for cpu in (None, "znver3", "sapphirerapids"):
        other = generate(GRAVITY_F64, "g.pik", "avx2", Options(name="K", cpu=cpu))
        assert "_mm256_rsqrt14_pd" not in other
    # one of the two i-vector copies through the divider (f64_div_every = 2), on AVX-512 too
    assert all(f"_mm256_sqrt_pd({r})" in g64 for r in div) and not any(f"_mm256_sqrt_pd({r})" in g64 for r in est)
    z512 = generate(GRAVITY_F64, "g.pik", "avx512", Options(name="K", cpu=zen))
    assert shape in z512
    assert all(f"_mm512_sqrt_pd({r})" in z512 for r in div) and not any(f"_mm512_sqrt_pd({r})" in z512 for r in est)
    assert "_mm512_sqrt_pd(r2_1)" not in generate(GRAVITY_F64, "g.pik", "avx512", Options(name="K"))
    f32 = generate(GRAVITY, "g.pik", "avx2", Options(name="K", cpu=zen))
    assert "_mm256_rsqrt_ps" in f32 and "rsqrt14" not in f32
    amd4 = "vendor_id\t: AuthenticAMD\ncpu family\t: 25\nmodel\t\t: 17\n"
    assert native_cpu(amd4) == "znver4"
    amd5 = "vendor_id\t: AuthenticAMD\ncpu family\t: 26\nmodel\t\t: 2\n"
    assert native_cpu(amd5) == "znver5"
