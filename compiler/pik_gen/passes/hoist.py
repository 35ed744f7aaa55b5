"""hoist: move loop-invariant ops out of the j loop (and out of the i loop).

Rewrites: every op goes to the outermost stage that can compute it. Constants,
parameters and expressions of them go to `setup` (once per call); EPI loads,
FORCE entry values and expressions of those and `setup` values go to `i` (once
per i-particle). Ops of `j` made only of `setup` values also go to `setup`.
Keeps: `accum` in `pair`, EPJ loads and everything depending on the j-particle
where they are (only `EPJ local` values are precomputed per j, by
precompute_locals), and the relative order of ops.
"""
from __future__ import annotations

from pik_gen.ir.nodes import Kernel, MemberRef, Op, Stage

_JOIN = {
    (Stage.SETUP, Stage.SETUP): Stage.SETUP,
    (Stage.SETUP, Stage.I): Stage.I, (Stage.I, Stage.SETUP): Stage.I, (Stage.I, Stage.I): Stage.I,
    (Stage.SETUP, Stage.J): Stage.J, (Stage.J, Stage.SETUP): Stage.J, (Stage.J, Stage.J): Stage.J,
}


def _join(a: Stage, b: Stage) -> Stage:
    return _JOIN.get((a, b), Stage.PAIR)


def hoist(k: Kernel) -> Kernel:
    where: dict[str, Stage] = {}
    blocks: dict[Stage, list[Op]] = {s: [] for s in Stage}
    for stage, ops in k.blocks():
        for op in ops:
            if op.opcode == "accum":
                target = Stage.PAIR
            elif op.opcode == "load":
                assert isinstance(op.attr, MemberRef)
                target = Stage.I if op.attr.role in ("EPI", "FORCE") else stage
                if op.attr.role == "EPJ":
                    target = stage
            else:
                target = Stage.SETUP
                for a in op.args:
                    target = _join(target, where[a])
                if stage == Stage.J and target == Stage.PAIR:
                    target = Stage.J  # cannot happen for valid IR; keep j ops in j
            # never move an op *inward*
            if _join(target, stage) != stage and not (stage == Stage.I and target == Stage.SETUP):
                target = stage
            if op.result:
                where[op.result] = target
            blocks[target].append(op)
    return k.with_blocks(blocks)
