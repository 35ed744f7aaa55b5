"""PIKG and FDPS users switch by changing one word (issue 16).

The corpus: kernels written here in pik's own words after PIKG's documented
language (docs/language.md, ../shared/LANGUAGE.md) for each kind of kernel PIKG
and FDPS ship as samples, each run with the flag set of the Makefile beside that
sample (`--epi-name ... --kernel-name ... --class-file ...`, `--c-interface`,
`--fortran-interface`). Every case is generated for every ISA this host runs
(and `auto`), compiled and compared with a direct double-precision evaluation of
the same physics written out in the driver (Newtonian gravity with Plummer
softening, Aarseth 2003 eq. 1.2; Lennard-Jones with the minimum-image convention,
Allen & Tildesley 1987 sec. 1.5; a min/count neighbour reduction).

Tolerances: F64 kernels agree to 1e-12 relative (rounding of a few hundred terms),
F32 kernels to 2e-5 (single-precision rounding).

Also: one test per PIKG option, the C caller (gcc) and the Fortran caller
(gfortran) against the direct sum, three headers and a header that is not
self-contained, and the name, nesting and cascade errors.

Cases that read a header need pikg-reflect (PIKG_REFLECT, or PIK_BUILD_DIR/bin);
they are skipped with a message without it, as are the Fortran cases without gfortran.
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from conftest import run_cli

from pik_gen.backends import ISAS  # noqa: E402


def _reflect_tool() -> str | None:
    env = os.environ.get("PIKG_REFLECT")
    if env and os.access(env, os.X_OK):
        return env
    build = os.environ.get("PIK_BUILD_DIR")
    if build and os.access(Path(build) / "bin" / "pikg-reflect", os.X_OK):
        os.environ["PIKG_REFLECT"] = str(Path(build) / "bin" / "pikg-reflect")
        return os.environ["PIKG_REFLECT"]
    return shutil.which("pikg-reflect")


REFLECT = _reflect_tool()
needs_reflect = pytest.mark.skipif(REFLECT is None, reason="pikg-reflect is not built (no libclang): header cases skipped")
needs_gxx = pytest.mark.skipif(shutil.which("g++") is None, reason="g++ is not installed")
needs_gfortran = pytest.mark.skipif(shutil.which("gfortran") is None,
                                    reason="gfortran is not installed (tools/deps.sh installs it): Fortran caller skipped")


def _cpu_flags() -> set[str]:
    try:
        m = re.search(r"^flags\s*:\s*(.*)$", Path("/proc/cpuinfo").read_text(), re.M)
    except OSError:
        return set()
    return set(m.group(1).split()) if m else set()


def host_isas() -> list[str]:
    """The ISAs whose code runs on this machine (no cross compiler or emulator needed)."""
    have, out = _cpu_flags(), []
    for name, cls in ISAS.items():
        if getattr(cls, "runners", None):
            continue
        need = [f[2:].replace("-", "_") for f in cls.cxx_flags if f.startswith("-m") and not f.startswith("-march")]
        if all(n in have for n in need):
            out.append(name)
    return out


HOST = host_isas()
HOST_FLAGS = sorted({f for n in HOST for f in ISAS[n].cxx_flags})


def pikg(*args) -> tuple[int, str]:
    rc, _out, err = run_cli([str(a) for a in args])
    return rc, err


def write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def compile_and_run(tmp: Path, sources: list[Path], extra: list[str] = (), cxx: str = "g++") -> str:
    exe = tmp / "driver"
    cmd = [cxx, "-std=c++20", "-O1", "-Wall", "-Wextra", "-Werror", f"-I{tmp}", *HOST_FLAGS, *extra,
           *map(str, sources), "-o", str(exe)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    assert p.returncode == 0, " ".join(cmd) + "\n" + p.stderr
    r = subprocess.run([str(exe)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    return r.stdout


# ----------------------------------------------------------------------------- corpus
# Each case: the kernel (.pik text, pik's words after PIKG's language), its header,
# the Makefile's flags, and a driver body that fills particles, runs KERNEL (a macro
# naming each generated class in turn) and checks against the direct sum.

COMMON = r"""
#include <cmath>
#include <cstdio>
#include <vector>
static unsigned long long rng_state = 12345;
static double uniform() { rng_state = rng_state * 6364136223846793005ULL + 1442695040888963407ULL;
                          return static_cast<double>(rng_state >> 11) * 0x1.0p-53; }
