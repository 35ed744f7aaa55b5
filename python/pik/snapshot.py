"""Readers for every pik snapshot format (docs/snapshots.md), returning NumPy arrays.

    s = pik.read_snapshot("out/snap_000064.pbin")   # binary, ASCII or HDF5; parts joined
    s.pos, s.vel, s.mass, s.id, s.columns["Acceleration"], s.time, s.step, s.attrs

The format is recognised from the first bytes, as the C++ reader does
(`pik::io::detect_format`). A missing, truncated, corrupt or foreign file raises
`SnapshotError` with the message of the C++ reader: ``FILE: what is wrong``
(ASCII: ``FILE:LINE: ...``). Binary snapshots are read with one `numpy.fromfile`
per field after every CRC-32 (zlib's, the same as the writer's) is checked; the
arrays are views of nothing else and may be modified.
"""
from __future__ import annotations

import os
import zlib
from dataclasses import dataclass, field

import numpy as np

BINARY_MAGIC = b"\x89PIK\r\n\x1a\n"
BINARY_END = b"\x89PIKEND\n"
HDF5_MAGIC = b"\x89HDF\r\n\x1a\n"
ASCII_MAGIC = "# pik ascii snapshot 1"
ENDIAN_MARKER = 0x0A0B0C0D
HEADER_BYTES = 128
FIELD_ENTRY_BYTES = 64
# Element type codes of the binary field table.
TYPES = {1: "f4", 2: "f8", 3: "u4", 4: "u8", 5: "i4", 6: "i8"}
CORE = ("ParticleIDs", "Masses", "Coordinates", "Velocities")

# The 128-byte header of docs/snapshots.md, as a structured dtype ("<" or ">" set on use).
_HEADER_FIELDS = [
    ("magic", "V8", 0), ("version", "u4", 8), ("endian", "u4", 12), ("n_local", "u8", 16),
    ("n_total", "u8", 24), ("first_index", "u8", 32), ("part", "u4", 40), ("n_parts", "u4", 44),
    ("time", "f8", 48), ("step", "u8", 56), ("n_fields", "u4", 64), ("table_crc", "u4", 68),
    ("attr_offset", "u8", 72), ("attr_bytes", "u8", 80), ("attr_crc", "u4", 88),
    ("file_bytes", "u8", 96), ("header_crc", "u4", 124),
]
_FIELD_ENTRY = [("name", "S32", 0), ("type", "u1", 32), ("components", "u1", 33),
                ("crc", "u4", 36), ("offset", "u8", 40), ("bytes", "u8", 48)]


def _dtype(fields, itemsize: int, order: str = "<") -> np.dtype:
    return np.dtype({"names": [f[0] for f in fields],
                     "formats": [order + f[1] if f[1][0] in "uif" else f[1] for f in fields],
                     "offsets": [f[2] for f in fields], "itemsize": itemsize})


class SnapshotError(ValueError):
    """A snapshot that cannot be read: ``str(e)`` is ``FILE: what is wrong``."""

    def __init__(self, path: str, reason: str):
        super().__init__(f"{path}: {reason}")
        self.path = path
        self.reason = reason


@dataclass
class Snapshot:
    """One snapshot (or every part of one output, joined): NumPy arrays and the header."""

    id: np.ndarray  # uint64 (N,)
    mass: np.ndarray  # float64 (N,)
    pos: np.ndarray  # float64 (N, 3)
    vel: np.ndarray  # float64 (N, 3)
    columns: dict[str, np.ndarray] = field(default_factory=dict)  # (N,) or (N, 3)
    attrs: dict[str, str] = field(default_factory=dict)
    time: float = 0.0
    step: int = 0
    n_total: int = 0
    first_index: int = 0
    part: int = 0
    n_parts: int = 1
    format: str = "binary"  # "binary" | "ascii" | "hdf5"
    path: str = ""

    def __len__(self) -> int:
        return len(self.id)

    def __getitem__(self, name: str) -> np.ndarray:
        """`s["pos"]`, `s["Coordinates"]` (the HDF5/binary name) or an extra column."""
        core = {"id": self.id, "ParticleIDs": self.id, "mass": self.mass, "Masses": self.mass,
                "pos": self.pos, "Coordinates": self.pos, "vel": self.vel, "Velocities": self.vel}
        if name in core:
            return core[name]
        if name in self.columns:
            return self.columns[name]
        raise KeyError(f"{self.path}: no column '{name}' (columns: "
                       f"id mass pos vel {' '.join(self.columns)})")


