"""Diagnostics as values: a source span, a message, and a renderer.

Every user mistake becomes a `Diagnostic`; the compiler raises `CompileError`
carrying one or more of them, and the command line prints them as
``file:line:col: error: message`` followed by the source line and a caret.
"""
from __future__ import annotations

import difflib
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Span:
    """A place in a source file: 1-based line and column, and a length."""

    file: str
    line: int
    col: int
    length: int = 1

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}"


NO_SPAN = Span("<pikg-gen>", 0, 0, 0)


@dataclass(frozen=True)
class Diagnostic:
    span: Span
    message: str
    severity: str = "error"
    notes: tuple[str, ...] = ()

    def render(self, source: str | None) -> str:
        head = f"{self.span}: {self.severity}: {self.message}"
        lines = [head]
        if source is not None and self.span.line > 0:
            src_lines = source.splitlines()
            if self.span.line <= len(src_lines):
                text = src_lines[self.span.line - 1].replace("\t", " ")
                lines.append("  " + text)
                width = max(1, min(self.span.length, len(text) - self.span.col + 1))
                lines.append("  " + " " * (self.span.col - 1) + "^" + "~" * (width - 1))
        lines.extend(f"note: {n}" for n in self.notes)
        return "\n".join(lines)


@dataclass
class CompileError(Exception):
    """Raised with the diagnostics of a failed compilation (never a user-visible traceback)."""

    diagnostics: list[Diagnostic] = field(default_factory=list)

    def __str__(self) -> str:
        return "\n".join(f"{d.span}: {d.severity}: {d.message}" for d in self.diagnostics)


def error(span: Span, message: str, *notes: str) -> CompileError:
    """Build a CompileError holding a single diagnostic (callers `raise` it)."""
    return CompileError([Diagnostic(span, message, "error", tuple(notes))])


def suggest(name: str, candidates: "list[str] | tuple[str, ...] | set[str]") -> str:
    """`; did you mean 'x'?` when a candidate is close to `name`, else ''."""
    close = difflib.get_close_matches(name, sorted(candidates), n=1, cutoff=0.6)
    return f"; did you mean '{close[0]}'?" if close else ""
