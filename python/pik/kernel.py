"""pik.Kernel: a .pik kernel compiled by pikg-gen and the C++ compiler into a cached
shared library, called on NumPy arrays.

    k = pik.Kernel("gravity.pik")                # the kernel library, or any path
    f = k(particles, particles, eps2=1e-4)       # structured arrays: no copies

The particle types of the kernel are NumPy structured dtypes: given as `epi=`,
`epj=`, `force=`, or made from the kernel's declarations (`EPI F32vec xi:pos` makes
a field `pos` of 3 float32; EPI and EPJ share one dtype holding the members of
both, so one particle array serves as both). pikg-gen compiles the kernel for
C++ structs with exactly these layouts (checked with static_assert), so an array
of the kernel's dtype is passed to the kernel as it lies in memory. The library is
cached under $PIK_CACHE_DIR (default ~/.cache/pik/kernels), keyed by the kernel
source, the options, the dtypes, pikg-gen's own sources and the C++ compiler
(path, --version, flags): a second Kernel(...) with the same key loads it at once.
Calls go through ctypes, which releases the GIL; `threads=` splits the
i-particles over that many threads (results do not depend on the count: each
i-particle's sum over j runs in the same order).
"""
from __future__ import annotations

import ctypes
import hashlib
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import threading
from concurrent.futures import ThreadPoolExecutor
from functools import lru_cache
from typing import Any, Mapping

import numpy as np

from pik._paths import paths

# .pik scalar kinds <-> NumPy / C++ element types
_NUMPY = {"F64": "f8", "F32": "f4", "S64": "i8", "S32": "i4", "U64": "u8", "U32": "u4"}
_CXX = {"f8": "double", "f4": "float", "i8": "std::int64_t", "i4": "std::int32_t",
        "u8": "std::uint64_t", "u4": "std::uint32_t"}
_ROLES = ("EPI", "EPJ", "FORCE")
_COMPONENTS = "xyzw"
_DIAG = re.compile(r"^(?P<file>[^\s:][^:]*):(?P<line>\d+):(?P<col>\d+): (?:fatal )?error: (?P<msg>.*)$",
                   re.M)


class KernelError(Exception):
    """A kernel that pikg-gen refuses. `str(e)` is pikg-gen's message
    (``file:line:col: error: ...``, the source line and a caret); `file`, `line`,
    `col` and `message` are those of the first error."""

    def __init__(self, text: str):
        super().__init__(text.rstrip())
        self.text = text.rstrip()
        m = _DIAG.search(self.text)
        self.file = m["file"] if m else None
        self.line = int(m["line"]) if m else None
        self.col = int(m["col"]) if m else None
        self.message = m["msg"] if m else self.text


class BuildError(KernelError):
    """The C++ compiler failed on the generated code: its messages (``file:line:col:
    error: ...``) and the command line."""


# ------------------------------------------------------------------ the kernel's declarations
@lru_cache(maxsize=1)
def _pik_gen():
    """The pik_gen package (its frontend reads a kernel's declarations)."""
    d = paths().compiler_dir
    if d not in sys.path:
        sys.path.insert(0, d)
    from pik_gen import driver, diagnostics
    return driver, diagnostics


def _declarations(source: str, file: str, consts: Mapping[str, Any]):
    """(members by role: [(C++ member, scalar kind, lanes)], params: [(name, kind)])."""
    driver, diagnostics = _pik_gen()
    try:
        checked = driver.frontend(source, file)
    except diagnostics.CompileError as e:
        raise KernelError("\n".join(d.render(source) for d in e.diagnostics)) from None
    members: dict[str, list[tuple[str, str, int]]] = {r: [] for r in _ROLES}
    for m in checked.members:
        if m.name not in [x[0] for x in members[m.role]]:
            members[m.role].append((m.name, m.type.scalar.value, m.type.lanes))
    params = [(name, t.scalar.value) for name, t in checked.params if name not in consts]
    return members, params


def _field_dtype(kind: str, lanes: int) -> tuple:
    if kind not in _NUMPY:
        raise KernelError(f"members of type {kind} cannot be given from NumPy")
    return (_NUMPY[kind], (lanes,)) if lanes > 1 else (_NUMPY[kind],)