# ---------------------------------------------------------------- binary
def read_binary(path: str) -> Snapshot:
    """The pik binary format (".pbin"), every checksum verified."""
    try:
        f = open(path, "rb")
    except OSError as e:
        raise SnapshotError(path, f"cannot open: {e.strerror}") from None
    with f:
        size = os.fstat(f.fileno()).st_size

        def read_at(off: int, nbytes: int, what: str) -> bytes:
            if off + nbytes > size:
                raise SnapshotError(path, f"truncated: {what} ends at byte {off + nbytes} "
                                          f"but the file has {size} bytes")
            f.seek(off)
            return f.read(nbytes)

        if size < 8 or read_at(0, 8, "magic") != BINARY_MAGIC:
            raise SnapshotError(path, "not a pik binary snapshot (bad magic number)")
        raw = read_at(0, HEADER_BYTES, "the 128-byte header")
        marker = int.from_bytes(raw[12:16], "little")
        if marker == ENDIAN_MARKER:
            order = "<"
        elif marker == 0x0D0C0B0A:
            order = ">"
        else:
            raise SnapshotError(path, "corrupt header (bad endianness marker)")
        h = np.frombuffer(raw, dtype=_dtype(_HEADER_FIELDS, HEADER_BYTES, order))[0]
        if int(h["header_crc"]) != zlib.crc32(raw[:124]):
            raise SnapshotError(path, "corrupt header (checksum mismatch)")
        if int(h["version"]) != 1:
            raise SnapshotError(path, f"format version {int(h['version'])}, this reader knows version 1")
        file_bytes = int(h["file_bytes"])
        if size < file_bytes:
            raise SnapshotError(path, f"truncated: {size} bytes, the header says {file_bytes}")
        if size > file_bytes:
            raise SnapshotError(path, f"{size - file_bytes} unexpected bytes after the end")
        if read_at(file_bytes - 8, 8, "the end marker") != BINARY_END:
            raise SnapshotError(path, "corrupt end marker")
        n = int(h["n_local"])
        if n > file_bytes // 8:
            raise SnapshotError(path, f"corrupt header (particle count {n})")
        n_fields = int(h["n_fields"])
        if n_fields > 1024:
            raise SnapshotError(path, f"corrupt header ({n_fields} fields)")
        table_raw = read_at(HEADER_BYTES, n_fields * FIELD_ENTRY_BYTES, "the field table")
        if zlib.crc32(table_raw) != int(h["table_crc"]):
            raise SnapshotError(path, "corrupt field table (checksum mismatch)")
        attr_raw = read_at(int(h["attr_offset"]), int(h["attr_bytes"]), "the attributes")
        if zlib.crc32(attr_raw) != int(h["attr_crc"]):
            raise SnapshotError(path, "corrupt attributes (checksum mismatch)")
        attrs: dict[str, str] = {}
        for k, line in enumerate(attr_raw.split(b"\n")[:-1] if attr_raw else []):
            key, tab, value = line.partition(b"\t")
            if not tab:
                raise SnapshotError(path, f"malformed attribute line {k + 1}")
            attrs[key.decode("utf-8", "replace")] = value.decode("utf-8", "replace")
        if attr_raw and not attr_raw.endswith(b"\n"):
            raise SnapshotError(path, "malformed attributes (no final newline)")

        table = np.frombuffer(table_raw, dtype=_dtype(_FIELD_ENTRY, FIELD_ENTRY_BYTES, order))
        arrays: dict[str, np.ndarray] = {}
        for e in table:
            name = e["name"].decode("ascii", "replace")
            what = f"field '{name}'"
            code, comps, nbytes, off = int(e["type"]), int(e["components"]), int(e["bytes"]), int(e["offset"])
            if code not in TYPES:
                raise SnapshotError(path, f"{what} has unknown type code {code}")
            if comps not in (1, 3):
                raise SnapshotError(path, f"{what} has {comps} components")
            ts = int(TYPES[code][1])
            if nbytes != n * ts * comps:
                raise SnapshotError(path, f"{what} has {nbytes} bytes, expected {n * ts * comps}")
            if off + nbytes > file_bytes - 8:
                raise SnapshotError(path, f"{what} runs past the end of the data")
            data = read_at(off, nbytes, what)
            if zlib.crc32(data) != int(e["crc"]):
                raise SnapshotError(path, f"{what} is corrupt (checksum mismatch)")
            if name in arrays:
                raise SnapshotError(path, f"{what} appears twice")
            a = np.frombuffer(data, dtype=order + TYPES[code]).astype(TYPES[code], copy=True)
            arrays[name] = a.reshape(n, 3) if comps == 3 else a
    for name, comps in zip(CORE, (1, 1, 3, 3)):
        if name not in arrays:
            raise SnapshotError(path, f"required field '{name}' is missing")
        if arrays[name].ndim != (2 if comps == 3 else 1):
            raise SnapshotError(path, f"field '{name}' must have {comps} components")
    if arrays["ParticleIDs"].dtype != np.uint64:
        raise SnapshotError(path, "field 'ParticleIDs' must be u64")
    for name in CORE[1:]:
        if arrays[name].dtype.kind != "f":
            raise SnapshotError(path, f"field '{name}' must be floating point")
    s = Snapshot(id=arrays.pop("ParticleIDs"), mass=arrays.pop("Masses").astype(np.float64, copy=False),
                 pos=arrays.pop("Coordinates").astype(np.float64, copy=False),
                 vel=arrays.pop("Velocities").astype(np.float64, copy=False),
                 columns=arrays, attrs=attrs, time=float(h["time"]), step=int(h["step"]),
                 n_total=int(h["n_total"]), first_index=int(h["first_index"]), part=int(h["part"]),
                 n_parts=int(h["n_parts"]), format="binary", path=path)
    return _validate(s)


