"""Fuzz-style robustness: thousands of mutated kernels (token deletions, swaps,
duplications, random bytes, dropped lines) must each end in success or in
located diagnostics, never in a Python exception; a sample of the mutants that
compile must also produce C++ that g++ accepts."""
from __future__ import annotations

import random
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from conftest import KERNELS, ROOT
from pik_gen.backends import Options
from pik_gen.diagnostics import CompileError
from pik_gen.driver import frontend, generate

CORPUS = KERNELS + sorted((Path(__file__).parent / "pik").glob("*.pik"))
N_MUTANTS = 3000
LOCATED = re.compile(r"^\S+:\d+:\d+: error: .+")


def mutate(src: str, rng: random.Random) -> str:
    toks = re.findall(r"\s+|[A-Za-z_]\w*|\d*\.?\d+(?:[eE][+-]?\d+)?\w*|.", src, re.S)
    k = rng.randrange(6)
    i = rng.randrange(len(toks))
    if k == 0:
        del toks[i]
    elif k == 1 and i + 1 < len(toks):
        toks[i], toks[i + 1] = toks[i + 1], toks[i]
    elif k == 2:
        toks.insert(i, toks[rng.randrange(len(toks))])
    elif k == 3:
        toks.insert(i, chr(rng.choice([0, 7, 27, 35, 36, 64, 96, 127, 0xE9, 0x3B1, 0xFEFF]) if rng.random() < 0.5 else rng.randrange(32, 127)))
    elif k == 4:
        lines = "".join(toks).split("\n")
        del lines[rng.randrange(len(lines))]
        return "\n".join(lines)
    else:
        toks[i] = rng.choice(["if", "endif", "end", "else", "elsif", "function", "return", "EPI", "FORCE", "local",
                              "F32", "F64vec", "(", ")", "{", "}", "=", "+=", "max", "table", ".", ":", "1e", "0x1"])
    return "".join(toks)


def test_mutants_never_crash() -> None:
    rng = random.Random(2024)
    sources = [p.read_text() for p in CORPUS]
    ok, failed = 0, 0
    for n in range(N_MUTANTS):
        src = mutate(rng.choice(sources), rng)
        if rng.random() < 0.3:
            src = mutate(src, rng)
        try:
            generate(src, "m.pik", "reference", Options(f"M{n}"))
            ok += 1
        except CompileError as e:
            failed += 1
            assert e.diagnostics, src
            for d in e.diagnostics:
                text = d.render(src)
                assert LOCATED.match(text), f"unlocated diagnostic {text!r} for:\n{src}"
    # The corpus is small: both outcomes must be well represented.
    assert ok > N_MUTANTS // 20 and failed > N_MUTANTS // 4, (ok, failed)


@pytest.mark.skipif(shutil.which("g++") is None, reason="g++ is not installed")
def test_compiling_mutants_give_valid_cpp(tmp_path: Path) -> None:
    rng = random.Random(7)
    sources = [p.read_text() for p in CORPUS]
    parts = ["#include <pik/Vec.hpp>"]
    n_ok = 0
    for n in range(400):
        src = mutate(rng.choice(sources), rng)
        try:
            ck = frontend(src, "m.pik")
            names = {r: f"{r}_{n}" for r in ("EPI", "EPJ", "FORCE")}
            text = generate(src, "m.pik", "reference", Options(f"M{n}", names["EPI"], names["EPJ"], names["FORCE"]))
        except CompileError:
            continue
        for role, tname in names.items():
            fields = []
            for m in ck.members:
                if m.role == role:
                    base = "double" if m.type.scalar.is_float else "long long"
                    fields.append(f"{base if m.type.lanes == 1 else f'pik::Vec{m.type.lanes}<{base}>'} {m.name};")
            parts.append(f"struct {tname} {{ {' '.join(fields)} }};")
        parts.append(text.replace("#pragma once", ""))
        n_ok += 1
        if n_ok == 25:
            break
    assert n_ok >= 10
    (tmp_path / "all.cpp").write_text("\n".join(parts))
    cc = subprocess.run(["g++", "-std=c++20", "-fsyntax-only", "-Wall", "-Wextra", "-Werror",
                         f"-I{ROOT / 'runtime/include'}", str(tmp_path / "all.cpp")], capture_output=True, text=True)
    assert cc.returncode == 0, cc.stderr[:4000]
