"""`pikg-gen verify KERNEL.pik`: check every variant of a kernel against double precision.

What it does
------------
1. Synthesises particle structs from the kernel's declarations (every float
   member stored as `double`, integers as `long long`, vectors as {x, y, z, w}),
   so F32 kernels also exercise the conversions on load and store.
2. Generates each requested variant (default: reference and every x86 ISA the
   host CPU supports, found by compiling and running the ISAs' `cpu_check`), and
   an oracle: the same kernel with every F32/F16 type promoted to F64, through
   the reference backend.
3. Compiles one program with g++ -O2 -Wall -Wextra -Werror and runs it on seeded
   random particles for every (ni, nj) in SIZES x SIZES (0, 1, lanes-1, lanes,
   lanes+1 and 4 lanes + 3 for 4-, 8- and 16-lane vectors, and 300) plus
   nj = 5000 (several j blocks) for ni = 3 (j-parallel) and 70.
4. Prints per variant and per output component the error

       err = max over i of |got_i - want_i| / max over i of max(|want_i|, |init_i|)

   (the maximum over all sizes): an absolute error in units of the output's
   largest magnitude, so a component that cancels to ~0 for one particle is not
   reported as a huge relative error, while a wrong result anywhere still is.
   FORCE starts from random values init_i (the kernels accumulate), the same for
   every variant; init_i is part of the sum, so it belongs in the scale (at ni = 1
   a sum that cancels the start value, want = init + sum ~ 0, would otherwise be
   judged by its own tiny magnitude: sph_viscous's gradc, -0.0489 from a start
   of ~1, off by 2.5e-6). A call with nj = 0 must leave FORCE unchanged.

Tolerances (exit status 1 beyond them): the lowest float precision the kernel
uses decides: F64 1e-12, F32 5e-5, F16 5e-2 (with --fast-math, whose rsqrt/inv
keep the hardware estimate or one refinement step: F64 1e-6, F32 3e-3). An F32 sum over 5000 terms
carries ~sqrt(5000) * 6e-8 relative rounding noise; F64 kernels and refined
rsqrt/inv stay within a few ulp per term.

Inputs: positions (a member named pos, x or r) uniform in [0, box) where the
kernel has a parameter `box`, else [0, 1); other float members uniform in
[0.5, 1.5]; integers in {0, 1, 2, 3}. Parameters take --param NAME=VALUE, else
a default for common names (eps2 1e-2, box 3, rcut2 1.44, eps 1, sigma2 0.09),
else 0.5.
"""
from __future__ import annotations

import argparse
import dataclasses
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from pik_gen.backends import ISAS, TARGETS, Options
from pik_gen.backends.emit import render_header
from pik_gen.diagnostics import CompileError
from pik_gen.ir.build import build
from pik_gen.ir.nodes import Kernel
from pik_gen.passes import run_pipeline
from pik_gen.types import COMPONENTS, Scalar, Type

TOLERANCE = {Scalar.F64: 1e-12, Scalar.F32: 5e-5, Scalar.F16: 5e-2}
# --fast-math keeps the 12/14-bit estimates (F32) or one refinement step (F64). From
# Intel's 12-bit estimate (relative error up to 1.5 * 2^-12) one Newton step leaves
# 1.5 e^2 ~ 2e-7 per rsqrt, ~6e-7 in r^-3, and the force sums reach 2.3e-6 of the
# largest force (gravity_f64 on a Xeon, family 6 model 207; AMD hosts stayed below 1e-6).
FAST_TOLERANCE = {Scalar.F64: 1e-5, Scalar.F32: 3e-3, Scalar.F16: 5e-2}
PARAM_DEFAULTS = {"eps2": 1e-2, "box": 3.0, "rcut2": 1.44, "eps": 1.0, "sigma2": 0.09}
POSITION_NAMES = ("pos", "x", "r")
LANE_COUNTS = sorted({w for c in ISAS.values() for w in c.lane_counts if w > 1})  # 2: F64 on 128-bit SVE
SIZES = sorted({0, 1, 300} | {n for w in LANE_COUNTS for n in (w - 1, w, w + 1, 4 * w + 3)})
EXTRA = ((3, 5000), (70, 5000))


