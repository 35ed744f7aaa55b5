"""End to end: pikg-gen + pikg-reflect on real headers.

EPI, EPJ and FORCE live in three files and three namespaces (e2e/include/): a
template with members in a base and a derived class, an FDPS-style vector with
a user copy constructor, nested namespaces. `e2e/gravity_reflect.pik` uses only
`EPI.member` forms and names its header with `#pragma header`. For every ISA
pikg-gen has (and `auto`), the kernel is generated, compiled with g++ -Werror
(the offset assertions included) and compared with a direct double-precision
evaluation; a struct changed after generation must fail to compile; mismatches
between a .pik and the struct are located errors.

Needs PIKG_REFLECT (path of the built tool); run by CTest as `reflect.e2e`.
"""
from __future__ import annotations

import contextlib
import io
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
E2E = HERE / "e2e"
sys.path.insert(0, str(ROOT / "compiler"))

from pik_gen.backends import ISAS, auto_isas  # noqa: E402
from pik_gen.cli import main  # noqa: E402

TYPES = ["--epi", "sim::EPI", "--epj", "nbr::Source", "--force", "out::grav::Result"]
INCLUDES = [f"-I{ROOT / 'runtime' / 'include'}", f"-I{E2E / 'include'}"]

pytestmark = [
    pytest.mark.skipif(not os.environ.get("PIKG_REFLECT"), reason="PIKG_REFLECT (the built pikg-reflect) not set"),
    pytest.mark.skipif(shutil.which("g++") is None, reason="g++ is not installed"),
]

DRIVER = r"""
#include "particles.hpp"
#include "kernel.hpp"

#include <cmath>
#include <cstdio>
#include <vector>

// Direct double-precision sum, written out by hand from the physics.
static void direct(const std::vector<sim::EPI>& epi, const std::vector<nbr::Source>& epj, double eps2,
                   std::vector<double>& ax, std::vector<double>& ay, std::vector<double>& az, std::vector<double>& pot) {
  for (std::size_t i = 0; i < epi.size(); ++i)
    for (const nbr::Source& j : epj) {
      const double dx = epi[i].pos.x - j.pos.x, dy = epi[i].pos.y - j.pos.y, dz = epi[i].pos.z - j.pos.z;
      const double r2 = dx * dx + dy * dy + dz * dz + eps2 + epi[i].eps_i;
      const double rinv = 1.0 / std::sqrt(r2), mr = j.mass * rinv, f = mr * rinv * rinv;
      ax[i] -= f * dx; ay[i] -= f * dy; az[i] -= f * dz; pot[i] -= mr;
    }
}

int main() {
  unsigned long long state = 12345;
  auto uniform = [&] { state = state * 6364136223846793005ULL + 1442695040888963407ULL;
                       return static_cast<double>(state >> 11) * 0x1.0p-53; };
  const int sizes[][2] = {{0, 5}, {5, 0}, {1, 1}, {7, 13}, {37, 300}};
  const double eps2 = 1e-2;
  int bad = 0;
  for (const auto& s : sizes) {
    std::vector<sim::EPI> epi(s[0]);
    std::vector<nbr::Source> epj(s[1]);
    for (auto& p : epi) { p.pos.x = uniform(); p.pos.y = uniform(); p.pos.z = uniform(); p.eps_i = 1e-3 * uniform(); p.id = 7; }
    for (auto& p : epj) { p.pos.x = uniform(); p.pos.y = uniform(); p.pos.z = uniform(); p.mass = 0.5 + uniform(); }
    std::vector<out::grav::Result> force(s[0]);
    for (auto& f : force) { f.acc.x = f.acc.y = f.acc.z = 0; f.pot = 0; }
    const e2e::Gravity kernel(eps2);
    kernel(epi.data(), s[0], epj.data(), s[1], force.data());
    std::vector<double> ax(s[0]), ay(s[0]), az(s[0]), pot(s[0]);
    direct(epi, epj, eps2, ax, ay, az, pot);
    double scale = 1e-300, err = 0;
    for (int i = 0; i < s[0]; ++i) scale = std::fmax(scale, std::fmax(std::fabs(pot[i]), std::fabs(ax[i])));
    for (int i = 0; i < s[0]; ++i) {
      err = std::fmax(err, std::fabs(force[i].acc.x - ax[i]) / scale);
      err = std::fmax(err, std::fabs(force[i].acc.y - ay[i]) / scale);
      err = std::fmax(err, std::fabs(force[i].acc.z - az[i]) / scale);
      err = std::fmax(err, std::fabs(force[i].pot - pot[i]) / scale);
    }
    std::printf("%s ni=%d nj=%d max relative error %.3g\n", kernel.isa_name(), s[0], s[1], err);
    // FORCE members are float: single-precision rounding of sums of a few hundred terms.
    if (!(err < 2e-5)) ++bad;
  }
  return bad == 0 ? 0 : 1;
}
"""


