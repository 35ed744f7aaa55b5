"""Backends: one module per ISA (see base.py and docs/adding-a-target.md) and the header writer.

Every module of this package is imported here and every `Isa` subclass with a
`name` becomes a target, so a new ISA is its module alone; the driver, the
command line and `pikg-gen verify` take their lists from `ISAS`.
"""
from __future__ import annotations

import importlib
import pkgutil

from pik_gen.backends.base import Isa, Options


def _discover() -> dict[str, type[Isa]]:
    found: dict[str, type[Isa]] = {}
    for mod in pkgutil.iter_modules(__path__):
        module = importlib.import_module(f"{__name__}.{mod.name}")
        for obj in vars(module).values():
            if isinstance(obj, type) and issubclass(obj, Isa) and obj.__dict__.get("name"):
                found[obj.name] = obj
    # the auto variants from the reference up, then the others
    return dict(sorted(found.items(), key=lambda kv: (not kv[1].in_auto, kv[1].preference, kv[0])))


# Every ISA pikg-gen can emit, by target name.
ISAS: dict[str, type[Isa]] = _discover()

# What --target accepts: every ISA, and `auto` (the in_auto variants with run-time dispatch).
TARGETS: tuple[str, ...] = tuple(ISAS) + ("auto",)


def auto_isas() -> list[type[Isa]]:
    """The variants `--target auto` puts in one header, best first."""
    return sorted((c for c in ISAS.values() if c.in_auto), key=lambda c: -c.preference)


__all__ = ["ISAS", "TARGETS", "Isa", "Options", "auto_isas"]