# ---------------------------------------------------------------- ASCII
def read_ascii(path: str) -> Snapshot:
    """The ASCII format (".txt"): header lines, one particle a line, '# end'."""
    try:
        with open(path, encoding="utf-8") as f:
            lines = f.read().split("\n")
    except OSError as e:
        raise SnapshotError(path, f"cannot open: {e.strerror}") from None
    except UnicodeDecodeError:
        raise SnapshotError(path, "not a pik ASCII snapshot (not UTF-8 text)") from None
    if lines and lines[-1] == "":
        lines.pop()

    def fail(lineno: int, what: str) -> SnapshotError:
        return SnapshotError(f"{path}:{lineno}", what)

    def line(k: int, expect: str) -> str:
        if k >= len(lines):
            raise fail(k + 1, f"truncated: expected {expect}")
        return lines[k]

    def number(tok: str, k: int, kind=float):
        try:
            v = kind(tok)
            if kind is int and v < 0:
                raise ValueError
            return v
        except ValueError:
            noun = "a number" if kind is float else "an unsigned integer"
            raise fail(k + 1, f"'{tok}' is not {noun}") from None

    if line(0, "the header line") != ASCII_MAGIC:
        raise fail(1, f"not a pik ASCII snapshot (first line is not '{ASCII_MAGIC}')")
    t = line(1, "'# time'")
    if not t.startswith("# time "):
        raise fail(2, "expected '# time T'")
    time = number(t[7:].strip(), 1)
    st = line(2, "'# step'")
    if not st.startswith("# step "):
        raise fail(3, "expected '# step S'")
    step = number(st[7:].strip(), 2, int)
    w = line(3, "'# particles'").split()
    if len(w) != 11 or w[:2] != ["#", "particles"] or w[3] != "total" or w[5] != "first" \
            or w[7] != "part" or w[9] != "of":
        raise fail(4, "expected '# particles N total T first F part P of Q'")
    n, n_total, first, part, n_parts = (number(w[i], 3, int) for i in (2, 4, 6, 8, 10))
    k = 4
    attrs: dict[str, str] = {}
    while line(k, "'# columns'").startswith("# attr "):
        key, sp, value = lines[k][7:].partition(" ")
        if not sp:
            raise fail(k + 1, "expected '# attr NAME VALUE'")
        attrs[key] = value
        k += 1
    if not lines[k].startswith("# columns "):
        raise fail(k + 1, "expected '# columns ...'")
    cols = lines[k][10:].split()
    core = ["id", "mass", "x", "y", "z", "vx", "vy", "vz"]
    if cols[:8] != core:
        raise fail(k + 1, "the first 8 columns must be: id mass x y z vx vy vz")
    extra: list[tuple[str, int]] = []
    c = 8
    while c < len(cols):
        name = cols[c]
        if len(name) > 2 and name.endswith(".x"):
            base = name[:-2]
            if cols[c + 1:c + 3] != [base + ".y", base + ".z"]:
                raise fail(k + 1, f"column '{name}' must be followed by {base}.y {base}.z")
            extra.append((base, 3))
            c += 3
        else:
            extra.append((name, 1))
            c += 1
    if len({e[0] for e in extra}) != len(extra):
        raise fail(k + 1, "a column appears twice")
    body = k + 1
    rows = lines[body:body + n]
    for i, r in enumerate(rows):
        if r.startswith("#"):
            raise fail(body + i + 1, f"truncated: found '{r}' after {i} of {n} particles")
    if len(rows) < n:
        raise fail(body + len(rows) + 1,
                   f"truncated: expected particle line {len(rows) + 1} of {n}")
    end = body + n
    if end >= len(lines):
        raise fail(end + 1, "truncated: expected '# end'")
    if lines[end] != "# end":
        raise fail(end + 1, f"expected '# end' after {n} particles")
    for j in range(end + 1, len(lines)):
        if lines[j]:
            raise fail(j + 1, "unexpected text after '# end'")
    # The bulk: one parse of all rows; on failure, find the offending line.
    ncols = len(cols)
    tokens = " ".join(rows).split()
    if len(tokens) != n * ncols:
        for i, r in enumerate(rows):
            if len(r.split()) != ncols:
                raise fail(body + i + 1, f"expected {ncols} columns, found {len(r.split())}")
    try:
        ids = np.array([int(t) for t in tokens[0::ncols]], dtype=np.uint64) if n else np.zeros(0, np.uint64)
        vals = np.array(tokens).reshape(n, ncols)[:, 1:].astype(np.float64) \
            if n else np.zeros((0, ncols - 1))
    except (ValueError, OverflowError):
        for i, r in enumerate(rows):
            toks = r.split()
            number(toks[0], body + i, int)
            for tok in toks[1:]:
                number(tok, body + i)
        raise fail(body + 1, "malformed particle lines") from None
    columns: dict[str, np.ndarray] = {}
    c = 7
    for name, comps in extra:
        columns[name] = vals[:, c:c + comps].copy() if comps == 3 else vals[:, c].copy()
        c += comps
    s = Snapshot(id=ids, mass=vals[:, 0].copy(), pos=vals[:, 1:4].copy(), vel=vals[:, 4:7].copy(),
                 columns=columns, attrs=attrs, time=time, step=step, n_total=n_total,
                 first_index=first, part=part, n_parts=n_parts, format="ascii", path=path)
    return _validate(s)