static int bad = 0;
static void report(const char* what, const char* isa, double err, double tol) {
  std::printf("%s %s max relative error %.3g (tolerance %.1g)\n", what, isa, err, tol);
  if (!(err <= tol)) ++bad;
}
"""

GRAVITY_PIK = """\
// Plummer-softened gravity on members named in the user's header (EPI.pos, EPJ.mass)
F64 eps2
dr = EPI.pos - EPJ.pos
r2 = dr * dr + eps2
rinv = rsqrt(r2)
mrinv = EPJ.mass * rinv
FORCE.acc -= mrinv * rinv * rinv * dr
FORCE.pot -= mrinv
"""
GRAVITY_HPP = """\
#pragma once
struct Vec { double x, y, z; };
struct Body { double mass; Vec pos; Vec vel; long id; };
struct Acc { Vec acc; double pot; };
"""
GRAVITY_TEST = r"""
template <class K> void run_gravity(const char* isa) {
  const int n = 67; const double eps2 = 1e-3;
  std::vector<Body> b(n); std::vector<Acc> f(n);
  for (auto& p : b) { p.mass = 0.5 + uniform(); p.pos = {uniform(), uniform(), uniform()}; }
  for (auto& a : f) a = {{0, 0, 0}, 0};
  const K k(eps2);
  k(b.data(), n, b.data(), n, f.data());
  double err = 0, scale = 0;
  for (int i = 0; i < n; ++i) {
    double ax = 0, pot = 0;
    for (int j = 0; j < n; ++j) {
      const double dx = b[i].pos.x - b[j].pos.x, dy = b[i].pos.y - b[j].pos.y, dz = b[i].pos.z - b[j].pos.z;
      const double r = std::sqrt(dx * dx + dy * dy + dz * dz + eps2);
      ax -= b[j].mass * dx / (r * r * r); pot -= b[j].mass / r;
    }
    scale = std::fmax(scale, std::fabs(pot));
    err = std::fmax(err, std::fmax(std::fabs(f[i].acc.x - ax), std::fabs(f[i].pot - pot)));
  }
  report("gravity", isa, err / scale, 1e-12);
}
"""

FDPS_NBODY_PIK = """\
// FDPS sample style: every member declared in the file, single precision
EPI F32vec xi:pos
EPJ F32vec xj:pos
EPJ F32 mj:mass
FORCE F32vec acc:acc
FORCE F32 pot:pot
F32 eps2
rij = xi - xj
r2 = rij * rij + eps2
rinv = rsqrt(r2)
mr = mj * rinv
acc -= mr * rinv * rinv * rij
pot -= mr
"""
FDPS_NBODY_HPP = """\
#pragma once
struct F32v { float x, y, z; };
struct Epi { F32v pos; };
struct Epj { F32v pos; float mass; };
struct Force { F32v acc; float pot; };
"""
FDPS_NBODY_TEST = r"""
template <class K> void run_gravity(const char* isa) {
  const int n = 53; const float eps2 = 1e-3f;
  std::vector<Epi> ei(n); std::vector<Epj> ej(n); std::vector<Force> f(n);
  for (int i = 0; i < n; ++i) {
    ej[i].pos = {float(uniform()), float(uniform()), float(uniform())}; ej[i].mass = float(0.5 + uniform());
    ei[i].pos = ej[i].pos; f[i] = {{0, 0, 0}, 0};
  }
  const K k(eps2);
  k(ei.data(), n, ej.data(), n, f.data());
  double err = 0, scale = 0;
  for (int i = 0; i < n; ++i) {
    double az = 0, pot = 0;
    for (int j = 0; j < n; ++j) {
      const double dx = ei[i].pos.x - ej[j].pos.x, dy = ei[i].pos.y - ej[j].pos.y, dz = double(ei[i].pos.z) - ej[j].pos.z;
      const double r = std::sqrt(dx * dx + dy * dy + dz * dz + double(eps2));
      az -= ej[j].mass * dz / (r * r * r); pot -= ej[j].mass / r;
    }
    scale = std::fmax(scale, std::fabs(pot));
    err = std::fmax(err, std::fmax(std::fabs(f[i].acc.z - az), std::fabs(f[i].pot - pot)));
  }
  report("fdps-nbody", isa, err / scale, 2e-5);
}
"""

LJ_PIK = """\
// Lennard-Jones in a periodic box of side l, cut off at rc (minimum image)
F64 l
F64 rc
dx = EPI.rx - EPJ.rx
if dx < -0.5 * l
  dx = dx + l
elsif dx >= 0.5 * l
  dx = dx - l
endif
dy = EPI.ry - EPJ.ry
if dy < -0.5 * l
  dy = dy + l
elsif dy >= 0.5 * l
  dy = dy - l
endif
dz = EPI.rz - EPJ.rz
if dz < -0.5*l
  dz = dz + l
endif
if dz >= 0.5*l
  dz = dz - l
endif
r2 = dx * dx + dy * dy + dz * dz
if r2 < rc * rc && r2 > 0.0
  r2i = 1.0 / r2
  r6i = r2i * r2i * r2i
  f = (48.0 * r6i - 24.0) * r6i * r2i
  FORCE.fx += f * dx
  FORCE.fy += f * dy
  FORCE.fz += f * dz
  FORCE.p += 4.0 * r6i * (r6i - 1.0)
endif
"""
LJ_HPP = """\
#pragma once
struct Atom { double rx, ry, rz; };
struct LJForce { double fx, fy, fz, p; };
"""
LJ_TEST = r"""
template <class K> void run_lj(const char* isa) {
  const int n = 64; const double l = 4.0, rc = 2.5;
  std::vector<Atom> a(n); std::vector<LJForce> f(n);
  for (int i = 0; i < n; ++i) { a[i] = {(i % 4) + 0.2 * uniform(), ((i / 4) % 4) + 0.2 * uniform(), (i / 16) + 0.2 * uniform()}; f[i] = {0, 0, 0, 0}; }
  const K k(l, rc);
  k(a.data(), n, a.data(), n, f.data());
  double err = 0, scale = 0;
  for (int i = 0; i < n; ++i) {
    double fx = 0, p = 0;
    for (int j = 0; j < n; ++j) {
      double d[3] = {a[i].rx - a[j].rx, a[i].ry - a[j].ry, a[i].rz - a[j].rz};
      for (double& c : d) { if (c < -0.5 * l) c += l; if (c >= 0.5 * l) c -= l; }
      const double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
      if (r2 < rc * rc && r2 > 0) {
        const double r6i = 1 / (r2 * r2 * r2);
        fx += (48 * r6i - 24) * r6i / r2 * d[0]; p += 4 * r6i * (r6i - 1);
      }
    }
    scale = std::fmax(scale, std::fmax(std::fabs(fx), std::fabs(p)));
    err = std::fmax(err, std::fmax(std::fabs(f[i].fx - fx), std::fabs(f[i].p - p)));
  }
  report("lennard-jones", isa, err / scale, 1e-12);
}
"""

NESTED_IF_PIK = """\
// nested conditions, a min reduction and a count, integer ids compared
dr = EPI.pos - EPJ.pos
r2 = dr * dr
if r2 < 1.0f
  if EPI.id != EPJ.id
    FORCE.r2min = min(r2, FORCE.r2min)
    FORCE.count += 1
  endif
