"""pik.read_snapshot on files written by the C++ runtime (pik::io), every format,
per-rank parts, and damaged files."""
import os
import zlib

import numpy as np
import pytest

import pik
from pik.snapshot import Snapshot

FORMATS = ["binary", "ascii", "hdf5"]
EXT = {"binary": ".pbin", "ascii": ".txt", "hdf5": ".hdf5"}


def need(native, fmt):
    if fmt == "hdf5":
        if not native.have_hdf5:
            pytest.skip("the bindings were built without HDF5 (libhdf5-dev)")
        pytest.importorskip("h5py", reason="reading HDF5 needs h5py (python3-h5py)")


def make(rng, n, **kw):
    s = Snapshot(id=rng.permutation(n).astype(np.uint64) + 100, mass=rng.uniform(size=n),
                 pos=rng.normal(size=(n, 3)), vel=rng.normal(size=(n, 3)),
                 columns={"Acceleration": rng.normal(size=(n, 3)), "Potential": -rng.uniform(size=n)},
                 attrs={"theta": "0.5", "kernel": "gravity f32", "note": "a b\u00e9"},
                 time=0.1 + 1e-17 * 3, step=64)
    for k, v in kw.items():
        setattr(s, k, v)
    return s


def same(a, b):
    for f in ("id", "mass", "pos", "vel"):
        assert getattr(a, f).dtype == getattr(b, f).dtype
        assert getattr(a, f).tobytes() == getattr(b, f).tobytes(), f  # bit for bit
    assert list(a.columns) == list(b.columns)
    for k in a.columns:
        assert a.columns[k].tobytes() == b.columns[k].tobytes(), k
    assert a.time == b.time and a.step == b.step and a.attrs == b.attrs


@pytest.mark.parametrize("fmt", FORMATS)
def test_round_trip_every_format(native, rng, tmp_path, fmt):
    need(native, fmt)
    s = make(rng, 1001)
    path = tmp_path / ("snap" + EXT[fmt])
    pik.write_snapshot(path, s, fmt)
    r = pik.read_snapshot(path)
    assert r.format == fmt and pik.detect_format(str(path)) == fmt
    same(s, r)
    assert r.pos.shape == (1001, 3) and r["Coordinates"] is r.pos and r["Potential"].shape == (1001,)
    assert len(r) == 1001 and r.n_parts == 1 and r.n_total == 1001


@pytest.mark.parametrize("fmt", FORMATS)
def test_empty_snapshot(native, rng, tmp_path, fmt):
    need(native, fmt)
    s = make(rng, 0)
    path = tmp_path / ("empty" + EXT[fmt])
    pik.write_snapshot(path, s, fmt)
    r = pik.read_snapshot(path)
    assert len(r) == 0 and r.pos.shape == (0, 3) and r.step == 64


@pytest.mark.parametrize("fmt", FORMATS)
def test_per_rank_parts_are_joined(native, rng, tmp_path, fmt):
    need(native, fmt)
    whole = make(rng, 1000)
    cuts = [0, 300, 301, 1000]  # part 1 holds one particle
    out = tmp_path / ("snap_000064" + EXT[fmt])
    for p in range(3):
        a, b = cuts[p], cuts[p + 1]
        part = Snapshot(id=whole.id[a:b], mass=whole.mass[a:b], pos=whole.pos[a:b], vel=whole.vel[a:b],
                        columns={k: v[a:b] for k, v in whole.columns.items()}, attrs=whole.attrs,
                        time=whole.time, step=whole.step, part=p, n_parts=3, first_index=a, n_total=1000)
        pik.write_snapshot(out, part, fmt)
    assert not out.exists() and (tmp_path / ("snap_000064.2" + EXT[fmt])).exists()
    r = pik.read_snapshot(out)
    same(whole, r)
    one = pik.read_snapshot(tmp_path / ("snap_000064.1" + EXT[fmt]))  # a part on its own
    assert len(one) == 1 and one.part == 1 and one.n_parts == 3 and one.first_index == 300
    # a missing part is an error naming it
    os.remove(tmp_path / ("snap_000064.2" + EXT[fmt]))
    with pytest.raises(pik.SnapshotError, match=r"snap_000064\.2"):
        pik.read_snapshot(out)


def test_binary_checksums_are_zlib_crc32(native, rng, tmp_path):
    """The header's CRC-32 is zlib's (docs/snapshots.md): files stay readable by any zlib."""
    path = tmp_path / "s.pbin"
    pik.write_snapshot(path, make(rng, 10), "binary")
    raw = path.read_bytes()
    assert int.from_bytes(raw[124:128], "little") == zlib.crc32(raw[:124])


