"""Skipped branches (Simd.skip_region, docs/simd.md): where every sum of a kernel is
under one `if`, the SIMD variants skip a vector of pairs in which no lane takes it.
The results must be those of the same kernel with `#pragma blend` (every lane
computed and blended) bit for bit, in every loop shape (i-parallel blocks and tail,
j-parallel), for particles placed so that most vectors skip and some do not: a chain
of particles in order along x (each within the cut-off of a few neighbours) and a
far row of isolated particles (whose i-vectors skip every j); and the same particles
in random order, where the loop turns to its compacted passes (Simd.skip_state,
Simd.compacted: the j-particles in the branch listed, then only those run; a
mutation that drops the last listed one makes 121-234 i-particles differ)."""
from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from conftest import ROOT, run_cli
from test_simd_run import host

pytestmark = pytest.mark.skipif(shutil.which("g++") is None, reason="g++ is not installed")

CASES = {
    # kernels/lj.pik: F64, the cut-off and r > 0 under one `if`; parameters box, rcut2, eps, sigma2
    "lj": ([], """
struct V { double x, y, z; };
struct EP { V pos; };
struct F { V acc; double pot, vir; };
#define MAKE(K) K(1.0e6, 9.0, 1.0, 1.0)
#define SET(p, x, y, z) (p.pos = V{x, y, z})
#define OUT(f) f.acc.x, f.acc.y, f.acc.z, f.pot, f.vir
#define COUNT(f) (f.pot != 0.0)
"""),
    # kernels/sph_density.pik: F32, every sum under `if r2 < hi * hi`
    "sph_density": (["--const", "shape=0", "--const", "dim=3"], """
struct V { float x, y, z; };
struct EP { V pos; float h; V vel; float mass; float u; };
struct F { float rho, drhodh, q, divv; V rotv; float nngb; };
#define MAKE(K) K()
#define SET(p, x_, y_, z_) (p.pos = V{float(x_), float(y_), float(z_)}, p.h = 3.0f, p.vel = V{float(0.1 * x_), 0.0f, float(-0.2 * y_)}, p.mass = 1.0f, p.u = float(1.0 + 0.01 * x_))
#define OUT(f) f.rho, f.drhodh, f.q, f.divv, f.rotv.x, f.rotv.y, f.rotv.z, f.nngb
#define COUNT(f) (f.nngb > 1.5f)  // the particle itself is counted
"""),
}

MAIN = r"""
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>
#include "K_skip.hpp"
#include "K_blend.hpp"
// a chain along x (spacing 0.7, cut-off or support 3: a few neighbours each side), in order,
// with a slight zigzag in y and z; the last 20 particles far away and apart (no neighbours)
static void place(std::vector<EP>& p) {
  const int n = static_cast<int>(p.size());
  for (int k = 0; k < n; ++k) {
    if (k < n - 20) SET(p[k], 0.7 * k, 0.05 * (k % 3), 0.03 * (k % 5));
    else SET(p[k], 1.0e4 + 10.0 * (k - n), 0.0, 0.0);
  }
}
int main() {
  const auto skip = MAKE(K_skip);
  const auto blend = MAKE(K_blend);
  int bad = 0, runs = 0, inside = 0, outside = 0;
  const int sizes[][2] = {{300, 300}, {37, 300}, {5, 300}, {1, 3000}, {7, 40}, {300, 5}, {2000, 2000}};
  std::mt19937 rng(7);
  for (int shuffled = 0; shuffled < 2; ++shuffled)
  for (const auto& s : sizes) {
    // the i-particles are a window of the chain (or the far row), the j-particles all of it;
    // shuffled: in random order, where the branch is unpredictable and the loop runs every
    // vector after a while (skip_state), which must give the same sums too
    std::vector<EP> pj(s[1] + 20);
    place(pj);
    if (shuffled) std::shuffle(pj.begin(), pj.end(), rng);
    for (int off : {0, s[1] / 2, s[1] + 20 - s[0] > 0 ? s[1] + 20 - s[0] : 0}) {
      const int ni = s[0] + off <= static_cast<int>(pj.size()) ? s[0] : static_cast<int>(pj.size()) - off;
      std::vector<F> a(ni), b(ni);
      std::memset(a.data(), 0, sizeof(F) * ni);
      std::memset(b.data(), 0, sizeof(F) * ni);
      skip(pj.data() + off, ni, pj.data(), static_cast<int>(pj.size()), a.data());
      blend(pj.data() + off, ni, pj.data(), static_cast<int>(pj.size()), b.data());
      ++runs;
      for (int i = 0; i < ni; ++i) {
        if (std::memcmp(&a[i], &b[i], sizeof(F)) != 0) {
          if (bad++ < 5) std::printf("differs: ni %d nj %zu off %d i %d\n", ni, pj.size(), off, i);
        }
        (COUNT(b[i]) ? inside : outside) += 1;
      }
    }
  }
  std::printf("runs %d, i-particles with neighbours %d, without %d, differing %d\n", runs, inside, outside, bad);
  return bad != 0 || inside == 0 || outside == 0;
}
"""


def variants() -> list[tuple[str, list[str]]]:
    out = [(i, []) for i in ("avx2", "avx512") if host().get(i)]
    if host().get("avx512"):
        out.append(("avx2", ["--cpu", "znver4"]))  # AVX2 with EVEX registers, U = 2 where it applies
    return out


@pytest.mark.parametrize("name", sorted(CASES))
def test_skipped_branches_give_the_blended_results_bit_for_bit(name: str, tmp_path: Path) -> None:
    if not variants():
        pytest.skip("this CPU has neither AVX2 nor AVX-512")
    opts, structs = CASES[name]
    src = (ROOT / "kernels" / f"{name}.pik").read_text()
    (tmp_path / "blend.pik").write_text("#pragma blend\n" + src)
    (tmp_path / "skip.pik").write_text(src)
    for isa, cpu in variants():
        for kind in ("skip", "blend"):
            rc, _, err = run_cli([tmp_path / f"{kind}.pik", "-o", tmp_path / f"K_{kind}.hpp", "--target", isa,
                                  "--name", f"K_{kind}", "--epi", "EP", "--epj", "EP", "--force", "F", *opts, *cpu])
            assert rc == 0, err
        assert "skip_region" in (tmp_path / "K_skip.hpp").read_text() and "Simd.compacted" in (tmp_path / "K_skip.hpp").read_text()
        assert "skip_region" not in (tmp_path / "K_blend.hpp").read_text()
        (tmp_path / "main.cpp").write_text(structs + MAIN)
        exe = tmp_path / "main"
        cc = subprocess.run(["g++", "-std=c++20", "-O2", "-march=native", "-I", str(tmp_path), str(tmp_path / "main.cpp"),
                             "-o", str(exe)], capture_output=True, text=True)
        assert cc.returncode == 0, cc.stderr[-3000:]
        r = subprocess.run([str(exe)], capture_output=True, text=True, timeout=120)
        assert r.returncode == 0, f"{isa} {cpu}: {r.stdout}{r.stderr}"
