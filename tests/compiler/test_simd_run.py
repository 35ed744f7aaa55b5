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