def promote(k: Kernel) -> Kernel:
    """The kernel with every F32/F16 type replaced by F64: the double-precision oracle."""

    def p(t: Type | None) -> Type | None:
        if t is None or t.scalar not in (Scalar.F32, Scalar.F16):
            return t
        return t.with_scalar(Scalar.F64)

    blocks = {s: tuple(dataclasses.replace(op, type=p(op.type)) for op in ops) for s, ops in k.blocks()}
    members = tuple(dataclasses.replace(m, type=p(m.type)) for m in k.members)
    params = tuple(dataclasses.replace(x, type=p(x.type)) for x in k.params)
    tables = tuple(dataclasses.replace(t, type=p(t.type)) for t in k.tables)
    return dataclasses.replace(k.with_blocks(blocks), members=members, params=params, tables=tables)


def host_isas(cxx: str, work: Path) -> dict[str, bool]:
    """Which ISAs' cpu_check holds on this machine (compiled and run once)."""
    checks = {n: c.cpu_check for n, c in ISAS.items() if c.in_auto}
    body = "\n".join(f'  std::printf("{n} %d\\n", ({chk}) ? 1 : 0);' for n, chk in checks.items())
    src = work / "probe.cpp"
    src.write_text(f"#include <cstdio>\nint main() {{\n  __builtin_cpu_init();\n{body}\n  return 0;\n}}\n")
    exe = work / "probe"
    subprocess.run([cxx, "-O0", str(src), "-o", str(exe)], check=True, capture_output=True)
    out = subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout
    return {line.split()[0]: line.split()[1] == "1" for line in out.splitlines()}


def _struct(name: str, members) -> str:
    lines = [f"struct {name} {{"]
    for m in members:
        storage = "double" if m.type.scalar.is_float else "long long"
        if m.type.lanes == 1:
            lines.append(f"  {storage} {m.name}{{}};")
        else:
            comps = ", ".join(COMPONENTS[: m.type.lanes])
            lines.append(f"  struct {{ {storage} {comps}; }} {m.name}{{}};")
    lines.append("};")
    return "\n".join(lines)


def _fill(arr: str, members, box: float) -> str:
    out = []
    for m in members:
        comps = [""] if m.type.lanes == 1 else [f".{c}" for c in COMPONENTS[: m.type.lanes]]
        for c in comps:
            if not m.type.scalar.is_float:
                dist = "pick"
            elif m.name in POSITION_NAMES:
                dist = "pos"
            else:
                dist = "val"
            out.append(f"    {arr}[p].{m.name}{c} = {dist}(rng);")
    return "\n".join(out)


def _outputs(members) -> list[tuple[str, str]]:
    """(label, C++ access suffix) per FORCE output component."""
    outs = []
    for m in members:
        if m.type.lanes == 1:
            outs.append((m.name, f".{m.name}"))
        else:
            outs += [(f"{m.name}.{c}", f".{m.name}.{c}") for c in COMPONENTS[: m.type.lanes]]
    return outs


