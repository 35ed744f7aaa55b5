"""PIKG's C and Fortran interfaces (`--c-interface [HEADER]`, `--fortran-interface MODULE`).

With either option, PIKG's meaning (PIKG 0.4's documented behaviour) is kept:

* the generated file is a translation unit (compile it once, as PIKG's `kernel.cpp`):
  the kernel class is `NAME_` and two C entry points are defined,
  `void NAME(const EPI* epi, int ni, const EPJ* epj, int nj, FORCE* force)` and
  `void NAME_initialize(params...)` (name changed by `--initializer-name`), which
  stores the kernel parameters (`F64 eps2` -> `double eps2_`) for later calls;
* the particle types the C or Fortran caller defines (`typedef struct {...} particle;`,
  `type, bind(c) :: epi_grav`) are restated in C++ with the same layout: from the
  class file when one is read (every member at its offset, checked by `offsetof`
  assertions), else from the `.pik` declarations in declaration order (PIKG's rule:
  the caller's struct holds exactly the declared members, in that order);
* `--c-interface` writes a C prototype header (default: the output's name with `.h`),
  `--fortran-interface MODULE` writes `MODULE.F90`, a module of `bind(c)` interfaces
  with ISO_C_BINDING kinds; the particle arrays are passed as `type(c_ptr)`
  (`c_loc(...)`), `ni`/`nj` and the parameters by value.

A Fortran class file (PIKG reads `--class-file` as Fortran source with
`--fortran-interface`) is read here: `type[, bind(c)] :: NAME` ... `end type` with
`real(kind=c_double)`, `integer(kind=c_int)`, `type(fdps_f64vec)`-style members
(`read_fortran_types`).
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from pik_gen import __version__
from pik_gen.diagnostics import NO_SPAN, Span, error
from pik_gen.frontend import ast
from pik_gen.reflect import ROLES, ReflectedField, ReflectedRecord, Reflection
from pik_gen.types import Scalar, Type, parse_type_name

C_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
CXX_OF_CODE = {
    "f64": "double", "f32": "float", "s64": "long long", "s32": "int", "u64": "unsigned long long",
    "u32": "unsigned int", "s16": "short", "u16": "unsigned short", "s8": "signed char",
    "u8": "unsigned char", "bool": "bool",
}
CODE_OF_SCALAR = {Scalar.F64: "f64", Scalar.F32: "f32", Scalar.S64: "s64", Scalar.S32: "s32",
                  Scalar.U64: "u64", Scalar.U32: "u32"}
SIZE_OF_CODE = {"f64": 8, "f32": 4, "s64": 8, "s32": 4, "u64": 8, "u32": 4}
C_PARAM = {"F64": "double", "F32": "float", "S64": "long long", "S32": "int",
           "U64": "unsigned long long", "U32": "unsigned int"}
# Fortran has no unsigned integers: U64/U32 parameters travel in the signed kind of their width
FORTRAN_PARAM = {"F64": "real(kind=c_double)", "F32": "real(kind=c_float)", "S64": "integer(kind=c_long_long)",
                 "S32": "integer(kind=c_int)", "U64": "integer(kind=c_long_long)", "U32": "integer(kind=c_int)"}


@dataclass(frozen=True)
class InterfaceRequest:
    """What the command line asks for."""

    c: bool = False                  # --c-interface
    prototype: str | None = None     # its PROTOTYPE_HEADER (default: output with .h)
    fortran_module: str | None = None  # --fortran-interface MODULE
    initializer: str | None = None   # --initializer-name (default NAME_initialize)
    name: str = "Kernel"             # the C entry point (--kernel-name)

    @property
    def on(self) -> bool:
        return self.c or self.fortran_module is not None

    @property
    def init_name(self) -> str:
        return self.initializer or f"{self.name}_initialize"

    @property
    def class_name(self) -> str:
        return f"{self.name}_"


@dataclass(frozen=True)
class _Member:
    name: str
    cxx: str      # the declaration's type part (e.g. "double", "pik_c::vec3<float>")
    array: str    # "" or "[3]" (C arrays, opaque bytes)
    offset: int   # -1: in declaration order (no layout known)
    size: int
    align: int


def _vector_type(code: str, count: int) -> str:
    return f"pik_c::vec{count}<{CXX_OF_CODE[code]}>"


def _members_from_record(rec: ReflectedRecord) -> list[_Member]:
    out = []
    for f in sorted(rec.fields.values(), key=lambda f: f.offset):
        out.append(_member_from_field(f))
    return out


def _member_from_field(f: ReflectedField) -> _Member:
    code = f.scalar_code
    if f.kind == "scalar" and code in CXX_OF_CODE:
        return _Member(f.name, CXX_OF_CODE[code], "", f.offset, f.size, f.align)
    if f.kind == "vector" and code in CXX_OF_CODE and f.indexed:
        return _Member(f.name, CXX_OF_CODE[code], f"[{f.count}]", f.offset, f.size, f.align)
    if f.kind == "vector" and code in CXX_OF_CODE:
        return _Member(f.name, _vector_type(code, f.count), "", f.offset, f.size, f.align)
    # anything a kernel cannot read keeps its bytes and alignment
    return _Member(f.name, f"alignas({max(f.align, 1)}) unsigned char", f"[{max(f.size, 1)}]", f.offset, f.size, f.align)


def _members_from_declarations(module: ast.Module, role: str) -> list[_Member]:
    out, seen = [], set()
    for s in module.decls:
        if isinstance(s, ast.MemberDecl) and s.role == role and not s.local and s.member not in seen:
            seen.add(s.member)
            t = parse_type_name(s.type_name)
            if t is None:
                continue  # sema reports the unknown type
            code = CODE_OF_SCALAR.get(t.scalar)
            if code is None:
                raise error(s.type_span, f"a {s.type_name} member cannot be passed through the C interface "
                            "(its types are F64, F32, S64, S32, U64, U32 and F64vec/F32vec forms)")
            cxx = _vector_type(code, t.lanes) if t.lanes > 1 else CXX_OF_CODE[code]
            out.append(_Member(s.member, cxx, "", -1, SIZE_OF_CODE[code] * t.lanes, SIZE_OF_CODE[code]))
    return out


def _struct_text(cxx_name: str, members: list[_Member], size: int | None) -> str:
    lines = [f"struct {cxx_name} {{"]
    at, pad = 0, 0
    for m in members:
        if m.offset >= 0 and m.offset > at:
            lines.append(f"  unsigned char pik_pad{pad}_[{m.offset - at}];")
            pad += 1
            at = m.offset
        lines.append(f"  {m.cxx} {m.name}{m.array};")
        at = (m.offset if m.offset >= 0 else at) + m.size
    if size is not None and size > at:
        # tail padding the compiler may not add by itself (explicitly aligned originals)
        lines.append(f"  unsigned char pik_pad{pad}_[{size - at}];")
    lines.append("};")
    return "\n".join(lines)


def c_structs(module: ast.Module, types: dict[str, str], reflection: Reflection | None) -> str:
    """C++ definitions of the caller's particle types (those that are plain C names)."""
    done: dict[str, list[_Member]] = {}
    sizes: dict[str, int | None] = {}
    for role in ROLES:
        name = types[role]
        if not C_NAME.match(name):
            continue  # a C++ type (PS::SPJMonopole, ns::Body<double>): the user's header defines it
        if reflection is not None:
            rec = reflection.records[role]
            members, size = _members_from_record(rec), rec.size
        else:
            members, size = _members_from_declarations(module, role), None
        if name in done:
            if reflection is None:  # one type for several roles: the union, in role then declaration order
                have = {m.name: m for m in done[name]}
                for m in members:
                    if m.name in have and have[m.name].cxx != m.cxx:
                        raise error(NO_SPAN, f"member '{m.name}' of '{name}' is declared with two types "
                                    f"({have[m.name].cxx}, {m.cxx}) for different roles")
                    if m.name not in have:
                        done[name].append(m)
            continue
        done[name], sizes[name] = members, size
    if not done:
        return ""
    parts = ["// The caller's particle types, restated for C++ with the same layout (C/Fortran interface).",
             "namespace pik_c {",
             "template <class T> struct vec2 { T x, y; };",
             "template <class T> struct vec3 { T x, y, z; };",
             "template <class T> struct vec4 { T x, y, z, w; };",
             "}  // namespace pik_c"]
    for name, members in done.items():
        if not members:
            members = [_Member("pik_empty_", "unsigned char", "", -1, 1, 1)]
        parts.append(_struct_text(name, members, sizes[name]))
    return "\n".join(parts) + "\n"


