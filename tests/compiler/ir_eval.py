"""A double-precision interpreter of the IR, straight after `build` (before any
pass): the oracle the compile-and-run tests compare generated kernels with.

Values are numpy arrays over (i, j) pairs (vectors have a trailing component
axis); every float type is evaluated in float64, integers in int64."""
from __future__ import annotations

import math

import numpy as np

from pik_gen.ir.nodes import Comp, Const, Kernel, MemberRef, ParamRef, Reduce, TableRef


def evaluate(k: Kernel, params: dict[str, float], epi: dict[str, np.ndarray], epj: dict[str, np.ndarray],
             force0: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    ni = next(iter(epi.values())).shape[0] if epi else next(iter(force0.values())).shape[0]
    nj = next(iter(epj.values())).shape[0] if epj else 1
    env: dict[str, np.ndarray] = {}
    vec: dict[str, bool] = {}
    out = {m: v.astype(np.float64).copy() for m, v in force0.items()}

    def b(x: np.ndarray, is_vec: bool, want_vec: bool) -> np.ndarray:
        return x[..., None] if want_vec and not is_vec else x

    for op in k.all_ops():
        t = op.type
        isv = bool(t is not None and t.is_vec)
        a = [env[x] for x in op.args]
        av = [vec[x] for x in op.args]
        a = [b(x, v, isv and op.opcode not in ("comp", "dot", "insert")) for x, v in zip(a, av)]
        match op.opcode:
            case "const":
                assert isinstance(op.attr, Const)
                r = np.full((1, 1) + ((t.lanes,) if isv else ()), float(op.attr.value))
            case "param":
                assert isinstance(op.attr, ParamRef)
                r = np.full((1, 1), float(params[op.attr.name]))
            case "load":
                ref = op.attr
                assert isinstance(ref, MemberRef)
                src = {"EPI": epi, "EPJ": epj, "FORCE": force0}[ref.role][ref.member].astype(np.float64)
                if ref.component is not None:
                    src = src[:, ref.component]
                r = src[:, None] if ref.role != "EPJ" else src[None, :]
            case "neg": r = -a[0]
            case "not": r = ~a[0].astype(bool)
            case "add": r = a[0] + a[1]
            case "sub": r = a[0] - a[1]
            case "mul": r = a[0] * a[1]
            case "div": r = a[0] / a[1] if t.scalar.is_float else np.trunc(a[0] / a[1])
            case "eq": r = a[0] == a[1]
            case "ne": r = a[0] != a[1]
            case "lt": r = a[0] < a[1]
            case "gt": r = a[0] > a[1]
            case "le": r = a[0] <= a[1]
            case "ge": r = a[0] >= a[1]
            case "and": r = a[0] & a[1]
            case "or": r = a[0] | a[1]
            case "select": r = np.where(b(a[0], False, isv), a[1], a[2])
            case "sqrt": r = np.sqrt(a[0])
            case "rsqrt": r = 1.0 / np.sqrt(a[0])
            case "rsqrt2": r = 2.0 / np.sqrt(a[0])
            case "inv": r = 1.0 / a[0]
            case "exp": r = np.exp(a[0])
            case "erfc": r = np.vectorize(math.erfc, otypes=[np.float64])(a[0])
            case "log": r = np.log(a[0])
            case "floor": r = np.floor(a[0])
            case "abs": r = np.abs(a[0])
            case "min": r = np.minimum(a[0], a[1])
            case "max": r = np.maximum(a[0], a[1])
            case "pow": r = np.power(a[0], a[1])
            case "madd": r = a[0] * a[1] + a[2]
            case "msub": r = a[0] * a[1] - a[2]
            case "nmadd": r = a[2] - a[0] * a[1]
            case "nmsub": r = -(a[0] * a[1]) - a[2]
            case "cast": r = a[0].astype(np.float64) if t.scalar.is_float else np.trunc(a[0])
            case "table":
                assert isinstance(op.attr, TableRef)
                tab = next(x for x in k.tables if x.name == op.attr.name)
                r = np.asarray(tab.values)[a[0].astype(np.int64)]
            case "dot": r = np.sum(a[0] * a[1], axis=-1)
            case "cross": r = np.cross(a[0], a[1])
            case "comp":
                assert isinstance(op.attr, Comp)
                r = a[0][..., op.attr.index]
            case "insert":
                assert isinstance(op.attr, Comp)
                shape = np.broadcast_shapes(a[0].shape, a[1].shape + (1,))
                r = np.broadcast_to(a[0], shape).copy()
                r[..., op.attr.index] = np.broadcast_to(a[1], shape[:-1])
            case "accum":
                red = op.attr
                assert isinstance(red, Reduce)
                v = np.broadcast_to(a[0], (ni, nj) + a[0].shape[2:]).astype(np.float64)
                ident = {"add": 0.0, "sub": 0.0, "mul": 1.0, "div": 1.0, "max": -np.inf, "min": np.inf}[red.kind]
                if len(a) > 1:
                    m = np.broadcast_to(env[op.args[1]], (ni, nj))
                    v = np.where(m[(...,) + (None,) * (v.ndim - 2)], v, ident)
                cur = out[red.member] if red.component is None else out[red.member][:, red.component]
                match red.kind:
                    case "add": cur += red.scale * v.sum(axis=1)
                    case "sub": cur -= red.scale * v.sum(axis=1)
                    case "mul": cur *= v.prod(axis=1)
                    case "div": cur /= v.prod(axis=1)
                    case "max": cur[...] = np.maximum(cur, v.max(axis=1, initial=-np.inf))
                    case "min": cur[...] = np.minimum(cur, v.min(axis=1, initial=np.inf))
                continue
            case _:
                raise AssertionError(op.opcode)
        env[op.result] = np.asarray(r)
        vec[op.result] = isv
    return out
