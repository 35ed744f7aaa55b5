"""Bind kernel parameters to compile-time constants (`pikg-gen --const NAME=VALUE`).

A bound parameter leaves the generated constructor; each `param` op that reads it
becomes a `const` op of the parameter's type, so `fold_constants` can evaluate
what depends on it and turn an `if` on it into straight code (the other branch is
then dropped by `dce`). One `.pik` file can so serve several specialisations
(e.g. the dimension or the smoothing-function shape of an SPH kernel) with no
run-time cost. Runs on the IR right after `build`, before the pass pipeline.
"""
from __future__ import annotations

import math
from dataclasses import replace

from pik_gen.diagnostics import NO_SPAN, error
from pik_gen.ir.nodes import Const, Kernel, Op, ParamRef
from pik_gen.types import Scalar, Type, round_to


def parse_value(name: str, text: str, t: Type) -> float | int | bool:
    """The value of `--const name=text` for a parameter of type t (a clear error if it
    does not fit)."""
    s = t.scalar
    try:
        if s == Scalar.BOOL:
            if text not in ("true", "false", "1", "0"):
                raise ValueError
            return text in ("true", "1")
        if s.is_int:
            v = int(text, 0)
            lo, hi = (0, (1 << s.bits) - 1) if s.is_unsigned else (-(1 << (s.bits - 1)), (1 << (s.bits - 1)) - 1)
            if not lo <= v <= hi:
                raise error(NO_SPAN, f"--const {name}={text}: out of range of the parameter's type {t}")
            return v
        v = float(text)
        if not math.isfinite(v):
            raise ValueError
        return v
    except ValueError:
        kind = "an integer" if s.is_int else ("true or false" if s == Scalar.BOOL else "a finite number")
        raise error(NO_SPAN, f"--const {name}={text}: the parameter has type {t}, the value must be {kind}") from None


def bind_constants(k: Kernel, constants: tuple[tuple[str, str], ...]) -> Kernel:
    """Replace the named parameters by constants; unknown names are errors."""
    if not constants:
        return k
    params = {p.name: p for p in k.params}
    values: dict[str, float | int | bool] = {}
    for name, text in constants:
        if name not in params:
            known = ", ".join(params) or "none"
            raise error(NO_SPAN, f"--const {name}: the kernel has no parameter '{name}' (parameters: {known})")
        if name in values:
            raise error(NO_SPAN, f"--const {name} given twice")
        t = params[name].type
        if t.is_vec:
            raise error(NO_SPAN, f"--const {name}: only scalar parameters can be bound (this one is {t})")
        values[name] = round_to(parse_value(name, text, t), t)

    def rewrite(op: Op) -> Op:
        if op.opcode == "param" and isinstance(op.attr, ParamRef) and op.attr.name in values:
            return replace(op, opcode="const", attr=Const(values[op.attr.name]))  # type: ignore[arg-type]
        return op

    blocks = {s: tuple(rewrite(op) for op in ops) for s, ops in k.blocks()}
    k = k.with_blocks(blocks)
    return replace(k, params=tuple(p for p in k.params if p.name not in values))
