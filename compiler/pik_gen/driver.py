"""The compilation pipeline as functions (used by the command line and the tests)."""
from __future__ import annotations

from dataclasses import replace
from typing import Callable

from pik_gen.backends import ISAS, TARGETS, Options, auto_isas
from pik_gen.backends.emit import render_header
from pik_gen.diagnostics import NO_SPAN, error
from pik_gen.frontend import parse
from pik_gen.ir.bind import bind_constants
from pik_gen.ir.build import build
from pik_gen.interfaces import InterfaceRequest, interface_parts
from pik_gen.ir.nodes import Kernel
from pik_gen.passes import run_pipeline
from pik_gen.pragmas import interpret as interpret_pragmas
from pik_gen.reflect import ReflectSetup, load as load_reflection
from pik_gen.sema import CheckedKernel, check


def frontend(source: str, file: str, setup: ReflectSetup | None = None) -> CheckedKernel:
    """Parse and check; with `setup`, member types may come from the user's
    header through pikg-reflect (setup.reflection is filled)."""
    module = parse(source, file)
    if setup is not None:
        setup.reflection = load_reflection(module, setup.request, setup.types, setup.notes)
    return check(module, setup.reflection if setup is not None else None)


def lower(source: str, file: str, name: str = "Kernel",
          after: Callable[[str, Kernel], None] | None = None, setup: ReflectSetup | None = None,
          constants: tuple[tuple[str, str], ...] = ()) -> Kernel:
    """Parse, check, build the IR (parameters in `constants` bound to their values)
    and run the pass pipeline."""
    k = bind_constants(build(frontend(source, file, setup), name), constants)
    if after is not None:
        after("build", k)
    return run_pipeline(k, after)


def select_isas(target: str) -> list:
    if target == "auto":
        return auto_isas()
    if target in ISAS:
        return [ISAS[target]]
    raise error(NO_SPAN, f"unknown target '{target}'; choose one of {', '.join(TARGETS)}")


def generate(source: str, file: str, target: str, options: Options,
             after: Callable[[str, Kernel], None] | None = None, setup: ReflectSetup | None = None,
             interface: InterfaceRequest | None = None, additional_text: str = "",
             side_files: dict[str, str] | None = None, pikg_call: bool = False) -> str:
    """The generated header's text. With `interface` (PIKG's --c-interface /
    --fortran-interface, interfaces.py) the text is a translation unit with C entry
    points, and the prototype header / Fortran module are put into `side_files`
    (path -> text) for the caller to write."""
    isas = select_isas(target)
    if setup is None:  # a `#pragma header` in the file still works
        setup = ReflectSetup(None, {"EPI": options.epi, "EPJ": options.epj, "FORCE": options.force})
    unroll, blend = interpret_pragmas(parse(source, file), any(i.vector for i in isas), setup.notes)
    if unroll is not None:
        options = replace(options, unroll=unroll)
    if blend:
        options = replace(options, blend=True)
    k = lower(source, file, options.name, after, setup, options.constants)
    checks = tuple(setup.reflection.layout_checks()) if setup.reflection is not None else ()
    # pikg_call: PIKG's command line (-i): operator() also takes PIKG's kernel selector
    extra: dict[str, object] = {"additional_text": additional_text, "pikg_select": pikg_call}
    if interface is not None and interface.on:
        extra.update(interface_parts(parse(source, file), k, setup, interface, file, side_files))
    return render_header(k, isas, options, source, file, checks, extra)
