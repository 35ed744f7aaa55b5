"""Command line of pikg-gen.

    pikg-gen KERNEL.pik -o OUT.hpp --target ISA|auto [options]   (the ISAs: backends.ISAS)

PIKG's spellings are accepted too (-i, --conversion-type, --kernel-name,
--epi-name, --epj-name, --force-name), so an FDPS/PIKG Makefile works by changing
the program name. User mistakes end in `file:line:col: error: ...` and exit
status 1; command-line mistakes in a usage message and exit status 2.
"""
from __future__ import annotations

import argparse
import os
import re
import sys
import tempfile
from pathlib import Path

from pik_gen import __version__
from pik_gen.backends import ISAS, TARGETS, Options
from pik_gen.diagnostics import CompileError
from pik_gen.driver import generate
from pik_gen.ir.printer import format_kernel
from pik_gen.passes import PASS_NAMES
from pik_gen.pikg_options import OptionError, add_options as add_pikg_options, interpret as interpret_pikg
from pik_gen.reflect import HeaderRequest, ReflectSetup

CONVERSION_TYPES = {c.pikg_name: name for name, c in ISAS.items() if c.pikg_name}
IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(::[A-Za-z_][A-Za-z0-9_]*)*$")
DUMP_CHOICES = ("build",) + PASS_NAMES + ("all",)


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # type: ignore[override]
        self.print_usage(sys.stderr)
        sys.stderr.write(f"pikg-gen: error: {message}\n")
        raise SystemExit(2)


def make_parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="pikg-gen", allow_abbrev=False,
        description="Compile a .pik pairwise-interaction kernel into a C++ header.",
        epilog="Targets: " + ", ".join(f"{n} ({c.summary})" for n, c in ISAS.items())
               + ", auto (every x86 variant with run-time CPU dispatch). See docs/pikg-gen.md.",
    )
    p.add_argument("kernel", nargs="?", metavar="KERNEL.pik", help="the kernel source")
    p.add_argument("-i", "--input", dest="input", metavar="KERNEL.pik", help="the kernel source (PIKG spelling)")
    p.add_argument("-o", "--output", metavar="OUT.hpp", help="the header to write (atomically)")
    p.add_argument("--target", metavar="ISA", help=" | ".join(TARGETS) + " (default: auto)")
    p.add_argument("--conversion-type", metavar="TYPE", help="PIKG spelling of --target: " + " | ".join(CONVERSION_TYPES))
    p.add_argument("--name", "--kernel-name", dest="name", metavar="CLASS",
                   help="generated class name, may be qualified (sim::Gravity); default: the file stem")
    p.add_argument("--epi", "--epi-name", dest="epi", default="EPI", metavar="TYPE", help="i-particle type (default EPI)")
    p.add_argument("--epj", "--epj-name", dest="epj", default="EPJ", metavar="TYPE", help="j-particle type (default EPJ)")
    p.add_argument("--force", "--force-name", dest="force", default="FORCE", metavar="TYPE", help="result type (default FORCE)")
    p.add_argument("--emit-c", action="store_true", help="also emit an extern \"C\" entry point pik_<CLASS>(...)")
    p.add_argument("--cpu", "--march", dest="cpu", metavar="NAME",
                   help="microarchitecture family the SIMD loop shape is sized for (register-pressure model, "
                        "docs/simd.md): native (this machine's), generic (default) or one of the ISA tables' "
                        "families, e.g. znver3, skylake-avx512, sapphirerapids, a64fx")
    p.add_argument("--fast-math", action="store_true", help="allow approximate rsqrt/inv on SIMD targets (noted in the banner)")
    p.add_argument("--dump-ir-after", metavar="PASS", action="append", default=[],
                   help=f"print the IR after PASS to stdout ({', '.join(DUMP_CHOICES)})")
    p.add_argument("--header", metavar="particle.hpp", action="append", default=[],
                   help="the user's particle header: member types and layout checks from pikg-reflect "
                        "(or name it in the .pik file: #pragma header \"particle.hpp\"); repeatable, "
                        "included in order")
    p.add_argument("-I", dest="include_dirs", action="append", default=[], metavar="DIR",
                   help="include directory for reading --header")
    p.add_argument("-D", dest="defines", action="append", default=[], metavar="NAME[=VALUE]",
                   help="macro definition for reading --header")
    p.add_argument("--const", dest="constants", action="append", default=[], metavar="NAME=VALUE",
                   help="bind parameter NAME to a compile-time constant (it leaves the constructor; "
                        "code depending on it is folded)")
    p.add_argument("--version", action="version", version=f"pikg-gen {__version__}")
    add_pikg_options(p)
    return p


