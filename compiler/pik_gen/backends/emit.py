"""Write the generated header: one implementation class per ISA variant (from the
ISA's template) and the public class that forwards or dispatches to them."""
from __future__ import annotations

import functools
import hashlib
from pathlib import Path

import jinja2

from pik_gen import __version__
from pik_gen.backends.base import Isa, Options
from pik_gen.ir.nodes import Kernel

TEMPLATES = Path(__file__).resolve().parent.parent / "templates"


@functools.lru_cache(maxsize=1)
def environment() -> jinja2.Environment:
    """The template environment (built once: compiling templates dominates small runs)."""
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(TEMPLATES)),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        autoescape=False,
    )


def render_header(k: Kernel, isas: list[type[Isa]], options: Options, source_text: str, source_name: str,
                  layout_checks: tuple[str, ...] = (), extra: dict[str, object] | None = None) -> str:
    """layout_checks: static_asserts on the particle structs (from pikg-reflect);
    extra: the C/Fortran interface's parts (interfaces.py) and --additional-text."""
    env = environment()
    flat = options.name.replace("::", "_")
    digest = hashlib.sha256(
        (source_text + "\0" + repr(options) + "\0" + __version__).encode()
    ).hexdigest()[:8]
    variants, members = [], []
    for cls in isas:
        isa = cls(options)
        impl = f"{flat}_{cls.name}_{digest}"
        ctx = isa.context(k, impl)
        ctx["public_name"] = options.name
        variants.append(env.get_template(cls.template).render(**ctx))
        members.append({"impl": impl, "field": f"{cls.name}_", "check": isa.variant_check()})
        params = ctx["params"]
    *namespaces, class_name = options.name.split("::")
    fast = ""
    if options.fast_math:
        # the reference is the semantic definition: --fast-math never changes it
        simd = [c.isa_label for c in isas if c.vector]
        fast = ("no effect on the reference target (exact 1/sqrt and 1/x)" if not simd else
                f"approximate rsqrt/inv allowed in {', '.join(simd)}"
                + ("; no effect on the reference variant" if len(simd) < len(isas) else ""))
    return env.get_template("header.hpp.j2").render(
        version=__version__, source=source_name, public_name=options.name, class_name=class_name,
        namespaces=namespaces, isa_summary=", ".join(c.isa_label for c in isas) + (" (run-time dispatch)" if len(isas) > 1 else ""),
        fast_math=fast, epi=options.epi, epj=options.epj, force=options.force, params=params,
        variants=variants, members=members, emit_c=options.emit_c, c_name=f"pik_{flat}",
        includes=sorted({h for c in isas for h in c.includes}),
        ignores=sorted({w for c in isas for w in c.gcc_ignores}),
        layout_checks=list(layout_checks),
        **{"translation_unit": False, "pikg_select": False, "additional_text": "", "c_structs": "", "c_entry_points": "", **(extra or {})},
    )
