"""The register-pressure model against the compiled code: the j loop of every corpus
kernel, compiled with g++ -O3 -march=<an AVX2-only CPU> (16 ymm: haswell) or
-march=skylake-avx512 (32 zmm) and disassembled with objdump
(compiler/pik_gen/hotloop.py), reads or writes no stack slot at a fixed offset
(no spill, no reload) whenever the model says its block fits the registers; the
model's U is then the largest that does not spill (U = 2 spills where the
model says it does not fit, e.g. gravity F32 on AVX2, the issue-15 case: two
i-vectors in flight on 16 ymm load 9 values from the stack per iteration on
Zen 3). Kernels whose single i-vector already needs more registers than the ISA
has (the SPH kernels on AVX2) get U = 1 and are only reported. An ISA the host
lacks is skipped, as is the whole test without g++ or objdump."""
from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from conftest import KERNELS
from test_simd_run import host

pytestmark = pytest.mark.skipif(shutil.which("g++") is None or shutil.which("objdump") is None,
                                reason="needs g++ and objdump")

MARCH = {"avx2": "-O3 -march=haswell", "avx512": "-O3 -march=skylake-avx512"}


def model(path: Path, isa: str) -> tuple[int, int, int]:
    """(U, live vectors at U, live vectors at 2U) of the model for the kernel."""
    from pik_gen.backends import ISAS, Options
    from pik_gen.driver import lower

    k = lower(path.read_text(), str(path), "K")
    c = ISAS[isa](Options(name="K"))
    st = c.begin(k)
    U = c.unroll(st, len(st.plan.accs))
    return U, c.live_vectors(st, U), c.live_vectors(st, 2 * U)


@pytest.mark.parametrize("isa", ["avx2", "avx512"])
@pytest.mark.parametrize("path", KERNELS, ids=[p.stem for p in KERNELS])
def test_no_stack_traffic_in_the_hot_loop(path: Path, isa: str) -> None:
    if not host().get(isa):
        pytest.skip(f"this CPU does not support {isa}")
    from pik_gen.backends import ISAS
    from pik_gen.hotloop import hot_loop, spills, stack_traffic

    U, live, _ = model(path, isa)
    loop = hot_loop(path, isa, flags=MARCH[isa])
    assert loop.U == U and loop.instructions, "the hot loop was not found"
    spilled, reads = spills(loop), stack_traffic(loop)
    print(f"{path.stem} {isa}: U = {U}, model {live} of {ISAS[isa].registers} registers, "
          f"{len(loop.instructions)} instructions, {len(spilled)} spill accesses, "
          f"{len(reads) - len(spilled)} loads of loop invariants from the stack")
    if live <= ISAS[isa].registers:
        assert not spilled, f"{path.stem} {isa} U={U}: the model says it fits, the loop spills:\n" + "\n".join(spilled)
    else:
        assert U == 1, f"{path.stem} {isa}: the model says U = {U} does not fit ({live} registers)"


@pytest.mark.parametrize("name,isa", [("gravity", "avx2"), ("gravity_f64", "avx2")])
def test_one_more_i_vector_spills(name: str, isa: str) -> None:
    """Where the model stops (its 2U does not fit), the compiled loop with 2U spills."""
    if not host().get(isa):
        pytest.skip(f"this CPU does not support {isa}")
    from pik_gen.backends import ISAS
    from pik_gen.hotloop import hot_loop, spills

    path = next(p for p in KERNELS if p.stem == name)
    U, _live, live2 = model(path, isa)
    assert live2 > ISAS[isa].registers
    assert spills(hot_loop(path, isa, flags=MARCH[isa], unroll=2 * U)), f"{name} {isa} U={2 * U} did not spill"
    if isa == "avx2":
        assert U == 1  # the issue-15 case: one i-vector on 16 ymm


