"""Compile and run every kernel on every x86 SIMD ISA the host has, through
`pikg-gen verify`: every kernel in kernels/, the PIKG-style kernel in pik/ and
the SIMD coverage kernels in simd_kernels/ (mixed precision, tables, exp/log/pow,
control flow, integers), for ni, nj in {0, 1, lanes-1, lanes, lanes+1, 4 lanes+3,
300} and nj = 5000 (j-parallel and several j blocks), each compared with the
double-precision oracle at verify's documented tolerance (F64 1e-12, F32 5e-5).
An ISA the CPU lacks is skipped with a message."""
from __future__ import annotations

import functools
import shutil
import tempfile
from pathlib import Path

import pytest

from conftest import KERNELS, run_cli

HERE = Path(__file__).parent
CORPUS = KERNELS + sorted((HERE / "pik").glob("*.pik")) + sorted((HERE / "simd_kernels").glob("*.pik"))

pytestmark = pytest.mark.skipif(shutil.which("g++") is None, reason="g++ is not installed")


@functools.cache
def host() -> dict[str, bool]:
    from pik_gen.verify import host_isas

    with tempfile.TemporaryDirectory() as d:
        return host_isas("g++", Path(d))


@pytest.mark.parametrize("isa", ["avx2", "avx512"])
@pytest.mark.parametrize("path", CORPUS, ids=[p.stem for p in CORPUS])
def test_verify_passes(path: Path, isa: str) -> None:
    if not host().get(isa):
        pytest.skip(f"this CPU does not support {isa}")
    rc, out, err = run_cli(["verify", path, "--target", isa])
    assert rc == 0, out + err
    rows = [line.split() for line in out.splitlines() if line.startswith("  ")]
    assert rows and all(r[0] == isa for r in rows), out  # one row per output, all for this ISA
    assert out.rstrip().endswith(f"ok ({isa})"), out


@pytest.mark.parametrize("isa", ["avx2", "avx512"])
def test_fast_math_variant_within_its_wider_tolerance(isa: str) -> None:
    if not host().get(isa):
        pytest.skip(f"this CPU does not support {isa}")
    rc, out, err = run_cli(["verify", HERE.parents[1] / "kernels/gravity_f64.pik", "--target", isa, "--fast-math"])
    assert rc == 0, out + err


@pytest.mark.parametrize("cpu", ["znver4", "znver5"])
@pytest.mark.parametrize("isa", ["avx2", "avx512"])
@pytest.mark.parametrize("name", ["gravity", "gravity_f64", "lj", "gravity_quadrupole", "gravity_treepm"])
def test_verify_passes_sized_for_zen(name: str, isa: str, cpu: str) -> None:
    # --cpu znver4/znver5: AVX2 with EVEX encodings (32 ymm, U = 2 for gravity) and the F64 rsqrt
    # by AVX-512VL's vrsqrt14pd ymm + a fourth-order step; on both ISAs one F64 rsqrt copy in two
    # by the divider. The AVX2 variant runs only where AVX-512VL is.
    if not host().get("avx512"):
        pytest.skip(f"this CPU lacks AVX-512VL, which the {cpu} variants need")
    rc, out, err = run_cli(["verify", HERE.parents[1] / f"kernels/{name}.pik", "--target", isa, "--cpu", cpu])
    assert rc == 0, out + err
    assert out.rstrip().endswith(f"ok ({isa})"), out


def test_verify_rejects_an_unknown_cpu() -> None:
    rc, _out, err = run_cli(["verify", HERE.parents[1] / "kernels/gravity.pik", "--cpu", "pentium4"])
    assert rc == 2 and "unknown --cpu 'pentium4'" in err


