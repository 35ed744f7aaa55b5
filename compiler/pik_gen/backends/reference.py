"""The reference backend: portable scalar C++, the semantic definition of every op.

Every other ISA inherits this table and overrides entries (see base.py).
"""
from __future__ import annotations

from pik_gen.backends.base import Isa
from pik_gen.types import Scalar

_F16 = Scalar.F16


def _f16(fn: str) -> str:
    return f"static_cast<_Float16>({fn.format('static_cast<float>({0})', 'static_cast<float>({1})')})"


class Reference(Isa):
    name = "reference"
    isa_label = "reference"
    in_auto = True
    preference = 0
    cpu_check = "true"
    lanes = {s: 1 for s in Scalar}
    OPS = {
        "neg": "-{0}", "not": "!{0}",
        "add": "{0} + {1}", "sub": "{0} - {1}", "mul": "{0} * {1}", "div": "{0} / {1}",
        "eq": "{0} == {1}", "ne": "{0} != {1}", "lt": "{0} < {1}", "gt": "{0} > {1}",
        "le": "{0} <= {1}", "ge": "{0} >= {1}",
        "and": "{0} && {1}", "or": "{0} || {1}",
        "select": "{0} ? {1} : {2}",
        "sqrt": "std::sqrt({0})", "rsqrt": "{one} / std::sqrt({0})",
        "rsqrt2": "static_cast<{T}>(2) / std::sqrt({0})", "inv": "{one} / {0}",
        "exp": "std::exp({0})", "log": "std::log({0})", "floor": "std::floor({0})",
        "abs": "std::abs({0})", "min": "std::min({0}, {1})", "max": "std::max({0}, {1})",
        "pow": "std::pow({0}, {1})",
        # The reference leaves fusing to the C++ compiler (both are within a few ulp).
        "madd": "{0} * {1} + {2}", "msub": "{0} * {1} - {2}",
        "nmadd": "{2} - {0} * {1}", "nmsub": "-({0} * {1}) - {2}",
        "cast": "static_cast<{T}>({0})",
        "table": "{table}[{0}]",
        ("abs", Scalar.U32): "{0}", ("abs", Scalar.U64): "{0}",
        ("sqrt", _F16): _f16("std::sqrt({0})"), ("rsqrt", _F16): _f16("1.0f / std::sqrt({0})"),
        ("rsqrt2", _F16): _f16("2.0f / std::sqrt({0})"),
        ("exp", _F16): _f16("std::exp({0})"), ("log", _F16): _f16("std::log({0})"),
        ("floor", _F16): _f16("std::floor({0})"), ("abs", _F16): _f16("std::abs({0})"),
        ("pow", _F16): _f16("std::pow({0}, {1})"),
    }
