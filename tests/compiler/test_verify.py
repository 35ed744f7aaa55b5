"""`pikg-gen verify` itself: it must fail on a wrong variant, report per output,
reject bad arguments with a clear message, and report kernel errors located."""
from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from conftest import ROOT, run_cli

GRAVITY = ROOT / "kernels/gravity_f64.pik"
pytestmark = pytest.mark.skipif(shutil.which("g++") is None, reason="g++ is not installed")


def test_a_wrong_variant_fails(monkeypatch) -> None:
    """A reference backend whose subtraction is off by one ulp-scale term must be caught."""
    from pik_gen.backends import ISAS
    from pik_gen.backends.reference import Reference

    class Broken(Reference):
        name = "broken"
        OPS = {"sub": "({0} - {1}) * (1.0 + 1e-9)"}

    monkeypatch.setitem(ISAS, "broken", Broken)
    rc, out, err = run_cli(["verify", GRAVITY, "--target", "broken"])
    assert rc == 1, out + err
    assert "FAIL" in out and "FAILED" in out


def test_reports_every_output_component() -> None:
    rc, out, err = run_cli(["verify", GRAVITY, "--target", "reference", "--param", "eps2=0.5"])
    assert rc == 0, out + err
    outputs = [line.split()[1] for line in out.splitlines() if line.startswith("  reference")]
    assert outputs == ["acc.x", "acc.y", "acc.z", "pot"]
    assert "tolerance 1e-12 (F64)" in out


@pytest.mark.parametrize("args,message", [
    (["--param", "eps3=1"], "has no parameter 'eps3'"),
    (["--param", "eps2"], "is not NAME=VALUE"),
    (["--target", "mips"], "unknown target 'mips'"),
])
def test_bad_arguments(args: list[str], message: str) -> None:
    rc, out, err = run_cli(["verify", GRAVITY, *args])
    assert rc == 2 and message in err, out + err


def test_kernel_errors_are_located(tmp_path: Path) -> None:
    bad = tmp_path / "bad.pik"
    bad.write_text("EPI F64vec xi:pos\nFORCE F64 pot:pot\npot += rsqrt(xi * xj)\n")
    rc, out, err = run_cli(["verify", bad])
    assert rc == 1
    assert f"{bad}:3:" in err and "error:" in err and "Traceback" not in err