def c_entry_points(req: InterfaceRequest, types: dict[str, str], params: list[tuple[str, str]]) -> str:
    """The extern "C" initializer and kernel call; params: (.pik type name, name)."""
    store = [f"static {C_PARAM[t]} pik_c_{req.name}_{n} = 0;" for t, n in params]
    init_args = ", ".join(f"{C_PARAM[t]} {n}_" for t, n in params) or "void"
    init_body = "".join(f"  pik_c_{req.name}_{n} = {n}_;\n" for _t, n in params)
    ctor = ", ".join(f"pik_c_{req.name}_{n}" for _t, n in params)
    obj = f"const {req.class_name} kernel({ctor});" if params else f"const {req.class_name} kernel;"
    return ("\n// C interface (PIKG's --c-interface / --fortran-interface): the parameters given to\n"
            f"// {req.init_name}() are used by every later call of {req.name}().\n"
            + "\n".join(store) + ("\n" if store else "")
            + 'extern "C" {\n'
            f"void {req.init_name}({init_args}) {{\n{init_body}}}\n"
            f"void {req.name}(const {types['EPI']}* epi, int ni, const {types['EPJ']}* epj, int nj, "
            f"{types['FORCE']}* force) {{\n"
            f"  {obj}\n  kernel(epi, ni, epj, nj, force);\n}}\n"
            '}  // extern "C"\n')