def pikg_gen(*args) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = main([str(a) for a in args])
    return rc, err.getvalue()


def cpu_flags() -> set[str]:
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return set()
    m = re.search(r"^flags\s*:\s*(.*)$", text, re.M)
    return set(m.group(1).split()) if m else set()


def missing_cpu_features(flags: list[str]) -> list[str]:
    """-m flags of an ISA that this CPU lacks (the binary could not run here)."""
    have = cpu_flags()
    need = [f[2:].replace("-", "_").replace(".", "_") for f in flags if f.startswith("-m") and not f.startswith("-march")]
    return [n for n in need if n not in have and n.replace("avx512", "avx512") not in have]


def compile_driver(tmp: Path, header: Path, extra: list[str], cxx: str = "g++") -> subprocess.CompletedProcess:
    (tmp / "driver.cpp").write_text(DRIVER)
    shutil.copy(header, tmp / "kernel.hpp")
    cmd = [cxx, "-std=c++20", "-O1", "-Wall", "-Wextra", "-Werror", *INCLUDES, f"-I{E2E}", f"-I{tmp}",
           *extra, str(tmp / "driver.cpp"), "-o", str(tmp / "driver")]
    return subprocess.run(cmd, capture_output=True, text=True)


TARGETS = list(ISAS) + (["auto"] if auto_isas() else [])


@pytest.mark.parametrize("target", TARGETS)
def test_generated_kernel_matches_direct_sum(tmp_path: Path, target: str) -> None:
    out = tmp_path / "gen.hpp"
    rc, err = pikg_gen(E2E / "gravity_reflect.pik", "-o", out, "--target", target, "--name", "e2e::Gravity",
                       *TYPES, *INCLUDES)
    assert rc == 0, err
    text = out.read_text()
    # One offset assertion per used member, one size assertion per type.
    for check in ("sizeof(sim::EPI) == 40", "offsetof(sim::EPI, pos) == 0", "offsetof(sim::EPI, eps_i) == 24",
                  "sizeof(nbr::Source) == 32", "offsetof(nbr::Source, mass) == 0", "offsetof(nbr::Source, pos) == 8",
                  "sizeof(out::grav::Result) == 16", "offsetof(out::grav::Result, acc) == 0",
                  "offsetof(out::grav::Result, pot) == 12"):
        assert f"static_assert({check}," in text, check
    assert text.count("static_assert(") == 9
    isas = [ISAS[target]] if target in ISAS else auto_isas()
    flags = [f for cls in isas for f in getattr(cls, "cxx_flags", ())] if target != "auto" else []
    cross = isas[0] if target in ISAS and isas[0].runners else None
    if cross is not None:
        # An ISA the host cannot execute (SVE): build with its compiler, run under its emulator.
        missing = [t for t in (cross.cxx, next(iter(cross.runners.values()))[0]) if shutil.which(t) is None]
        if missing:
            pytest.skip(f"target {target} needs {', '.join(missing)} (cross compiler / emulator) to run")
        runners = list(cross.runners.values())
    else:
        lacking = missing_cpu_features(flags)
        if lacking:
            pytest.skip(f"this CPU lacks {', '.join(lacking)} needed by target {target}")
        runners = [()]
    p = compile_driver(tmp_path, out, flags, cross.cxx if cross is not None else "g++")
    assert p.returncode == 0, p.stderr
    for runner in runners:
        run = subprocess.run([*runner, str(tmp_path / "driver")], capture_output=True, text=True, timeout=120)
        assert run.returncode == 0, f"{' '.join(runner)}: " + run.stdout + run.stderr