def _default_dtype(members: list[tuple[str, str, int]]) -> np.dtype:
    fields = [(name, *_field_dtype(kind, lanes)) for name, kind, lanes in members]
    return np.dtype(fields, align=True)


def _merge(a: list, b: list) -> list:
    """EPI and EPJ members together (the wider float type where both name a member)."""
    out = {name: (kind, lanes) for name, kind, lanes in a}
    for name, kind, lanes in b:
        if name in out:
            k0, l0 = out[name]
            if l0 != lanes:
                raise KernelError(f"member '{name}' has {l0} components as EPI and {lanes} as EPJ: "
                                  "give epi= and epj= dtypes")
            if k0 != kind:
                out[name] = ("F64" if "F64" in (k0, kind) else k0, lanes)
        else:
            out[name] = (kind, lanes)
    return [(n, k, l) for n, (k, l) in out.items()]


# ------------------------------------------------------------------ C++ structs from dtypes
def _cxx_struct(name: str, dtype: np.dtype, used: list[tuple[str, str, int]], role: str) -> str:
    """A C++ struct with `dtype`'s layout: the kernel's members at their offsets,
    padding bytes elsewhere. Refuses a dtype lacking a member or with the wrong shape."""
    if dtype.fields is None:
        raise ValueError(f"{role} dtype {dtype} is not a structured dtype")
    lines, asserts, packed = [], [], False
    entries = []
    for member, kind, lanes in used:
        if member not in dtype.fields:
            raise ValueError(f"{role} dtype has no field '{member}' (the kernel uses "
                             f"{', '.join(m[0] for m in used)}; dtype fields: {', '.join(dtype.names)})")
        fdt, off = dtype.fields[member][:2]
        base, shape = fdt.base, fdt.shape
        if not base.isnative or base.str[1:] not in _CXX:
            raise ValueError(f"{role} field '{member}' has type {base}; use float32/64 or (u)int32/64 "
                             "in native byte order")
        want = (lanes,) if lanes > 1 else ()
        if shape != want:
            raise ValueError(f"{role} field '{member}' has shape {shape}, the kernel reads "
                             f"{'a vector of ' + str(lanes) if lanes > 1 else 'a scalar'}")
        ct = _CXX[base.str[1:]]
        if lanes > 1:
            ct = f"PikVec{lanes}<{ct}>"
        if off % base.itemsize:
            packed = True
        entries.append((off, member, ct, fdt.itemsize, base.itemsize))
    entries.sort()
    pos = 0
    for k, (off, member, ct, size, _) in enumerate(entries):
        if off < pos:
            raise ValueError(f"{role} fields overlap at '{member}'")
        if off > pos:
            lines.append(f"  unsigned char pad{k}_[{off - pos}];")
        lines.append(f"  {ct} {member};")
        asserts.append(f"static_assert(offsetof({name}, {member}) == {off});")
        pos = off + size
    if dtype.itemsize > pos:
        lines.append(f"  unsigned char pad_end_[{dtype.itemsize - pos}];")
    align = max([e[4] for e in entries] or [1])
    attr = " __attribute__((packed))" if packed or dtype.itemsize % align else ""
    asserts.append(f"static_assert(sizeof({name}) == {dtype.itemsize});")
    return "struct" + attr + f" {name} {{\n" + "\n".join(lines) + "\n};\n" + "\n".join(asserts) + "\n"


# ------------------------------------------------------------------ cache and build
def _cache_dir() -> str:
    d = os.environ.get("PIK_CACHE_DIR")
    if not d:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        d = os.path.join(base, "pik", "kernels")
    return d


@lru_cache(maxsize=8)
def _compiler_id(cxx: str) -> str:
    exe = shutil.which(cxx)
    if exe is None:
        raise BuildError(f"C++ compiler '{cxx}' not found (set CXX or pass cxx=)")
    try:
        out = subprocess.run([exe, "--version"], capture_output=True, text=True, timeout=30).stdout
    except (OSError, subprocess.TimeoutExpired) as e:
        raise BuildError(f"cannot run '{cxx} --version': {e}") from None
    return os.path.realpath(exe) + "\n" + out.strip()


