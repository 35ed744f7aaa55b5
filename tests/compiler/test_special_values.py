"""IEEE special values of the refined built-ins: rsqrt(+-0) = +-inf, rsqrt(inf) = 0,
rsqrt(-1) = NaN, as in the reference, on every ISA the host has, in F32 and F64,
both as rsqrt2 (gravity's form after defer_scale) and as plain rsqrt, in the
i-parallel and the j-parallel shapes. The guarded forms (the result reaches the sums
only through arithmetic: Simd.guarded) take the fast body without the special-value
fix and must come out right through the redo pass; `unguarded` (through min) keeps
the fix in every pair. (inv of the F32 estimate paths is documented in
docs/language.md instead: see there.)"""
from __future__ import annotations

import math
import shutil
import subprocess
from pathlib import Path

import pytest

from conftest import ROOT, run_cli
from test_simd_run import host

pytestmark = pytest.mark.skipif(shutil.which("g++") is None, reason="g++ is not installed")

VALUES = [0.0, -0.0, math.inf, 4.0, -1.0, 2.5e-5]
# F64 only: subnormal, outside the F32 range, and next to the F64 limits (the AVX2
# F64 estimate path scales x by a power of four before its F32 estimate)
VALUES_F64 = [5e-324, 1e-310, 1e-300, 1e-39, 1e39, 1e300, 1.7e308]
KERNELS = {
    # becomes rsqrt2 with the factor 1/2 on the sum
    "twice": "EPJ {T} m:mass\nFORCE {T} pot:pot\npot += rsqrt(m)\n",
    # differs between i-particles (x = 0 here): one rsqrt per unrolled i-vector,
    # where AVX2 F64 sends one vector in eight through its estimate path
    "ivec": "EPI {T} xi:x\nEPJ {T} m:mass\nFORCE {T} pot:pot\npot += rsqrt(m - xi)\n",
    # sqrt of the result: the factor would have to be applied, so rsqrt stays plain
    "plain": "EPJ {T} m:mass\nFORCE {T} pot:pot\npot += sqrt(rsqrt(m)) * sqrt(rsqrt(m))\n",
    # min does not carry an inf or NaN to the sum: no guard, the fix in the pair loop
    "unguarded": "EPJ {T} m:mass\nFORCE {T} pot:pot\npot += min(rsqrt(m), 1.0e30)\n",
    # a masked sum of a product with a finite-looking operand: AVX2's fast body premasks the
    # other one, fma(inv(..) & mask, m, pot) (Simd.premasked); m = inf or NaN in a masked-out
    # pair gives 0 * inf there, and the redo pass must give the reference's 0
    "premask": "EPJ {T} m:mass\nFORCE {T} pot:pot\nif m < 1.0e30\n  pot += inv(2.0 - m) * m\nendif\n",
}


def expect(v: float, form: str) -> float:
    if form == "premask":
        return (1 / (2 - v)) * v if v < 1.0e30 else 0.0
    if v < 0 and v != 0:
        return math.nan
    r = math.copysign(math.inf, v) if v == 0 else 1 / math.sqrt(v)
    if form == "plain":  # sqrt(r)^2
        return math.nan if r < 0 else r
    if form == "unguarded":  # std::min(r, 1e30) = 1e30 < r ? 1e30 : r
        return 1.0e30 if 1.0e30 < r else r
    return r


@pytest.mark.parametrize("T", ["F32", "F64"])
@pytest.mark.parametrize("form", sorted(KERNELS))
def test_rsqrt_special_values(form: str, T: str, tmp_path: Path) -> None:
    # (label, target, options): avx2z5 is the AVX2 variant sized for Zen 5 (--cpu znver5: EVEX,
    # F64 rsqrt by vrsqrt14pd ymm), run where the host has AVX-512VL
    variants = [(i, i, []) for i in ["reference"] + [i for i in ("avx2", "avx512") if host().get(i)]]
    if host().get("avx512"):
        variants.append(("avx2z5", "avx2", ["--cpu", "znver5"]))
    isas = [v[0] for v in variants]
    src = tmp_path / "k.pik"
    src.write_text(KERNELS[form].format(T=T))
    includes, calls = [], []
    for isa, target, opts in variants:
        rc, _, err = run_cli([src, "-o", tmp_path / f"K_{isa}.hpp", "--target", target, "--name", f"K_{isa}", *opts])
        assert rc == 0, err
        includes.append(f'#include "K_{isa}.hpp"')
        calls.append(f'  run(K_{isa}{{}}, "{isa}");')
    values = VALUES + (VALUES_F64 if T == "F64" else [])
    vals = ", ".join(repr(v) if math.isfinite(v) else ("-" if v < 0 else "") + "INFINITY" for v in values)
    (tmp_path / "main.cpp").write_text(f"""#include <cmath>
#include <cstdio>
struct EPI {{ double x; }};
struct EPJ {{ double mass; }};
struct FORCE {{ double pot; }};
{chr(10).join(includes)}
template <class K> void run(const K& k, const char* isa) {{
  const double vals[] = {{{vals}}};
  EPI epi[40] = {{}};  // 40: whole unrolled blocks of every ISA and single vectors
  for (double v : vals) {{
    EPJ j{{v}};
    FORCE f[40] = {{}};
    k(epi, 40, &j, 1, f);
    std::printf("%s %.17g", isa, f[0].pot);
    // lanes may take different paths (AVX2 F64: divider or estimate): equal to 1e-13
    for (int i = 1; i < 40; ++i) if (!(f[i].pot == f[0].pot || (f[i].pot != f[i].pot && f[0].pot != f[0].pot)
                                       || std::fabs(f[i].pot - f[0].pot) <= 1e-13 * std::fabs(f[0].pot))) std::printf(" lane%d-differs", i);
    std::printf("\\n");
    // j-parallel (one i-particle, 16 j-particles in lanes): 16 equal terms
    EPJ js[16];
    for (EPJ& e : js) e = j;
    FORCE g[1] = {{}};
    k(epi, 1, js, 16, g);
    std::printf("%s-jpar %.17g\\n", isa, g[0].pot / 16);
  }}
}}
int main() {{
{chr(10).join(calls)}
}}
""")
    exe = tmp_path / "a.out"
    cc = subprocess.run(["g++", "-std=c++20", "-O1", f"-I{tmp_path}", f"-I{ROOT / 'runtime/include'}",
                         str(tmp_path / "main.cpp"), "-o", str(exe)], capture_output=True, text=True)
    assert cc.returncode == 0, cc.stderr
    out = subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout.split("\n")
    rows = [line.split() for line in out if line]
    assert len(rows) == 2 * len(isas) * len(values)
    for n, row in enumerate(rows):
        v = values[(n // 2) % len(values)]
        isa, got, want = row[0], float(row[1]), expect(v, form)
        assert len(row) == 2, f"{isa}: lanes differ for {v}: {row}"
        where = f"{isa} {T} {form}: rsqrt({v}) = {got}, want {want}"
        if math.isnan(want) or math.isinf(want) or want == 0:
            assert (math.isnan(got) and math.isnan(want)) or got == want, where
        else:
            assert abs(got - want) <= 1e-6 * abs(want), where
