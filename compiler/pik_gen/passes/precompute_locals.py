"""precompute_locals: compute `EPI local` / `EPJ local` values once per particle.

Rewrites: the backward slice of every value assigned to an EPI local moves from
`pair` to `i` (computed once per i-particle), that of an EPJ local to `j`
(computed once per j-particle before the double loop; backends keep `j`
values in per-j buffers). Ops of a slice that depend on no particle at all
(constants, parameters) go to `setup`. Keeps: everything else, and op order.
Sema guarantees an EPI local's slice reads no EPJ or FORCE member and vice versa.
"""
from __future__ import annotations

from pik_gen.ir.nodes import Kernel, MemberRef, Op, Stage


def precompute_locals(k: Kernel) -> Kernel:
    defs = {op.result: op for op in k.pair if op.result}
    target: dict[str, Stage] = {}
    roles: dict[str, frozenset[str]] = {}

    def role_deps(name: str) -> frozenset[str]:
        if name not in defs:
            return frozenset({"?"})  # defined in another stage already
        if name not in roles:
            op = defs[name]
            r = frozenset({op.attr.role}) if isinstance(op.attr, MemberRef) else frozenset()
            roles[name] = r.union(*(role_deps(a) for a in op.args))
        return roles[name]

    def mark(name: str, stage: Stage) -> None:
        if name not in defs or name in target:
            return
        deps = role_deps(name)
        target[name] = Stage.SETUP if not deps else stage
        for a in defs[name].args:
            mark(a, stage)

    for lv in k.locals:
        stage = Stage.I if lv.role == "EPI" else Stage.J
        for v in lv.values:
            mark(v, stage)
    if not target:
        return k
    blocks: dict[Stage, list[Op]] = {s: list(ops) for s, ops in k.blocks()}
    blocks[Stage.PAIR] = []
    for op in k.pair:
        blocks[target.get(op.result, Stage.PAIR)].append(op)
    return k.with_blocks(blocks)
