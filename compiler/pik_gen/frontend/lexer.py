"""Hand-written lexer of .pik files.

Tokens: identifiers, numbers (with C-like suffixes and PIKG's `h` for F16),
operators, NEWLINE (statements end at line ends), PRAGMA (a whole `#pragma`
line) and EOF. `//` and `/* */` comments may appear anywhere.
"""
from __future__ import annotations

from dataclasses import dataclass

from pik_gen.diagnostics import Span, error

KEYWORDS = frozenset(
    {"if", "elsif", "else", "endif", "end", "function", "return", "local", "EPI", "EPJ", "FORCE"}
)

# Longest first so that `+=` wins over `+`.
OPERATORS = (
    "+=", "-=", "*=", "/=", "==", "!=", "<=", ">=", "&&", "||",
    "+", "-", "*", "/", "^", "(", ")", ",", ".", "=", "<", ">", "!", ":", "{", "}", "[", "]",
)


@dataclass(frozen=True)
class Token:
    kind: str  # "ident", "keyword", "int", "float", "op", "newline", "pragma", "eof"
    text: str
    span: Span

    def __repr__(self) -> str:
        return f"{self.kind}:{self.text!r}"


def _is_ident_start(c: str) -> bool:
    return c.isascii() and (c.isalpha() or c == "_")


def _is_ident_char(c: str) -> bool:
    return c.isascii() and (c.isalnum() or c == "_")


def tokenize(source: str, file: str) -> list[Token]:
    toks: list[Token] = []
    i, line, col = 0, 1, 1
    n = len(source)

    def span(length: int) -> Span:
        return Span(file, line, col, max(1, length))

    while i < n:
        c = source[i]
        if c == "\n":
            toks.append(Token("newline", "\n", span(1)))
            i, line, col = i + 1, line + 1, 1
            continue
        if c in " \t\r\f\v":
            i, col = i + 1, col + 1
            continue
        if source.startswith("//", i):
            while i < n and source[i] != "\n":
                i += 1
            continue
        if source.startswith("/*", i):
            end = source.find("*/", i + 2)
            if end < 0:
                raise error(span(2), "unterminated comment '/*'")
            for ch in source[i:end + 2]:
                if ch == "\n":
                    line, col = line + 1, 1
                else:
                    col += 1
            i = end + 2
            continue
        if c == "#":
            j = source.find("\n", i)
            j = n if j < 0 else j
            text = source[i:j]
            if not text[1:].lstrip().startswith("pragma"):
                raise error(span(len(text)), "unknown directive (only '#pragma ...' is accepted)")
            toks.append(Token("pragma", text, span(len(text))))
            col += j - i
            i = j
            continue
        if c.isdigit() or (c == "." and i + 1 < n and source[i + 1].isdigit()):
            j = i
            is_float = False
            while j < n and source[j].isdigit():
                j += 1
            if j < n and source[j] == "." and not (j + 1 < n and _is_ident_start(source[j + 1]) and source[j + 1] not in "eE"):
                is_float = True
                j += 1
                while j < n and source[j].isdigit():
                    j += 1
            if j < n and source[j] in "eE":
                k = j + 1
                if k < n and source[k] in "+-":
                    k += 1
                if k < n and source[k].isdigit():
                    is_float = True
                    j = k
                    while j < n and source[j].isdigit():
                        j += 1
                else:
                    raise error(Span(file, line, col + (j - i), 1), "malformed exponent in number")
            k = j
            while k < n and _is_ident_char(source[k]):
                k += 1
            suffix = source[j:k].lower()
            ok = ("", "f", "h", "d") if is_float else ("", "l", "u", "ul", "lu", "ll", "ull", "f", "h", "d")
            if suffix not in ok:
                raise error(Span(file, line, col + (j - i), k - j), f"invalid suffix '{source[j:k]}' on number")
            if suffix in ("f", "h", "d"):
                is_float = True
            text = source[i:k]
            toks.append(Token("float" if is_float else "int", text, span(k - i)))
            col += k - i
            i = k
            continue
        if _is_ident_start(c):
            j = i
            while j < n and _is_ident_char(source[j]):
                j += 1
            text = source[i:j]
            toks.append(Token("keyword" if text in KEYWORDS else "ident", text, span(j - i)))
            col += j - i
            i = j
            continue
        for op in OPERATORS:
            if source.startswith(op, i):
                toks.append(Token("op", op, span(len(op))))
                i, col = i + len(op), col + len(op)
                break
        else:
            shown = c if c.isprintable() else f"\\x{ord(c):02x}" if ord(c) < 256 else f"U+{ord(c):04X}"
            raise error(span(1), f"unexpected character '{shown}'")
    toks.append(Token("newline", "\n", Span(file, line, col, 1)))
    toks.append(Token("eof", "", Span(file, line, col, 1)))
    return toks
