"""The ARM SVE backend: generated code shape, and every kernel cross-compiled
(aarch64-linux-gnu-g++ -march=armv8.2-a+sve, -Wall -Wextra -Werror) and run
under QEMU at vector lengths 128, 256 and 512 bits through `pikg-gen verify
--target sve`: one build per kernel, three runs, each compared per output with
a double-precision evaluation of the kernel for (ni, nj) in 0, 1, 2, 3, lanes
+-1, 300 and nj = 5000 (so both loop shapes, the predicated tails and several j
blocks run). Tolerances are verify's: F32 5e-5, F64 1e-12 (relative to each
output's largest magnitude). The reference backend meets the same tolerance
against the same evaluation in test_run_reference.py.

Skipped, with the reason, when the cross compiler or QEMU is missing
(`make deps` installs g++-aarch64-linux-gnu and qemu-user)."""
from __future__ import annotations

import contextlib
import io
import re
import shutil
from pathlib import Path

import pytest

from conftest import KERNELS, run_cli

HERE = Path(__file__).parent
# the kernel library, the PIKG-style kernel and the SIMD coverage kernels (mixed
# precision, tables, exp/log/pow, nested control flow, integer reductions)
CORPUS = KERNELS + sorted((HERE / "pik").glob("*.pik")) + sorted((HERE / "simd_kernels").glob("*.pik"))
VLS = ("VL128", "VL256", "VL512")

# What the corpus does not cover: F32 (32-bit lanes) vector exp with
# elsif masks, S32 min/max, masked product/max/min reductions; F64 inv refinement
# under masks and an S64 count.
EXTRA = {
    "branches_f32": """
EPI F32vec xi:pos
EPI F32 h:h
EPJ F32vec xj:pos
EPJ F32 m:mass
FORCE F32 a:a
FORCE F32 b:b
FORCE F32 c:c
FORCE F32 d:d
FORCE F32 e:e
F32 eps2
rij = xi - xj
r2 = rij * rij + eps2
r = sqrt(r2)
q = r * inv(h)
k = to_s32(floor(q * 4.0))
k = min(max(k, 1), 3)
if q < 0.5
  w = exp(-q) * 2.0
elsif q < 1.0
  w = sqrt(1.0 + q)
else
  w = q * to_f32(k)
endif
a += m * w
b = max(b, w * m)
c = min(c, q)
if r2 < 1.0
  d += abs(w - 0.5)
  e *= 1.0 + 0.01 * w
endif
""",
    "branches_f64": """
EPI F64vec xi:pos
EPJ F64vec xj:pos
EPJ F64 m:mass
FORCE F64 a:a
FORCE F64 b:b
FORCE S64 n:n
F64 eps2
rij = xi - xj
r2 = rij * rij + eps2
if r2 < 0.25
  w = inv(r2)
elsif r2 < 0.5
  w = sqrt(r2) * m
else
  w = abs(r2 - 0.7) + floor(r2)
endif
a += w * m
b = max(b, sqrt(r2))
if r2 < 0.3 && m > 0.8
  n += 1l
endif
""",
}

pytestmark = pytest.mark.skipif(
    any(shutil.which(t) is None for t in ("aarch64-linux-gnu-g++", "qemu-aarch64")),
    reason="SVE tests need aarch64-linux-gnu-g++ and qemu-aarch64 (make deps: g++-aarch64-linux-gnu, qemu-user)",
)


def run_verify(args: list[str]) -> tuple[int, str, str]:
    from pik_gen.verify import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main([str(a) for a in args])
    return rc, out.getvalue(), err.getvalue()


def rows_of(out: str, prefix: str) -> dict[tuple[str, str], float]:
    """{(variant, output): error} from verify's report."""
    return {(v, o): float(e) for v, o, e in re.findall(rf"^  ({prefix}\S*)\s+(\S+)\s+(\S+)", out, re.M)}


def check_report(source: Path, rc: int, out: str, err: str) -> None:
    """Every vector length ran and compared every output; each error is within
    verify's tolerance, or (an ill-conditioned output, e.g. a sum that cancels
    for one particle) within twice the reference backend's error on it."""
    assert "did not compile" not in err and "crashed" not in err, f"{source.name}\n{out}\n{err}"
    rows = rows_of(out, "sve@")
    assert rows, f"{source.name}\n{out}\n{err}"
    assert sorted({v for v, _o in rows}) == [f"sve@{vl}" for vl in VLS], out
    outputs = {o for _v, o in rows}
    assert len(rows) == len(outputs) * len(VLS), out
    m = re.search(r"tolerance (\S+) ", out)
    assert m, out
    tol = float(m.group(1))
    over = {key: e for key, e in rows.items() if not e <= tol}
    assert (rc == 0) == (not over), out
    if over:
        _rc, ref_out, ref_err = run_verify([source, "--target", "reference"])
        ref = {o: e for (_v, o), e in rows_of(ref_out, "reference").items()}
        assert ref, ref_out + ref_err
        for (v, o), e in over.items():
            assert e <= 2 * ref[o], f"{source.name} {v} {o}: error {e:.2e} > tolerance {tol:.0e} and > 2 x reference {ref[o]:.2e}\n{out}"


@pytest.mark.parametrize("path", CORPUS, ids=[p.stem for p in CORPUS])
def test_kernel_under_qemu(path: Path) -> None:
    check_report(path, *run_verify([path, "--target", "sve"]))


@pytest.mark.parametrize("name", sorted(EXTRA))
def test_extra_kernel_under_qemu(name: str, tmp_path: Path) -> None:
    src = tmp_path / f"{name}.pik"
    src.write_text(EXTRA[name])
    check_report(src, *run_verify([src, "--target", "sve"]))


