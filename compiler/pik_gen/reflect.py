"""Member types from the user's C++ header, through pikg-reflect.

With `--header particle.hpp` (or `#pragma header "particle.hpp"` in the .pik
file, resolved relative to that file), pikg-gen runs the `pikg-reflect` tool
(Clang libTooling, compiler/reflect/) on the header for the EPI, EPJ and FORCE
types and uses its JSON (schema in docs/reflect.md) to

* type `EPI.member` accesses that the .pik file does not declare,
* check the declarations it does make against the real struct (a located error
  naming both types on a mismatch), and
* emit one `static_assert(offsetof(T, m) == N)` per used member and a `sizeof`
  check per type into the generated header, so a struct changed after
  generation fails to compile instead of giving wrong forces.

Precision may differ between a declaration and the struct for floating-point
members (`EPJ F32 mj:mass` on a `double mass` loads and converts: PIKG's mixed
precision idiom); anything else (vector vs scalar, component count, float vs
integer, integer width or signedness) is a mismatch.

When pikg-reflect was not built (no libclang), `load` returns None and leaves a
note; in-file declarations keep working.
"""
from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from pik_gen.diagnostics import NO_SPAN, CompileError, Diagnostic, Span, error, suggest
from pik_gen.frontend import ast
from pik_gen.types import Scalar, Type

ROLES = ("EPI", "EPJ", "FORCE")
# Stand-ins for PIKG's vector headers (pikg_vector.h for C, pikg_vector.hpp), searched
# after every -I directory (-idirafter): a header that includes them reads without
# PIKG's inc/ on the include path, as PIKG itself (which never compiles the header) does.
FORTRAN_SUFFIXES = (".f90", ".f95", ".f03", ".f08", ".f")
COMPAT_DIR = Path(__file__).resolve().parent / "compat"
SCHEMA = 1
SCALARS = {
    "f64": Scalar.F64, "f32": Scalar.F32, "f16": Scalar.F16,
    "s64": Scalar.S64, "s32": Scalar.S32, "u64": Scalar.U64, "u32": Scalar.U32,
}
_PRAGMA = re.compile(r'^#\s*pragma\s+header\b\s*(.*)$')
_PRAGMA_ARG = re.compile(r'^"([^"]+)"\s*(//.*)?$')


@dataclass(frozen=True)
class HeaderRequest:
    """What the command line says about the user's headers: `header` is one path
    or several (repeated `--header`, PIKG's `--class-file EPI_FILE EPJ_FILE
    FORCE_FILE`), included in that order; `preludes` are included before them."""

    header: str | tuple[str, ...] | None = None
    include_dirs: tuple[str, ...] = ()
    defines: tuple[str, ...] = ()
    preludes: tuple[str, ...] = ()
    # the file being generated and its class: a class file that includes the output
    # (PIKG's LennardJones sample reads its structs from main.cpp, which includes
    # kernel.hpp) finds a placeholder declaring the class, as PIKG never compiles it
    output: str | None = None
    class_name: str = ""

    @property
    def headers(self) -> tuple[str, ...]:
        if not self.header:
            return ()
        if isinstance(self.header, str):
            return (self.header,)
        return tuple(dict.fromkeys(self.header))  # the same file twice is read once


@dataclass(frozen=True)
class ReflectedField:
    name: str
    kind: str        # pikg-reflect's kind: scalar, vector, array, record, ...
    cxx_type: str    # canonical C++ type
    offset: int
    declared_in: str
    location: str    # file:line of the member's declaration
    type: Type | None  # its .pik type, None when kernels cannot read it
    why_not: str = ""  # when type is None: why
    indexed: bool = False  # a vector read as m[0], m[1], ... (std::array, C array), not m.x, m.y
    size: int = 0     # sizeof and alignof of the member's type (C interface: the struct is restated)
    align: int = 0
    scalar_code: str = ""  # pikg-reflect's `scalar` (f64, s32, ...; for vectors the element's)
    count: int = 0    # components of a vector or array


