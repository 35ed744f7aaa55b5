"""pik.Kernel: the library cache and the errors (pikg-gen, the C++ compiler, bad dtypes)."""
import os
import subprocess
import sys

import numpy as np
import pytest

import pik


def test_wrong_dtypes_are_refused():
    with pytest.raises(ValueError, match="no field 'mass'"):
        pik.Kernel("gravity.pik", epi=np.dtype([("pos", "f4", 3)]), epj=np.dtype([("pos", "f4", 3)]))
    with pytest.raises(ValueError, match="shape"):
        bad = np.dtype([("pos", "f4"), ("mass", "f4")])
        pik.Kernel("gravity.pik", epi=bad, epj=bad)


# -- the cache ------------------------------------------------------------------
def test_second_construction_is_a_cache_hit(tmp_path):
    src = tmp_path / "g.pik"
    # pikg-gen's sources are part of the key: hash them now, as the child process will
    pik.kernel._pikg_gen_id.cache_clear()
    # a source no earlier run has compiled (the cache outlives test runs)
    src.write_text(open(pik.Kernel("gravity.pik").path).read() + f"// {os.urandom(8).hex()}\n")
    k1 = pik.Kernel(src)
    assert not k1.cache_hit
    mtime = os.path.getmtime(k1.library)
    k2 = pik.Kernel(src)
    assert k2.cache_hit and k2.library == k1.library and os.path.getmtime(k2.library) == mtime
    # another process finds it too
    code = f"import pik; k = pik.Kernel({str(src)!r}); print(k.cache_hit, k.library)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["True", k1.library]
    # source, options and compiler flags are part of the key
    assert pik.Kernel(src, target="reference").key != k1.key
    assert pik.Kernel(src, cxxflags=["-O2"]).key != k1.key
    src.write_text(src.read_text() + "\n// a comment changes the source\n")
    assert pik.Kernel(src).key != k1.key


# -- errors -----------------------------------------------------------------------
def test_bad_kernel_raises_with_its_location(tmp_path):
    src = tmp_path / "bad.pik"
    src.write_text("EPI F32vec xi:pos\nEPJ F32vec xj:pos\nFORCE F32 pot:pot\n"
                   "r2 = (xi - xj) * (xi - xj)\npot += rsqrt(r2) * undefined_name\n")
    with pytest.raises(pik.KernelError) as e:
        pik.Kernel(src)
    assert e.value.file == str(src) and e.value.line == 5 and e.value.col == 20
    assert f"{src}:5:20: error:" in str(e.value)
    assert "undefined_name" in e.value.message
    assert "^" in str(e.value)  # the source line and a caret, as pikg-gen prints them


def test_syntax_error_raises_with_its_location(tmp_path):
    src = tmp_path / "syntax.pik"
    src.write_text("EPI F32vec xi:pos\nFORCE F32 pot:pot\npot += (xi * xi\n")
    with pytest.raises(pik.KernelError) as e:
        pik.Kernel(src)
    assert e.value.line == 3 and str(e.value).startswith(f"{src}:3:")


def test_compiler_errors_raise_build_error(tmp_path):
    with pytest.raises(pik.BuildError) as e:
        pik.Kernel("gravity.pik", cxxflags=["-O2", "-include", str(tmp_path / "missing.h")])
    assert "missing.h" in str(e.value) and "command:" in str(e.value)


def test_missing_file():
    with pytest.raises(FileNotFoundError, match="no such kernel file"):
        pik.Kernel("no_such_kernel.pik")


def test_pikg_gen_errors_raise_kernel_error():
    """An error pikg-gen itself reports (here a --const for no parameter)."""
    with pytest.raises(pik.KernelError, match="nope"):
        pik.Kernel("gravity.pik", consts={"nope": 1})