def test_verification_catches_an_unrefined_rsqrt(monkeypatch: pytest.MonkeyPatch) -> None:
    """The checks can fail: the bare 8-bit estimate (no Newton step) must be rejected."""
    from pik_gen.backends.simd import Let
    from pik_gen.backends.sve import Sve
    from pik_gen.types import Type

    def estimate_only(self, st, opcode, x, s, out):
        est = "svrsqrte" if opcode == "rsqrt" else "svrecpe"
        return [Let(self.vtype(st, Type(s)), out, f"{est}({x})")]

    monkeypatch.setattr(Sve, "refine", estimate_only)
    rc, out, _err = run_verify([KERNELS[0].parent / "gravity.pik", "--target", "sve"])
    assert rc == 1 and "FAIL" in out, out


# ---------------------------------------------------------------- code shape
def generate(tmp_path: Path, source: str | Path, *extra: str) -> str:
    src = source if isinstance(source, Path) else tmp_path / "k.pik"
    if not isinstance(source, Path):
        src.write_text(source)
    out = tmp_path / "k.hpp"
    rc, _o, err = run_cli([src, "-o", out, "--target", "sve", "--name", "K", *extra])
    assert rc == 0, err
    return out.read_text()


def sve_unroll(source: str | Path) -> int:
    """U, the i-vectors per block the register-pressure model gives the kernel on SVE."""
    from pik_gen.backends import ISAS, Options
    from pik_gen.driver import lower

    text = source.read_text() if isinstance(source, Path) else source
    c = ISAS["sve"](Options(name="K"))
    st = c.begin(lower(text, "k.pik", "K"))
    return c.unroll(st, len(st.plan.accs))


def test_vector_length_agnostic(tmp_path: Path) -> None:
    text = generate(tmp_path, KERNELS[0].parent / "gravity.pik")
    assert "#include <arm_sve.h>" in text and "_mm" not in text
    assert "svcntw()" in text and "svwhilelt_b32(jj, jn)" in text and "svwhilelt_b32(ib, ni)" in text
    # no fixed lane count: buffers are sized for 2048 bits, loops step by the run-time kW
    assert "constexpr int kW" not in text and "constexpr int kMaxW = 64;" in text
    # full-precision rsqrt: estimate + two Newton steps per vector; masked FMA in the j-parallel loop
    U = sve_unroll(KERNELS[0].parent / "gravity.pik")  # the block's U copies, the tail and the j-parallel shape
    assert text.count("svrsqrte(") == U + 1 + 1 and text.count("svrsqrts(") == 2 * (U + 1 + 1)
    assert "svmls_m(jvalid," in text and "svaddv(pg," in text
    assert 'isa_name() { return "SVE"; }' in text


def test_f64_and_mixed_lanes(tmp_path: Path) -> None:
    f64 = generate(tmp_path, KERNELS[0].parent / "gravity_f64.pik")
    assert "svptrue_b64()" in f64 and "svcntd()" in f64 and "constexpr int kMaxW = 32;" in f64
    U = sve_unroll(KERNELS[0].parent / "gravity_f64.pik")
    assert f64.count("svrsqrts(") == 3 * (U + 1 + 1)  # three Newton steps for F64
    mixed = generate(tmp_path, HERE / "simd_kernels" / "mixed.pik")
    # F32 values of a kernel on 64-bit lanes are unpacked: converted with svcvt, loaded with ld1w into .D
    assert "svptrue_b64()" in mixed and "svcvt_f32_f64_x(pg," in mixed and "svcvt_f64_f32_x(pg," in mixed
    assert "svrsqrte(" in mixed and mixed.count("svrsqrts(") % 2 == 0  # F32 rsqrt: two steps
    assert "svld1uw_u64(pg," in mixed and "svst1w(" in mixed


def test_fast_math_drops_one_step(tmp_path: Path) -> None:
    text = generate(tmp_path, KERNELS[0].parent / "gravity.pik", "--fast-math")
    assert text.count("svrsqrts(") == 1 * (sve_unroll(KERNELS[0].parent / "gravity.pik") + 1 + 1)


def test_fallbacks_and_masks(tmp_path: Path) -> None:
    text = generate(tmp_path, EXTRA["branches_f32"])
    assert "std::exp(" not in text and "svrintn_x(pg," in text  # vector exp (vmath.py)
    assert "svlsl_n_u32_x(pg," in text  # 2^n into the exponent field
    assert "for (int lane = 0; lane < kW; ++lane)" in generate(tmp_path, HERE / "simd_kernels/transcendental.pik")
    assert "svsel(" in text and "svsqrt_x(pg," in text and "svrintm_x(pg," in text
    assert "svmul_m(" in text and "svmax_x(pg," in text  # masked product; S32 max
    f64 = generate(tmp_path, EXTRA["branches_f64"])
    U = sve_unroll(EXTRA["branches_f64"])
    assert f64.count("svrecps(") == 3 * (U + 1 + 1) and "svand_z(pg," in f64


def test_auto_stays_x86(tmp_path: Path) -> None:
    out = tmp_path / "auto.hpp"
    rc, _o, err = run_cli([KERNELS[0].parent / "gravity.pik", "-o", out, "--target", "auto", "--name", "K"])
    assert rc == 0, err
    assert "arm_sve.h" not in out.read_text() and "SVE" not in out.read_text()


def test_user_names_never_clash_with_the_skeleton(tmp_path: Path) -> None:
    text = generate(tmp_path, """
EPI F32 x:x
EPJ F32 y:y
FORCE F32 f:f
pg = x - y
kMaxW = pg * pg
ivalid = kMaxW + 1.0
f += ivalid
""")
    assert "const svbool_t pg = " in text
    assert not re.search(r"svfloat32_t (pg|kMaxW|ivalid)\b", text)
