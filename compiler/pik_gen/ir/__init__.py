"""The SSA IR of pikg-gen: frozen dataclasses, a builder, a printer and a verifier."""
from pik_gen.ir.nodes import (
    Attr, Comp, Const, Kernel, LocalValue, MemberRef, Op, Param, ParamRef, Reduce, Stage, TableRef,
)

__all__ = [
    "Attr", "Comp", "Const", "Kernel", "LocalValue", "MemberRef", "Op", "Param", "ParamRef",
    "Reduce", "Stage", "TableRef",
]