@dataclass(frozen=True)
class ReflectedRecord:
    requested: str
    name: str
    size: int
    location: str
    fields: dict[str, ReflectedField]
    align: int = 0


def pik_type(f: dict) -> tuple[Type | None, str]:
    """The .pik type of one JSON field, or None and the reason it has none."""
    scalar = SCALARS.get(f.get("scalar", ""))
    kind = f["kind"]
    if kind == "scalar" and scalar is not None:
        return Type(scalar), ""
    if kind == "vector" and scalar is not None and scalar.is_float:
        # access "members": .x .y .z (.w); "index" (std::array, C arrays): [0] [1] [2] ([3])
        return Type(scalar, int(f["count"])), ""
    if kind in ("scalar", "enum", "vector", "array"):
        return None, "the .pik types are F64, F32, F16, S64, S32, U64, U32 and F64vec/F32vec/F16vec (2 to 4 components)"
    if kind == "bitfield":
        return None, "a bit-field has no address to load from"
    return None, f"a {kind} member cannot be read by a kernel"


class Reflection:
    """The reflected EPI/EPJ/FORCE records of one compilation, and the members
    the kernel uses (for the layout assertions). A context object, passed to sema."""

    def __init__(self, header: str, span: Span, types: dict[str, str], records: dict[str, ReflectedRecord]) -> None:
        self.header = header  # the header's path (several: joined with ", ")
        self.span = span
        self.types = types      # role -> C++ type name as given (--epi ...)
        self.records = records  # role -> record
        self.used: dict[tuple[str, str], ReflectedField] = {}

    def field(self, role: str, member: str) -> ReflectedField | None:
        return self.records[role].fields.get(member)

    def indexed(self, role: str, member: str) -> bool:
        """True when the member's components are read as [0], [1], ... (std::array, C array)."""
        f = self.field(role, member)
        return f is not None and f.indexed

    def _use(self, role: str, member: str, span: Span) -> ReflectedField:
        rec = self.records[role]
        f = rec.fields.get(member)
        if f is None:
            raise error(span, f"{role} type '{rec.name}' has no member '{member}'{suggest(member, list(rec.fields))}",
                        f"{rec.name} is defined at {rec.location}")
        self.used[(role, member)] = f
        return f

    def member_type(self, role: str, member: str, span: Span) -> Type:
        """Type of `ROLE.member` from the struct; a located error when it has none."""
        f = self._use(role, member, span)
        if f.type is None:
            raise error(span, f"{role} member '{member}' has C++ type '{f.cxx_type}', which a kernel cannot read: {f.why_not}",
                        f"declared at {f.location}")
        return f.type

    def check_declaration(self, role: str, member: str, declared: Type, type_span: Span, span: Span) -> None:
        """An in-file declaration `ROLE TYPE name:member` against the struct."""
        f = self._use(role, member, span)
        real = f.type
        ok = real is not None and real.lanes == declared.lanes and (
            real.scalar == declared.scalar or (real.scalar.is_float and declared.scalar.is_float))
        if not ok:
            shown = str(real) if real is not None else "no .pik type"
            raise error(type_span, f"{role} member '{member}' is declared {declared} here, but "
                        f"{self.records[role].name}::{member} is '{f.cxx_type}' ({shown})",
                        f"declared at {f.location}")

    def layout_checks(self) -> list[str]:
        """C++ static_asserts: sizeof of each record, offsetof of each used member."""
        out: list[str] = []
        seen: set[tuple[str, str]] = set()
        for role in ROLES:
            cxx = self.types[role]
            rec = self.records[role]
            if (cxx, "") not in seen:
                seen.add((cxx, ""))
                out.append(f'static_assert(sizeof({cxx}) == {rec.size}, "pikg-gen: {cxx} changed size since this '
                           f'kernel was generated from {self._shown()}; regenerate the kernel");')
            for (r, member), f in self.used.items():
                if r != role or (cxx, member) in seen:
                    continue
                seen.add((cxx, member))
                out.append(f'static_assert(offsetof({cxx}, {member}) == {f.offset}, "pikg-gen: {cxx}::{member} moved since '
                           f'this kernel was generated from {self._shown()}; regenerate the kernel");')
        return out

    def _shown(self) -> str:
        return ", ".join(Path(h).name for h in self.header.split(", "))


