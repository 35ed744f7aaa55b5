"""The optimisation pipeline: each pass is a pure function Kernel -> Kernel in its own file."""
from __future__ import annotations

from typing import Callable

from pik_gen.ir.nodes import Kernel
from pik_gen.passes.contract_fma import contract_fma
from pik_gen.passes.cse import cse
from pik_gen.passes.dce import dce
from pik_gen.passes.defer_scale import defer_scale
from pik_gen.passes.expand_vectors import expand_vectors
from pik_gen.passes.fold_constants import fold_constants
from pik_gen.passes.hoist import hoist
from pik_gen.passes.precompute_locals import precompute_locals

Pass = Callable[[Kernel], Kernel]

PIPELINE: tuple[Pass, ...] = (
    precompute_locals,  # EPI/EPJ locals: their slices computed once per particle (stages i, j)
    expand_vectors,     # F64vec & co. become x, y, z components: everything below is scalar
    fold_constants,     # literal arithmetic done now, rounded to its type
    cse,                # each value computed once (repeated loads, repeated subexpressions)
    dce,                # drop what no accumulation needs
    defer_scale,        # power-of-two factors (rsqrt's Newton 1/2, x*0.5) applied once per sum
    contract_fma,       # a*b+c -> madd(a, b, c) where the product has no other use
    hoist,              # parameter-only ops to setup, i-only ops out of the j loop
)

PASS_NAMES: tuple[str, ...] = tuple(p.__name__ for p in PIPELINE)


def run_pipeline(k: Kernel, after: Callable[[str, Kernel], None] | None = None) -> Kernel:
    """Run every pass in order; `after(name, kernel)` sees the IR after each one."""
    for p in PIPELINE:
        k = p(k)
        if after is not None:
            after(p.__name__, k)
    return k