endif
"""
NESTED_IF_HPP = """\
#pragma once
struct P { float x, y, z; };
struct Pt { P pos; int id; };
struct Near { float r2min; int count; };
"""
NESTED_IF_TEST = r"""
template <class K> void run_near(const char* isa) {
  const int n = 45;
  std::vector<Pt> p(n); std::vector<Near> f(n);
  for (int i = 0; i < n; ++i) { p[i] = {{float(2 * uniform()), float(2 * uniform()), float(2 * uniform())}, i}; f[i] = {1e30f, 0}; }
  const K k;
  k(p.data(), n, p.data(), n, f.data());
  double err = 0;
  for (int i = 0; i < n; ++i) {
    float m = 1e30f; int c = 0;
    for (int j = 0; j < n; ++j) {
      const float dx = p[i].pos.x - p[j].pos.x, dy = p[i].pos.y - p[j].pos.y, dz = p[i].pos.z - p[j].pos.z;
      const float r2 = dx * dx + dy * dy + dz * dz;
      if (r2 < 1.0f && i != j) { m = std::fmin(m, r2); ++c; }
    }
    if (c != f[i].count) err = 1;
    if (c) err = std::fmax(err, std::fabs(f[i].r2min - m) / m);
  }
  report("nested-if", isa, err, 2e-5);
}
"""

# FDPS's planetary-ring sample style: a header written for FDPS that uses PS:: types
# and does not include particle_simulator.hpp (pikg-reflect's stand-ins read it); the
# generated code is compiled against a definition of PS:: with the same layout.
RING_PIK = """\
// gravity plus a spring between overlapping particles; unprefixed acc/pot on the left are FORCE
F32 eps2
F32 kappa
rij = EPI.pos - EPJ.pos
r2 = rij * rij + eps2
if r2 != eps2
  rinv = rsqrt(r2)
  rc = EPI.r_coll + EPJ.r_coll
  acc_sprg = rij * 0.0f
  if rc * rc > r2
    dr = rc - r2 * rinv
    acc_sprg = kappa * dr * rinv * rij
  endif
  acc -= EPJ.mass * rinv * rinv * rinv * rij - acc_sprg
  pot -= EPJ.mass * rinv