def test_cpu_families_and_native(tmp_path: Path) -> None:
    """--cpu selects a row of the ISA's table (A64FX's FMA latency 9 asks for more
    i-vectors); an unknown name is an error; native maps /proc/cpuinfo fields."""
    from conftest import run_cli
    from pik_gen.backends.simd import native_cpu

    src = next(p for p in KERNELS if p.stem == "gravity_treepm")
    rc, _, err = run_cli([src, "-o", tmp_path / "a.hpp", "--target", "sve", "--cpu", "a64fx"])
    assert rc == 0, err
    rc, _, err = run_cli([src, "-o", tmp_path / "g.hpp", "--target", "sve"])
    assert rc == 0, err
    a, g = (tmp_path / "a.hpp").read_text(), (tmp_path / "g.hpp").read_text()
    assert "2 * kW" in a and "2 * kW" not in g
    rc, _, err = run_cli([src, "-o", tmp_path / "x.hpp", "--cpu", "pentium4"])
    assert rc != 0 and "unknown --cpu 'pentium4'" in err
    intel = "vendor_id\t: GenuineIntel\ncpu family\t: 6\nmodel\t\t: 207\n"
    amd = "vendor_id\t: AuthenticAMD\ncpu family\t: 25\nmodel\t\t: 33\n"
    assert native_cpu(intel) == "sapphirerapids" and native_cpu(amd) == "znver3"


@pytest.mark.parametrize("name", ["gravity", "gravity_f64"])
def test_avx2_for_zen5_fits_32_registers(name: str) -> None:
    """--cpu znver5 sizes AVX2 for 32 ymm (EVEX): two gravity i-vectors per block, and the
    loop compiled as pik's builds compile it (-O2, only the variant's target attribute
    avx2,fma,avx512vl) touches no stack slot, with the F64 rsqrt's vrsqrt14pd and divider copy."""
    if not host().get("avx512"):
        pytest.skip("this CPU lacks AVX-512VL, which the znver5 AVX2 variant needs")
    from pik_gen.hotloop import hot_loop, spills

    path = next(p for p in KERNELS if p.stem == name)
    loop = hot_loop(path, "avx2", flags="-O2", cpu="znver5")
    assert loop.U == 2 and loop.instructions, "the hot loop was not found"
    assert not spills(loop), "\n".join(spills(loop))
    if name == "gravity_f64":
        text = "\n".join(str(i) for i in loop.instructions)
        assert "vrsqrt14pd" in text and "vsqrtpd" in text and "vdivpd" in text, text


@pytest.mark.parametrize("name,isa", [("gravity", "avx2"), ("gravity_f64", "avx2"), ("gravity_f64", "avx512")])
def test_j_copies_fit_where_the_model_says(name: str, isa: str) -> None:
    """--cpu znver4 asks for four j-particles per iteration beside one i-vector
    (Uarch.j_copies, Simd.j_copies_rule): the model puts V = 4 within the 32 registers
    and V = 5 above them, and so does the compiled loop (-O2, as pik's builds compile
    it): V = 4 touches no stack slot, V = 5 spills. A row that does not ask (the
    default) keeps one j-particle per iteration."""
    if not host().get("avx512"):
        pytest.skip("this CPU lacks AVX-512VL, which the znver4 variants need")
    from pik_gen.backends import ISAS, Options
    from pik_gen.driver import lower
    from pik_gen.hotloop import hot_loop, spills

    path = next(p for p in KERNELS if p.stem == name)
    k = lower(path.read_text(), str(path), "K")
    c = ISAS[isa](Options(name="K", cpu="znver4"))
    st = c.begin(k)
    assert c.j_copies_rule(st) == 4
    assert c.live_vectors(st, 1, V=4) <= 32 < c.live_vectors(st, 1, V=5)
    st = ISAS[isa](Options(name="K")).begin(k)
    assert ISAS[isa](Options(name="K")).j_copies_rule(st) == 1
    loop = hot_loop(path, isa, flags="-O2", cpu="znver4")
    assert (loop.U, loop.V) == (1, 4) and loop.instructions, "the hot loop was not found"
    assert not spills(loop), "\n".join(spills(loop))
    assert spills(hot_loop(path, isa, flags="-O2", cpu="znver4", j_copies=5)), f"{name} {isa} V=5 did not spill"