# ---------------------------------------------------------------- HDF5
def read_hdf5(path: str) -> Snapshot:
    """The GADGET-4/SWIFT-like HDF5 layout, through h5py (Debian: python3-h5py)."""
    try:
        import h5py
    except ImportError:
        raise SnapshotError(path, "reading HDF5 needs h5py (apt install python3-h5py)") from None
    try:
        f = h5py.File(path, "r")
    except OSError:
        raise SnapshotError(path, "not a readable HDF5 file (missing, truncated or corrupt)") from None
    with f:
        if "Header" not in f:
            raise SnapshotError(path, "no /Header group")
        h = f["Header"].attrs
        for a in ("NumPart_ThisFile", "NumPart_Total", "Time"):
            if a not in h:
                raise SnapshotError(path, f"missing attribute {a}")
        this_file = np.asarray(h["NumPart_ThisFile"], dtype=np.uint64)
        if len(this_file) != 6:
            raise SnapshotError(path, "attribute NumPart_ThisFile has the wrong length")
        for t in range(6):
            if t != 1 and this_file[t] != 0:
                raise SnapshotError(path, f"has PartType{t} particles; pik reads gravity-only PartType1")
        n = int(this_file[1])
        attrs = {}
        if "Parameters" in f:
            for k, v in f["Parameters"].attrs.items():
                attrs[k] = v.decode("utf-8", "replace").rstrip("\0") if isinstance(v, bytes) else str(v)
        data: dict[str, np.ndarray] = {}
        g = f.get("PartType1")
        if g is None and n:
            raise SnapshotError(path, "no /PartType1 group")
        names = list(g.keys()) if g is not None else []
        try:
            if g is not None and g.id.get_create_plist().get_link_creation_order():
                # read back extra columns in the order written (as the C++ reader does)
                order = []
                g.id.links.iterate(lambda nm: order.append(nm.decode()), idx_type=h5py.h5.INDEX_CRT_ORDER)
                names = order
        except Exception:  # an old h5py or a file without the index: names sorted
            pass
        for name, comps, typ in (("Coordinates", 3, np.float64), ("Velocities", 3, np.float64),
                                 ("Masses", 1, np.float64), ("ParticleIDs", 1, np.uint64)):
            if n == 0 and g is None:
                data[name] = np.zeros((0, 3) if comps == 3 else 0, typ)
                continue
            if name not in g:
                raise SnapshotError(path, f"cannot open dataset /PartType1/{name}")
            data[name] = _dataset(path, g[name], n, comps, typ)
        columns = {}
        for name in names:
            if name in CORE:
                continue
            ds = g[name]
            if not isinstance(ds, h5py.Dataset) or ds.ndim not in (1, 2):
                continue
            comps = 1 if ds.ndim == 1 else ds.shape[1]
            if comps in (1, 3):
                columns[name] = _dataset(path, ds, n, comps, np.float64)
        s = Snapshot(id=data["ParticleIDs"], mass=data["Masses"], pos=data["Coordinates"],
                     vel=data["Velocities"], columns=columns, attrs=attrs, time=float(h["Time"]),
                     step=int(h.get("Step", 0)), n_total=int(np.asarray(h["NumPart_Total"])[1]),
                     first_index=int(h.get("FirstIndex", 0)), part=int(h.get("ThisFile", 0)),
                     n_parts=int(h.get("NumFilesPerSnapshot", 1)), format="hdf5", path=path)
    return _validate(s)