endif
"""
RING_HPP = """\
#pragma once
struct Epi0 { PS::F32vec pos; PS::F32 mass; PS::F32 r_coll; };
struct Epj0 { PS::F32vec pos; PS::F32 mass; PS::F32 r_coll; };
struct Force0 { PS::F32vec acc; PS::F32 pot; };
"""
RING_PS = """\
#pragma once
namespace PS { typedef float F32; struct F32vec { F32 x, y, z; }; }
"""
RING_TEST = r"""
template <class K> void run_ring(const char* isa) {
  const int n = 40; const float eps2 = 1e-4f, kappa = 1e3f;
  std::vector<Epi0> ei(n); std::vector<Epj0> ej(n); std::vector<Force0> f(n);
  for (int i = 0; i < n; ++i) {
    ej[i].pos = {float(uniform()), float(uniform()), float(uniform())}; ej[i].mass = float(1e-3 * (1 + uniform()));
    ej[i].r_coll = 0.1f; ei[i] = {ej[i].pos, ej[i].mass, ej[i].r_coll}; f[i] = {{0, 0, 0}, 0};
  }
  const K k(eps2, kappa);
  k(ei.data(), n, ej.data(), n, f.data());
  double err = 0, scale = 0;
  for (int i = 0; i < n; ++i) {
    double ax = 0, pot = 0;
    for (int j = 0; j < n; ++j) {
      const double d[3] = {double(ei[i].pos.x) - ej[j].pos.x, double(ei[i].pos.y) - ej[j].pos.y, double(ei[i].pos.z) - ej[j].pos.z};
      const double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + double(eps2);
      if (i == j) continue;  // r2 == eps2: no force, and rinv of the self pair multiplies a zero rij
      const double rinv = 1 / std::sqrt(r2), rc = double(ei[i].r_coll) + ej[j].r_coll;
      double sp = 0;
      if (rc * rc > r2) sp = double(kappa) * (rc - r2 * rinv) * rinv * d[0];
      ax -= ej[j].mass * rinv * rinv * rinv * d[0] - sp; pot -= ej[j].mass * rinv;
    }
    scale = std::fmax(scale, std::fmax(std::fabs(ax), std::fabs(pot)));
    err = std::fmax(err, std::fmax(std::fabs(f[i].acc.x - ax), std::fabs(f[i].pot - pot)));
  }
  report("planetary-ring", isa, err / scale, 1e-4);
}
"""

# (id, kernel, header, flags of the sample's Makefile (before -i/-o), run function, needs reflect)
CORPUS = [
    ("pikg_cxx_nbody", GRAVITY_PIK, GRAVITY_HPP,
     ["--epi-name", "Body", "--epj-name", "Body", "--force-name", "Acc", "--class-file", "{hpp}"], "run_gravity", True),
    ("fdps_cxx_nbody", FDPS_NBODY_PIK, FDPS_NBODY_HPP,
     ["--epi-name", "Epi", "--epj-name", "Epj", "--force-name", "Force"], "run_gravity", False),
    ("pikg_lennard_jones", LJ_PIK, LJ_HPP,
     ["--epi-name", "Atom", "--epj-name", "Atom", "--force-name", "LJForce", "--class-file", "{hpp}"], "run_lj", True),
    ("pikg_nested_if", NESTED_IF_PIK, NESTED_IF_HPP,
     ["--epi-name", "Pt", "--epj-name", "Pt", "--force-name", "Near", "--class-file", "{hpp}"], "run_near", True),
    ("fdps_planetary_ring", RING_PIK, RING_HPP,
     ["--epi-name", "Epi0", "--epj-name", "Epj0", "--force-name", "Force0", "--class-file", "{hpp}"], "run_ring", True),
]
TESTS = {"pikg_cxx_nbody": GRAVITY_TEST, "fdps_cxx_nbody": FDPS_NBODY_TEST, "pikg_lennard_jones": LJ_TEST,
         "pikg_nested_if": NESTED_IF_TEST, "fdps_planetary_ring": RING_TEST}


@needs_gxx
@pytest.mark.parametrize("case", CORPUS, ids=[c[0] for c in CORPUS])
def test_corpus_every_host_isa_matches_direct_sum(tmp_path: Path, case) -> None:
    cid, kernel, header, flags, runner, reflect = case
    if reflect and REFLECT is None:
        pytest.skip("pikg-reflect is not built (no libclang): this case reads its header")
    pik = write(tmp_path / f"{cid}.pikg", kernel)
    hpp = write(tmp_path / "user_defined.hpp", header)
    includes, calls = [], []
    for isa in [*HOST, "auto"]:
        out = tmp_path / f"kernel_{isa}.hpp"
        # the Makefile's flags, with PIKG's spelling of the target where it has one
        spelled = {"reference": "reference", "avx2": "AVX2", "avx512": "AVX-512"}.get(isa)
        target = ["--conversion-type", spelled] if spelled else ["--target", isa]
        args = [a.replace("{hpp}", str(hpp)) for a in flags]
        rc, err = pikg(*target, *args, "--kernel-name", f"{cid}_{isa}", "-i", pik, "-o", out)
        assert rc == 0, err
        includes.append(f'#include "{out.name}"')
        calls.append(f'  {runner}<{cid}_{isa}>("{isa}");')
    prelude = ""
    if cid == "fdps_planetary_ring":
        write(tmp_path / "ps.hpp", RING_PS)
        prelude = '#include "ps.hpp"\n'
    driver = write(tmp_path / "driver.cpp", prelude + '#include "user_defined.hpp"\n' + "\n".join(includes) + "\n"
                   + COMMON + TESTS[cid] + "int main() {\n" + "\n".join(calls) + "\n  return bad;\n}\n")
    out = compile_and_run(tmp_path, [driver])
    assert out.count("max relative error") == len(HOST) + 1, out


# ----------------------------------------------------------------------------- C and Fortran callers

C_SAMPLE_PIK = """\
// PIKG's C sample style: no declarations, unprefixed names resolved through the header
// (pos, eps: EPI; EPJ.mass; acc, pot on the left: FORCE)
rij = pos - EPJ.pos
r2 = rij * rij + eps * eps
r_inv = rsqrt(r2)
mr_inv = EPJ.mass * r_inv
acc -= mr_inv * r_inv * r_inv * rij
pot -= mr_inv
"""
C_SAMPLE_H = """\
#ifndef USER_DEFINED_H
#define USER_DEFINED_H
#include <pikg_vector.h>
typedef struct {
  long long id;
  double mass;
  double eps;
  pikg_f64vec pos;
  pikg_f64vec vel;
  double pot;
  pikg_f64vec acc;
} particle;
#endif
"""
C_CALLER = r"""
#include <math.h>
#include <stdio.h>
#include "user_defined.h"
#include "kernel.h"
int main(void) {
  enum { N = 50 };
  static particle p[N];
  unsigned long long s = 99;
  for (int i = 0; i < N; ++i) {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL; p[i].pos.x = (double)(s >> 11) * 0x1.0p-53;
    s = s * 6364136223846793005ULL + 1442695040888963407ULL; p[i].pos.y = (double)(s >> 11) * 0x1.0p-53;
    s = s * 6364136223846793005ULL + 1442695040888963407ULL; p[i].pos.z = (double)(s >> 11) * 0x1.0p-53;
    p[i].mass = 1.0 / N; p[i].eps = 1.0 / 32; p[i].id = i;
    p[i].acc.x = p[i].acc.y = p[i].acc.z = 0; p[i].pot = 0;
  }
  calc_gravity(p, N, p, N, p);
  double err = 0, scale = 0;
  for (int i = 0; i < N; ++i) {
    double ax = 0, pot = 0;
    for (int j = 0; j < N; ++j) {
      double dx = p[i].pos.x - p[j].pos.x, dy = p[i].pos.y - p[j].pos.y, dz = p[i].pos.z - p[j].pos.z;
      double r = sqrt(dx * dx + dy * dy + dz * dz + p[i].eps * p[i].eps);
      ax -= p[j].mass * dx / (r * r * r); pot -= p[j].mass / r;
    }
    if (fabs(pot) > scale) scale = fabs(pot);
    if (fabs(p[i].acc.x - ax) > err) err = fabs(p[i].acc.x - ax);
    if (fabs(p[i].pot - pot) > err) err = fabs(p[i].pot - pot);
  }
  printf("C caller: max relative error %.3g\n", err / scale);
  return err / scale < 1e-12 ? 0 : 1;
}
"""


@needs_gxx
@needs_reflect
@pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc is not installed")
@pytest.mark.parametrize("isa", HOST)
def test_c_interface_from_a_c_caller(tmp_path: Path, isa: str) -> None:
    """PIKG's C sample's flags: --c-interface --kernel-name calc_gravity --class-file user_defined.h;
    the C header includes <pikg_vector.h>, which is not on any include path here."""
    pik = write(tmp_path / "kernel.pikg", C_SAMPLE_PIK)
    write(tmp_path / "user_defined.h", C_SAMPLE_H)
    rc, err = pikg("--target", isa, "--epi-name", "particle", "--epj-name", "particle", "--force-name", "particle",
                   "--c-interface", "--kernel-name", "calc_gravity", "--class-file", tmp_path / "user_defined.h",
                   "--output", tmp_path / "kernel.cpp", "-i", pik)
    assert rc == 0, err
    proto = (tmp_path / "kernel.h").read_text()  # default prototype header: the output's name with .h
    assert "void calc_gravity(const void* epi, int ni, const void* epj, int nj, void* force);" in proto
    assert "void calc_gravity_initialize(void);" in proto
    cpp = (tmp_path / "kernel.cpp").read_text()
    assert "#pragma once" not in cpp  # a translation unit
    assert "static_assert(sizeof(particle) == 104," in cpp
    # the C side is compiled with a pikg_vector.h of its own (as a PIKG user's inc/ would give)
    inc = tmp_path / "inc"
    inc.mkdir()
    write(inc / "pikg_vector.h", "typedef struct { double x, y, z; } pikg_f64vec;\n")
    obj = tmp_path / "kernel.o"
    p = subprocess.run(["g++", "-std=c++20", "-O2", "-Wall", "-Wextra", "-Werror", *ISAS[isa].cxx_flags, "-c",
                        str(tmp_path / "kernel.cpp"), "-o", str(obj)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    write(tmp_path / "main.c", C_CALLER)
    exe = tmp_path / "nbody"
    p = subprocess.run(["gcc", "-std=c11", "-O2", "-Wall", "-Werror", f"-I{inc}", f"-I{tmp_path}",
                        str(tmp_path / "main.c"), str(obj), "-lm", "-lstdc++", "-o", str(exe)],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    r = subprocess.run([str(exe)], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stdout + r.stderr


FORTRAN_CALLER = r"""
program nbody_f
  use, intrinsic :: iso_c_binding
  use pikg_module_ep_ep
  implicit none
  type, bind(c) :: vec3f
    real(kind=c_float) :: x, y, z
  end type vec3f
  type, bind(c) :: epi_grav
    type(vec3f) :: pos
  end type epi_grav
  type, bind(c) :: epj_grav
    type(vec3f) :: pos
    real(kind=c_float) :: mass
  end type epj_grav
  type, bind(c) :: force_grav
    type(vec3f) :: acc
    real(kind=c_float) :: pot
  end type force_grav
  integer, parameter :: n = 40
  type(epi_grav), target :: ei(n)
  type(epj_grav), target :: ej(n)
  type(force_grav), target :: f(n)
  real(kind=c_float) :: eps2
  double precision :: dx, dy, dz, r, ax, pot, err, scale, u(3)
  integer :: i, j
  eps2 = 1.0e-3
  do i = 1, n
    call random_number(u)
    ej(i)%pos = vec3f(real(u(1), c_float), real(u(2), c_float), real(u(3), c_float))
    ej(i)%mass = 1.0 / n
    ei(i)%pos = ej(i)%pos
    f(i)%acc = vec3f(0.0, 0.0, 0.0)
    f(i)%pot = 0.0
  end do
  call pikg_calc_grav_ep_ep_initialize(eps2)
  call pikg_calc_grav_ep_ep(c_loc(ei), n, c_loc(ej), n, c_loc(f))
  err = 0; scale = 0
  do i = 1, n
    ax = 0; pot = 0
    do j = 1, n
      dx = dble(ei(i)%pos%x) - ej(j)%pos%x
      dy = dble(ei(i)%pos%y) - ej(j)%pos%y
      dz = dble(ei(i)%pos%z) - ej(j)%pos%z
      r = sqrt(dx*dx + dy*dy + dz*dz + dble(eps2))
      ax = ax - ej(j)%mass * dx / r**3
      pot = pot - ej(j)%mass / r
    end do
    scale = max(scale, abs(pot))
    err = max(err, abs(f(i)%acc%x - ax), abs(f(i)%pot - pot))
  end do
  print '(a, es10.3)', 'Fortran caller: max relative error', err / scale
  if (err / scale > 2.0d-5) stop 1