@dataclass
class ReflectSetup:
    """What one compilation knows about the user's header: the command line's
    request and the C++ type names; `load` fills `reflection`, notes collect
    what the command line should print (e.g. pikg-reflect missing)."""

    request: HeaderRequest | None
    types: dict[str, str]
    notes: list[str] = field(default_factory=list)
    reflection: Reflection | None = None


def find_tool() -> tuple[str | None, str]:
    """Path of pikg-reflect, or None and why not: $PIKG_REFLECT, then next to the
    pikg-gen launcher (build/bin, or the install's bin), then PATH."""
    env = os.environ.get("PIKG_REFLECT")
    if env is not None:
        if env and os.access(env, os.X_OK):
            return env, ""
        return None, f"PIKG_REFLECT is '{env}', which is not an executable"
    here = Path(sys.argv[0]).resolve().parent / "pikg-reflect" if sys.argv and sys.argv[0] else None
    if here is not None and os.access(here, os.X_OK):
        return str(here), ""
    found = shutil.which("pikg-reflect")
    if found:
        return found, ""
    return None, "it was not built (configure with libclang-14-dev and llvm-14-dev installed)"


def header_pragma(module: ast.Module) -> tuple[str, Span] | None:
    """`#pragma header "particle.hpp"` in the .pik file, relative to that file."""
    found: tuple[str, Span] | None = None
    for s in module.body:
        if not isinstance(s, ast.Pragma):
            continue
        m = _PRAGMA.match(s.text.strip())
        if not m:
            continue
        arg = _PRAGMA_ARG.match(m.group(1).strip())
        if not arg:
            raise error(s.span, 'expected #pragma header "file.hpp"')
        if found is not None:
            raise error(s.span, "only one '#pragma header' is allowed; include the other headers from it",
                        f"first one at {found[1]}")
        path = Path(arg.group(1))
        if not path.is_absolute():
            path = Path(module.file).resolve().parent / path
        found = (str(path), s.span)
    return found


class _ReflectFailed(CompileError):
    def __init__(self, diagnostics: list[Diagnostic], stderr: str) -> None:
        super().__init__(diagnostics)
        self.stderr = stderr


_FIRST_ERROR = re.compile(r"^(/[^\n:]+):(\d+):\d+: (?:fatal )?error: (.*)$", re.M)


def _cut_point(lines: list[str], error_line: int) -> int:
    """The number of leading lines to keep so that the text before `error_line` ends
    between two top-level declarations (brace depth 0 after a ';', '}' or a
    preprocessor line): 0 when there is none."""
    depth, best = 0, 0
    last = ""
    for i, line in enumerate(lines[: error_line - 1]):
        code = line.split("//", 1)[0]
        stripped = code.strip()
        if depth == 0 and (not last or last.endswith((";", "}")) or last.startswith("#")):
            best = i
        depth += code.count("{") - code.count("}")
        if stripped:
            last = stripped
    if depth == 0 and error_line > 1 and (last.endswith((";", "}")) or last.startswith("#")):
        best = error_line - 1
    return best


def _block(lines: list[str], error_line: int) -> tuple[int, int]:
    """The lines (0-based, inclusive) of the top-level declaration or preprocessor
    line that contains line `error_line` (1-based)."""
    if lines[error_line - 1].strip().startswith("#"):
        return error_line - 1, error_line - 1
    first = _cut_point(lines, error_line)
    depth = 0
    for i in range(first, len(lines)):
        code = lines[i].split("//", 1)[0]
        depth += code.count("{") - code.count("}")
        if i >= error_line - 1 and depth <= 0 and code.strip().endswith((";", "}")):
            return first, i
    return first, len(lines) - 1


