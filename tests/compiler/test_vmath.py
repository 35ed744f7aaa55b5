"""Accuracy of the built-ins `exp` and `erfc` on every ISA the host has, F32 and F64,
against a long-double evaluation (`expl`, `erfcl`, 64-bit significand) of the same
argument: the error of each result in units in the last place of its type (the
spacing of the type's numbers at the exact value, the subnormal spacing below the
normal range), over dense grids that cross every threshold (exp: under- and
overflow; erfc: x < 0, the whole positive range to its underflow) and the special
values NaN, +-inf, +-0. The SIMD code is vmath.py's (no lane-by-lane libm call);
the reference is std::exp/std::erfc. Bounds (the measured maxima with a margin,
docs/language.md): exp <= 2 ulp, erfc <= 5 ulp (F64) / 6 ulp (F32); measured on x86: exp 0.86 / 0.90 ulp, erfc 4.0 / 5.0 ulp. SVE runs
under QEMU at 256 bits (fewer points). An ISA the host lacks is skipped."""
from __future__ import annotations

import math
import shutil
import subprocess
from pathlib import Path

import pytest

from conftest import ROOT, run_cli
from test_simd_run import host

pytestmark = pytest.mark.skipif(shutil.which("g++") is None, reason="g++ is not installed")

BOUND = {("exp", "F64"): 2.0, ("exp", "F32"): 2.0, ("erfc", "F64"): 5.0, ("erfc", "F32"): 6.0}
# grids [lo, hi] per function and type, and the extra points (thresholds, specials)
RANGES = {
    ("exp", "F64"): (-750.0, 712.0), ("exp", "F32"): (-106.0, 90.0),
    ("erfc", "F64"): (-7.0, 29.0), ("erfc", "F32"): (-5.0, 11.0),
}
EXTRA = ["0.0", "-0.0", "INFINITY", "-INFINITY", "NAN", "1e-300", "-1e-300", "1e-20", "-1e-20", "1e-8",
         "-1e-8", "0.3465735902799726", "-0.3465735902799726"]
EXTRA_EXP = {"F64": ["709.782712893384", "709.7827128933841", "709.79", "-708.3964185322641", "-708.4",
                     "-745.1332191019411", "-745.14", "-745.2", "-746.0"],
             "F32": ["88.72283", "88.7229", "-87.33654", "-87.34", "-103.2789", "-103.9721", "-104.0"]}
EXTRA_ERFC = {"F64": ["26.5", "26.55", "26.6", "27.2", "27.3", "0.5", "0.84375", "1.25", "6.0"],
              "F32": ["9.19", "10.0", "10.05", "10.06", "0.5", "3.0"]}

KERNEL = """EPI {T} x:x
EPJ {T} z:z
FORCE {T} e:e
FORCE {T} c:c
e += exp(x - z)
c += erfc(x - z)
"""

MAIN = r"""#include <cmath>
#include <cstdio>
#include <limits>
#include <initializer_list>
#include <vector>
struct EPI { double x; };
struct EPJ { double z; };
struct FORCE { double e, c; };
@INCLUDES@
using T = @CT@;
// error of got in ulp of T at the exact value want (long double)
static long double ulps(T got, long double want) {
  if (std::isnan(want)) return std::isnan(got) ? 0 : 1e30L;
  const long double wr = static_cast<T>(want);  // want rounded to T
  if (std::isinf(wr)) return got == wr ? 0 : 1e30L;
  if (std::isnan(got) || std::isinf(got)) return 1e30L;
  long double a = std::fabs(want), u = std::numeric_limits<T>::denorm_min();
  if (a >= std::numeric_limits<T>::min()) {
    int e; std::frexp(a, &e);
    u = std::ldexp(1.0L, e - std::numeric_limits<T>::digits);
  }
  return std::fabs(static_cast<long double>(got) - want) / u;
}
template <class K> void run(const K& k, const char* isa, const std::vector<double>& xs) {
  const int n = static_cast<int>(xs.size());
  std::vector<EPI> epi(n);
  std::vector<FORCE> f(n);
  for (int i = 0; i < n; ++i) epi[i].x = xs[i];
  EPJ j{0.0};
  k(epi.data(), n, &j, 1, f.data());
  long double worst_e = 0, worst_c = 0; double at_e = 0, at_c = 0;
  for (int i = 0; i < n; ++i) {
    const T x = static_cast<T>(xs[i]);
    const long double ue = ulps(static_cast<T>(f[i].e), std::exp(static_cast<long double>(x)));
    const long double uc = ulps(static_cast<T>(f[i].c), std::erfc(static_cast<long double>(x)));
    if (ue > worst_e) { worst_e = ue; at_e = x; }
    if (uc > worst_c) { worst_c = uc; at_c = x; }
  }
  std::printf("%s exp %.3Lf %.17g\n", isa, worst_e, at_e);
  std::printf("%s erfc %.3Lf %.17g\n", isa, worst_c, at_c);
}
int main(int argc, char** argv) {
  const int n = argc > 1 ? std::atoi(argv[1]) : 200000;
  const double lo[2] = {@LO@}, hi[2] = {@HI@};
  std::vector<double> xs;
  for (int f = 0; f < 2; ++f)
    for (int i = 0; i < n; ++i) xs.push_back(static_cast<T>(lo[f] + (hi[f] - lo[f]) * i / (n - 1)));
  for (double v : std::initializer_list<double>{@EXTRA@}) xs.push_back(static_cast<T>(v));
  for (int i = -300; i <= 30; ++i) { xs.push_back(static_cast<T>(std::pow(10.0, i / 10.0)));
                                     xs.push_back(-static_cast<T>(std::pow(10.0, i / 10.0))); }
@CALLS@
}
"""