end program nbody_f
"""


@needs_gxx
@needs_gfortran
@pytest.mark.parametrize("isa", HOST)
def test_fortran_interface_from_a_fortran_caller(tmp_path: Path, isa: str, monkeypatch) -> None:
    """FDPS's Fortran sample's flags: --fortran-interface pikg_module_ep_ep (MODULE.F90 in the
    working directory, as PIKG writes it), in-file declarations, no class file."""
    monkeypatch.chdir(tmp_path)
    pik = write(tmp_path / "kernel_ep_ep.pikg", FDPS_NBODY_PIK)
    rc, err = pikg("--conversion-type", {"reference": "reference", "avx2": "AVX2", "avx512": "AVX-512"}.get(isa, isa),
                   "--epi-name", "epi_grav", "--epj-name", "epj_grav", "--force-name", "force_grav",
                   "--kernel-name", "pikg_calc_grav_ep_ep", "--fortran-interface", "pikg_module_ep_ep",
                   "--output", "pikg_kernel_ep_ep.cpp", "-i", pik)
    assert rc == 0, err
    module = (tmp_path / "pikg_module_ep_ep.F90").read_text()
    assert "bind(c, name='pikg_calc_grav_ep_ep_initialize')" in module
    assert "real(kind=c_float), value :: eps2" in module
    assert not (tmp_path / "pikg_kernel_ep_ep.h").exists()  # PIKG: no C prototype header with the Fortran interface alone
    p = subprocess.run(["g++", "-std=c++20", "-O2", "-Wall", "-Wextra", "-Werror", *ISAS[isa].cxx_flags, "-c",
                        "pikg_kernel_ep_ep.cpp"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    write(tmp_path / "main.F90", FORTRAN_CALLER)
    p = subprocess.run(["gfortran", "-O2", "-Wall", "pikg_module_ep_ep.F90", "main.F90", "pikg_kernel_ep_ep.o",
                        "-lstdc++", "-o", "nbody_f"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    r = subprocess.run(["./nbody_f"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stdout + r.stderr


def test_fortran_class_file_is_read(tmp_path: Path, monkeypatch) -> None:
    """--class-file with --fortran-interface names Fortran source: bind(c) types are read,
    members typed and laid out as the companion C struct."""
    monkeypatch.chdir(tmp_path)
    write(tmp_path / "user_defined.F90", """\
module user_defined_types
  use, intrinsic :: iso_c_binding
  implicit none
  type, public, bind(c) :: full_particle !$fdps FP,EPI,EPJ,Force
    integer(kind=c_long_long) :: id
    real(kind=c_double)  mass !$fdps charge
    type(fdps_f64vec) :: pos !$fdps position
    real(kind=c_double) :: pot
    type(fdps_f64vec) :: acc
  end type full_particle