def _dataset(path: str, ds, n: int, comps: int, typ) -> np.ndarray:
    shape = (n, comps) if comps == 3 else (n,)
    if ds.ndim == 2 and comps == 1 and ds.shape[1] == 1:
        shape = (n, 1)
    if tuple(ds.shape) != shape:
        got = "x".join(str(d) for d in ds.shape)
        raise SnapshotError(path, f"dataset {ds.name} has shape {got}, expected {n}x{comps}")
    try:
        a = ds[...].astype(typ, copy=False)
    except OSError:
        raise SnapshotError(path, f"dataset {ds.name} cannot be read "
                                  "(corrupt data: checksum mismatch, or truncated file)") from None
    return a.reshape(n) if comps == 1 else a


# ---------------------------------------------------------------- any format, parts
def _validate(s: Snapshot) -> Snapshot:
    n = len(s.id)
    if s.n_parts == 0 or s.part >= s.n_parts:
        raise SnapshotError(s.path, f"part {s.part} of {s.n_parts}")
    if s.n_total and s.first_index + n > s.n_total:
        raise SnapshotError(s.path, f"particles {s.first_index}..{s.first_index + n} exceed "
                                    f"the total {s.n_total}")
    if s.n_total == 0:
        s.n_total = n
    return s


def detect_format(path: str) -> str:
    """"binary", "hdf5" or "ascii", from the first bytes (as pik::io::detect_format)."""
    if os.path.isdir(path):
        raise SnapshotError(path, "is a directory, not a snapshot file")
    try:
        with open(path, "rb") as f:
            head = f.read(24)
    except OSError as e:
        raise SnapshotError(path, f"cannot open: {e.strerror}") from None
    if head[:8] == BINARY_MAGIC:
        return "binary"
    if head[:8] == HDF5_MAGIC:
        return "hdf5"
    if head[:1] == b"#":
        return "ascii"
    if not head:
        raise SnapshotError(path, "empty file, not a snapshot")
    raise SnapshotError(path, "not a pik snapshot (unknown magic number: neither pik binary, "
                              "HDF5 nor pik ASCII)")