def program(ck, variants: list[str], params: list[float], box: float, seed: int) -> str:
    members = {r: [m for m in ck.members if m.role == r] for r in ("EPI", "EPJ", "FORCE")}
    outs = _outputs(members["FORCE"])
    nmax = max(SIZES + [n for p in EXTRA for n in p])
    args = ", ".join(repr(float(p)) for p in params)
    ctor = f"({args})" if params else "{}"
    sizes = ", ".join(f"{{{a}, {b}}}" for a in SIZES for b in SIZES) + ", " + ", ".join(f"{{{a}, {b}}}" for a, b in EXTRA)
    run_variants = "\n".join(
        f"""    {{
      std::vector<FORCE> got(init.begin(), init.begin() + ni);
      {v}{ctor}(epi.data(), ni, epj.data(), nj, got.data());
      compare({n}, init, want, got, ni, nj);
    }}""" for n, v in enumerate(variants))
    cmp_outs = "\n".join(
        f"""    {{
      double scale = 0, diff = 0;
      for (int i = 0; i < ni; ++i) {{
        const double w = static_cast<double>(want[i]{acc}), g = static_cast<double>(got[i]{acc});
        scale = std::max({{scale, std::fabs(w), std::fabs(static_cast<double>(init[i]{acc}))}});
        diff = std::isnan(g) || std::isinf(g) ? INFINITY : std::max(diff, std::fabs(g - w));
        if (nj == 0 && g != w) diff = INFINITY;
      }}
      const double e = diff == 0 ? 0 : diff / (scale > 0 ? scale : 1e-300);
      if (e > err[v][{o}] || std::isnan(e)) {{ err[v][{o}] = e; at[v][{o}][0] = ni; at[v][{o}][1] = nj; }}
    }}""" for o, (_label, acc) in enumerate(outs))
    labels = ", ".join(f'"{label}"' for label, _a in outs)
    names = ", ".join(f'"{v}"' for v in variants)
    return f"""#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>
{_struct('EPI', members['EPI'])}
{_struct('EPJ', members['EPJ'])}
{_struct('FORCE', members['FORCE'])}
#include "oracle.hpp"
{''.join(f'#include "{v}.hpp"{chr(10)}' for v in variants)}
namespace {{
constexpr int kVariants = {len(variants)}, kOutputs = {len(outs)};
double err[kVariants][kOutputs];
int at[kVariants][kOutputs][2];

void compare(int v, const std::vector<FORCE>& init, const std::vector<FORCE>& want, const std::vector<FORCE>& got, int ni, int nj) {{
{cmp_outs}
}}
}}  // namespace

int main() {{
  std::mt19937_64 rng({seed});
  std::uniform_real_distribution<double> pos(0.0, {box!r}), val(0.5, 1.5);
  std::uniform_int_distribution<int> pick(0, 3);
  std::vector<EPI> epi({nmax});
  std::vector<EPJ> epj({nmax});
  std::vector<FORCE> init({nmax});
  for (int p = 0; p < {nmax}; ++p) {{
{_fill('epi', members['EPI'], box)}
{_fill('epj', members['EPJ'], box)}
{_fill('init', members['FORCE'], box)}
  }}
  const int sizes[][2] = {{{sizes}}};
  for (const auto& s : sizes) {{
    const int ni = s[0], nj = s[1];
    std::vector<FORCE> want(init.begin(), init.begin() + ni);
    Oracle{ctor}(epi.data(), ni, epj.data(), nj, want.data());
{run_variants}
  }}
  const char* variants[] = {{{names}}};
  const char* outputs[] = {{{labels}}};
  for (int v = 0; v < kVariants; ++v)
    for (int o = 0; o < kOutputs; ++o)
      std::printf("%s %s %.3e %d %d\\n", variants[v], outputs[o], err[v][o], at[v][o][0], at[v][o][1]);
  return 0;
}}
"""


def make_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="pikg-gen verify", allow_abbrev=False,
                                description="Compile every variant of KERNEL.pik the host supports, run it on random "
                                            "particles and compare with a double-precision evaluation.")
    p.add_argument("kernel", metavar="KERNEL.pik")
    p.add_argument("--target", default="auto", metavar="ISA",
                   help="reference | avx2 | avx512 | sve | auto (default: reference and every x86 ISA the host "
                        "has); sve is cross-compiled and run under QEMU at 128, 256 and 512 bits")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE", help="a kernel parameter's value")
    p.add_argument("--seed", type=int, default=2026, help="random seed (default 2026)")
    p.add_argument("--fast-math", action="store_true", help="verify the --fast-math variants (tolerance F64 1e-5, F32 3e-3)")
    p.add_argument("--cpu", metavar="NAME",
                   help="microarchitecture family the SIMD variants are sized for, as pikg-gen --cpu "
                        "(native, generic or a row of an ISA's table; default generic)")
    p.add_argument("--cxx", default=os.environ.get("CXX", "g++"), help="C++ compiler (default $CXX or g++)")
    p.add_argument("--keep", metavar="DIR", help="keep the generated program in DIR")
    return p