end module user_defined_types
""")
    pik = write(tmp_path / "k.pikg", GRAVITY_PIK)
    rc, err = pikg("--epi-name", "full_particle", "--epj-name", "full_particle", "--force-name", "full_particle",
                   "--class-file", "user_defined.F90", "--fortran-interface", "kmod", "--kernel-name", "grav",
                   "-o", "k.cpp", "-i", pik, "--target", "reference")
    assert rc == 0, err
    cpp = (tmp_path / "k.cpp").read_text()
    assert "static_assert(offsetof(full_particle, pos) == 16," in cpp
    assert "static_assert(sizeof(full_particle) == 72," in cpp
    p = subprocess.run(["g++", "-std=c++20", "-Wall", "-Werror", "-c", "k.cpp"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert "subroutine grav_initialize" in (tmp_path / "kmod.F90").read_text()


# ----------------------------------------------------------------------------- one test per option

SIMPLE = FDPS_NBODY_PIK


def gen(tmp: Path, *args) -> tuple[int, str, Path]:
    pik = write(tmp / "k.pikg", SIMPLE)
    out = tmp / "k.hpp"
    rc, err = pikg("-i", pik, "-o", out, "--target", "reference", *args)
    return rc, err, out


def test_option_initializer_name(tmp_path: Path) -> None:
    rc, err, out = gen(tmp_path, "--c-interface", str(tmp_path / "p.h"), "--initializer-name", "init_grav",
                       "--kernel-name", "grav")
    assert rc == 0, err
    assert "void init_grav(float eps2_)" in out.read_text()
    assert "void init_grav(float eps2_);" in (tmp_path / "p.h").read_text()
    rc, err, _ = gen(tmp_path, "--initializer-name", "x")
    assert rc == 0 and "--initializer-name has an effect only with --c-interface" in err


def test_option_c_interface_prototype_name_and_kernel_name_rules(tmp_path: Path) -> None:
    rc, err, out = gen(tmp_path, "--c-interface", "--kernel-name", "grav")
    assert rc == 0, err
    assert (tmp_path / "k.h").is_file()
    text = out.read_text()
    assert "class grav_ {" in text  # PIKG: the class is NAME_, the C entry point NAME
    assert "void grav(const EPI* epi, int ni, const EPJ* epj, int nj, FORCE* force)" in text
    rc, err, _ = gen(tmp_path, "--c-interface", "--kernel-name", "ns::grav")
    assert rc == 1 and "must be a plain C name" in err


def test_option_additional_text(tmp_path: Path) -> None:
    rc, err, out = gen(tmp_path, "--additional-text", "#include <array> // added")
    assert rc == 0, err
    text = out.read_text()
    assert text.index("#include <array> // added") < text.index("namespace pik_kernels")


def test_option_spj_multiwalk_unroll_strip_mining_max_subwalk_are_notes(tmp_path: Path) -> None:
    rc, err, out = gen(tmp_path, "--spj-name", "PS::SPJMonopole", "--multiwalk", "--unroll", "4",
                       "--strip-mining", "8", "--max-subwalk-size", "64")
    assert rc == 0, err
    for what in ("--spj-name PS::SPJMonopole", "--multiwalk", "--unroll 4", "--strip-mining 8",
                 "--max-subwalk-size 64"):
        assert f"pikg-gen: note: {what}" in err, (what, err)
    rc, err, _ = gen(tmp_path, "--max-subwalk-size", "32")
    assert rc == 2 and "at least 64" in err
    rc, err, _ = gen(tmp_path, "--unroll", "x")
    assert rc == 2 and "integer" in err


def test_option_version_and_help(capsys) -> None:
    rc, _out, err = run_cli(["--version"])
    assert rc == 0
    rc, out, _err = run_cli(["--help"])
    assert rc == 0
    for o in ("--class-file", "--c-interface", "--fortran-interface", "--initializer-name", "--spj-name",
              "--additional-text", "--multiwalk", "--unroll", "--strip-mining", "--max-subwalk-size"):
        assert o in out, o


def test_option_class_file_counts(tmp_path: Path) -> None:
    h = write(tmp_path / "a.hpp", "struct A { double x; };\n")
    rc, err, _ = gen(tmp_path, "--class-file", h, h)
    assert rc == 1 and "one file (EPI, EPJ and FORCE in it) or three" in err


@needs_reflect
def test_option_class_file_three_headers_and_repeated_header(tmp_path: Path) -> None:
    """EPI, EPJ and FORCE in three headers: --class-file A B C and --header A --header B --header C."""
    a = write(tmp_path / "epi.hpp", "#pragma once\nstruct V { float x, y, z; };\nstruct Epi { V pos; };\n")
    b = write(tmp_path / "epj.hpp", '#pragma once\n#include "epi.hpp"\nstruct Epj { V pos; float mass; };\n')
    c = write(tmp_path / "force.hpp", '#pragma once\n#include "epi.hpp"\nstruct Force { V acc; float pot; };\n')
    pik = write(tmp_path / "k.pikg", GRAVITY_PIK.replace("F64 eps2", "F32 eps2"))
    types = ["--epi-name", "Epi", "--epj-name", "Epj", "--force-name", "Force"]
    for how in (["--class-file", a, b, c], ["--header", a, "--header", b, "--header", c]):
        out = tmp_path / "k.hpp"
        rc, err = pikg("-i", pik, "-o", out, "--target", "reference", *types, *how)
        assert rc == 0, err
        text = out.read_text()
        assert "static_assert(offsetof(Epj, mass) == 12," in text
        assert "generated from epi.hpp, epj.hpp, force.hpp" in text


@needs_reflect
def test_header_not_self_contained_reads_with_stand_ins_or_prelude(tmp_path: Path) -> None:
    """FDPS's user_defined.hpp uses PS:: without including particle_simulator.hpp."""
    h = write(tmp_path / "user_defined.hpp", RING_HPP)
    pik = write(tmp_path / "k.pikg", RING_PIK)
    types = ["--epi-name", "Epi0", "--epj-name", "Epj0", "--force-name", "Force0"]
    rc, err = pikg("-i", pik, "-o", tmp_path / "k.hpp", "--target", "reference", *types, "--class-file", h)
    assert rc == 0, err
    ps = write(tmp_path / "ps.hpp", RING_PS)
    rc, err = pikg("-i", pik, "-o", tmp_path / "k2.hpp", "--target", "reference", *types, "--class-file", h,
                   "--prelude", ps)
    assert rc == 0, err
    assert "static_assert(offsetof(Epi0, r_coll) == 16," in (tmp_path / "k2.hpp").read_text()


