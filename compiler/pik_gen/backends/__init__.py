"""Backends: one module per ISA (see base.py for how one plugs in) and the header writer."""
from __future__ import annotations

from pik_gen.backends.base import Isa, Options
from pik_gen.backends.avx2 import Avx2
from pik_gen.backends.avx512 import Avx512
from pik_gen.backends.reference import Reference
from pik_gen.backends.sve import Sve

# Every ISA pikg-gen can emit, by target name. Add new ISAs here.
ISAS: dict[str, type[Isa]] = {
    Reference.name: Reference,
    Avx2.name: Avx2,
    Avx512.name: Avx512,
    Sve.name: Sve,
}

# Targets that are part of the command line but not implemented yet.
PLANNED: tuple[str, ...] = ()


def auto_isas() -> list[type[Isa]]:
    """The variants `--target auto` puts in one header, best first."""
    return sorted((c for c in ISAS.values() if c.in_auto), key=lambda c: -c.preference)


__all__ = ["ISAS", "PLANNED", "Isa", "Options", "auto_isas"]
