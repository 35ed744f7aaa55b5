"""`#pragma` lines: the ones pikg-gen honours, and a note naming every other one.

  #pragma unroll N          i-vectors per block (U, 1..8) of the SIMD i-parallel
                            loop (docs/simd.md), instead of the backend's rule;
                            no effect on `reference` (a note says so)
  #pragma header "file.hpp" the user's particle header (read by reflect.py)
  #pragma blend             every `if` computed on all lanes and blended: no vector
                            of pairs is skipped where its mask is empty (docs/simd.md,
                            "Skipped branches"; for particles in no spatial order,
                            where that branch would mispredict)

Anything else (e.g. PIKG-era or compiler-specific hints) is accepted and ignored,
with a note on stderr naming the file and line, never silently.
"""
from __future__ import annotations

import re
from typing import Iterator

from pik_gen.diagnostics import error
from pik_gen.frontend import ast

_UNROLL = re.compile(r"^#\s*pragma\s+unroll\b\s*(.*)$")
_HEADER = re.compile(r"^#\s*pragma\s+header\b")
_BLEND = re.compile(r"^#\s*pragma\s+blend\s*$")
MAX_UNROLL = 8


def _walk(stmts: tuple[ast.Stmt, ...]) -> Iterator[ast.Pragma]:
    for s in stmts:
        if isinstance(s, ast.Pragma):
            yield s
        elif isinstance(s, ast.If):
            yield from _walk(s.body)
            yield from _walk(s.orelse)


def all_pragmas(module: ast.Module) -> list[ast.Pragma]:
    out = list(_walk(module.body))
    for fn in module.functions:
        out += list(_walk(fn.body))
    return sorted(out, key=lambda p: (p.span.line, p.span.col))


def interpret(module: ast.Module, simd: bool, notes: list[str]) -> tuple[int | None, bool]:
    """The `#pragma unroll` factor (None: none given) and whether `#pragma blend` was
    given; notes for the ignored ones. `simd`: False when every target is the scalar
    reference."""
    unroll: int | None = None
    blend = False
    for p in all_pragmas(module):
        text = p.text.strip()
        where = f"{p.span.file}:{p.span.line}"
        if _HEADER.match(text):
            continue
        if _BLEND.match(text):
            blend = True
            if not simd:
                notes.append(f"{where}: '{text}' has no effect on the reference target (scalar loops)")
            continue
        m = _UNROLL.match(text)
        if m is None:
            notes.append(f"{where}: '{text}' ignored (pikg-gen honours '#pragma unroll N', "
                         "'#pragma blend' and '#pragma header \"file.hpp\"')")
            continue
        arg = m.group(1).strip()
        if not arg.isdigit() or not 1 <= int(arg) <= MAX_UNROLL:
            raise error(p.span, f"expected '#pragma unroll N' with N from 1 to {MAX_UNROLL}, got '{arg}'")
        if unroll is not None and unroll != int(arg):
            raise error(p.span, f"'#pragma unroll {arg}' contradicts an earlier '#pragma unroll {unroll}'")
        unroll = int(arg)
        if not simd:
            notes.append(f"{where}: '{text}' has no effect on the reference target (scalar loops)")
    return unroll, blend