@needs_reflect
def test_template_id_particle_type(tmp_path: Path) -> None:
    h = write(tmp_path / "b.hpp", "#pragma once\ntemplate <class T> struct V { T x, y, z; };\n"
              "template <class T> struct Body { V<T> pos; T mass; };\nstruct F { V<double> acc; double pot; };\n")
    pik = write(tmp_path / "k.pikg", GRAVITY_PIK)
    out = tmp_path / "k.hpp"
    rc, err = pikg("-i", pik, "-o", out, "--target", "reference", "--epi", "Body<double>", "--epj", "Body<double>",
                   "--force", "F", "--header", h)
    assert rc == 0, err
    assert "static_assert(sizeof(Body<double>) == 32," in out.read_text()
    rc, err = pikg("-i", pik, "-o", out, "--epi", "Body<double", "--header", h)
    assert rc == 1 and "unbalanced '<'" in err
    rc, err = pikg("-i", pik, "-o", out, "--epi", "Body; int x", "--header", h)
    assert rc == 1 and "is not a C++ name" in err


# ----------------------------------------------------------------------------- names, nesting, cascades

def check_error(tmp: Path, text: str) -> str:
    pik = write(tmp / "e.pik", text)
    rc, err = pikg(pik, "-o", tmp / "e.hpp", "--target", "reference")
    assert rc == 1, err
    assert "internal error" not in err and "Traceback" not in err, err
    return err


def test_cxx_keyword_parameter_is_a_located_error(tmp_path: Path) -> None:
    err = check_error(tmp_path, "EPI F64 x:x\nFORCE F64 f:f\nF64 class\nf += x * class\n")
    assert "e.pik:3:5: error: the parameter name 'class' is a C++ keyword" in err, err
    assert err.count("error:") == 1


def test_cxx_keyword_member_and_reserved_names_are_located_errors(tmp_path: Path) -> None:
    err = check_error(tmp_path, "EPI F64 x:new\nFORCE F64 f:f\nf += x\n")
    assert "e.pik:1:11: error: the member name 'new' is a C++ keyword" in err, err
    err = check_error(tmp_path, "EPI F64 x:x\nFORCE F64 f:f\n__t = x\nf += __t\n")
    assert "e.pik:3:1: error: '__t' is a reserved identifier in C++" in err, err


@needs_gxx
def test_cxx_keyword_as_local_name_is_mangled_and_compiles(tmp_path: Path) -> None:
    pik = write(tmp_path / "k.pik", "EPI F64 x:x\nFORCE F64 f:f\nnew = x * 2.0\nclass = new + 1.0\nf += class\n")
    out = tmp_path / "k.hpp"
    rc, err = pikg(pik, "-o", out, "--target", "reference", "--epi", "P", "--epj", "P", "--force", "P")
    assert rc == 0, err
    driver = write(tmp_path / "d.cpp", "struct P { double x, f; };\n#include \"k.hpp\"\n"
                   "int main() { P p[2] = {{1, 0}, {2, 0}}; k kern; kern(p, 2, p, 2, p);\n"
                   "  return p[0].f == 2 * 3.0 && p[1].f == 2 * 5.0 ? 0 : 1; }\n")
    compile_and_run(tmp_path, [driver])


def test_deep_nesting_is_a_located_error(tmp_path: Path) -> None:
    err = check_error(tmp_path, "EPI F64 x:x\nFORCE F64 f:f\nf += " + "(" * 500 + "x" + ")" * 500 + "\n")
    assert "e.pik:3:" in err and "nested more than 64 levels" in err, err[:400]
    err = check_error(tmp_path, "EPI F64 x:x\nFORCE F64 f:f\nf += " + "-" * 400 + "x\n")
    assert "nested unary operators" in err, err[:400]
    err = check_error(tmp_path, "EPI F64 x:x\nFORCE F64 f:f\nf += x" + " + x" * 3000 + "\n")
    assert "more than 256 operations deep" in err, err[:400]
    err = check_error(tmp_path, "EPI F64 x:x\nFORCE F64 f:f\n" + "if x > 0\n" * 100 + "f += x\n" + "endif\n" * 100)
    assert "e.pik:67:1: error: 'if'/'elsif' nested more than 64 levels deep" in err, err[:400]


def test_nesting_within_limits_compiles(tmp_path: Path) -> None:
    pik = write(tmp_path / "k.pik", "EPI F64 x:x\nFORCE F64 f:f\nf += " + "(" * 60 + "x" + ")" * 60
                + " + x" * 200 + "\n")
    rc, err = pikg(pik, "-o", tmp_path / "k.hpp", "--target", "auto")
    assert rc == 0, err


def test_one_error_per_mistake_no_cascade(tmp_path: Path) -> None:
    err = check_error(tmp_path, "EPI F64 x:x\nFORCE F64 f:f\na = x + foo\nb = a * 2.0\n"
                      "if b > 0.0\n  c = b + a\nendif\nf += c + b\n")
    assert err.count("error:") == 1, err
    assert "e.pik:3:9: error: unknown name 'foo'" in err
    # a failing statement inside an if: its names are not reported again either
    err = check_error(tmp_path, "EPI F64 x:x\nFORCE F64 f:f\nif x > 0.0\n  a = x * bar\nendif\nf += a\n")
    assert err.count("error:") == 1, err
    # two independent mistakes are still two errors
    err = check_error(tmp_path, "EPI F64 x:x\nFORCE F64 f:f\na = x + foo\nb = x + baz\nf += a + b\n")
    assert err.count("error:") == 2, err


# ----------------------------------------------------------------------------- what PIKG's samples rely on