@lru_cache(maxsize=1)
def _pikg_gen_id() -> str:
    """A hash of pikg-gen's sources: a changed compiler never reuses old libraries."""
    h = hashlib.sha256()
    root = os.path.join(paths().compiler_dir, "pik_gen")
    for dirpath, dirnames, files in sorted(os.walk(root)):
        dirnames.sort()
        for f in sorted(files):
            if f.endswith((".py", ".j2")):
                h.update(os.path.relpath(os.path.join(dirpath, f), root).encode())
                with open(os.path.join(dirpath, f), "rb") as fh:
                    h.update(fh.read())
    return h.hexdigest()


def _pikg_gen_command() -> list[str]:
    gen = paths().pikg_gen
    if gen:
        return [gen]
    shim = ("import sys; sys.path.insert(0, sys.argv.pop(1)); sys.dont_write_bytecode = True; "
            "from pik_gen.cli import main; sys.exit(main())")
    return [sys.executable, "-c", shim, paths().compiler_dir]


_BUILD_LOCK = threading.Lock()


def _library(key: str, source_path: str, gen_args: list[str], wrapper: str, cxx: str,
             flags: list[str]) -> tuple[str, bool]:
    """The cached library for `key`, built if missing. Returns (path, cache hit)."""
    final = os.path.join(_cache_dir(), key[:2], key)
    lib = os.path.join(final, "kernel.so")
    if os.path.exists(lib):
        return lib, True
    with _BUILD_LOCK:
        if os.path.exists(lib):
            return lib, True
        os.makedirs(os.path.dirname(final), exist_ok=True)
        tmp = tempfile.mkdtemp(prefix=".build-", dir=os.path.dirname(final))
        try:
            hpp = os.path.join(tmp, "kernel.hpp")
            cmd = _pikg_gen_command() + [source_path, "-o", hpp] + gen_args
            r = subprocess.run(cmd, capture_output=True, text=True)
            if r.returncode != 0:
                raise KernelError(r.stderr or r.stdout or f"pikg-gen failed (exit status {r.returncode})")
            cpp = os.path.join(tmp, "wrapper.cpp")
            with open(cpp, "w") as f:
                f.write(wrapper)
            out = os.path.join(tmp, "kernel.so")
            cmd = [cxx, *flags, "-I", tmp, *[f"-I{d}" for d in paths().include_dirs], cpp, "-o", out]
            r = subprocess.run(cmd, capture_output=True, text=True)
            if r.returncode != 0:
                raise BuildError((r.stderr or r.stdout) + "\ncommand: " + shlex.join(cmd))
            with open(os.path.join(tmp, "command.txt"), "w") as f:
                f.write(shlex.join(cmd) + "\n")
            try:
                os.rename(tmp, final)
            except OSError:  # another process built it first: use theirs
                shutil.rmtree(tmp, ignore_errors=True)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
    return lib, False


# CPU flags (Linux /proc/cpuinfo) a single-ISA library needs: running one the CPU
# lacks would end the process with SIGILL instead of an error.
_ISA_FLAGS = {"avx2": ("avx2", "fma"), "avx512": ("avx512f",)}


def _check_cpu(target: str) -> None:
    need = _ISA_FLAGS.get(target)
    if not need:
        return
    try:
        with open("/proc/cpuinfo") as f:
            flags = next((ln.split(":", 1)[1].split() for ln in f if ln.startswith("flags")), None)
    except OSError:
        return
    if flags is not None and not all(x in flags for x in need):
        raise KernelError(f"target '{target}': this CPU lacks {', '.join(x for x in need if x not in flags)}; "
                          "use target='auto' (the best variant this CPU has) or 'reference'")


def _resolve(path: str | os.PathLike) -> str:
    p = os.fspath(path)
    if os.path.exists(p):
        return os.path.abspath(p)
    lib = os.path.join(paths().kernels_dir, p)
    if not os.path.isabs(p) and os.path.exists(lib):
        return lib
    raise FileNotFoundError(f"{p}: no such kernel file (nor in the kernel library {paths().kernels_dir})")