def test_struct_changed_after_generation_does_not_compile(tmp_path: Path) -> None:
    out = tmp_path / "gen.hpp"
    rc, err = pikg_gen(E2E / "gravity_reflect.pik", "-o", out, "--target", "reference", "--name", "e2e::Gravity",
                       *TYPES, *INCLUDES)
    assert rc == 0, err
    p = compile_driver(tmp_path, out, ["-DPIK_E2E_SHIFT_EPI"])
    assert p.returncode != 0
    assert "sim::EPI::eps_i moved since this kernel was generated" in p.stderr, p.stderr
    assert "sim::EPI changed size" in p.stderr, p.stderr


def write(tmp: Path, name: str, text: str) -> Path:
    p = tmp / name
    p.write_text(text)
    return p


def test_declaration_mismatch_is_a_located_error(tmp_path: Path) -> None:
    pik = write(tmp_path, "k.pik",
                f'#pragma header "{E2E / "particles.hpp"}"\n'
                "EPJ F32 mj:mass\n"        # float on a double member: allowed (mixed precision)
                "EPJ F64vec m3:mass\n"     # vector on a scalar: error at the type
                "FORCE.pot -= mj + to_f32(EPI.pos.x + EPJ.pos.x)\n")
    rc, err = pikg_gen(pik, "-o", tmp_path / "k.hpp", "--target", "reference", *TYPES, *INCLUDES)
    assert rc == 1
    assert f"{pik}:3:5: error: EPJ member 'mass' is declared F64vec here, but nbr::Source::mass is 'double' (F64)" in err, err
    assert "epj.hpp:19" in err, err  # where the member is declared
    assert err.count("error:") == 1, err


def test_unknown_and_unreadable_members_are_located_errors(tmp_path: Path) -> None:
    header = write(tmp_path, "p.hpp", "#include <array>\n"
                   "struct P { double mass; bool alive; std::array<double, 6> pos; };\n"
                   "struct F { double pot; };\n")
    for line, expect in (
        ("FORCE.pot += EPI.mas", "EPI type 'P' has no member 'mas'; did you mean 'mass'?"),
        ("FORCE.pot += to_f64(EPI.alive)", "EPI member 'alive' has C++ type 'bool', which a kernel cannot read"),
        ("FORCE.pot += EPJ.pos.x", "EPJ member 'pos' has C++ type 'std::array<double, 6>', which a kernel cannot read"),
        ("FORCE.potential += EPJ.mass", "FORCE type 'F' has no member 'potential'"),
    ):
        pik = write(tmp_path, "k.pik", line + "\n")
        rc, err = pikg_gen(pik, "-o", tmp_path / "k.hpp", "--target", "reference", "--header", header,
                           "--epi", "P", "--epj", "P", "--force", "F")
        assert rc == 1, line
        assert re.search(rf"{re.escape(str(pik))}:1:\d+: error: {re.escape(expect)}", err), err


def test_header_errors_reach_the_user(tmp_path: Path) -> None:
    header = write(tmp_path, "bad.hpp", "struct P {\n  double mass\n};\n")
    pik = write(tmp_path, "k.pik", "FORCE.pot += EPJ.mass\n")
    rc, err = pikg_gen(pik, "-o", tmp_path / "k.hpp", "--header", header, "--epi", "P", "--epj", "P", "--force", "P")
    assert rc == 1
    assert "pikg-reflect could not read the particle types" in err and f"{header}:2:14: error:" in err, err
    rc, err = pikg_gen(pik, "-o", tmp_path / "k.hpp", "--header", header, "--epi", "Q", "--epj", "P", "--force", "P")
    assert rc == 1 and "type 'Q' not found" in err, err