def test_truncated_binary(native, rng, tmp_path):
    path = tmp_path / "s.pbin"
    pik.write_snapshot(path, make(rng, 500), "binary")
    raw = path.read_bytes()
    for keep in (len(raw) - 1, len(raw) // 2, 200, 100, 5):
        path.write_bytes(raw[:keep])
        with pytest.raises(pik.SnapshotError, match="truncated|bad magic") as e:
            pik.read_snapshot(path)
        assert str(e.value).startswith(f"{path}: ")
    path.write_bytes(raw[:len(raw) // 2])
    with pytest.raises(pik.SnapshotError, match=rf"truncated: {len(raw) // 2} bytes, the header says {len(raw)}"):
        pik.read_snapshot(path)


def test_corrupt_binary(native, rng, tmp_path):
    path = tmp_path / "s.pbin"
    pik.write_snapshot(path, make(rng, 500), "binary")
    raw = bytearray(path.read_bytes())
    bad = raw.copy()
    bad[-100] ^= 0x40  # a bit in the last field's data
    path.write_bytes(bad)
    with pytest.raises(pik.SnapshotError, match="corrupt \\(checksum mismatch\\)"):
        pik.read_snapshot(path)
    bad = raw.copy()
    bad[20] ^= 1  # the header
    path.write_bytes(bad)
    with pytest.raises(pik.SnapshotError, match="corrupt header"):
        pik.read_snapshot(path)
    path.write_bytes(bytes(raw) + b"\0")
    with pytest.raises(pik.SnapshotError, match="unexpected bytes after the end"):
        pik.read_snapshot(path)


def test_truncated_and_malformed_ascii(native, rng, tmp_path):
    path = tmp_path / "s.txt"
    pik.write_snapshot(path, make(rng, 50), "ascii")
    lines = path.read_text().split("\n")
    path.write_text("\n".join(lines[:30]) + "\n")  # cut inside the particle lines
    with pytest.raises(pik.SnapshotError, match=r"s\.txt:\d+: truncated"):
        pik.read_snapshot(path)
    path.write_text("\n".join(lines[:-2]) + "\n")  # no '# end'
    with pytest.raises(pik.SnapshotError, match="truncated: expected '# end'"):
        pik.read_snapshot(path)
    bad = list(lines)
    bad[12] = bad[12].replace(" ", " x", 1)
    path.write_text("\n".join(bad))
    with pytest.raises(pik.SnapshotError, match=r":13: 'x[^']*' is not a number"):
        pik.read_snapshot(path)
    bad = list(lines)
    bad[12] = " ".join(bad[12].split()[:-1])
    path.write_text("\n".join(bad))
    with pytest.raises(pik.SnapshotError, match=r":13: expected 12 columns, found 11"):
        pik.read_snapshot(path)


def test_truncated_hdf5(native, rng, tmp_path):
    need(native, "hdf5")
    path = tmp_path / "s.hdf5"
    pik.write_snapshot(path, make(rng, 2000), "hdf5")
    raw = path.read_bytes()
    path.write_bytes(raw[:len(raw) // 2])
    with pytest.raises(pik.SnapshotError, match="s.hdf5: .*(truncated|corrupt)"):
        pik.read_snapshot(path)


def test_foreign_missing_and_empty_files(tmp_path):
    with pytest.raises(pik.SnapshotError, match="no such file"):
        pik.read_snapshot(tmp_path / "none.pbin")
    (tmp_path / "e.pbin").write_bytes(b"")
    with pytest.raises(pik.SnapshotError, match="empty file"):
        pik.read_snapshot(tmp_path / "e.pbin")
    (tmp_path / "x.pbin").write_bytes(b"GIF89a....")
    with pytest.raises(pik.SnapshotError, match="not a pik snapshot"):
        pik.read_snapshot(tmp_path / "x.pbin")
    with pytest.raises(pik.SnapshotError, match="is a directory"):
        pik.read_snapshot(tmp_path)


def test_file_written_before_zlib_crc(native):
    """tests/python/data/crc_v1.pbin was written with pik's hand-written CRC-32."""
    here = os.path.dirname(os.path.abspath(__file__))
    s = pik.read_snapshot(os.path.join(here, "data", "crc_v1.pbin"))
    assert len(s) == 16 and s.step == 32 and s.time == 0.125 and int(s.id[5]) == 38
    np.testing.assert_array_equal(s.columns["Potential"], -1.0 / (np.arange(16) + 2))