def build(tmp_path: Path, T: str, isas: list[str], cxx: str, flags: tuple[str, ...]) -> Path:
    src = tmp_path / "k.pik"
    src.write_text(KERNEL.format(T=T))
    includes, calls = [], []
    for isa in isas:
        rc, _, err = run_cli([src, "-o", tmp_path / f"K_{isa}.hpp", "--target", isa, "--name", f"K_{isa}"])
        assert rc == 0, err
        includes.append(f'#include "K_{isa}.hpp"')
        calls.append(f'  run(K_{isa}{{}}, "{isa}", xs);')
    extra = EXTRA + EXTRA_EXP[T] + EXTRA_ERFC[T]
    main = (MAIN.replace("@INCLUDES@", "\n".join(includes)).replace("@CALLS@", "\n".join(calls))
            .replace("@CT@", "double" if T == "F64" else "float")
            .replace("@LO@", f"{RANGES[('exp', T)][0]}, {RANGES[('erfc', T)][0]}")
            .replace("@HI@", f"{RANGES[('exp', T)][1]}, {RANGES[('erfc', T)][1]}")
            .replace("@EXTRA@", ", ".join(extra)))
    (tmp_path / "main.cpp").write_text("#include <cstdlib>\n" + main)
    exe = tmp_path / "a.out"
    cc = subprocess.run([cxx, "-std=c++20", "-O2", *flags, f"-I{tmp_path}", f"-I{ROOT / 'runtime/include'}",
                         str(tmp_path / "main.cpp"), "-o", str(exe)], capture_output=True, text=True)
    assert cc.returncode == 0, cc.stderr
    return exe


def check(out: str, T: str, isas: list[str]) -> None:
    rows = [line.split() for line in out.splitlines() if line]
    assert len(rows) == 2 * len(isas), out
    report = []
    for isa, fn, u, at in rows:
        report.append(f"{isa} {fn} {T}: {float(u):.2f} ulp (worst at x = {at})")
    print("\n".join(report))
    for isa, fn, u, at in rows:
        assert float(u) <= BOUND[(fn, T)], f"{isa} {fn} {T}: {u} ulp at x = {at} > {BOUND[(fn, T)]}\n" + out


@pytest.mark.parametrize("T", ["F32", "F64"])
def test_exp_erfc_x86(T: str, tmp_path: Path) -> None:
    isas = ["reference"] + [i for i in ("avx2", "avx512") if host().get(i)]
    for i in ("avx2", "avx512"):
        if i not in isas:
            print(f"{i}: skipped, this CPU does not support it")
    exe = build(tmp_path, T, isas, "g++", ())
    out = subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout
    check(out, T, isas)


@pytest.mark.skipif(any(shutil.which(t) is None for t in ("aarch64-linux-gnu-g++", "qemu-aarch64")),
                    reason="SVE needs aarch64-linux-gnu-g++ and qemu-aarch64 (make deps)")
@pytest.mark.parametrize("T", ["F32", "F64"])
def test_exp_erfc_sve(T: str, tmp_path: Path) -> None:
    from pik_gen.backends.sve import QEMU

    exe = build(tmp_path, T, ["sve"], "aarch64-linux-gnu-g++", ("-march=armv8.2-a+sve",))
    out = subprocess.run([*QEMU, "-cpu", "max,sve-max-vq=2", str(exe), "20000"], capture_output=True, text=True,
                         check=True, timeout=600).stdout
    check(out, T, ["sve"])


def test_erfc_folds_and_checks_types(tmp_path: Path) -> None:
    """erfc of a constant is folded with math.erfc; erfc of an S32 member is a type error."""
    src = tmp_path / "f.pik"
    src.write_text("EPI F64 x:x\nEPJ F64 z:z\nFORCE F64 c:c\nc += erfc(0.5) * (x - z)\n")
    rc, _, err = run_cli([src, "-o", tmp_path / "f.hpp", "--target", "reference"])
    assert rc == 0, err
    text = (tmp_path / "f.hpp").read_text()
    assert repr(math.erfc(0.5)) in text and "std::erfc" not in text
    src.write_text("EPI S32 n:n\nEPJ F64 z:z\nFORCE F64 c:c\nc += erfc(n) * z\n")
    rc, _, err = run_cli([src, "-o", tmp_path / "g.hpp", "--target", "reference"])
    assert rc != 0 and "erfc needs floating-point arguments" in err, err
