"""Each pass: a table of input -> expected IR text, idempotence, and the verifier
after every pass over the whole kernel corpus."""
from __future__ import annotations

from pathlib import Path

import pytest

from conftest import KERNELS

from pik_gen.driver import frontend
from pik_gen.ir.build import build
from pik_gen.ir.printer import format_kernel
from pik_gen.ir.verifier import check, verify
from pik_gen.passes import (PIPELINE, contract_fma, cse, dce, defer_scale, expand_vectors, fold_constants, hoist,
                             precompute_locals)

CORPUS = KERNELS + sorted((Path(__file__).parent / "pik").glob("*.pik"))
H = "EPI F64vec xi:pos\nEPJ F64vec xj:pos\nEPJ F64 mj:mass\nFORCE F64vec acc:acc\nFORCE F64 pot:pot\nF64 eps2\n"


def ir(src: str):
    return build(frontend(src, "t.pik"), "T")


def body(k, stage: str = "pair") -> list[str]:
    """The ops of one stage as printed, for compact expectations."""
    text = format_kernel(k).split("\n")
    start = text.index(f"{stage}:") + 1
    out = []
    for line in text[start:]:
        if not line.startswith("  "):
            break
        out.append(line.strip())
    return out


CASES = [
    # (pass, source, stage, expected ops of that stage after the pass)
    # fold_constants: literal arithmetic is evaluated in the literal's type
    (fold_constants, 'pot += mj * (2.0 * 3.0)', 'pair',
     ['mj: F64 = load EPJ.mass', 'c: F64 = const 2.0', 'c_2: F64 = const 3.0', 'dpot_1: F64 = const 6.0', 'dpot_2: F64 = mul mj, dpot_1', 'accum.add FORCE.pot, dpot_2']),
    # fold_constants: x * 1 is x
    (fold_constants, 'pot += mj * 1.0', 'pair',
     ['mj: F64 = load EPJ.mass', 'c: F64 = const 1.0', 'accum.add FORCE.pot, mj']),
    # cse: the same load and the same product are computed once
    (cse, 'pot += mj * mj + mj * mj', 'pair',
     ['mj: F64 = load EPJ.mass', 'dpot_1: F64 = mul mj, mj', 'dpot_3: F64 = add dpot_1, dpot_1', 'accum.add FORCE.pot, dpot_3']),
    # dce: a variable nothing accumulates disappears
    (dce, 'unused = mj * 2.0\npot += mj', 'pair',
     ['mj_2: F64 = load EPJ.mass', 'accum.add FORCE.pot, mj_2']),
    # contract_fma: a*b + c with a single-use product becomes madd; c - a*b becomes nmadd
    (contract_fma, 'pot += mj * eps2 + mj\npot += mj - eps2 * mj', 'pair',
     ['mj: F64 = load EPJ.mass', 'eps2: F64 = param eps2', 'mj_2: F64 = load EPJ.mass', 'dpot_2: F64 = madd mj, eps2, mj_2', 'accum.add FORCE.pot, dpot_2', 'mj_3: F64 = load EPJ.mass', 'eps2_2: F64 = param eps2', 'mj_4: F64 = load EPJ.mass', 'dpot_4: F64 = nmadd eps2_2, mj_4, mj_3', 'accum.add FORCE.pot, dpot_4']),
    # contract_fma: an addend joins the innermost product of a fused chain (no separate add)
    (contract_fma, 'pot += xi.x * xi.x + xj.x * xj.x + eps2', 'pair',
     ['xi_x: F64 = load EPI.pos.x', 'xi_x_2: F64 = load EPI.pos.x', 'xj_x: F64 = load EPJ.pos.x', 'xj_x_2: F64 = load EPJ.pos.x', 'eps2: F64 = param eps2', 'dpot_2: F64 = madd xj_x, xj_x_2, eps2', 'dpot_4: F64 = madd xi_x, xi_x_2, dpot_2', 'accum.add FORCE.pot, dpot_4']),
    # defer_scale: rsqrt -> rsqrt2 and x * 0.5 -> x; the factors end in the sums' scale
    (defer_scale, 'r = rsqrt(mj)\npot += mj * r\nFORCE.acc.x += r * 0.5 * xj.x', 'pair',
     ['mj: F64 = load EPJ.mass', 'r: F64 = rsqrt2 mj', 'mj_2: F64 = load EPJ.mass', 'dpot_1: F64 = mul mj_2, r', 'accum.add FORCE.pot, dpot_1 * 0.5', 'c: F64 = const 0.5', 'xj_x: F64 = load EPJ.pos.x', 'dacc_x_2: F64 = mul r, xj_x', 'accum.add FORCE.acc.x, dacc_x_2 * 0.25']),
    # defer_scale: a second sum into pot with another factor is multiplied by the ratio
    (defer_scale, 'r = rsqrt(mj)\npot += r * 0.25\npot += mj * r', 'pair',
     ['scale: F64 = const 4.0', 'mj: F64 = load EPJ.mass', 'r: F64 = rsqrt2 mj', 'c: F64 = const 0.25', 'accum.add FORCE.pot, r * 0.125', 'mj_2: F64 = load EPJ.mass', 'dpot_2: F64 = mul mj_2, r', 'dpot_2_s: F64 = mul dpot_2, scale', 'accum.add FORCE.pot, dpot_2_s * 0.125']),
    # defer_scale: nothing to gain (the factor would have to be applied for a compare): unchanged
    (defer_scale, 'r = rsqrt(mj)\nif r < 1.0\n  pot += mj\nendif', 'pair',
     ['mj: F64 = load EPJ.mass', 'r: F64 = rsqrt mj', 'c: F64 = const 1.0', 'cond_1: BOOL = lt r, c', 'mj_2: F64 = load EPJ.mass', 'accum.add FORCE.pot, mj_2 if cond_1']),
    # hoist: parameter-only ops go to setup ...
    (hoist, 'pot += xi.x * (eps2 * eps2) + mj', 'setup',
     ['eps2: F64 = param eps2', 'eps2_2: F64 = param eps2', 'dpot_1: F64 = mul eps2, eps2_2']),
    # ... EPI loads and i-only ops to i
    (hoist, 'pot += xi.x * (eps2 * eps2) + mj', 'i',
     ['xi_x: F64 = load EPI.pos.x', 'dpot_2: F64 = mul xi_x, dpot_1']),
    # expand_vectors: dot becomes a multiply/add chain over components
    (expand_vectors, 'pot += xi * xj', 'pair',
     ['xi_x: F64 = load EPI.pos.x', 'xi_y: F64 = load EPI.pos.y', 'xi_z: F64 = load EPI.pos.z', 'xj_x: F64 = load EPJ.pos.x', 'xj_y: F64 = load EPJ.pos.y', 'xj_z: F64 = load EPJ.pos.z', 'dpot_1_x: F64 = mul xi_x, xj_x', 'dpot_1_y: F64 = mul xi_y, xj_y', 'dpot_1_s1: F64 = add dpot_1_x, dpot_1_y', 'dpot_1_z: F64 = mul xi_z, xj_z', 'dpot_1: F64 = add dpot_1_s1, dpot_1_z', 'accum.add FORCE.pot, dpot_1']),
    # expand_vectors: a vector accumulation becomes one per component
    (expand_vectors, 'acc -= xj', 'pair',
     ['xj_x: F64 = load EPJ.pos.x', 'xj_y: F64 = load EPJ.pos.y', 'xj_z: F64 = load EPJ.pos.z', 'accum.sub FORCE.acc.x, xj_x', 'accum.sub FORCE.acc.y, xj_y', 'accum.sub FORCE.acc.z, xj_z']),
    # precompute_locals: an EPJ local's slice moves to the j stage
    (precompute_locals, 'EPJ local F64 m2\nm2 = mj * mj\npot += m2 * xi.x', 'j',
     ['mj: F64 = load EPJ.mass', 'mj_2: F64 = load EPJ.mass', 'm2: F64 = mul mj, mj_2']),
]