_TYPE_TOKEN = re.compile(r"\s*(::|[A-Za-z_][A-Za-z0-9_]*|[0-9]+[uUlL]*|<|>|,|\*|&|\(|\))")


def type_name_problem(text: str) -> str:
    """Why `text` is not a C++ type name as --epi/--epj/--force take it (a qualified
    name, template arguments allowed: `Body<double>`, `sim::P<float, 3>::Meta`); "" if it is."""
    if not text.strip():
        return "it is empty"
    pos, depth, tokens = 0, 0, []
    while pos < len(text):
        m = _TYPE_TOKEN.match(text, pos)
        if not m or not m.group(1):
            if text[pos:].strip() == "":
                break
            return f"unexpected '{text[pos:].strip()[0]}'"
        tok = m.group(1)
        if depth == 0 and tokens and re.match(r"[A-Za-z_]", tok) and re.match(r"[A-Za-z_]", tokens[-1]):
            return f"two names in a row ('{tokens[-1]} {tok}')"
        depth += {"<": 1, ">": -1}.get(tok, 0)
        if depth < 0:
            return "unbalanced '>'"
        tokens.append(tok)
        pos = m.end()
    if depth:
        return "unbalanced '<'"
    if not re.match(r"[A-Za-z_]", tokens[0] if tokens[0] != "::" else (tokens[1:] or ["?"])[0]):
        return "it must start with a name"
    if tokens[-1] in ("::", ",", "<"):
        return f"it ends in '{tokens[-1]}'"
    return ""


def _fail(message: str) -> int:
    sys.stderr.write(f"pikg-gen: error: {message}\n")
    return 1


def _print_notes(notes: list[str]) -> None:
    for n in notes:
        sys.stderr.write(f"pikg-gen: note: {n}\n")


