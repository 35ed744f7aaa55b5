"""One .pik file per diagnostic in errors/: its first line says where the error is
and what it says (`// expect LINE:COL: message`). Each must end in exactly that
located message, the source line, a caret, exit status 1 and no traceback."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from conftest import run_cli

ERRORS = sorted((Path(__file__).parent / "errors").glob("*.pik"))
EXPECT = re.compile(rb"^// expect (\d+):(\d+): (.*)$")


@pytest.mark.parametrize("path", ERRORS, ids=[p.stem for p in ERRORS])
def test_error_file(path: Path, tmp_path: Path) -> None:
    first = path.read_bytes().splitlines()[0]
    m = EXPECT.match(first)
    assert m, f"{path.name}: first line must be '// expect LINE:COL: message'"
    line, col, message = int(m.group(1)), int(m.group(2)), m.group(3).decode()
    out = tmp_path / "out.hpp"
    rc, _stdout, err = run_cli([path, "-o", out, "--target", "reference"])
    assert rc == 1, err
    assert not out.exists(), "no output may be written on error"
    assert "Traceback" not in err and "internal error" not in err
    head = err.splitlines()[0]
    assert head.startswith(f"{path}:{line}:{col}: error: "), head
    assert message in head, head
    if "UTF-8" not in message:
        assert re.search(r"^\s*\^~*$", err, re.M), f"no caret line in:\n{err}"


def test_every_diagnostic_has_a_file() -> None:
    # A guard against the suite silently shrinking.
    assert len(ERRORS) >= 35


CLI_ERRORS = [
    # (arguments, exit status, expected text)
    (["--target", "avx3"], 1, "unknown target 'avx3'"),
    (["--conversion-type", "SSE"], 1, "unknown --conversion-type 'SSE'"),
    (["--bogus"], 2, "unrecognized arguments: --bogus"),
    (["--name", "1Bad"], 1, "--name '1Bad' is not a C++ name"),
    (["--epi", "a b"], 1, "--epi 'a b' is not a C++ name"),
    (["--dump-ir-after", "nosuchpass"], 1, "unknown pass 'nosuchpass'"),
]


@pytest.mark.parametrize("args,status,text", CLI_ERRORS, ids=[" ".join(a[0]) for a in CLI_ERRORS])
def test_command_line_errors(args: list[str], status: int, text: str, tmp_path: Path) -> None:
    from conftest import KERNELS

    out = tmp_path / "o.hpp"
    rc, _o, err = run_cli([KERNELS[0], "-o", out] + args)
    assert rc == status, err
    assert text in err
    assert "Traceback" not in err
    assert not out.exists()


def test_missing_file(tmp_path: Path) -> None:
    rc, _o, err = run_cli([tmp_path / "none.pik", "-o", tmp_path / "o.hpp"])
    assert rc == 1 and "cannot read" in err


def test_several_errors_reported_at_once(tmp_path: Path) -> None:
    src = tmp_path / "two.pik"
    src.write_text("EPI F64 x:x\nFORCE F64 p:p\na = yy\nb = zz\np += x\n")
    rc, _o, err = run_cli([src, "-o", tmp_path / "o.hpp", "--target", "reference"])
    assert rc == 1
    assert f"{src}:3:5: error: unknown name 'yy'" in err and f"{src}:4:5: error: unknown name 'zz'" in err