def prototype_header(req: InterfaceRequest, params: list[tuple[str, str]], source: str, file_name: str) -> str:
    guard = "PIKG_GEN_" + re.sub(r"[^A-Za-z0-9]", "_", Path(file_name).name).upper()
    args = ", ".join(f"{C_PARAM[t]} {n}_" for t, n in params) or "void"
    return (f"/* {req.name}: C interface of the kernel in {source}, generated by pikg-gen {__version__}. Do not edit. */\n"
            f"#ifndef {guard}\n#define {guard}\n"
            "#ifdef __cplusplus\nextern \"C\" {\n#endif\n"
            f"/* epi, epj, force: arrays of the particle types the kernel was generated for; accumulates into force[0, ni) */\n"
            f"void {req.name}(const void* epi, int ni, const void* epj, int nj, void* force);\n"
            f"/* sets the kernel parameters for later calls of {req.name} */\n"
            f"void {req.init_name}({args});\n"
            "#ifdef __cplusplus\n}\n#endif\n"
            f"#endif\n")


def _fortran_lines(head: str, args: list[str], tail: str) -> list[str]:
    """`head(a, b, ...) tail` split over continuation lines (free form, 132 columns)."""
    lines = [f"{head}( &"]
    for i, a in enumerate(args):
        lines.append(f"      {a}{', &' if i + 1 < len(args) else ') &'}")
    if not args:
        lines[0] = f"{head}() &"
    lines.append(f"      {tail}")
    return lines


def fortran_module(req: InterfaceRequest, params: list[tuple[str, str]], source: str) -> str:
    module = Path(req.fortran_module or "pikg_module").name
    ind = "  "
    out = [f"! {module}: Fortran interface of the kernel in {source}, generated by pikg-gen {__version__}. Do not edit.",
           f"! call {req.init_name}(params) once, then {req.name}(c_loc(epi), ni, c_loc(epj), nj, c_loc(force));",
           "! the particle types are bind(c) derived types with the members the kernel was generated for.",
           f"module {module}",
           f"{ind}use, intrinsic :: iso_c_binding",
           f"{ind}implicit none",
           f"{ind}interface"]
    sub = _fortran_lines(f"{ind * 2}subroutine {req.name}", ["epi", "ni", "epj", "nj", "force"],
                         f"bind(c, name='{req.name}')")
    out += sub + [f"{ind * 3}import :: c_ptr, c_int",
                  f"{ind * 3}type(c_ptr), value :: epi, epj, force",
                  f"{ind * 3}integer(kind=c_int), value :: ni, nj",
                  f"{ind * 2}end subroutine {req.name}"]
    out += _fortran_lines(f"{ind * 2}subroutine {req.init_name}", [n for _t, n in params],
                          f"bind(c, name='{req.init_name}')")
    kinds = sorted({FORTRAN_PARAM[t].split("=")[1].rstrip(")") for t, _n in params})
    if kinds:
        out.append(f"{ind * 3}import :: {', '.join(kinds)}")
    for t, n in params:
        out.append(f"{ind * 3}{FORTRAN_PARAM[t]}, value :: {n}")
    out += [f"{ind * 2}end subroutine {req.init_name}", f"{ind}end interface", f"end module {module}", ""]
    return "\n".join(out)


# ---------------------------------------------------------------- Fortran class files