MAX_SKIPPED = 12


def run_tool(tool: str, header: str | list[str], types: list[str], request: HeaderRequest, span: Span,
             notes: list[str] | None = None) -> dict[str, dict]:
    """Run pikg-reflect on one header or several (in order); JSON records by
    requested name. Errors become a CompileError.

    PIKG only scans a class file for struct definitions, so PIKG users' class files
    need not compile: FDPS's planetary_ring user_defined_kernel.hpp includes the
    kernels being generated and uses types of the main program. With `notes`, a
    class file Clang rejects is read again without the top-level declarations (or
    preprocessor lines) that hold its errors, one at a time (at most MAX_SKIPPED),
    with a note naming them; the original errors stand when that does not help."""
    headers = [header] if isinstance(header, str) else list(header)
    try:
        return _run_once(tool, headers, types, request, span)
    except _ReflectFailed as e:
        original = e
        if notes is None:
            raise
    resolved = [str(Path(h).resolve()) for h in headers]
    texts: dict[str, list[str]] = {}
    skipped: list[str] = []
    err = original
    with tempfile.TemporaryDirectory(prefix="pikg-gen-skip-") as tmp:
        dirs = tuple(dict.fromkeys(str(Path(h).parent) for h in resolved))
        retry = HeaderRequest(request.header, (*request.include_dirs, *dirs), request.defines,
                              request.preludes, request.output, request.class_name)
        for _ in range(MAX_SKIPPED):
            first = _FIRST_ERROR.search(err.stderr)
            if first is None:
                break
            bad = str(Path(first.group(1)).resolve())
            copies = {str((Path(tmp) / f"{i}" / Path(h).name).resolve()): h for i, h in enumerate(resolved)}
            if bad in copies:
                bad = copies[bad]
            if bad not in resolved:
                break
            lines = texts.setdefault(bad, Path(bad).read_text(encoding="utf-8", errors="replace")
                                     .splitlines(keepends=True))
            line = int(first.group(2))
            if line > len(lines) or not lines[line - 1].strip():
                break
            a, b = _block(lines, line)
            for i in range(a, b + 1):
                lines[i] = "\n"
            skipped.append(f"{Path(bad).name}:{a + 1}" + (f"-{b + 1}" if b > a else "")
                           + f" ({first.group(3).strip()})")
            paths = []
            for i, h in enumerate(resolved):
                if h in texts:
                    d = Path(tmp) / f"{i}"
                    d.mkdir(exist_ok=True)
                    (d / Path(h).name).write_text("".join(texts[h]))
                    paths.append(str(d / Path(h).name))
                else:
                    paths.append(h)
            try:
                found = _run_once(tool, paths, types, retry, span)
            except _ReflectFailed as again:
                err = again
                continue
            notes.append("read the class file as PIKG does, for its struct definitions: skipped what Clang rejects, "
                         + "; ".join(skipped))
            return found
    raise original


def _run_once(tool: str, headers: list[str], types: list[str], request: HeaderRequest, span: Span) -> dict[str, dict]:
    header = ", ".join(headers)
    cmd = [tool, *headers, *[a for t in types for a in ("--type", t)],
           *[a for f in request.preludes for a in ("--prelude", f)], "--compact", "--", "-std=c++20",
           *[f"-I{d}" for d in request.include_dirs], *[f"-D{d}" for d in request.defines],
           "-idirafter", str(COMPAT_DIR)]
    with tempfile.TemporaryDirectory(prefix="pikg-gen-") as tmp:
        if request.output and request.class_name:
            _placeholder(Path(tmp), request.output, request.class_name)
            cmd.extend(["-idirafter", tmp])
        return _run(cmd, header, span)