@pytest.mark.parametrize("fn,src,stage,expected", CASES, ids=[f"{c[0].__name__}-{i}" for i, c in enumerate(CASES)])
def test_pass_table(fn, src: str, stage: str, expected: list[str]) -> None:
    k = fn(ir(H + src + "\n"))
    assert body(k, stage) == expected, format_kernel(k)
    verify(k, expanded=fn is not precompute_locals and "vec" not in format_kernel(k).split("setup:")[1])


def test_if_lowers_to_select_and_masked_accum() -> None:
    k = ir(H + "d = mj\nif d < 1.0\n  d = d * 2.0\nelse\n  pot += d\nendif\npot += d\n")
    ops = body(k)
    assert "d_3: F64 = select cond_1, d_2, d" in ops
    assert "accum.add FORCE.pot, d if not_cond_1" in ops


@pytest.mark.parametrize("path", CORPUS, ids=[p.stem for p in CORPUS])
def test_corpus_verified_and_idempotent(path: Path) -> None:
    k = build(frontend(path.read_text(), str(path)), "K")
    assert check(k) == []
    expanded = False
    for p in PIPELINE:
        k2 = p(k)
        expanded = expanded or p is expand_vectors
        assert check(k2, expanded=expanded) == [], p.__name__
        assert p(k2) == k2, f"{p.__name__} is not idempotent on {path.name}"
        k = k2
    # Fully optimised: nothing left in pair that hoisting could move.
    assert all(op.opcode != "param" for op in k.pair)
    assert all(not (op.opcode == "load" and op.attr.role == "EPI") for op in k.pair)


def test_gravity_pair_loop_is_minimal() -> None:
    # rsqrt once (as 2/sqrt, its factor 1/2 deferred to the sums), loads of EPJ only, the
    # squared distance fused with eps2 as its first addend (no separate add).
    k = build(frontend((KERNELS[0].parent / "gravity.pik").read_text(), "g"), "G")
    for p in PIPELINE:
        k = p(k)
    ops = [op.opcode for op in k.pair]
    assert ops.count("rsqrt2") == 1 and ops.count("rsqrt") == 0 and ops.count("madd") == 3
    assert ops.count("add") == 0
    assert sorted(op.attr.scale for op in k.pair if op.opcode == "accum") == [0.125, 0.125, 0.125, 0.5]
    assert [op.opcode for op in k.i] == ["load"] * 3


def test_inlined_function_result_named_after_the_caller_variable() -> None:
    # dx = wrap(...): the returned value is `dx` in the IR (and in the C++), not `wrap_w_5`
    k = ir(H + "function wrap(d, l)\n  w = d\n  if w < -0.5 * l\n    w = w + l\n  endif\n  return w\nend\n"
           "dx = wrap(xi.x - xj.x, eps2)\ndy = wrap(xi.y - xj.y, eps2)\npot += dx * dy\n")
    ops = body(k)
    assert any(o.startswith("dx: F64 = select ") for o in ops), ops
    assert any(o.startswith("dy: F64 = select ") for o in ops), ops
    assert "accum.add FORCE.pot, dpot_1" in ops and "dpot_1: F64 = mul dx, dy" in ops