@needs_gxx
def test_pikg_defaults_and_kernel_selector(tmp_path: Path, monkeypatch) -> None:
    """With PIKG's -i: class Kernel, output kernel.hpp, and operator() also takes PIKG's
    kernel selector (PIKG's test/nested_if calls kernel(ep, n, ep, n, f, k))."""
    monkeypatch.chdir(tmp_path)
    write(tmp_path / "k.pikg", SIMPLE)
    rc, err = pikg("-i", "k.pikg", "--epi-name", "Epi", "--epj-name", "Epj", "--force-name", "Force")
    assert rc == 0, err
    write(tmp_path / "user_defined.hpp", FDPS_NBODY_HPP)
    driver = write(tmp_path / "d.cpp", '#include "user_defined.hpp"\n#include "kernel.hpp"\n'
                   "int main() { Epi i{{0, 0, 0}}; Epj j{{1, 0, 0}, 2}; Force f{{0, 0, 0}, 0};\n"
                   "  const Kernel k(0.0f); k(&i, 1, &j, 1, &f, 2);\n"
                   "  return f.acc.x == 2.0f && f.pot == -2.0f ? 0 : 1; }\n")
    compile_and_run(tmp_path, [driver])


@needs_gxx
def test_component_assignment_defines_a_vector(tmp_path: Path) -> None:
    """PIKG: `v.x = 0.0f` on a new name defines an F32vec (FDPS planetary_ring's kernel_ep)."""
    pik = write(tmp_path / "k.pik", "EPI F32vec xi:pos\nFORCE F32vec a:acc\n"
                "t.x = 1.0f\nt.z = xi.y\na += t\n")
    out = tmp_path / "k.hpp"
    rc, err = pikg(pik, "-o", out, "--target", "reference", "--epi", "P", "--epj", "P", "--force", "P")
    assert rc == 0, err
    driver = write(tmp_path / "d.cpp", "struct V { float x, y, z; };\nstruct P { V pos, acc; };\n#include \"k.hpp\"\n"
                   "int main() { P p[2] = {{{0, 3, 0}, {0, 0, 0}}, {{0, 5, 0}, {0, 0, 0}}}; k kern; kern(p, 2, p, 2, p);\n"
                   "  return p[0].acc.x == 2 && p[0].acc.y == 0 && p[0].acc.z == 6 && p[1].acc.z == 10 ? 0 : 1; }\n")
    compile_and_run(tmp_path, [driver])
    err = check_error(tmp_path, "EPI F64 x:x\nFORCE F64 f:f\nq.x = x * nope\nq.y = 1.0\nf += q.x + q.y\n")
    assert err.count("error:") == 1, err  # the failed definition of q is reported once


@needs_reflect
def test_class_file_that_includes_the_output_or_the_main_program(tmp_path: Path) -> None:
    """PIKG's LennardJones sample names main.cpp (which includes kernel.hpp) as the class
    file; FDPS's planetary_ring header includes the kernels and uses types of the main
    program after its structs. Both are read as PIKG reads them: for the structs."""
    main = write(tmp_path / "main.cpp", "#include <cmath>\nstruct Atom { double rx, ry, rz; };\n"
                 "struct LJForce { double fx, fy, fz, p; };\n#include \"kernel.hpp\"\n"
                 "int main() { Atom a[1]{}; LJForce f[1]{}; Kernel k(4.0, 2.5); k(a, 1, a, 1, f); }\n")
    pik = write(tmp_path / "kernel.pikg", LJ_PIK)
    out = tmp_path / "kernel.hpp"
    rc, err = pikg("-i", pik, "-o", out, "--epi-name", "Atom", "--epj-name", "Atom", "--force-name", "LJForce",
                   "--class-file", main, "--target", "reference")
    assert rc == 0, err
    assert "static_assert(offsetof(LJForce, p) == 24," in out.read_text()
    hdr = write(tmp_path / "user_defined_kernel.hpp", RING_HPP + '#include "kernel_other.hpp"\n'
                "template <class T> struct Uses { void f() { T::eps = FP_t::eps; } };\n")
    rc, err = pikg("-i", write(tmp_path / "ring.pikg", RING_PIK), "-o", tmp_path / "ring.hpp", "--epi-name", "Epi0",
                   "--epj-name", "Epj0", "--force-name", "Force0", "--class-file", hdr, "--target", "reference")
    assert rc == 0, err
    assert "note: read the class file as PIKG does" in err and "user_defined_kernel.hpp:5 ('kernel_other.hpp'" in err, err
    assert "user_defined_kernel.hpp:6 (use of undeclared identifier 'FP_t')" in err, err


@needs_reflect
def test_class_file_including_fdps_and_pikg_headers_without_their_paths(tmp_path: Path) -> None:
    """PIKG's sc25 benchmark header includes <particle_simulator.hpp>, PIKG's samples
    <pikg_vector.hpp>, and the Makefiles give pikg no -I: stand-ins of the same layout."""
    h = write(tmp_path / "user-defined.hpp", "#pragma once\n#include <particle_simulator.hpp>\n#include <pikg_vector.hpp>\n"
              "class EPIGrav { public: PS::F64vec pos; PS::F64 eps; void clear() { pos = 0.0; } };\n"
              "class EPJGrav { public: PIKG::F64vec pos; PS::F64 mass; PS::S64 id; };\n"
              "class ForceGrav { public: PS::F64vec acc; PS::F64 pot; template <class T> void f(T& t) { t.copyFromForce(*this); } };\n")
    pik = write(tmp_path / "k.pikg", GRAVITY_PIK)
    out = tmp_path / "k.hpp"
    rc, err = pikg("-i", pik, "-o", out, "--epi-name", "EPIGrav", "--epj-name", "EPJGrav", "--force-name", "ForceGrav",
                   "--class-file", h, "--conversion-type", "AVX2")
    assert rc == 0, err
    text = out.read_text()
    assert "static_assert(offsetof(EPJGrav, mass) == 24," in text and "static_assert(sizeof(ForceGrav) == 32," in text
