"""Language features the SPH kernels need: `--const NAME=VALUE` binds a parameter at
compile time (one .pik file for every smoothing function and dimension)."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from conftest import ROOT, run_cli

DENSITY = ROOT / "kernels" / "sph_density.pik"

SRC = """EPI F32vec xi:pos
EPJ F32vec xj:pos
FORCE F32 s:s
S32 mode
F32 scale
F32vec off
r2 = (xi - xj) * (xi - xj)
if mode == 0
  v = r2
elsif mode == 1
  v = sqrt(r2)
else
  v = exp(r2)
endif
s += scale * v + off.x
"""


def _write(tmp_path: Path, text: str = SRC) -> Path:
    p = tmp_path / "k.pik"
    p.write_text(text)
    return p


@pytest.mark.parametrize("mode, kept, dropped", [
    ("0", None, ("sqrt", "exp")),   # first branch: neither sqrt nor exp survives
    ("1", "sqrt", ("exp",)),        # elsif branch
    ("2", "exp", ("sqrt",)),        # else branch
])
def test_bound_parameter_folds_branches(tmp_path: Path, mode: str, kept: str | None, dropped: tuple) -> None:
    rc, out, err = run_cli([_write(tmp_path), "--const", f"mode={mode}", "--dump-ir-after", "hoist"])
    assert rc == 0, err
    assert "param mode" not in out and "select" not in out
    if kept:
        assert f"= {kept} " in out
    for op in dropped:
        assert f"= {op} " not in out


def test_bound_parameter_leaves_the_constructor(tmp_path: Path) -> None:
    out = tmp_path / "k.hpp"
    rc, _o, err = run_cli([_write(tmp_path), "-o", out, "--target", "reference", "--name", "K",
                           "--const", "mode=1", "--const", "scale=2.5"])
    assert rc == 0, err
    text = out.read_text()
    assert re.search(r"explicit K\(float off_x|explicit K\(pik::Vec3<float> off|explicit K\([^)]*off", text)
    assert "mode" not in re.search(r"explicit K\(([^)]*)\)", text).group(1)
    assert "scale" not in re.search(r"explicit K\(([^)]*)\)", text).group(1)


def test_different_constants_give_different_implementation_names(tmp_path: Path) -> None:
    names = []
    for mode in ("0", "1"):
        out = tmp_path / f"k{mode}.hpp"
        rc, _o, err = run_cli([_write(tmp_path), "-o", out, "--target", "reference", "--name", "K",
                               "--const", f"mode={mode}"])
        assert rc == 0, err
        names.append(re.search(r"class (K_reference_[0-9a-f]{8})", out.read_text()).group(1))
    assert names[0] != names[1]  # both may be linked into one program


@pytest.mark.parametrize("arg, message", [
    ("nosuch=1", "the kernel has no parameter 'nosuch' (parameters: mode, scale, off)"),
    ("mode=1.5", "--const mode=1.5: the parameter has type S32, the value must be an integer"),
    ("mode=99999999999", "out of range of the parameter's type S32"),
    ("scale=abc", "--const scale=abc: the parameter has type F32, the value must be a finite number"),
    ("scale=inf", "the value must be a finite number"),
    ("off=1", "only scalar parameters can be bound (this one is F32vec)"),
    ("mode", "--const 'mode': expected NAME=VALUE"),
    ("=3", "expected NAME=VALUE"),
])
def test_bad_constants_are_clear_errors(tmp_path: Path, arg: str, message: str) -> None:
    rc, _o, err = run_cli([_write(tmp_path), "-o", tmp_path / "k.hpp", "--const", arg])
    assert rc == 1
    assert message in err and "Traceback" not in err


def test_twice_is_an_error(tmp_path: Path) -> None:
    rc, _o, err = run_cli([_write(tmp_path), "-o", tmp_path / "k.hpp", "--const", "mode=1", "--const", "mode=2"])
    assert rc == 1 and "--const mode given twice" in err


@pytest.mark.parametrize("shape", ["0", "1", "2"])
@pytest.mark.parametrize("dim", ["2", "3"])
def test_sph_density_specialises(shape: str, dim: str) -> None:
    # Every smoothing function x dimension folds to straight code with no parameter.
    rc, out, err = run_cli([DENSITY, "--const", f"shape={shape}", "--const", f"dim={dim}",
                            "--dump-ir-after", "hoist"])
    assert rc == 0, err
    assert "param " not in out
    # the cubic spline keeps one select (inner/outer part of its gradient); Wendland none
    assert out.count("select") == (1 if shape == "0" else 0)


# A name first assigned in the 'then' branch is not defined in the 'else' branch
# (found by the fuzz test on the SPH kernels: was an internal error).
@pytest.mark.parametrize("body, where", [
    ("if a < b\n  x = a\nelse\n  y = x\n  s += y\nendif\n", 7),                        # top level
    ("if a < b\n  x = a\nelse\n  x += 1.0f\nendif\ns += x\n", 7),                      # compound
    ("function f(v)\n  if v < 0.0f\n    t = v\n  else\n    w = t\n  endif\n  return v\nend\ns += f(a)\n", 8),
    ("function f(v)\n  if v < 0.0f\n    t = v\n  elsif v > 1.0f\n    t = 2.0f\n  else\n    t = t + 1.0f\n  endif\n"
     "  return t\nend\ns += f(a)\n", 10),
])
def test_then_branch_names_are_not_defined_in_else(tmp_path: Path, body: str, where: int) -> None:
    src = "EPI F32 a:a\nEPJ F32 b:b\nFORCE F32 s:s\n" + body
    rc, _o, err = run_cli([_write(tmp_path, src), "-o", tmp_path / "k.hpp"])
    assert rc == 1, err
    assert f"k.pik:{where}:" in err and "is assigned only in another branch of an 'if', not before it" in err


def test_names_assigned_in_every_branch_merge(tmp_path: Path) -> None:
    # the same name defined in each branch (as the smoothing functions do) is fine
    src = ("EPI F32 a:a\nEPJ F32 b:b\nFORCE F32 s:s\nfunction f(v)\n  if v < 0.0f\n    t = v\n  else\n"
           "    t = 2.0f * v\n  endif\n  return t\nend\nif a < b\n  x = a\nelse\n  x = b\nendif\ns += f(x)\n")
    rc, out, err = run_cli([_write(tmp_path, src), "--dump-ir-after", "hoist"])
    assert rc == 0, err
    assert out.count("select") == 2
