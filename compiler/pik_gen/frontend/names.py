"""Which .pik names cannot become C++ names, and the nesting limits of the parser.

A `.pik` local variable becomes a suffixed C++ local (`new` -> `new_2_x`), so a C++
keyword is a fine local name. Parameter names reach the generated C++ as written
(constructor arguments, members `name_`), and member names are the user's struct's:
there a C++ keyword is a located error. Reserved identifiers (containing `__`, or
`_` followed by an upper-case letter: C++ [lex.name]) are refused everywhere, as
every suffixed form of them is reserved too.
"""
from __future__ import annotations

import re

CXX_KEYWORDS = frozenset("""
alignas alignof and and_eq asm auto bitand bitor bool break case catch char char8_t char16_t char32_t
class compl concept const consteval constexpr constinit const_cast continue co_await co_return co_yield
decltype default delete do double dynamic_cast else enum explicit export extern false float for friend
goto if inline int long mutable namespace new noexcept not not_eq nullptr operator or or_eq private
protected public register reinterpret_cast requires return short signed sizeof static static_assert
static_cast struct switch template this thread_local throw true try typedef typeid typename union
unsigned using virtual void volatile wchar_t while xor xor_eq
""".split())
_RESERVED = re.compile(r"__|^_[A-Z]")

# Expressions nested deeper than this (parentheses, calls, unary operators, operator
# chains) and `if`/`elsif` nested deeper than MAX_IF_DEPTH are located errors, not a
# RecursionError in the compiler.
MAX_EXPR_DEPTH = 64
MAX_TREE_DEPTH = 256
MAX_IF_DEPTH = 64


def reserved_problem(name: str) -> str:
    if _RESERVED.search(name):
        return (f"'{name}' is a reserved identifier in C++ (it contains '__' or starts with '_' and an "
                "upper-case letter); choose another name")
    return ""


def cxx_name_problem(name: str, what: str) -> str:
    """Why `name` cannot be a parameter or member name in the generated C++, or ""."""
    if name in CXX_KEYWORDS:
        return f"the {what} '{name}' is a C++ keyword and would not compile in the generated code; choose another name"
    return reserved_problem(name)
