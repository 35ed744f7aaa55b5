"""PIKG 0.4's command-line options that pikg-gen accepts with PIKG's meaning.

`-i/--input`, `--conversion-type`, `--kernel-name`, `--epi-name`, `--epj-name` and
`--force-name` are spellings in cli.py; this module adds the rest:

| option | meaning in pikg-gen |
|---|---|
| `--class-file FILE` / `--class-file EPI_FILE EPJ_FILE FORCE_FILE` | the headers that define the structs (pikg-reflect; a Fortran source with `--fortran-interface`) |
| `--c-interface [PROTOTYPE_HEADER]` | C entry points and initializer, prototype header (interfaces.py) |
| `--fortran-interface MODULE` | writes MODULE.F90 and turns on the C entry points |
| `--initializer-name NAME` | the C initializer's name (default KERNEL_initialize) |
| `--additional-text TEXT` | TEXT inserted verbatim after the includes of the generated file |
| `--spj-name NAME` | accepted; PIKG uses it only for its CUDA multiwalk kernels (a note says so) |
| `--multiwalk`, `--unroll N`, `--strip-mining N`, `--max-subwalk-size N` | tune PIKG's own code: accepted with a note saying what pikg-gen does instead |
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

from pik_gen.interfaces import C_NAME, InterfaceRequest

KERNEL_SUFFIXES = (".pik", ".pikg")


def add_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("PIKG options (PIKG 0.4's meaning; see docs/pikg-gen.md)")
    g.add_argument("--class-file", nargs="+", metavar="FILE",
                   help="header defining EPI, EPJ and FORCE, or three headers EPI_FILE EPJ_FILE FORCE_FILE "
                        "(same as --header; with --fortran-interface a Fortran source with bind(c) types)")
    g.add_argument("--c-interface", nargs="?", const=True, default=None, metavar="PROTOTYPE_HEADER",
                   help="define the C entry points KERNEL(epi, ni, epj, nj, force) and KERNEL_initialize(params) "
                        "and write their C prototypes to PROTOTYPE_HEADER (default: the output's name with .h)")
    g.add_argument("--fortran-interface", metavar="MODULE",
                   help="write MODULE.F90 (ISO_C_BINDING interfaces of the C entry points); implies the C entry points")
    g.add_argument("--initializer-name", metavar="NAME", help="name of the C initializer (default KERNEL_initialize)")
    g.add_argument("--spj-name", metavar="TYPE", help="PIKG's super-particle type for CUDA multiwalk (accepted, unused)")
    g.add_argument("--additional-text", metavar="TEXT", help="text inserted verbatim after the generated file's includes")
    g.add_argument("--multiwalk", action="store_true", help="PIKG's multiwalk code (accepted; see the note)")
    g.add_argument("--unroll", type=_positive("--unroll"), metavar="N", help="PIKG's j-loop unroll (accepted; see the note)")
    g.add_argument("--strip-mining", type=_positive("--strip-mining"), metavar="N",
                   help="PIKG's j-loop strip mining (accepted; see the note)")
    g.add_argument("--max-subwalk-size", type=_positive("--max-subwalk-size", 64), metavar="N",
                   help="PIKG's MN-Core 2 subwalk size (accepted; see the note)")
    g.add_argument("--prelude", action="append", default=[], metavar="FILE",
                   help="a header pikg-reflect includes before --header/--class-file (FDPS's particle_simulator.hpp)")


def _positive(option: str, least: int = 1):
    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{option} expects an integer, not '{text}'") from None
        if v < least:
            raise argparse.ArgumentTypeError(f"{option} must be at least {least}, not {v}")
        return v
    return parse


class OptionError(Exception):
    """A PIKG option with a bad value (exit status 1, one line)."""


@dataclass
class PikgSettings:
    headers: list[str]
    interface: InterfaceRequest | None
    additional_text: str
    kernel_from_options: str | None  # a kernel file swallowed by --class-file / --c-interface
    notes: list[str]


def interpret(args: argparse.Namespace, name: str) -> PikgSettings:
    """The PIKG options of `args` (after parsing); `name` is --kernel-name or the default."""
    notes: list[str] = []
    kernel = None
    headers: list[str] = list(args.header)
    if args.class_file:
        files = list(args.class_file)
        if len(files) in (2, 4) and files[-1].endswith(KERNEL_SUFFIXES) and not (args.kernel or args.input):
            kernel = files.pop()  # `--class-file h.hpp kernel.pikg`: the last one is the kernel
        if len(files) not in (1, 3):
            raise OptionError(f"--class-file takes one file (EPI, EPJ and FORCE in it) or three "
                              f"(EPI_FILE EPJ_FILE FORCE_FILE), not {len(files)}: {' '.join(files)}")
        headers += files
    proto = None
    c = args.c_interface is not None
    if isinstance(args.c_interface, str):
        if args.c_interface.endswith(KERNEL_SUFFIXES) and not (args.kernel or args.input or kernel):
            kernel = args.c_interface  # `--c-interface kernel.pikg`: no prototype name was given
        else:
            proto = args.c_interface
    interface = None
    if c or args.fortran_interface is not None:
        if not C_NAME.match(name):
            raise OptionError(f"--kernel-name '{name}' must be a plain C name (no '::') with "
                              f"{'--c-interface' if c else '--fortran-interface'}: it names the C entry point")
        if args.initializer_name is not None and not C_NAME.match(args.initializer_name):
            raise OptionError(f"--initializer-name '{args.initializer_name}' is not a C name")
        if args.fortran_interface is not None and not C_NAME.match(Path(args.fortran_interface).name):
            raise OptionError(f"--fortran-interface '{args.fortran_interface}' is not a Fortran module name")
        if c and proto is None:
            out = args.output or "kernel.hpp"
            p = Path(out)
            proto = str(p.with_suffix(".h")) if p.suffix else out + ".h"
            if proto == out:
                proto = out + ".h"
        interface = InterfaceRequest(c=c, prototype=proto, fortran_module=args.fortran_interface,
                                     initializer=args.initializer_name, name=name)
    elif args.initializer_name is not None:
        notes.append("--initializer-name has an effect only with --c-interface or --fortran-interface")
    if args.spj_name:
        notes.append(f"--spj-name {args.spj_name}: PIKG uses it only in its CUDA multiwalk kernels; a pik kernel "
                     "takes its j-particles (super-particles included) as --epj")
    if args.multiwalk:
        notes.append("--multiwalk: pikg-gen emits one kernel for one i/j group; the pik runtime batches groups "
                     "itself (no PIKG multiwalk interface)")
    if args.unroll is not None:
        notes.append(f"--unroll {args.unroll}: pikg-gen chooses the SIMD block shape itself; "
                     "'#pragma unroll N' in the .pik file sets the i-block unroll")
    if args.strip_mining is not None:
        notes.append(f"--strip-mining {args.strip_mining}: pikg-gen always blocks the j-loop "
                     "(EPJ locals in per-block buffers, docs/pikg-gen.md)")
    if args.max_subwalk_size is not None:
        notes.append(f"--max-subwalk-size {args.max_subwalk_size}: only PIKG's MN-Core 2 target uses it; no effect")
    return PikgSettings(headers, interface, args.additional_text or "", kernel, notes)