def test_without_pikg_reflect_declarations_keep_working(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PIKG_REFLECT", str(tmp_path / "no-such-tool"))
    declared = write(tmp_path, "d.pik", "EPJ F64 mj:mass\nFORCE F64 pot:pot\npot -= mj\n")
    rc, err = pikg_gen(declared, "-o", tmp_path / "d.hpp", "--header", E2E / "particles.hpp", *TYPES)
    assert rc == 0, err
    assert "pikg-gen: note: pikg-reflect is not available" in err, err
    assert "static_assert(" not in (tmp_path / "d.hpp").read_text()
    rc, err = pikg_gen(E2E / "gravity_reflect.pik", "-o", tmp_path / "g.hpp", *TYPES)
    assert rc == 1 and "pikg-reflect is not available" in err and "is unknown; declare it" in err, err


ARRAY_HEADER = """#include <array>
struct P { std::array<double, 3> pos; double mass; };
struct F { float acc[3]; double pot; };
"""
# std::array and C-array vectors (read as [0] [1] [2]) and plain names resolved through
# the header: `pos` and `mass` on the right are EPI's (EPI, then EPJ, then FORCE),
# `pot` on the left FORCE's; no declarations in the file.
ARRAY_PIK = """rij = pos - EPJ.pos
r2 = rij * rij + 0.01
rinv = rsqrt(r2)
FORCE.acc -= to_f32(EPJ.mass * rinv * rinv * rinv * rij)
pot -= mass * EPJ.mass * rinv
"""
ARRAY_DRIVER = r"""#include <cmath>
#include <cstdio>
#include "p.hpp"
%(includes)s
template <class K> int check(const char* isa) {
  P p[19];
  for (int i = 0; i < 19; ++i) p[i] = P{{0.1 * i, std::sin(1.0 * i), 0.3 * std::cos(2.0 * i)}, 1.0 + 0.1 * i};
  F f[19] = {};
  K{}(p, 19, p, 19, f);
  double err = 0;
  for (int i = 0; i < 19; ++i) {
    double a[3] = {0, 0, 0}, pot = 0;
    for (int j = 0; j < 19; ++j) {
      double d[3], r2 = 0.01;
      for (int c = 0; c < 3; ++c) { d[c] = p[i].pos[c] - p[j].pos[c]; r2 += d[c] * d[c]; }
      const double rinv = 1 / std::sqrt(r2);
      for (int c = 0; c < 3; ++c) a[c] -= p[j].mass * rinv * rinv * rinv * d[c];
      pot -= p[i].mass * p[j].mass * rinv;
    }
    for (int c = 0; c < 3; ++c) err = std::fmax(err, std::fabs(f[i].acc[c] - a[c]) / 100);
    err = std::fmax(err, std::fabs(f[i].pot - pot) / std::fabs(pot));
  }
  std::printf("%%s %%.3g\n", isa, err);
  return err < 1e-5 ? 0 : 1;
}
int main() { return %(checks)s; }
"""


def test_array_members_and_plain_names_through_the_header(tmp_path: Path) -> None:
    header = write(tmp_path, "p.hpp", ARRAY_HEADER)
    pik = write(tmp_path, "k.pik", ARRAY_PIK)
    flags = cpu_flags()
    isas = ["reference"] + [i for i, need in (("avx2", {"avx2", "fma"}), ("avx512", {"avx512f", "avx512dq", "avx512vl"}))
                            if need <= flags]
    for isa in isas:
        rc, err = pikg_gen(pik, "-o", tmp_path / f"K_{isa}.hpp", "--target", isa, "--name", f"K_{isa}",
                           "--header", header, "--epi", "P", "--epj", "P", "--force", "F")
        assert rc == 0, err
    code = (tmp_path / "K_reference.hpp").read_text()
    assert "epi[i].pos[0]" in code and "force[i].acc[2]" in code and "epi[i].mass" in code, code
    write(tmp_path, "main.cpp", ARRAY_DRIVER % {
        "includes": "\n".join(f'#include "K_{i}.hpp"' for i in isas),
        "checks": " + ".join(f'check<K_{i}>("{i}")' for i in isas)})
    p = subprocess.run(["g++", "-std=c++20", "-O1", "-Wall", "-Wextra", "-Werror", f"-I{tmp_path}",
                        str(tmp_path / "main.cpp"), "-o", str(tmp_path / "a.out")], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    run = subprocess.run([str(tmp_path / "a.out")], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0 and len(run.stdout.split("\n")) == len(isas) + 1, run.stdout