# ------------------------------------------------------------------ the kernel
class Kernel:
    """A compiled .pik kernel, callable on NumPy arrays.

    Kernel(path, epi=None, epj=None, force=None, *, params=None, consts=None,
           target="auto", fast_math=False, cxx=None, cxxflags=None, name=None)

    path     a .pik file (a bare name is also looked up in pik's kernel library)
    epi, epj, force
             NumPy structured dtypes of the i-particles, j-particles and results
             (default: made from the kernel's declarations; epi and epj then share
             `particle_dtype`); other fields of a dtype are carried along unread
    params   default values of the kernel's parameters (a call may override them)
    consts   parameters bound at compile time (pikg-gen --const NAME=VALUE)
    target   pikg-gen target: auto (run-time choice among the x86 variants),
             reference, avx2, avx512
    cxx, cxxflags
             the C++ compiler (default $CXX or c++) and its flags
             (default -O3 -march=native -fno-math-errno)
    """

    def __init__(self, path: str | os.PathLike, epi: Any = None, epj: Any = None, force: Any = None, *,
                 params: Mapping[str, float] | None = None, consts: Mapping[str, Any] | None = None,
                 target: str = "auto", fast_math: bool = False, cxx: str | None = None,
                 cxxflags: list[str] | None = None, name: str | None = None):
        self.path = _resolve(path)
        with open(self.path, encoding="utf-8") as f:
            self.source = f.read()
        consts = dict(consts or {})
        members, self.param_types = _declarations(self.source, self.path, consts)
        self.param_names = [p for p, _ in self.param_types]
        self.params = dict(params or {})
        for p in self.params:
            if p not in self.param_names:
                raise ValueError(f"{self.path}: the kernel has no parameter '{p}' "
                                 f"(parameters: {', '.join(self.param_names) or 'none'})")
        self.members = members
        if epi is None and epj is None:
            self.particle_dtype = _default_dtype(_merge(members["EPI"], members["EPJ"]))
            epi = epj = self.particle_dtype
        elif epi is None or epj is None:
            epi = epj = np.dtype(epi if epi is not None else epj)
            self.particle_dtype = epi
        else:
            self.particle_dtype = None
        self.epi_dtype = np.dtype(epi)
        self.epj_dtype = np.dtype(epj)
        self.force_dtype = np.dtype(force) if force is not None else _default_dtype(members["FORCE"])
        _check_cpu(target)
        self.name = name or re.sub(r"\W", "_", os.path.splitext(os.path.basename(self.path))[0])
        self.target = target

        structs = ("template <class T> struct PikVec2 { T x, y; };\n"
                   "template <class T> struct PikVec3 { T x, y, z; };\n"
                   "template <class T> struct PikVec4 { T x, y, z, w; };\n")
        structs += _cxx_struct("PikEPI", self.epi_dtype, members["EPI"], "epi")
        structs += _cxx_struct("PikEPJ", self.epj_dtype, members["EPJ"], "epj")
        structs += _cxx_struct("PikFORCE", self.force_dtype, members["FORCE"], "force")
        args = ", ".join(f"static_cast<{_CXX[_NUMPY[k]] if k in _NUMPY else 'double'}>("
                         f"{'pi' if k[0] in 'SU' else 'pf'}[{i}])"
                         for i, (_, k) in enumerate(self.param_types))
        wrapper = _WRAPPER.format(structs=structs, args=f"({args})" if args else "")
        gen_args = ["--target", target, "--name", "PikKernel", "--epi", "PikEPI", "--epj", "PikEPJ",
                    "--force", "PikFORCE"]
        for k, v in sorted(consts.items()):
            gen_args += ["--const", f"{k}={v}"]
        if fast_math:
            gen_args.append("--fast-math")
        self.cxx = cxx or os.environ.get("CXX") or "c++"
        self.cxxflags = list(cxxflags) if cxxflags is not None else ["-O3", "-march=native", "-fno-math-errno"]
        flags = ["-std=c++20", *self.cxxflags, "-fPIC", "-shared", "-fvisibility=hidden"]
        key_text = json.dumps({"source": self.source, "file": os.path.basename(self.path),
                               "gen": gen_args, "wrapper": wrapper, "flags": flags,
                               "compiler": _compiler_id(self.cxx), "pikg_gen": _pikg_gen_id()},
                              sort_keys=True)
        self.key = hashlib.sha256(key_text.encode()).hexdigest()[:32]
        self.library, self.cache_hit = _library(self.key, self.path, gen_args, wrapper, self.cxx, flags)
        self._lib = ctypes.CDLL(self.library)  # ctypes releases the GIL in every call
        self._lib.pik_kernel_new.restype = ctypes.c_void_p
        self._lib.pik_kernel_new.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
        self._lib.pik_kernel_delete.argtypes = [ctypes.c_void_p]
        self._lib.pik_kernel_run.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int,
                                             ctypes.c_void_p, ctypes.c_int, ctypes.c_void_p]
        self._lib.pik_kernel_isa.restype = ctypes.c_char_p
        self._objects: dict[tuple, int] = {}
        self._flags = flags
        self._sr: dict[str, Any] = {}

    # -- introspection
    @property
    def isa(self) -> str:
        """The instruction set the kernel runs with (chosen at run time for target auto)."""
        return self._lib.pik_kernel_isa().decode()

    def __repr__(self) -> str:
        return f"pik.Kernel({os.path.basename(self.path)!r}, isa={self.isa!r}, params={self.param_names})"

    def zeros(self, n: int, role: str = "force") -> np.ndarray:
        """A zeroed array of n elements of the dtype of `role` (epi, epj or force)."""
        return np.zeros(n, dtype={"epi": self.epi_dtype, "epj": self.epj_dtype, "force": self.force_dtype}[role])

    # -- calling
    def _object(self, params: Mapping[str, Any], lib: Any = None) -> int:
        values = {**self.params, **params}
        missing = [p for p in self.param_names if p not in values]
        if missing:
            raise TypeError(f"{os.path.basename(self.path)}: missing kernel parameter(s) {', '.join(missing)}")
        extra = [p for p in values if p not in self.param_names]
        if extra:
            raise TypeError(f"{os.path.basename(self.path)}: unknown kernel parameter(s) {', '.join(extra)} "
                            f"(parameters: {', '.join(self.param_names) or 'none'})")
        lib = lib or self._lib
        key = (id(lib),) + tuple(values[p] for p in self.param_names)
        obj = self._objects.get(key)
        if obj is None:
            vals = key[1:]
            pf = (ctypes.c_double * max(1, len(vals)))(*[float(v) for v in vals])
            pi = (ctypes.c_int64 * max(1, len(vals)))(
                *[int(v) if k[0] in "SU" else 0 for v, (_, k) in zip(vals, self.param_types)])
            if len(self._objects) > 16:
                self._release()
            obj = lib.pik_kernel_new(pf, pi)
            self._objects[key] = (obj, lib)
            return obj
        return obj[0]

    def _release(self) -> None:
        for obj, lib in self._objects.values():
            lib.pik_kernel_delete(obj)
        self._objects.clear()

    def __del__(self):
        try:
            self._release()
        except Exception:
            pass

    @staticmethod
    def _as_input(a: Any, dtype: np.dtype, role: str) -> np.ndarray:
        """`a` as a C-contiguous aligned array of `dtype`: itself when it already is one."""
        if isinstance(a, np.ndarray) and a.dtype == dtype and a.ndim == 1 and a.flags.c_contiguous \
                and a.flags.aligned:
            return a
        return _pack(a, dtype, role)

    def __call__(self, epi: Any, epj: Any = None, force: Any = None, *, threads: int | None = None,
                 **params: Any):
        """Accumulates the kernel's sums into `force` and returns it.

        epi, epj   structured arrays (passed without a copy when of the kernel's
                   dtype, C-contiguous) or dicts of arrays {"pos": (N, 3), "mass":
                   (N,), ...} (packed into one array, a copy); epj defaults to epi
        force      None (a new zeroed array of force_dtype is returned), an array
                   of force_dtype (accumulated into in place, no copy), or a dict
                   of arrays (updated in place; missing members are added)
        threads    threads over the i-particles (default: the CPUs this process
                   may use); the GIL is released meanwhile
        params     the kernel's parameters (overriding those given at construction)
        """
        obj = self._object(params)
        epj = epi if epj is None else epj
        ai = self._as_input(epi, self.epi_dtype, "epi")
        aj = ai if (epj is epi and self.epj_dtype == self.epi_dtype) else self._as_input(epj, self.epj_dtype, "epj")
        ni, nj = len(ai), len(aj)
        if max(ni, nj) > 2**31 - 1:
            raise ValueError("at most 2^31 - 1 particles a call")
        if force is None:
            out = np.zeros(ni, dtype=self.force_dtype)
            result = out
        elif isinstance(force, np.ndarray) and force.dtype == self.force_dtype and force.flags.c_contiguous \
                and force.flags.aligned and force.flags.writeable and force.ndim == 1:
            out = result = force
        else:
            out = _pack(force, self.force_dtype, "force", fill_missing=True, n=ni)
            result = force
        if len(out) != ni:
            raise ValueError(f"force has {len(out)} entries for {ni} i-particles")
        if threads is None:
            threads = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
        threads = max(1, min(int(threads), ni // 64 or 1))
        pi, pj, pf = ai.ctypes.data, aj.ctypes.data, out.ctypes.data
        si, sf = self.epi_dtype.itemsize, self.force_dtype.itemsize
        run = self._lib.pik_kernel_run
        if threads == 1:
            run(obj, pi, ni, pj, nj, pf)
        else:
            # Blocks of i-particles, a multiple of 64 (whole SIMD vectors); ctypes drops the GIL.
            block = -(-ni // threads)
            block = -(-block // 64) * 64
            spans = [(s, min(block, ni - s)) for s in range(0, ni, block)]
            with ThreadPoolExecutor(len(spans)) as ex:
                list(ex.map(lambda sp: run(obj, pi + sp[0] * si, sp[1], pj, nj, pf + sp[0] * sf), spans))
        if result is not out:
            _unpack(out, result)
        return result


    # -- the kernel through the runtime's neighbour search
    def neighbour_sum(self, particles: Any, radius: Any, *, mode: str = "gather", box: Any = None,
                      pos: str | None = None, force: Any = None, threads: int | None = None, **params: Any):
        """The kernel over neighbours found by the runtime's short-range tree
        (pik::ShortRangeTree), SPH-style: for each i-particle the kernel gets the
        j-particles that may lie within the search radius r (gather: radius[i],
        SPH's support of h_i; scatter: radius[j]; symmetric: the larger) and must
        apply the exact cut itself (as FDPS kernels do: a smoothing function that
        vanishes beyond its support does). One particle array serves as i and j
        (epi and epj dtypes must be the same); `radius` is a number or an (N,)
        array; `box=[[lo...], [hi...]]` makes the three dimensions periodic (the
        kernel sees shifted images); `pos` names the position member (default:
        the first 3-vector the kernel reads as EPI). Returns the sums in a new
        force array, or adds them into `force`. The walk runs on the runtime's
        OpenMP threads (`threads`), with the GIL released. The first call builds a
        second cached library with the tree (a few seconds more)."""
        if self.epi_dtype != self.epj_dtype:
            raise ValueError("neighbour_sum needs one particle dtype for epi and epj")
        vecs = [m for m, _, lanes in self.members["EPI"] if lanes == 3]
        pos = pos or (vecs[0] if vecs else None)
        if pos is None or pos not in self.epi_dtype.names or self.epi_dtype[pos].shape != (3,):
            raise ValueError(f"neighbour_sum: no 3-vector position member {pos!r} in the particle dtype")
        modes = {"gather": 0, "scatter": 1, "symmetric": 2}
        if mode not in modes:
            raise ValueError(f"mode must be 'gather', 'scatter' or 'symmetric', not {mode!r}")
        lib = self._short_range_library(pos)
        obj = self._object(params, lib)
        p = self._as_input(particles, self.epi_dtype, "particles")
        n = len(p)
        r = np.ascontiguousarray(radius, dtype=np.float64).reshape(-1)
        if len(r) not in (1, n) or (n and not np.all(r >= 0)):
            raise ValueError("radius must be a number >= 0 or one per particle")
        b = None
        if box is not None:
            b = np.ascontiguousarray(box, dtype=np.float64)
            if b.shape != (2, 3):
                raise ValueError("box must be [[xlo, ylo, zlo], [xhi, yhi, zhi]]")
        out = np.zeros(n, dtype=self.force_dtype)
        if threads is None:
            threads = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
        err = ctypes.create_string_buffer(1024)
        rc = lib.pik_kernel_short_range(obj, p.ctypes.data, r.ctypes.data, n, len(r), modes[mode],
                                        None if b is None else b.ctypes.data, out.ctypes.data, int(threads),
                                        err, len(err))
        if rc != 0:
            raise ValueError(err.value.decode(errors="replace"))
        if force is None:
            return out
        for name in out.dtype.names:
            force[name] += out[name]
        return force

    def _short_range_library(self, pos: str):
        lib = self._sr.get(pos)
        if lib is not None:
            return lib
        folder = os.path.dirname(self.library)
        path = os.path.join(folder, f"kernel_sr_{pos}.so")
        if not os.path.exists(path):
            with _BUILD_LOCK:
                if not os.path.exists(path):
                    fd, tmp = tempfile.mkstemp(prefix=".sr-", suffix=".so", dir=folder)
                    os.close(fd)
                    cmd = [self.cxx, *self._flags, "-fopenmp", f"-DPIK_SR_POS={pos}", "-I", folder,
                           *[f"-I{d}" for d in paths().include_dirs], os.path.join(folder, "wrapper.cpp"),
                           "-o", tmp]
                    r = subprocess.run(cmd, capture_output=True, text=True)
                    if r.returncode != 0:
                        os.unlink(tmp)
                        raise BuildError((r.stderr or r.stdout) + "\ncommand: " + shlex.join(cmd))
                    os.replace(tmp, path)
        lib = ctypes.CDLL(path)
        lib.pik_kernel_new.restype = ctypes.c_void_p
        lib.pik_kernel_new.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
        lib.pik_kernel_delete.argtypes = [ctypes.c_void_p]
        lib.pik_kernel_short_range.restype = ctypes.c_int
        lib.pik_kernel_short_range.argtypes = [
            ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_long, ctypes.c_int, ctypes.c_int,
            ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_int]
        self._sr[pos] = lib
        return lib


def _pack(a: Any, dtype: np.dtype, role: str, fill_missing: bool = False, n: int | None = None) -> np.ndarray:
    """Copies a dict of arrays or a structured array with other fields into `dtype`."""
    if isinstance(a, np.ndarray) and a.dtype.names is not None:
        cols = {name: a[name] for name in a.dtype.names}
    elif isinstance(a, Mapping):
        cols = dict(a)
    else:
        raise TypeError(f"{role}: expected a structured array or a dict of arrays, got {type(a).__name__}")
    lengths = {len(np.asarray(v)) for v in cols.values() if np.ndim(v) > 0}
    if n is None:
        if len(lengths) != 1:
            raise ValueError(f"{role}: arrays of different lengths {sorted(lengths)}")
        n = lengths.pop()
    out = np.zeros(n, dtype=dtype)
    for name in dtype.names:
        if name in cols:
            v = np.asarray(cols[name])
            want = out[name].shape
            if v.shape != want and not (v.ndim == 0):
                raise ValueError(f"{role}['{name}'] has shape {v.shape}, expected {want}")
            out[name] = v
        elif not fill_missing:
            raise ValueError(f"{role}: no '{name}' (needed: {', '.join(dtype.names)})")
    return out


def _unpack(out: np.ndarray, dest: Any) -> None:
    for name in out.dtype.names:
        if isinstance(dest, np.ndarray):
            if name in dest.dtype.names:
                dest[name] = out[name]
        elif name in dest and isinstance(dest[name], np.ndarray) and dest[name].shape == out[name].shape:
            dest[name][...] = out[name]
        else:
            dest[name] = out[name].copy()


_WRAPPER = """\
// pik.Kernel wrapper: the particle structs of the NumPy dtypes, the generated
// kernel, and a C entry point for ctypes.
#include <cstddef>
#include <cstdint>
#include <cstdio>

{structs}
#include "kernel.hpp"

#define PIK_EXPORT extern "C" __attribute__((visibility("default")))

PIK_EXPORT void* pik_kernel_new(const double* pf, const std::int64_t* pi) {{
  (void)pf, (void)pi;
  return new PikKernel{args};
}}
PIK_EXPORT void pik_kernel_delete(void* k) {{ delete static_cast<PikKernel*>(k); }}
PIK_EXPORT void pik_kernel_run(const void* k, const void* epi, int ni, const void* epj, int nj,
                               void* force) {{
  (*static_cast<const PikKernel*>(k))(static_cast<const PikEPI*>(epi), ni,
                                      static_cast<const PikEPJ*>(epj), nj,
                                      static_cast<PikFORCE*>(force));
}}
PIK_EXPORT const char* pik_kernel_isa() {{ return PikKernel::isa_name(); }}

#ifdef PIK_SR_POS
// Kernel.neighbour_sum: the kernel through the runtime's short-range tree
// (pik::ShortRangeTree), built into a second library with -DPIK_SR_POS=<member>.
#include <algorithm>
#include <cstring>
#include <exception>
#include <vector>

#include <pik/detail/Threads.hpp>
#include <pik/particle/ParticleSystem.hpp>
#include <pik/walk/ShortRangeTree.hpp>

namespace {{
struct SrP {{  // a particle with its search radius
  PikEPI v;
  double r;
  pik::Vec3<double> getPos() const {{ return {{double(v.PIK_SR_POS.x), double(v.PIK_SR_POS.y), double(v.PIK_SR_POS.z)}}; }}
  double getRSearch() const {{ return r; }}
  void setPos(const pik::Vec3<double>& x) {{  // periodic images
    using T = decltype(v.PIK_SR_POS.x);
    v.PIK_SR_POS.x = T(x.x), v.PIK_SR_POS.y = T(x.y), v.PIK_SR_POS.z = T(x.z);
  }}
  void copyFromFP(const SrP& p) {{ *this = p; }}
}};
struct SrF {{
  PikFORCE f;
  void clear() {{ f = PikFORCE{{}}; }}
}};
static_assert(sizeof(PikEPI) == sizeof(PikEPJ), "one particle dtype for i and j");
// The tree hands groups of SrP; the generated kernel reads packed PikEPI/PikEPJ
// arrays: copy a group and its candidates (O(ni + nj) against the kernel's ni * nj).
struct SrKernel {{
  const PikKernel* k;
  void operator()(const SrP* epi, int ni, const SrP* epj, int nj, SrF* force) const {{
    thread_local std::vector<PikEPI> bi;
    thread_local std::vector<PikEPJ> bj;
    thread_local std::vector<PikFORCE> bf;
    bi.resize(std::size_t(ni));
    bj.resize(std::size_t(nj));
    bf.resize(std::size_t(ni));
    for (int i = 0; i < ni; ++i) bi[std::size_t(i)] = epi[i].v, bf[std::size_t(i)] = force[i].f;
    for (int j = 0; j < nj; ++j) std::memcpy(&bj[std::size_t(j)], &epj[j].v, sizeof(PikEPJ));
    (*k)(bi.data(), ni, bj.data(), nj, bf.data());
    for (int i = 0; i < ni; ++i) force[i].f = bf[std::size_t(i)];
  }}
}};
template <pik::SearchMode M>
void short_range(const PikKernel* k, std::vector<SrP> parts, const double* box, PikFORCE* out) {{
  const std::size_t n = parts.size();
  pik::ParticleSystem<SrP> ps(std::move(parts));
  pik::ShortRangeTree<SrF, SrP, SrP, M> tree;
  if (box) tree.setBoundary(pik::Boundary<3>::periodic_box({{box[0], box[1], box[2]}}, {{box[3], box[4], box[5]}}));
  tree.calcForceAll(SrKernel{{k}}, ps);
  const auto f = tree.sortedForce();
  for (std::size_t i = 0; i < n; ++i) out[tree.sortedIndex(i)] = f[i].f;
}}
}}  // namespace

PIK_EXPORT int pik_kernel_short_range(const void* k, const void* particles, const double* radius, long n,
                                      int n_radius, int mode, const double* box, void* force, int threads,
                                      char* error, int error_bytes) {{
  try {{
    std::vector<SrP> parts(static_cast<std::size_t>(n));
    const auto* p = static_cast<const PikEPI*>(particles);
    for (long i = 0; i < n; ++i) parts[std::size_t(i)] = SrP{{p[i], radius[n_radius == 1 ? 0 : i]}};
    const int before = pik::detail::max_threads();
    if (threads > 0) pik::detail::set_threads(threads);
    const auto* kk = static_cast<const PikKernel*>(k);
    auto* out = static_cast<PikFORCE*>(force);
    try {{
      if (mode == 0) short_range<pik::SearchMode::gather>(kk, std::move(parts), box, out);
      else if (mode == 1) short_range<pik::SearchMode::scatter>(kk, std::move(parts), box, out);
      else short_range<pik::SearchMode::symmetric>(kk, std::move(parts), box, out);
    }} catch (...) {{
      pik::detail::set_threads(before);
      throw;
    }}
    pik::detail::set_threads(before);
    return 0;
  }} catch (const std::exception& e) {{
    std::snprintf(error, std::size_t(error_bytes), "%s", e.what());
    return 1;
  }}
}}
#endif
"""