# Shared by the drivers below: gravity F32 on the same particles stored as floats (the
# kernel's own types) and as doubles, and a byte comparison of two kernels over ni x nj.
COMPARE_PRELUDE = r"""
#include <cstdio>
#include <cstring>
#include <initializer_list>
#include <random>
#include <vector>
template <class T> struct V3 { T x, y, z; };
struct PF { V3<float> pos; float mass; };    // the kernel's own types: j values straight from epj (kJDirect)
struct PD { V3<double> pos; double mass; };  // doubles: through the j buffers
struct F { V3<float> acc; float pot; };
HEADERS
static void particles(int n, unsigned seed, std::vector<PF>& pf, std::vector<PD>& pd) {
  std::mt19937 g(seed);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  pf.resize(n);
  pd.resize(n);
  for (int k = 0; k < n; ++k) {
    pf[k] = {{u(g), u(g), u(g)}, 0.5f + u(g)};
    pd[k] = {{pf[k].pos.x, pf[k].pos.y, pf[k].pos.z}, pf[k].mass};
  }
}
// a on pa against b on pb (i-particles from index 7): the number of (ni, nj) whose results differ
template <class A, class PA, class B, class PB>
int compare(const A& a, const std::vector<PA>& pa, const B& b, const std::vector<PB>& pb, const char* what,
            std::initializer_list<int> nis, std::initializer_list<int> njs, int& runs) {
  int bad = 0;
  for (int ni : nis)
    for (int nj : njs) {
      std::vector<F> x(ni), y(ni);
      std::memset(x.data(), 0, sizeof(F) * ni);
      std::memset(y.data(), 0, sizeof(F) * ni);
      a(pa.data() + 7, ni, pa.data(), nj, x.data());
      b(pb.data() + 7, ni, pb.data(), nj, y.data());
      ++runs;
      if (std::memcmp(x.data(), y.data(), sizeof(F) * ni) != 0) {
        ++bad;
        std::printf("%s: differ at ni=%d nj=%d\n", what, ni, nj);
      }
    }
  return bad;
}
"""

DIRECT_DRIVER = COMPARE_PRELUDE.replace("HEADERS", '#include "kf.hpp"\n#include "kd.hpp"') + r"""
// the header's own kJDirect condition (copied in by the test): true for the floats, false
// for the doubles, so the two runs below really take the two paths
namespace direct_check {
const PF* epj = nullptr;
static_assert(KJDIRECT, "kJDirect does not hold for the kernel's own member types");
}
namespace buffer_check {
const PD* epj = nullptr;
static_assert(!(KJDIRECT), "kJDirect holds for double members");
}
int main() {
  std::vector<PF> pf;
  std::vector<PD> pd;
  particles(2600, 7, pf, pd);  // two and a half j blocks of every ISA's buffer
  int runs = 0;
  const int bad = compare(KF(1e-4f), pf, KD(1e-4f), pd, "float/double members", {1, 3, 8, 9, 17, 40, 64, 100},
                          {1, 15, 16, 33, 1100, 2600}, runs);
  std::printf("%d of %d differ\n", bad, runs);
  return bad != 0;
}
"""


@pytest.mark.parametrize("isa", ["avx2", "avx512"])
def test_j_values_straight_from_epj_as_through_the_buffer(isa: str, tmp_path: Path) -> None:
    """Simd.direct_j: where the members have the kernel's types (F32 here) an i-parallel
    block broadcasts the j values from epj[jb + jj] and the j buffers are filled only
    for the j-parallel shape; a struct of doubles keeps the buffers. verify's structs
    store doubles, so this runs the direct path of an F32 kernel: both struct layouts
    must give the same bits, over the i-parallel and j-parallel shapes, tails and
    several j blocks (the driver as C++11, which the header keeps to). A kernel whose
    pair stage reads an EPJ local keeps the buffers."""
    import subprocess

    if not host().get(isa):
        pytest.skip(f"this CPU does not support {isa}")
    grav = HERE.parents[1] / "kernels/gravity.pik"
    for name, p in (("KF", "PF"), ("KD", "PD")):
        rc, _, err = run_cli([grav, "-o", tmp_path / f"{name.lower()}.hpp", "--target", isa,
                              "--name", name, "--epi", p, "--epj", p, "--force", "F"])
        assert rc == 0, err
    text = (tmp_path / "kf.hpp").read_text()
    assert "constexpr bool kJDirect" in text and "epj[jb + jj].pos.x" in text and "epj[jb + jj].mass" in text
    cond = text.split("constexpr bool kJDirect =", 1)[1].split(";", 1)[0].strip()
    (tmp_path / "d.cpp").write_text(DIRECT_DRIVER.replace("KJDIRECT", cond))
    exe = tmp_path / "d"
    cc = subprocess.run(["g++", "-std=c++11", "-O2", "-march=native", "-o", str(exe), str(tmp_path / "d.cpp")],
                        capture_output=True, text=True)
    assert cc.returncode == 0, cc.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True)
    assert run.returncode == 0 and "0 of 48 differ" in run.stdout, run.stdout + run.stderr