_F_TYPE_START = re.compile(r"^\s*type\s*(,[^:]*)?::\s*([A-Za-z_][A-Za-z0-9_]*)", re.I)
_F_TYPE_END = re.compile(r"^\s*end\s*type\b", re.I)
_F_MEMBER = re.compile(
    r"^\s*(real\s*\(\s*(?:kind\s*=\s*)?(c_double|c_float)\s*\)|integer\s*\(\s*(?:kind\s*=\s*)?"
    r"(c_int|c_long_long|c_long|c_int32_t|c_int64_t)\s*\)|type\s*\(\s*(?:pikg|fdps)_f(32|64)vec([234]?)\s*\))"
    r"\s*(?:,\s*[^:]*)?(?:::)?\s*([A-Za-z_][A-Za-z0-9_]*(?:\s*,\s*[A-Za-z_][A-Za-z0-9_]*)*)\s*$", re.I)
_F_INT = {"c_int": "s32", "c_int32_t": "s32", "c_long_long": "s64", "c_long": "s64", "c_int64_t": "s64"}


def read_fortran_types(path: str, wanted: dict[str, str]) -> dict[str, ReflectedRecord]:
    """The bind(c) derived types named in `wanted` (role -> Fortran type name) from a
    Fortran source, laid out as the companion C struct (natural alignment)."""
    try:
        text = Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError as e:
        raise error(NO_SPAN, f"cannot read class file '{path}': {e.strerror or e}") from None
    records: dict[str, ReflectedRecord] = {}
    current, fields, at, align, start = None, {}, 0, 1, 0
    for lineno, raw in enumerate(text.splitlines(), 1):
        line = raw.split("!", 1)[0]
        if current is None:
            m = _F_TYPE_START.match(line)
            if m and not re.match(r"^\s*type\s*\(", line, re.I):
                current, fields, at, align, start = m.group(2), {}, 0, 1, lineno
            continue
        if _F_TYPE_END.match(line):
            size = (at + align - 1) // align * align
            records[current.lower()] = ReflectedRecord(current, current, size, f"{path}:{start}", fields, align)
            current = None
            continue
        m = _F_MEMBER.match(line)
        if not m:
            continue
        if m.group(2):
            code, count = ("f64" if m.group(2).lower() == "c_double" else "f32"), 1
        elif m.group(3):
            code, count = _F_INT[m.group(3).lower()], 1
        else:
            code, count = ("f64" if m.group(4) == "64" else "f32"), int(m.group(5) or 3)
        el = SIZE_OF_CODE[code]
        for name in (n.strip() for n in m.group(6).split(",")):
            at = (at + el - 1) // el * el
            scalar = {"f64": Scalar.F64, "f32": Scalar.F32, "s32": Scalar.S32, "s64": Scalar.S64}[code]
            fields[name] = ReflectedField(name, "vector" if count > 1 else "scalar",
                                          f"{CXX_OF_CODE[code]}" + (f"[{count}]" if count > 1 else ""), at, current,
                                          f"{path}:{lineno}", Type(scalar, count), "", False, el * count, el, code, count)
            at += el * count
            align = max(align, el)
    out = {}
    for role, name in wanted.items():
        rec = records.get(name.lower())
        if rec is None:
            known = ", ".join(r.name for r in records.values()) or "none"
            raise error(NO_SPAN, f"type '{name}' ({role}) not found in Fortran class file '{path}' (types there: {known})")
        out[role] = ReflectedRecord(name, rec.name, rec.size, rec.location, rec.fields, rec.align)
    return out


def fortran_reflection(path: str, types: dict[str, str], span: Span = NO_SPAN) -> Reflection:
    recs = read_fortran_types(path, types)
    r = Reflection(str(Path(path).resolve()), span, dict(types), recs)
    return r


def interface_parts(module: ast.Module, kernel, setup, req: InterfaceRequest, source: str,
                    side_files: dict[str, str] | None) -> dict[str, object]:
    """The header template's parts for the C interface, and the side files."""
    params = [(str(p.type), p.name) for p in kernel.params]
    for t, n in params:
        if t not in C_PARAM:
            raise error(NO_SPAN, f"parameter '{n}' has type {t}, which the C interface cannot pass")
    if side_files is not None:
        if req.c and req.prototype:
            side_files[req.prototype] = prototype_header(req, params, source, req.prototype)
        if req.fortran_module is not None:
            side_files[req.fortran_module + ".F90"] = fortran_module(req, params, source)
    return {"translation_unit": True,
            "c_structs": c_structs(module, setup.types, setup.reflection),
            "c_entry_points": c_entry_points(req, setup.types, params)}