def main(argv: list[str]) -> int:
    try:
        args = make_parser().parse_args(argv)
    except SystemExit as e:
        return int(e.code) if isinstance(e.code, int) else 2
    from pik_gen.driver import frontend

    path = Path(args.kernel)
    try:
        source = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        sys.stderr.write(f"pikg-gen verify: error: cannot read '{path}': {e.strerror or e}\n")
        return 1
    if shutil.which(args.cxx) is None:
        sys.stderr.write(f"pikg-gen verify: error: C++ compiler '{args.cxx}' not found\n")
        return 1
    try:
        ck = frontend(source, str(path))
        k0 = build(ck, "K")
        k = run_pipeline(k0)
        oracle = run_pipeline(promote(k0))
    except CompileError as e:
        for d in e.diagnostics:
            sys.stderr.write((d.render(source) if d.span.line else f"pikg-gen: error: {d.message}") + "\n")
        return 1

    given: dict[str, float] = {}
    for item in args.param:
        name, sep, value = item.partition("=")
        try:
            given[name] = float(value)
        except ValueError:
            sep = ""
        if not sep:
            sys.stderr.write(f"pikg-gen verify: error: --param '{item}' is not NAME=VALUE\n")
            return 2
    pnames = [n for n, _t in ck.params]
    for n in given:
        if n not in pnames:
            sys.stderr.write(f"pikg-gen verify: error: kernel {path.name} has no parameter '{n}' "
                             f"(parameters: {', '.join(pnames) or 'none'})\n")
            return 2
    from pik_gen.backends.simd import all_cpus, native_cpu
    cpu = args.cpu
    if cpu == "native":
        cpu = native_cpu()
    elif cpu not in (None, "generic") and cpu not in all_cpus():
        sys.stderr.write(f"pikg-gen verify: error: unknown --cpu '{cpu}'; choose native, generic or one of "
                         f"{', '.join(all_cpus())}\n")
        return 2
    if cpu == "generic":
        cpu = None
    params = [given.get(n, PARAM_DEFAULTS.get(n, 0.5)) for n in pnames]
    box = given.get("box", PARAM_DEFAULTS["box"]) if "box" in pnames else 1.0

    scalars = {m.type.scalar for m in ck.members} | {t.scalar for _n, t in ck.params}
    scalars |= {op.type.scalar for op in k.all_ops() if op.type is not None}
    lowest = next((s for s in (Scalar.F16, Scalar.F32, Scalar.F64) if s in scalars), Scalar.F64)
    tol = (FAST_TOLERANCE if args.fast_math else TOLERANCE)[lowest]

    work = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="pikg-verify-"))
    work.mkdir(parents=True, exist_ok=True)
    try:
        try:
            host = host_isas(args.cxx, work)
        except (subprocess.CalledProcessError, OSError) as e:
            sys.stderr.write(f"pikg-gen verify: error: cannot probe the host CPU: {e}\n")
            return 1
        if args.target == "auto":
            wanted = [n for n, c in ISAS.items() if c.in_auto]
        elif args.target in ISAS:
            wanted = [args.target]
        else:
            sys.stderr.write(f"pikg-gen verify: error: unknown target '{args.target}'; choose one of "
                             f"{', '.join(TARGETS)}\n")
            return 2
        # Native variants share one program built with --cxx; an ISA the host cannot
        # execute but can emulate (Isa.runners) gets its own program, built with
        # the ISA's compiler (Isa.cxx) and run under each of its runners.
        variants, emulated = [], []
        for n in wanted:
            cls = ISAS[n]
            if cls.runners:
                missing = [t for t in [cls.cxx] + sorted({r[0] for r in cls.runners.values()}) if shutil.which(t) is None]
                if missing:
                    print(f"{path.name}: {n}: skipped, {' and '.join(missing)} not found "
                          "(make deps installs the cross compiler and the emulator)")
                    continue
                emulated.append(n)
            elif not host.get(n, n == "reference"):
                print(f"{path.name}: {n}: skipped, this CPU does not support it")
                continue
            elif cpu in getattr(cls, "UARCH", {}) and cls.UARCH[cpu].evex and not host.get("avx512"):
                print(f"{path.name}: {n}: skipped, its --cpu {cpu} variant needs AVX-512VL, which this CPU lacks")
                continue
            else:
                variants.append(n)
        if not variants and not emulated:
            return 0
        opts = Options(name="Oracle")
        (work / "oracle.hpp").write_text(render_header(oracle, [ISAS["reference"]], opts, source + "\0oracle", path.name))
        for n in variants + emulated:
            o = Options(name=n, fast_math=args.fast_math, cpu=cpu)
            (work / f"{n}.hpp").write_text(render_header(k, [ISAS[n]], o, source, path.name))
        # (label, compiler, flags, variants, runners {suffix: argv prefix})
        builds = [("verify", args.cxx, (), variants, {"": ()})] if variants else []
        builds += [(f"verify_{n}", ISAS[n].cxx or args.cxx, ISAS[n].cxx_flags, [n],
                    {f"@{label}": tuple(r) for label, r in ISAS[n].runners.items()}) for n in emulated]
        lines: list[str] = []
        for label, cxx, flags, names, runners in builds:
            (work / f"{label}.cpp").write_text(program(ck, names, params, box, args.seed))
            exe = work / label
            cc = subprocess.run([cxx, "-std=c++20", "-O2", "-Wall", "-Wextra", "-Werror", *flags, f"-I{work}",
                                 str(work / f"{label}.cpp"), "-o", str(exe)], capture_output=True, text=True)
            if cc.returncode != 0:
                sys.stderr.write(cc.stderr[-6000:])
                sys.stderr.write(f"pikg-gen verify: error: the generated code of {path.name} did not compile "
                                 f"with {cxx} (a pikg-gen bug; please report it with the kernel file)\n")
                return 1
            for suffix, prefix in runners.items():
                run = subprocess.run([*prefix, str(exe)], capture_output=True, text=True)
                if run.returncode != 0:
                    sys.stderr.write(run.stderr[-4000:])
                    how = f" under {' '.join(prefix)}" if prefix else ""
                    sys.stderr.write(f"pikg-gen verify: error: the verification program crashed{how} "
                                     f"(status {run.returncode})\n")
                    return 1
                for line in run.stdout.splitlines():
                    v, rest = line.split(" ", 1)
                    lines.append(f"{v}{suffix} {rest}")
        failed = 0
        print(f"{path.name}: max error vs double precision, max|got - want| / max|want| over "
              f"{len(SIZES) ** 2 + len(EXTRA)} (ni, nj); tolerance {tol:.0e} ({lowest.value})")
        for line in lines:
            v, out, e, ni, nj = line.split()
            bad = not float(e) <= tol
            failed += bad
            print(f"  {v:<10} {out:<10} {float(e):9.2e}  (worst at ni={ni}, nj={nj}){'  FAIL' if bad else ''}")
        ran = variants + [f"{n}@{label}" for n in emulated for label in ISAS[n].runners]
        print(f"{path.name}: {'FAILED' if failed else 'ok'} ({', '.join(ran)})")
        return 1 if failed else 0
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)
