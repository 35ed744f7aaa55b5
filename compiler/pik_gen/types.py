"""The types of the .pik language: a scalar kind and a component count (1..4)."""
from __future__ import annotations

import re
import struct
from dataclasses import dataclass
from enum import Enum


class Scalar(Enum):
    F64 = "F64"
    F32 = "F32"
    F16 = "F16"
    S64 = "S64"
    S32 = "S32"
    U64 = "U64"
    U32 = "U32"
    BOOL = "BOOL"

    @property
    def is_float(self) -> bool:
        return self in (Scalar.F64, Scalar.F32, Scalar.F16)

    @property
    def is_int(self) -> bool:
        return self in (Scalar.S64, Scalar.S32, Scalar.U64, Scalar.U32)

    @property
    def is_unsigned(self) -> bool:
        return self in (Scalar.U64, Scalar.U32)

    @property
    def bits(self) -> int:
        return {"F64": 64, "F32": 32, "F16": 16, "S64": 64, "S32": 32, "U64": 64, "U32": 32, "BOOL": 1}[
            self.value
        ]


COMPONENTS = ("x", "y", "z", "w")


@dataclass(frozen=True)
class Type:
    """`lanes` is the number of vector components (F64vec has 3); 1 means scalar."""

    scalar: Scalar
    lanes: int = 1

    @property
    def is_vec(self) -> bool:
        return self.lanes > 1

    @property
    def element(self) -> "Type":
        return Type(self.scalar, 1)

    def with_scalar(self, scalar: Scalar) -> "Type":
        return Type(scalar, self.lanes)

    def __str__(self) -> str:
        if self.lanes == 1:
            return self.scalar.value
        return f"{self.scalar.value}vec" + ("" if self.lanes == 3 else str(self.lanes))


BOOL = Type(Scalar.BOOL)
F64 = Type(Scalar.F64)
F32 = Type(Scalar.F32)
S32 = Type(Scalar.S32)

_TYPE_RE = re.compile(r"^(F64|F32|F16)vec([234]?)$|^(F64|F32|F16|S64|S32|U64|U32)$")


def parse_type_name(name: str) -> Type | None:
    """`F64vec` -> Type(F64, 3); `F32vec2` -> Type(F32, 2); `S32` -> Type(S32); else None."""
    m = _TYPE_RE.match(name)
    if not m:
        return None
    if m.group(3):
        return Type(Scalar(m.group(3)))
    return Type(Scalar(m.group(1)), int(m.group(2) or 3))


TYPE_NAMES = tuple(
    [s for s in ("F64", "F32", "F16", "S64", "S32", "U64", "U32")]
    + [f"{s}vec{n}" for s in ("F64", "F32", "F16") for n in ("", "2", "3", "4")]
)

CXX_SCALAR = {
    Scalar.F64: "double",
    Scalar.F32: "float",
    Scalar.F16: "_Float16",
    Scalar.S64: "std::int64_t",
    Scalar.S32: "std::int32_t",
    Scalar.U64: "std::uint64_t",
    Scalar.U32: "std::uint32_t",
    Scalar.BOOL: "bool",
}


def round_to(v: float | int | bool, t: Type) -> float | int | bool:
    """Value v as type t holds it: integers wrapped to their width, F32 and F16
    rounded as the hardware would (to nearest even)."""
    s = t.scalar
    if s == Scalar.BOOL:
        return bool(v)
    if s.is_int:
        bits = s.bits
        iv = int(v) % (1 << bits)
        if not s.is_unsigned and iv >= 1 << (bits - 1):
            iv -= 1 << bits
        return iv
    fv = float(v)
    if s == Scalar.F32:
        return struct.unpack("f", struct.pack("f", fv))[0]
    if s == Scalar.F16:
        return struct.unpack("e", struct.pack("e", fv))[0]
    return fv
