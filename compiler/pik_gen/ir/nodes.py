"""IR nodes: frozen dataclasses in SSA form.

A `Kernel` holds four flat tuples of `Op`s, one per *stage*, i.e. per loop level
the op runs in:

  setup  once per call (parameters, constants, parameter-only expressions)
  i      once per i-particle, before the j loop (EPI loads, i-only expressions)
  j      once per j-particle, before the double loop (EPJ locals)
  pair   once per (i, j) pair

Every value is defined exactly once across the four tuples. An op may use values
of its own stage defined earlier and of the stages it is nested in: setup values
everywhere; i values in i and pair; j values in j and pair. `if` has already
been lowered to masks and selects, so every tuple is straight-line code.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from enum import Enum
from typing import Iterator

from pik_gen.diagnostics import Span
from pik_gen.typed import Member, Table
from pik_gen.types import Type


class Stage(Enum):
    SETUP = "setup"
    I = "i"
    J = "j"
    PAIR = "pair"


# Stages whose values an op of a given stage may use.
VISIBLE = {
    Stage.SETUP: (Stage.SETUP,),
    Stage.I: (Stage.SETUP, Stage.I),
    Stage.J: (Stage.SETUP, Stage.J),
    Stage.PAIR: (Stage.SETUP, Stage.I, Stage.J, Stage.PAIR),
}


@dataclass(frozen=True)
class Const:
    value: float | int


@dataclass(frozen=True)
class ParamRef:
    name: str


@dataclass(frozen=True)
class MemberRef:
    role: str  # EPI | EPJ | FORCE
    member: str
    component: int | None  # None: the whole (vector or scalar) member


@dataclass(frozen=True)
class Comp:
    index: int


@dataclass(frozen=True)
class TableRef:
    name: str


@dataclass(frozen=True)
class Reduce:
    kind: str  # add | sub | mul | div | max | min
    member: str
    component: int | None
    scale: float = 1.0  # add/sub: FORCE.member op= scale * (sum of the values); a power of two


Attr = Const | ParamRef | MemberRef | Comp | TableRef | Reduce | None


@dataclass(frozen=True)
class Op:
    """One SSA operation. `result` is '' for `accum` (no value); `type` is None then."""

    result: str
    opcode: str
    args: tuple[str, ...]
    type: Type | None
    attr: Attr = None
    span: Span = field(default=Span("<ir>", 0, 0, 0), compare=False)

    def key(self) -> tuple:
        """What makes two ops compute the same value (for CSE)."""
        return (self.opcode, self.args, self.type, self.attr)


@dataclass(frozen=True)
class Param:
    name: str
    type: Type


@dataclass(frozen=True)
class LocalValue:
    """A value assigned to an `EPI local` / `EPJ local` variable (its components
    after vector expansion)."""

    name: str
    role: str
    values: tuple[str, ...]


@dataclass(frozen=True)
class Kernel:
    name: str
    source: str
    params: tuple[Param, ...]
    members: tuple[Member, ...]
    tables: tuple[Table, ...]
    locals: tuple[LocalValue, ...]
    setup: tuple[Op, ...] = ()
    i: tuple[Op, ...] = ()
    j: tuple[Op, ...] = ()
    pair: tuple[Op, ...] = ()
    pragmas: tuple[str, ...] = ()

    def block(self, stage: Stage) -> tuple[Op, ...]:
        return getattr(self, stage.value)

    def blocks(self) -> Iterator[tuple[Stage, tuple[Op, ...]]]:
        for s in Stage:
            yield s, self.block(s)

    def all_ops(self) -> Iterator[Op]:
        for _s, ops in self.blocks():
            yield from ops

    def with_blocks(self, blocks: dict[Stage, tuple[Op, ...]] | dict[Stage, list[Op]]) -> "Kernel":
        return replace(self, **{s.value: tuple(ops) for s, ops in blocks.items()})

    def defs(self) -> dict[str, Op]:
        return {op.result: op for op in self.all_ops() if op.result}

    def names(self) -> set[str]:
        return {op.result for op in self.all_ops() if op.result}


def rename_args(kernel: Kernel, mapping: dict[str, str]) -> Kernel:
    """Replace uses of values (op arguments and local values) through `mapping`."""
    if not mapping:
        return kernel

    def m(name: str) -> str:
        while name in mapping:
            name = mapping[name]
        return name

    blocks = {
        s: tuple(replace(op, args=tuple(m(a) for a in op.args)) for op in ops) for s, ops in kernel.blocks()
    }
    locals_ = tuple(replace(lv, values=tuple(m(v) for v in lv.values)) for lv in kernel.locals)
    return replace(kernel.with_blocks(blocks), locals=locals_)


def fresh_name(used: set[str], base: str) -> str:
    """`base` if unused, else base_2, base_3, ...; records the name in `used`."""
    name, k = base, 1
    while name in used or name in RESERVED:
        k += 1
        name = f"{base}_{k}"
    used.add(name)
    return name


# Names a generated kernel uses itself, C++ keywords and common macros: never an SSA name.
RESERVED = frozenset(
    """i j ni nj jb je jn epi epj force std pik_kernels kJBlock
    l ib n jj kW kU kIB kJPad jvalid lane
    pg kMaxW ivalid
    alignas alignof and and_eq asm auto bitand bitor bool break case catch char char8_t char16_t
    char32_t class compl concept const consteval constexpr constinit const_cast continue co_await
    co_return co_yield decltype default delete do double dynamic_cast else enum explicit export
    extern false float for friend goto if inline int long mutable namespace new noexcept not
    not_eq nullptr operator or or_eq private protected public register reinterpret_cast requires
    return short signed sizeof static static_assert static_cast struct switch template this
    thread_local throw true try typedef typeid typename union unsigned using virtual void volatile
    wchar_t while xor xor_eq NULL assert errno EOF INFINITY NAN main""".split()
)
