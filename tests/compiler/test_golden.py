"""Generated code is pinned: every .pik in the tree x every target x the option
variants the CMake files use (plus --fast-math, --emit-c and a fixed sample of
fuzz mutants that compile) must give exactly the recorded output. The record is
the SHA-256 of each case's output and of its source (golden/outputs.sha256),
so a change of pikg-gen that changes one byte of one header fails here. A case
whose source was added or edited after the record is not compared until it is
recorded again.

    python3 test_golden.py --record      rewrite golden/outputs.sha256 (only after
                                         checking the new output, see docs/adding-a-target.md)
    python3 test_golden.py --dump DIR    write every output to DIR/<case> (diff two dumps)
"""
from __future__ import annotations

import hashlib
import json
import random
import sys
import tempfile
from pathlib import Path

from conftest import ROOT, run_cli

HERE = Path(__file__).resolve().parent
RECORD = HERE / "golden" / "outputs.sha256"
from pik_gen.backends import TARGETS  # noqa: E402  every target, a new ISA included
N_MUTANTS = 40  # compiling fuzz mutants (odd corners of every backend)
MUTANT_SOURCES = ("kernels/gravity.pik", "kernels/gravity_f64.pik", "kernels/gravity_quadrupole.pik", "kernels/lj.pik",
                  "kernels/sph_density.pik", "kernels/sph_force_disph.pik", "kernels/sph_force_ssph.pik",
                  "tests/compiler/pik/pikg_style.pik")


def pik_files() -> list[Path]:
    files = [*ROOT.glob("kernels/*.pik"), *ROOT.glob("tests/**/*.pik"), *ROOT.glob("examples/**/*.pik"),
             *ROOT.glob("bench/**/*.pik")]
    # tests/reflect reads its members from a C++ header through pikg-reflect, which may not be built
    return sorted(f for f in set(files) if "reflect" not in f.relative_to(ROOT).parts)


def variants(path: Path) -> list[tuple[str, tuple[str, ...]]]:
    """(label, extra options): the defaults, --fast-math, --emit-c and, for the SPH
    kernels, every --const binding of examples/sph and bench/sph; the error
    corpus once (its diagnostics come from the front end)."""
    if path.parent.name == "errors":
        return [("default", ())]
    out = [("default", ()), ("fast", ("--fast-math",)), ("emitc", ("--emit-c", "--name", "ns::K"))]
    if path.stem.startswith("sph_"):
        for dim in (2, 3):
            for shape in (0, 1, 2):
                out.append((f"const-d{dim}-s{shape}", ("--const", f"shape={shape}", "--const", f"dim={dim}")))
    return out


def mutants() -> list[tuple[str, str]]:
    """A fixed sample of fuzz mutants of the kernels that compile for the reference."""
    from pik_gen.backends import Options
    from pik_gen.diagnostics import CompileError
    from pik_gen.driver import generate
    from test_fuzz import mutate

    rng = random.Random(17)
    sources = [(ROOT / p).read_text() for p in MUTANT_SOURCES]
    out: list[tuple[str, str]] = []
    tries = 0
    while len(out) < N_MUTANTS and tries < 20000:
        tries += 1
        src = mutate(rng.choice(sources), rng)
        if rng.random() < 0.3:
            src = mutate(src, rng)
        try:
            generate(src, "m.pik", "reference", Options("M"))
        except CompileError:
            continue
        out.append((f"mutant{len(out):02d}", src))
    return out


def inline_kernels() -> list[tuple[str, str]]:
    """The kernels other tests write inline (special values, SVE extras, op checks)."""
    import test_simd_opcheck
    import test_special_values
    import test_sve

    out = [(f"special-{form}-{T}", src.format(T=T)) for form, src in sorted(test_special_values.KERNELS.items())
           for T in ("F32", "F64")]
    out += [(f"sve-{name}", src) for name, src in sorted(test_sve.EXTRA.items())]
    out += [(f"opcheck-{name.lower()}", getattr(test_simd_opcheck, name)) for name in ("MIXED", "TABLE", "TRANSCENDENTAL")]
    return out


def output(src: Path, target: str, extra: tuple[str, ...], tmp: Path) -> str:
    """The header pikg-gen writes (or its status and diagnostics when it fails)."""
    out = tmp / "out.hpp"
    out.unlink(missing_ok=True)
    rel = src.relative_to(ROOT) if src.is_absolute() else src
    rc, stdout, stderr = run_cli([str(rel), "-o", str(out), "--target", target, *extra])
    text = out.read_text() if out.exists() else ""
    return f"rc={rc}\n{stderr}{stdout}\n{text}"


def cases(tmp: Path):
    """(case name, source text, output) for the whole corpus."""
    import os

    cwd = os.getcwd()
    os.chdir(ROOT)  # paths in the banner are relative to the repository
    try:
        for p in pik_files():
            for label, extra in variants(p):
                for t in TARGETS:
                    yield f"{p.relative_to(ROOT)}:{t}:{label}", p.read_text(errors="replace"), output(p, t, extra, tmp)
        os.chdir(tmp)  # inline kernels and mutants by a relative name: the same banner in every run
        for name, src in inline_kernels() + mutants():
            f = Path(f"{name}.pik")
            f.write_text(src)
            for t in TARGETS:
                yield f"{name}:{t}", src, output(f, t, (), tmp)
    finally:
        os.chdir(cwd)


def digest(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()


def record(source: str, out: str) -> str:
    """A case's record: the digests of its source (a prefix) and of its output."""
    return digest(source)[:16] + ":" + digest(out)


def test_generated_code_is_unchanged(tmp_path: Path) -> None:
    want = json.loads(RECORD.read_text())
    got = {name: record(src, out) for name, src, out in cases(tmp_path)}
    same_source = [n for n in want.keys() & got.keys() if want[n].split(":")[0] == got[n].split(":")[0]]
    changed = sorted(n for n in same_source if want[n] != got[n])
    # a case is gone when pikg-gen no longer produces it for a file that still exists
    missing = sorted(n for n in want.keys() - got.keys() if n.startswith(("mutant", "special", "sve-", "opcheck"))
                     or (ROOT / n.split(":")[0]).exists())
    assert not changed and not missing, (
        f"{len(changed)} outputs changed (first: {changed[:8]}), {len(missing)} cases gone {missing[:4]}; "
        "see the header of test_golden.py")
    # a .pik file added or edited since the record has nothing to compare with (--record it);
    # most of the corpus must still be compared
    assert len(same_source) >= 0.5 * len(want), f"only {len(same_source)} of {len(want)} recorded cases compared"


def main(argv: list[str]) -> int:
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        if argv[:1] == ["--record"]:
            RECORD.parent.mkdir(exist_ok=True)
            rec = {name: record(src, out) for name, src, out in cases(tmp)}
            RECORD.write_text(json.dumps(rec, indent=0, sort_keys=True) + "\n")
            print(f"recorded {len(rec)} outputs in {RECORD}")
            return 0
        if argv[:1] == ["--dump"] and len(argv) == 2:
            dst = Path(argv[1])
            dst.mkdir(parents=True, exist_ok=True)
            n = 0
            for name, _src, out in cases(tmp):
                (dst / name.replace("/", "__")).write_text(out)
                n += 1
            print(f"wrote {n} outputs to {dst}")
            return 0
    print(__doc__)
    return 2


if __name__ == "__main__":
    sys.path.insert(0, str(HERE))
    raise SystemExit(main(sys.argv[1:]))