def read_file(path: str) -> Snapshot:
    """One snapshot file of any format (no joining of parts)."""
    return {"binary": read_binary, "ascii": read_ascii, "hdf5": read_hdf5}[detect_format(path)](path)


def part_path(path: str, part: int, n_parts: int) -> str:
    """`stem.<part>.ext`, the name of part `part` (pik::io::part_path)."""
    if n_parts <= 1:
        return path
    slash, dot = path.rfind("/"), path.rfind(".")
    if dot == -1 or dot < slash or dot == slash + 1:
        return f"{path}.{part}"
    return f"{path[:dot]}.{part}{path[dot:]}"


def read_snapshot(path: str | os.PathLike, parts: bool = True) -> Snapshot:
    """Reads a snapshot of any pik format. With `parts` (the default), an output
    written one part per rank is read whole: `path` names the output
    ("snap_000064.pbin" for snap_000064.0.pbin, .1.pbin, ...); the parts are checked
    to agree (part, count, step, time, columns) and to cover every particle once,
    and are concatenated in global order (pik::io::read_snapshot_parts)."""
    path = os.fspath(path)
    if not parts:
        return read_file(path)
    if os.path.exists(path):
        file0, single = path, True
    else:
        file0, single = part_path(path, 0, 2), False
        if not os.path.exists(file0):
            raise SnapshotError(path, f"cannot open: no such file (nor a per-rank part {file0})")
    first = read_file(file0)
    if single and first.n_parts == 1:
        return first
    if single:  # a part named directly: just that part
        return first
    n_parts = first.n_parts
    if first.part != 0 or first.first_index != 0:
        raise SnapshotError(part_path(path, 0, n_parts), "expected part 0 starting at particle 0")
    snaps = [first]
    for p in range(1, n_parts):
        file = part_path(path, p, n_parts)
        s = read_file(file)
        if s.part != p or s.n_parts != n_parts or s.n_total != first.n_total or s.step != first.step \
                or s.time != first.time:
            raise SnapshotError(file, "header does not match part 0 (part, count, step or time)")
        held = sum(len(x) for x in snaps)
        if s.first_index != held:
            raise SnapshotError(file, f"starts at particle {s.first_index}, expected {held}")
        if [(k, v.ndim) for k, v in s.columns.items()] != [(k, v.ndim) for k, v in first.columns.items()]:
            raise SnapshotError(file, "has different extra columns than part 0")
        snaps.append(s)
    total = sum(len(x) for x in snaps)
    if total != first.n_total:
        raise SnapshotError(path, f"parts hold {total} particles, the header says {first.n_total}")
    return Snapshot(id=np.concatenate([s.id for s in snaps]),
                    mass=np.concatenate([s.mass for s in snaps]),
                    pos=np.concatenate([s.pos for s in snaps]),
                    vel=np.concatenate([s.vel for s in snaps]),
                    columns={k: np.concatenate([s.columns[k] for s in snaps]) for k in first.columns},
                    attrs=first.attrs, time=first.time, step=first.step, n_total=total, first_index=0,
                    part=0, n_parts=1, format=first.format, path=path)
