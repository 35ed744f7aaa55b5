"""Lexer and parser tables: source text in, tokens or tree shape out."""
from __future__ import annotations

import pytest

import conftest  # noqa: F401  (puts compiler/ on sys.path)
from pik_gen.frontend import ast, parse, tokenize
from pik_gen.sema import check, literal_value
from pik_gen.types import Scalar

LEX = [
    # numbers in every form LANGUAGE.md lists; PIKG 0.4 rejected several of them
    ("1 1l 1u 1ul", ["int:1", "int:1l", "int:1u", "int:1ul"]),
    ("1.5 1.5f 1.5h 1e-3 2.5e+4f .5 .5f 1.", ["float:1.5", "float:1.5f", "float:1.5h", "float:1e-3", "float:2.5e+4f", "float:.5", "float:.5f", "float:1."]),
    # member access chains and component access
    ("FORCE.acc.x", ["keyword:FORCE", "op:.", "ident:acc", "op:.", "ident:x"]),
    # ^ without spaces, compound assignment, comparison operators
    ("a^b+=c<=d", ["ident:a", "op:^", "ident:b", "op:+=", "ident:c", "op:<=", "ident:d"]),
    # comments anywhere, pragmas as tokens
    ("a // comment\n/* b */ c", ["ident:a", "newline:\n", "ident:c"]),
    ("#pragma unroll 4", ["pragma:#pragma unroll 4"]),
]


@pytest.mark.parametrize("src,expected", LEX, ids=[s for s, _ in LEX])
def test_lexer(src: str, expected: list[str]) -> None:
    toks = [f"{t.kind}:{t.text}" for t in tokenize(src, "t") if t.kind != "eof"]
    assert toks[:-1] == expected  # the lexer always ends with a newline


LITERALS = [
    ("1", 1, Scalar.S32), ("1l", 1, Scalar.S64), ("1u", 1, Scalar.U32), ("1ul", 1, Scalar.U64),
    ("1.5", 1.5, Scalar.F64), ("1.5f", 1.5, Scalar.F32), ("1.5h", 1.5, Scalar.F16), ("1e-3", 1e-3, Scalar.F64),
    ("2.5e+4f", 2.5e4, Scalar.F32), (".5", 0.5, Scalar.F64),
]


@pytest.mark.parametrize("text,value,scalar", LITERALS, ids=[t for t, _v, _s in LITERALS])
def test_literal_types(text: str, value, scalar: Scalar) -> None:
    v, t = literal_value(ast.Number(text, any(c in text for c in ".eEfh"), None))  # type: ignore[arg-type]
    assert v == value and t.scalar == scalar


def shape(e) -> str:
    """A compact prefix form of an expression tree."""
    match e:
        case ast.Binary(): return f"({e.op} {shape(e.left)} {shape(e.right)})"
        case ast.Unary(): return f"({e.op} {shape(e.operand)})"
        case ast.Call(): return f"{e.func}(" + " ".join(shape(a) for a in e.args) + ")"
        case ast.Component(): return f"{shape(e.base)}.{e.comp}"
        case ast.RoleMember(): return f"{e.role}.{e.member}"
        case ast.Name(): return e.name
        case ast.Number(): return e.text
    raise AssertionError(e)


PRECEDENCE = [
    # precedence: || < && < comparison < + - < * / < ^ < unary < postfix
    ("a + b * c", "(+ a (* b c))"),
    ("a * b ^ c", "(* a (^ b c))"),
    ("-a * b", "(* (- a) b)"),
    ("a < b && c > d || e", "(|| (&& (< a b) (> c d)) e)"),
    ("(a + b) * c", "(* (+ a b) c)"),
    ("EPI.pos.x - EPJ.pos.x", "(- EPI.pos.x EPJ.pos.x)"),
    ("madd(a, b, c)", "madd(a b c)"),
    ("table(tab,k)", "table(tab k)"),
    ("a - b - c", "(- (- a b) c)"),
]


@pytest.mark.parametrize("src,expected", PRECEDENCE, ids=[s for s, _ in PRECEDENCE])
def test_expression_precedence(src: str, expected: str) -> None:
    m = parse(f"x = {src}\n", "t")
    assert shape(m.body[0].value) == expected


def test_declarations_functions_and_nested_if() -> None:
    src = """
EPI F64vec xi:pos   // binding
EPJ local F32 h
F64 eps2
t = { 1.0, -2.0,
      3.0 }
function f(a, b)
  c = a * b
  return c + 1.0
end
if a < 1.0
  if b < 2.0
    x = 1.0
  end
elsif a < 2.0
  x = 2.0
else
  x = 3.0
endif
"""
    m = parse(src, "t")
    kinds = [type(d).__name__ for d in m.decls]
    assert kinds == ["MemberDecl", "MemberDecl", "ParamDecl", "TableDecl"]
    assert m.decls[0].member == "pos" and m.decls[1].local
    assert [v.text for v in m.decls[3].values] == ["1.0", "-2.0", "3.0"]
    assert m.functions[0].params == ("a", "b") and len(m.functions[0].body) == 1
    top = m.body[0]
    assert isinstance(top, ast.If) and isinstance(top.body[0], ast.If)
    elsif = top.orelse[0]
    assert isinstance(elsif, ast.If) and len(elsif.orelse) == 1


def test_literal_typing_from_context() -> None:
    # F32 * 2.0 is F32 (PIKG 0.4 reported a type error here).
    ck = check(parse("EPI F32 x:x\nFORCE F32 p:p\np += x * 2.0 + max(0.0, x)\n", "t"))
    acc = ck.body[0]
    assert str(acc.value.type) == "F32"


def test_name_resolution_order() -> None:
    # Unprefixed names on the right: EPI before EPJ before FORCE.
    ck = check(parse("EPI F64 m:m\nEPJ F64 m:m\nFORCE F64 m2:m\nm2 += m\n", "t"))
    assert ck.body[0].value.role == "EPI" and ck.body[0].member == "m"