def write_atomically(path: Path, text: str) -> None:
    """Write via a temporary file in the same folder and rename: never a half-written file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=str(path.parent))
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def default_name(path: str) -> str:
    stem = re.sub(r"[^A-Za-z0-9_]", "_", Path(path).stem) or "Kernel"
    return stem if not stem[0].isdigit() else f"Kernel_{stem}"


def run(argv: list[str]) -> int:
    if argv[:1] == ["verify"]:  # pikg-gen verify KERNEL.pik: see verify.py
        from pik_gen.verify import main as verify_main

        return verify_main(argv[1:])
    args = make_parser().parse_args(argv)
    try:  # PIKG's default kernel name is Kernel: with the C interface it names the entry point
        pikg = interpret_pikg(args, args.name or "Kernel")
    except OptionError as e:
        return _fail(str(e))
    if pikg.kernel_from_options:
        args.kernel = pikg.kernel_from_options
    src_path = args.kernel or args.input
    if args.kernel and args.input:
        return _fail("give the kernel file either as an argument or with -i, not both")
    if not src_path:
        return _fail("no kernel file given (pikg-gen KERNEL.pik -o OUT.hpp --target ISA)")
    if args.target and args.conversion_type:
        return _fail("give either --target or --conversion-type, not both")
    if args.conversion_type:
        if args.conversion_type not in CONVERSION_TYPES:
            return _fail(f"unknown --conversion-type '{args.conversion_type}'; choose one of {', '.join(CONVERSION_TYPES)}")
        target = CONVERSION_TYPES[args.conversion_type]
    else:
        target = args.target or "auto"
    if target not in TARGETS:
        return _fail(f"unknown target '{target}'; choose one of {', '.join(TARGETS)}")
    for d in args.dump_ir_after:
        if d not in DUMP_CHOICES:
            return _fail(f"unknown pass '{d}' for --dump-ir-after; choose one of {', '.join(DUMP_CHOICES)}")
    if not args.output and args.input and not args.dump_ir_after:
        args.output = "kernel.hpp"  # PIKG's default output (with PIKG's spelling -i)
    if not args.output and not args.dump_ir_after:
        return _fail("no output file given (-o OUT.hpp)")
    # the class: --name; else PIKG's default Kernel when the kernel came with PIKG's -i; else the file stem
    name = args.name or ("Kernel" if args.input else default_name(src_path))
    if not IDENT.match(name):
        return _fail(f"--name '{name}' is not a C++ name (letters, digits, '_', optionally qualified with '::')")
    for what, value in (("--epi", args.epi), ("--epj", args.epj), ("--force", args.force)):
        why = type_name_problem(value)
        if why:
            return _fail(f"{what} '{value}' is not a C++ name (a type, qualified with '::', template "
                         f"arguments allowed): {why}")
    try:
        raw = Path(src_path).read_bytes()
    except OSError as e:
        return _fail(f"cannot read '{src_path}': {e.strerror or e}")
    try:
        source = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        line = raw[: e.start].count(b"\n") + 1
        col = e.start - (raw.rfind(b"\n", 0, e.start) + 1) + 1
        sys.stderr.write(f"{src_path}:{line}:{col}: error: the file is not UTF-8 text\n")
        return 1
    setup = ReflectSetup(HeaderRequest(tuple(pikg.headers), tuple(args.include_dirs), tuple(args.defines),
                                       tuple(args.prelude), args.output,
                                       pikg.interface.class_name if pikg.interface is not None else name),
                         {"EPI": args.epi, "EPJ": args.epj, "FORCE": args.force})

    dumps = set(args.dump_ir_after)

    def after(pass_name: str, kernel) -> None:
        if "all" in dumps or pass_name in dumps:
            sys.stdout.write(f"; IR after {pass_name}\n{format_kernel(kernel)}")

    constants = []
    for c in args.constants:
        cname, eq, cvalue = c.partition("=")
        if not eq or not re.match(r"^[A-Za-z_][A-Za-z0-9_]*$", cname) or not cvalue:
            return _fail(f"--const '{c}': expected NAME=VALUE")
        constants.append((cname, cvalue))
    if pikg.interface is not None:
        name = pikg.interface.class_name  # PIKG's rule: the C entry point is NAME, the class NAME_
    cpu = args.cpu
    if cpu is not None:
        from pik_gen.backends.simd import all_cpus, native_cpu
        if cpu == "native":
            cpu = native_cpu()
        elif cpu != "generic" and cpu not in all_cpus():
            return _fail(f"unknown --cpu '{cpu}'; choose native, generic or one of {', '.join(all_cpus())}")
        if cpu == "generic":
            cpu = None
    options = Options(name=name, epi=args.epi, epj=args.epj, force=args.force,
                      fast_math=args.fast_math, emit_c=args.emit_c, constants=tuple(constants), cpu=cpu)
    try:
        side_files: dict[str, str] = {}
        text = generate(source, src_path, target, options, after, setup, pikg.interface,
                        pikg.additional_text, side_files, pikg_call=bool(args.input))
    except CompileError as e:
        _print_notes(pikg.notes + setup.notes)
        for d in e.diagnostics:
            if d.span.line == 0:
                sys.stderr.write(f"pikg-gen: error: {d.message}\n")
            else:
                sys.stderr.write(d.render(source) + "\n")
        return 1
    _print_notes(pikg.notes + setup.notes)
    if args.output:
        for path, body in [(args.output, text), *side_files.items()]:
            try:
                write_atomically(Path(path), body)
            except OSError as e:
                return _fail(f"cannot write '{path}': {e.strerror or e}")
    return 0


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    try:
        return run(argv)
    except SystemExit as e:
        return int(e.code) if isinstance(e.code, int) else 2
    except KeyboardInterrupt:
        return 130
    except Exception as e:  # last resort: a compiler bug must still not show a traceback
        sys.stderr.write(f"pikg-gen: internal error: {type(e).__name__}: {e}\n"
                         "pikg-gen: this is a bug in pikg-gen; please report it with the kernel file\n")
        return 3