def _placeholder(tmp: Path, output: str, class_name: str) -> None:
    *namespaces, cls = class_name.split("::")
    text = ("// pikg-gen: placeholder for the file being generated (a class file includes it)\n#pragma once\n"
            + "".join(f"namespace {n} {{ " for n in namespaces)
            + f"struct {cls} {{ template <class... A> explicit {cls}(const A&...); "
            "template <class... A> void operator()(const A&...) const; static const char* isa_name(); };"
            + " }" * len(namespaces) + "\n")
    (tmp / Path(output).name).write_text(text)


def _run(cmd: list[str], header: str, span: Span) -> dict[str, dict]:
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    except (OSError, subprocess.TimeoutExpired) as e:
        raise error(span, f"cannot run pikg-reflect ({cmd[0]}): {e}") from None
    if p.returncode != 0:
        detail = p.stderr.strip() or f"exit status {p.returncode}"
        raise _ReflectFailed([Diagnostic(span, f"pikg-reflect could not read the particle types from {header}:\n{detail}")],
                             p.stderr)
    try:
        doc = json.loads(p.stdout)
    except json.JSONDecodeError as e:
        raise error(span, f"pikg-reflect printed invalid JSON ({e})") from None
    if doc.get("schema") != SCHEMA:
        raise error(span, f"pikg-reflect speaks JSON schema {doc.get('schema')}, this pikg-gen expects {SCHEMA}; "
                    "rebuild them together")
    return {r["requested"]: r for r in doc["records"]}


def _record(r: dict) -> ReflectedRecord:
    fields: dict[str, ReflectedField] = {}
    for f in r["fields"]:
        if f.get("hidden"):
            continue
        t, why = pik_type(f)
        loc = f["location"]
        fields[f["name"]] = ReflectedField(f["name"], f["kind"], f["type"], int(f["offset"]), f["declared_in"],
                                           f"{loc['file']}:{loc['line']}", t, why,
                                           f["kind"] == "vector" and f.get("access") == "index",
                                           int(f.get("size", 0)), int(f.get("align", 0)), f.get("scalar", ""),
                                           int(f.get("count", 0)))
    loc = r["location"]
    return ReflectedRecord(r["requested"], r["name"], int(r["size"]), f"{loc['file']}:{loc['line']}", fields,
                           int(r.get("align", 0)))


def load(module: ast.Module, request: HeaderRequest | None, types: dict[str, str],
         notes: list[str]) -> Reflection | None:
    """Reflect the EPI/EPJ/FORCE types when a header is named on the command line
    (it wins) or by `#pragma header`; None (with a note when a header was named
    but pikg-reflect is missing) otherwise."""
    pragma = header_pragma(module)
    if request is not None and request.headers:
        headers, span = [str(Path(h).resolve()) for h in request.headers], NO_SPAN
    elif pragma is not None:
        headers, span = [pragma[0]], pragma[1]
    else:
        return None
    header = ", ".join(headers)
    request = request or HeaderRequest()
    if len(headers) == 1 and Path(headers[0]).suffix.lower() in FORTRAN_SUFFIXES:
        # PIKG's --class-file with --fortran-interface: bind(c) derived types in Fortran source
        from pik_gen.interfaces import fortran_reflection  # noqa: PLC0415 (interfaces imports this module)

        if not Path(headers[0]).is_file():
            raise error(span, f"class file '{headers[0]}' does not exist")
        return fortran_reflection(headers[0], types, span)
    tool, why = find_tool()
    if tool is None:
        notes.append(f"pikg-reflect is not available ({why}); member types come from the declarations in "
                     f"{module.file}, not from {header}")
        return None
    for h in headers:
        if not Path(h).is_file():
            raise error(span, f"particle header '{h}' does not exist")
    for f in request.preludes:
        if not Path(f).is_file():
            raise error(span, f"prelude header '{f}' does not exist")
    wanted = list(dict.fromkeys(types[r] for r in ROLES))
    found = run_tool(tool, headers, wanted, request, span, notes)
    records = {role: _record(found[types[role]]) for role in ROLES}
    return Reflection(header, span, dict(types), records)