J_COPIES_DRIVER = COMPARE_PRELUDE.replace(
    "HEADERS", '#include "f4.hpp"\n#include "f1.hpp"\n#include "d4.hpp"\n#include "d1.hpp"') + r"""
int main() {
  std::vector<PF> pf;
  std::vector<PD> pd;
  particles(2610, 11, pf, pd);
  const std::initializer_list<int> nis = {1, 3, 7, 8, 9, 16, 17, 40, 64, 100};
  const std::initializer_list<int> njs = {1, 2, 3, 4, 5, 7, 15, 16, 33, 1100, 2601};
  int runs = 0;
  const int bad = compare(KF4(1e-4f), pf, KF1(1e-4f), pf, "floats", nis, njs, runs) +
                  compare(KD4(1e-4f), pd, KD1(1e-4f), pd, "doubles", nis, njs, runs);
  std::printf("%d of %d differ\n", bad, runs);
  return bad != 0;
}
"""


@pytest.mark.parametrize("isa", ["avx2", "avx512"])
def test_j_copies_sum_as_one_j_per_iteration(isa: str, tmp_path: Path) -> None:
    """Simd.j_copies_rule: V = 4 j-particles per iteration of the i-parallel block (its
    copies op by op, each accumulator taking j-copy 0's term, then 1's, ...) gives the
    bits of one j-particle per iteration (V = 1: two i-vectors per block, the same
    per-lane arithmetic), over tails of the j loop (nj mod 4 = 1, 2, 3), i tails,
    several j blocks, and both the direct-j and the buffered path. gravity F32, --cpu
    znver4 (V = 4 by its AVX2 row; forced on AVX-512, whose row keeps F32 at V = 1).
    The AVX2 variant needs AVX-512VL (EVEX)."""
    import subprocess

    if not host().get("avx512"):
        pytest.skip("this CPU lacks AVX-512VL, which the znver4 variants need")
    from pik_gen.backends import ISAS, Options
    from pik_gen.backends.emit import render_header
    from pik_gen.driver import lower

    grav = HERE.parents[1] / "kernels/gravity.pik"
    source = grav.read_text()
    k = lower(source, str(grav), "K")
    for V in (4, 1):
        for p in ("F", "D"):
            opts = Options(name=f"K{p}{V}", epi=f"P{p}", epj=f"P{p}", force="F", cpu="znver4", j_copies=V)
            text = render_header(k, [ISAS[isa]], opts, source, str(grav))
            assert ("4 j-particles per iteration" in text) == (V == 4)
            (tmp_path / f"{p.lower()}{V}.hpp").write_text(text)
    (tmp_path / "j.cpp").write_text(J_COPIES_DRIVER)
    exe = tmp_path / "j"
    cc = subprocess.run(["g++", "-std=c++11", "-O2", "-march=native", "-o", str(exe), str(tmp_path / "j.cpp")],
                        capture_output=True, text=True)
    assert cc.returncode == 0, cc.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True)
    assert run.returncode == 0 and "0 of 220 differ" in run.stdout, run.stdout + run.stderr


def test_an_epj_local_keeps_the_j_buffers() -> None:
    """A j value computed from members (an EPJ local) is not a member load: no kJDirect."""
    from pik_gen.backends import ISAS, Options
    from pik_gen.driver import lower

    src = ("EPI F32vec xi:pos\nEPJ F32vec xj:pos\nEPJ F32 mj:mass\nEPJ F32 hj:h\nFORCE F32 s:s\n"
           "EPJ local F32 mh\nmh = mj * hj\n"
           "r = xi - xj\ns += mh * (r * r)\n")
    c = ISAS["avx512"](Options(name="K"))
    st = c.begin(lower(src, "local.pik", "K"))
    assert st.plan.jdirect == {}
    plain = src.replace("EPJ local F32 mh\nmh = mj * hj\n", "").replace("mh * (r * r)", "mj * (r * r)")
    st = c.begin(lower(plain, "plain.pik", "K"))
    assert set(st.plan.jdirect.values()) == {".pos.x", ".pos.y", ".pos.z", ".mass"}
