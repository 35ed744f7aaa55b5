#!/usr/bin/env python3
"""Put a finite-difference solution (fd_reference.py --save) into a convection snapshot, to
start an SPH run from the converged fields:

    fd_to_snapshot.py --fd FILE.npz --template SNAP.pbin --out NEW.pbin

The template is any 2D binary snapshot or checkpoint of the problem (its Ra, viscosity law
and contrast; the resolution does not matter): the new file is a copy of it with each
particle's temperature and velocity replaced by the FD fields interpolated (bilinearly) at
its position, the velocity in the run's code units (times convection.c). Everything else
(positions, masses, attributes, the other columns) is kept, and every checksum of the
format (docs/snapshots.md) is rewritten. Start from it with

    convection ... --init NEW.pbin --init-pressure no

(T and v interpolated onto the run's lattice; the pressure perturbation of the template
does not belong to the new fields, so it starts at 0). Used for case 2a in
docs/convection.md: a run started from the converged solution and one started from case
1a's cell bracket the steady state of a resolution from both sides. Not a test.
"""
from __future__ import annotations

import argparse
import shutil
import sys
import zlib
from pathlib import Path

import numpy as np
from scipy.interpolate import RegularGridInterpolator

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "python"))
import pik  # noqa: E402
from pik import snapshot as snap  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--fd", required=True, help="an fd_reference.py --save file (T, vx, vz)")
    ap.add_argument("--template", required=True, help="a 2D binary snapshot or checkpoint of the problem")
    ap.add_argument("--out", required=True, help="the new snapshot (must not exist)")
    a = ap.parse_args()
    out = Path(a.out)
    if out.exists():
        sys.exit(f"fd_to_snapshot.py: error: {out} exists (not overwritten)")
    try:
        d = np.load(a.fd)
        T, vx, vz = d["T"], d["vx"], d["vz"]
    except (OSError, KeyError, ValueError) as e:
        sys.exit(f"fd_to_snapshot.py: error: cannot read T, vx, vz from {a.fd}: {e}")
    try:
        s = snap.read_binary(a.template)
    except pik.SnapshotError as e:
        sys.exit(f"fd_to_snapshot.py: error: {e}")
    if int(s.attrs.get("convection.dim", "0")) != 2 or "Temperature" not in s.columns:
        sys.exit(f"fd_to_snapshot.py: error: {a.template} is not a 2D convection snapshot")
    if float(s.attrs.get("convection.aspect", "1")) != 1.0:
        sys.exit("fd_to_snapshot.py: error: the FD solution is for aspect 1 only")
    c = float(s.attrs.get("convection.c", "1"))
    g = np.linspace(0.0, 1.0, T.shape[0])  # fd grids are [i, j] = (x_i, z_j)
    xz = np.clip(s.pos[:, :2], 0.0, 1.0)
    new = {"Temperature": RegularGridInterpolator((g, g), T)(xz)}
    vel = s.vel.copy()
    vel[:, 0] = RegularGridInterpolator((g, g), vx)(xz) * c
    vel[:, 1] = RegularGridInterpolator((g, g), vz)(xz) * c
    new["Velocities"] = vel

    raw = bytearray(Path(a.template).read_bytes())
    order = "<" if int.from_bytes(raw[12:16], "little") == snap.ENDIAN_MARKER else ">"
    hdr = np.dtype(snap._dtype(snap._HEADER_FIELDS, snap.HEADER_BYTES, order))
    h = np.frombuffer(bytes(raw[:snap.HEADER_BYTES]), dtype=hdr)[0]
    nf = int(h["n_fields"])
    ent = snap._dtype(snap._FIELD_ENTRY, snap.FIELD_ENTRY_BYTES, order)
    t0, t1 = snap.HEADER_BYTES, snap.HEADER_BYTES + nf * snap.FIELD_ENTRY_BYTES
    table = np.frombuffer(bytes(raw[t0:t1]), dtype=ent).copy()
    done = set()
    for e in table:
        name = e["name"].decode("ascii", "replace").rstrip("\0")
        if name not in new:
            continue
        dt = np.dtype(order + snap.TYPES[int(e["type"])])
        data = np.ascontiguousarray(new[name], dtype=dt).tobytes()
        off = int(e["offset"])
        if len(data) != int(e["bytes"]):
            sys.exit(f"fd_to_snapshot.py: error: field '{name}' of {a.template} has an unexpected size")
        raw[off:off + len(data)] = data
        e["crc"] = zlib.crc32(data)
        done.add(name)
    if done != set(new):
        sys.exit(f"fd_to_snapshot.py: error: {a.template} lacks {sorted(set(new) - done)}")
    tab = table.tobytes()
    raw[t0:t1] = tab
    raw[68:72] = np.array(zlib.crc32(tab), dtype=order + "u4").tobytes()
    raw[124:128] = np.array(zlib.crc32(bytes(raw[:124])), dtype=order + "u4").tobytes()
    tmp = out.with_name(out.name + ".part")
    tmp.write_bytes(bytes(raw))
    snap.read_binary(str(tmp))  # every checksum verified before the name is given
    shutil.move(tmp, out)
    w = np.full(T.shape[0], 1.0 / (T.shape[0] - 1))
    w[[0, -1]] *= 0.5
    print(f"wrote {out}: {len(s.pos)} particles, <T> {new['Temperature'].mean():.4f} "
          f"(FD {float(np.sum(w[:, None] * w[None, :] * T)):.4f}), "
          f"v_rms {np.sqrt(np.mean(vel[:, 0] ** 2 + vel[:, 1] ** 2)) / c:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
