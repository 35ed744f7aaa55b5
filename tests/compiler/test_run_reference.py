"""Compile and run: the reference backend of every kernel in kernels/ (and the
PIKG-style kernel in pik/) is generated, compiled with g++ -Wall -Wextra -Werror
against synthesized particle structs (members stored as double, so F32 kernels
also exercise the conversions), run on seeded random particles for several
(ni, nj) including 0, 1, odd sizes and nj beyond the EPJ-local block of 256,
and compared with a double-precision evaluation of the unoptimised IR.

Tolerances: relative to the largest magnitude of each output, 2e-4 for F32
kernels (single-precision sums over a few hundred terms), 1e-11 for F64."""
from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from conftest import KERNELS, ROOT, run_cli
from ir_eval import evaluate

CORPUS = KERNELS + sorted((Path(__file__).parent / "pik").glob("*.pik"))
SIZES = [(0, 5), (5, 0), (1, 1), (7, 13), (33, 300)]
PARAMS = {  # physically sensible values per parameter name; 0.5 otherwise
    "eps2": 1e-2, "box": 3.0, "rcut2": 1.2**2, "eps": 1.0, "sigma2": 0.3**2, "scale": 2.0,
    "shape": 0, "dim": 3, "gamma": 5.0 / 3.0, "alpha": 1.0,  # SPH kernels
}

pytestmark = pytest.mark.skipif(shutil.which("g++") is None, reason="g++ is not installed")


def struct(name: str, members) -> str:
    lines = [f"struct {name} {{"]
    for m in members:
        storage = "double" if m.type.scalar.is_float else "long long"
        lanes = m.type.lanes
        t = storage if lanes == 1 else f"pik::Vec{lanes}<{storage}>"
        lines.append(f"  {t} {m.name}{{}};")
    lines.append("};")
    return "\n".join(lines)


def random_members(rng, members, n: int, box: float) -> dict[str, np.ndarray]:
    data = {}
    for m in members:
        shape = (n,) if m.type.lanes == 1 else (n, m.type.lanes)
        if m.name == "pos":
            data[m.name] = rng.uniform(0.0, box, shape)
        elif m.type.scalar.is_float:
            data[m.name] = rng.uniform(0.5, 1.5, shape)
        else:
            data[m.name] = rng.integers(0, 4, shape).astype(np.float64)
    return data


def fill(name: str, members, data, n: int) -> str:
    out = []
    for m in members:
        for p in range(n):
            if m.type.lanes == 1:
                out.append(f"  {name}[{p}].{m.name} = {data[m.name][p]!r};")
            else:
                for c in range(m.type.lanes):
                    out.append(f"  {name}[{p}].{m.name}.{'xyzw'[c]} = {data[m.name][p, c]!r};")
    return "\n".join(out)


@pytest.mark.parametrize("path", CORPUS, ids=[p.stem for p in CORPUS])
def test_reference_matches_double_evaluation(path: Path, tmp_path: Path) -> None:
    from pik_gen.driver import frontend
    from pik_gen.ir.build import build

    source = path.read_text()
    ck = frontend(source, str(path))
    ir = build(ck, "K")
    members = {r: [m for m in ck.members if m.role == r] for r in ("EPI", "EPJ", "FORCE")}
    params = [PARAMS.get(n, 0.5 if t.scalar.is_float else 1) for n, t in ck.params]
    header = tmp_path / "K.hpp"
    rc, _o, err = run_cli([path, "-o", header, "--target", "reference", "--name", "K"])
    assert rc == 0, err

    rng = np.random.default_rng(12345)
    box = PARAMS["box"] if "box" in dict(ck.params) else 1.0
    nmax = max(max(s) for s in SIZES)
    epi = random_members(rng, members["EPI"], nmax, box)
    epj = random_members(rng, members["EPJ"], nmax, box)
    prints = []
    for m in members["FORCE"]:
        comps = [""] if m.type.lanes == 1 else [f".{c}" for c in "xyzw"[: m.type.lanes]]
        for c in comps:
            prints.append(f'std::printf("%.17g\\n", static_cast<double>(force[i].{m.name}{c}));')
    ctor = f"K kernel({', '.join(repr(p) for p in params)});" if params else "K kernel;"
    main = f"""
#include <cstdio>
#include <vector>
#include <pik/Vec.hpp>
{struct('EPI', members['EPI'])}
{struct('EPJ', members['EPJ'])}
{struct('FORCE', members['FORCE'])}
#include "K.hpp"
int main() {{
  static EPI epi[{nmax}];
  static EPJ epj[{nmax}];
{fill('epi', members['EPI'], epi, nmax)}
{fill('epj', members['EPJ'], epj, nmax)}
  {ctor}
  const int sizes[][2] = {{{', '.join(f'{{{a}, {b}}}' for a, b in SIZES)}}};
  for (const auto& s : sizes) {{
    std::vector<FORCE> force(static_cast<std::size_t>(s[0]));
    kernel(epi, s[0], epj, s[1], force.data());
    for (int i = 0; i < s[0]; ++i) {{
      {' '.join(prints)}
    }}
  }}
  return 0;
}}
"""
    (tmp_path / "main.cpp").write_text(main)
    exe = tmp_path / "main"
    cc = subprocess.run(["g++", "-std=c++20", "-O1", "-Wall", "-Wextra", "-Werror", f"-I{ROOT / 'runtime/include'}",
                         f"-I{tmp_path}", str(tmp_path / "main.cpp"), "-o", str(exe)], capture_output=True, text=True)
    assert cc.returncode == 0, cc.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True, check=True)
    values = iter(float(x) for x in run.stdout.split())

    f32 = any(m.type.scalar.value == "F32" for m in ck.members)
    tol = 2e-4 if f32 else 1e-11
    pdict = dict(zip([n for n, _t in ck.params], params))
    for ni, nj in SIZES:
        force0 = {m.name: np.zeros((ni,) if m.type.lanes == 1 else (ni, m.type.lanes)) for m in members["FORCE"]}
        want = evaluate(ir, pdict, {k: v[:ni] for k, v in epi.items()}, {k: v[:nj] for k, v in epj.items()}, force0)
        got = {m.name: np.zeros_like(force0[m.name]) for m in members["FORCE"]}
        for i in range(ni):
            for m in members["FORCE"]:
                if m.type.lanes == 1:
                    got[m.name][i] = next(values)
                else:
                    for c in range(m.type.lanes):
                        got[m.name][i, c] = next(values)
        for name in got:
            w, g = np.asarray(want[name]), got[name]
            if w.size == 0:
                continue
            scale = max(np.max(np.abs(w)), 1e-300)
            err = np.max(np.abs(g - w)) / scale
            assert err <= tol, f"{path.name} ni={ni} nj={nj} {name}: relative error {err:.3e} > {tol}"
            if nj == 0:
                assert np.all(g == 0), "nj = 0 must leave FORCE unchanged"
    assert next(values, None) is None