def test_copies_printed_op_by_op_where_they_fit(tmp_path: Path) -> None:
    """A block of U i-vectors is printed op by op (copy 0, 1, ... of each op; the values
    that do not depend on i once, before them) where the register-pressure model says
    that order fits, copy after copy where only that order fits (gravity_treepm on
    A64FX: 34 against 30 of its 32 registers)."""
    from conftest import run_cli
    from pik_gen.backends import ISAS, Options
    from pik_gen.driver import lower

    def pair_lines(src: Path, isa: str, cpu: str) -> list[str]:
        out = tmp_path / f"{src.stem}_{isa}_{cpu}.hpp"
        rc, _, err = run_cli([src, "-o", out, "--target", isa, "--cpu", cpu])
        assert rc == 0, err
        text = [ln.strip() for ln in out.read_text().splitlines()]
        start = next(i for i, ln in enumerate(text) if "rij_x_0 = " in ln)
        return text[start:start + 40]

    grav = next(p for p in KERNELS if p.stem == "gravity")
    lines = pair_lines(grav, "avx512", "znver4")
    assert lines[0].startswith("const __m512 rij_x_0 = ") and lines[1].startswith("const __m512 rij_x_1 = "), lines[:4]
    # rinv of copy 1 is computed before mr of copy 0 (op by op), not after copy 0's sums
    first = lambda pre: next(i for i, ln in enumerate(lines) if pre in ln)  # noqa: E731
    assert first("rinv_1 = ") < first("mr_0 = ") < first("acc_x_0 = ")

    treepm = next(p for p in KERNELS if p.stem == "gravity_treepm")
    k = lower(treepm.read_text(), str(treepm), "K")
    c = ISAS["sve"](Options(name="K", cpu="a64fx"))
    st = c.begin(k)
    U = c.unroll(st, len(st.plan.accs))
    assert U == 2 and c.live_vectors(st, U) <= 32 < c.live_vectors(st, U, interleaved=True)
    out = tmp_path / "treepm.hpp"
    rc, _, err = run_cli([treepm, "-o", out, "--target", "sve", "--cpu", "a64fx"])
    assert rc == 0, err
    text = [ln.strip() for ln in out.read_text().splitlines()]
    acc0 = next(i for i, ln in enumerate(text) if ln.startswith("acc_x_0 = "))  # copy 0's last op
    assert next(i for i, ln in enumerate(text) if "rij_x_1 = " in ln) > acc0, "copy 1 printed inside copy 0"


def test_split_fma_chains_only_where_the_row_asks() -> None:
    """Uarch.split_sums (AVX-512 znver4): r^2 + eps^2, three fused products and an addend,
    becomes (e*f + g) + (a*b + c*d), one add more and one FMA latency less on the chain;
    a chain without an addend (Lennard-Jones' r^2) and the other rows stay as they are.
    (The variants' accuracy: test_simd_run's --cpu znver4 verify.)"""
    from pik_gen.backends import ISAS, Options
    from pik_gen.backends.simd import split_fma_chains
    from pik_gen.driver import lower

    grav = next(p for p in KERNELS if p.stem == "gravity")
    k = lower(grav.read_text(), str(grav), "K")
    s = split_fma_chains(k)
    before = [op.opcode for op in k.pair]
    after = [op.opcode for op in s.pair]
    assert before.count("madd") - after.count("madd") == 1 and after.count("add") == before.count("add") + 1
    assert after.count("mul") == before.count("mul") + 1
    r2 = next(op for op in s.pair if op.opcode == "add")
    defs = {op.result: op for op in s.pair}
    assert {defs[a].opcode for a in r2.args} == {"madd"}
    assert any(defs[a].args[2] in defs and defs[defs[a].args[2]].opcode == "mul" for a in r2.args)
    lj = next(p for p in KERNELS if p.stem == "lj")
    kl = lower(lj.read_text(), str(lj), "K")
    assert [op.opcode for op in split_fma_chains(kl).pair] == [op.opcode for op in kl.pair]
    assert ISAS["avx512"](Options(name="K", cpu="znver4")).uarch()[1].split_sums
    assert not any(ISAS[isa](Options(name="K", cpu=c)).uarch()[1].split_sums
                   for isa in ("avx2", "avx512") for c in ISAS[isa].UARCH if (isa, c) != ("avx512", "znver4"))
