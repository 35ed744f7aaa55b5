"""pik.Kernel: compile a .pik file and call it on NumPy arrays; the cache; errors."""
import os
import subprocess
import textwrap

import numpy as np
import pytest

import pik
from conftest import direct_gravity

EPS = 0.05


def particles(k, rng, n):
    p = np.zeros(n, k.particle_dtype)
    p["pos"] = rng.normal(size=(n, 3))
    p["mass"] = rng.uniform(0.5, 1.5, n) / n
    return p


@pytest.fixture(scope="module")
def gravity_kernel():
    return pik.Kernel("gravity.pik")  # from pik's kernel library


# -- compile and call -----------------------------------------------------------
def test_default_dtypes_follow_the_declarations(gravity_kernel):
    k = gravity_kernel
    # EPI F32vec xi:pos; EPJ F32vec xj:pos, F32 mj:mass; FORCE F32vec acc:acc, F32 pot:pot
    assert k.particle_dtype.names == ("pos", "mass")
    assert k.particle_dtype["pos"] == np.dtype(("f4", (3,)))
    assert k.force_dtype.names == ("acc", "pot")
    assert k.param_names == ["eps2"]
    assert k.isa in ("reference", "AVX2", "AVX-512")


@pytest.mark.parametrize("n", [1, 7, 64, 300, 1001])  # odd sizes: tails of every SIMD width
def test_gravity_matches_float64_direct_sum(gravity_kernel, rng, n):
    k = gravity_kernel
    p = particles(k, rng, n)
    f = k(p, eps2=EPS * EPS, threads=1)
    acc, pot = direct_gravity(p["pos"].astype(np.float64), p["mass"].astype(np.float64), EPS)
    # F32 kernel: relative error of the sum a few ulp of float times sqrt(n)
    scale = np.abs(acc).max()
    assert np.abs(f["acc"] - acc).max() <= 2e-5 * scale
    assert np.abs(f["pot"] - pot).max() <= 2e-5 * np.abs(pot).max()


def test_same_results_as_the_runtime_kernel(gravity_kernel, rng, native):
    """The same gravity.pik through the C++ runtime (pik.gravity at theta 0 is the
    direct sum over leaves with the generated kernel) agrees to float rounding."""
    k = gravity_kernel
    p = particles(k, rng, 2000)
    f = k(p, eps2=np.float32(EPS) ** 2)
    acc, pot = pik.gravity(p["pos"], p["mass"], eps=float(np.float32(EPS)), theta=0.0)
    assert np.abs(f["acc"] - acc).max() <= 1e-5 * np.abs(acc).max()
    assert np.abs(f["pot"] - pot).max() <= 1e-5 * np.abs(pot).max()


def test_zero_size_and_accumulation_in_place(gravity_kernel, rng):
    k = gravity_kernel
    p = particles(k, rng, 100)
    assert len(k(p[:0], p, eps2=0.01)) == 0
    assert np.all(k(p, p[:0], eps2=0.01)["pot"] == 0)
    out = k.zeros(100)
    r1 = k(p, p, out, eps2=0.01)
    assert r1 is out  # the caller's array, no copy
    first = out.copy()
    k(p, p, out, eps2=0.01)  # kernels accumulate (the caller clears)
    np.testing.assert_allclose(out["pot"], 2 * first["pot"], rtol=1e-6)


def test_threads_do_not_change_results(gravity_kernel, rng):
    k = gravity_kernel
    p = particles(k, rng, 5000)
    one = k(p, eps2=0.01, threads=1)
    three = k(p, eps2=0.01, threads=3)
    assert one.tobytes() == three.tobytes()  # each i sums its j in the same order


def test_dicts_of_arrays_and_foreign_dtypes(gravity_kernel, rng):
    k = gravity_kernel
    p = particles(k, rng, 257)
    ref = k(p, eps2=0.01)
    d = {"pos": p["pos"].astype(np.float64), "mass": p["mass"].astype(np.float64)}
    force = {"pot": np.zeros(257)}
    out = k(d, d, force, eps2=0.01)
    assert out is force and force["pot"].dtype == np.float64  # updated in place
    np.testing.assert_array_equal(force["pot"], ref["pot"])
    np.testing.assert_array_equal(force["acc"], ref["acc"])
    with pytest.raises(ValueError, match="no 'mass'"):
        k({"pos": d["pos"]}, eps2=0.01)


def test_user_dtype_with_doubles_and_other_fields(rng):
    """A program's own particle layout (doubles, extra fields): the kernel is
    compiled for it and reads the array in place."""
    body = np.dtype([("id", "u8"), ("pos", "f8", 3), ("vel", "f8", 3), ("mass", "f8"), ("flag", "i4")],
                    align=True)
    res = np.dtype([("pot", "f8"), ("acc", "f8", 3), ("spare", "f8")])
    k = pik.Kernel("gravity_f64.pik", epi=body, epj=body, force=res, params={"eps2": EPS ** 2})
    b = np.zeros(400, body)
    b["pos"] = rng.normal(size=(400, 3))
    b["mass"] = 1 / 400
    b["id"] = np.arange(400)
    f = k(b, b)
    acc, pot = direct_gravity(b["pos"], b["mass"], EPS)
    np.testing.assert_allclose(f["acc"], acc, rtol=0, atol=1e-12 * np.abs(acc).max())
    np.testing.assert_allclose(f["pot"], pot, rtol=1e-12)
    assert np.all(f["spare"] == 0)


def test_a_new_kernel_with_an_integer_parameter_and_constants(tmp_path, rng):
    src = tmp_path / "count.pik"
    src.write_text(textwrap.dedent("""\
        // neighbours within r (a cut-off count) and the sum of w * r^2 inside it
        EPI F64vec xi:x
        EPJ F64vec xj:x
        FORCE F64 n:n
        FORCE F64 s:s
        F64 r
        S32 power
        F64 w
        d = xi - xj
        d2 = d * d
        if d2 < r * r
          n += 1.0
          if power == 2
            s += w * d2
          else
            s += w
          endif
        endif
        """))
    x = rng.uniform(size=(500, 3))
    k = pik.Kernel(src, consts={"w": 2.0})
    assert k.param_names == ["r", "power"]
    out = k({"x": x}, r=0.2, power=2)
    d2 = ((x[:, None, :] - x[None, :, :]) ** 2).sum(-1)
    inside = d2 < 0.04
    np.testing.assert_array_equal(out["n"], inside.sum(1))
    np.testing.assert_allclose(out["s"], 2.0 * (d2 * inside).sum(1), rtol=1e-12)
    out1 = k({"x": x}, r=0.2, power=1)
    np.testing.assert_allclose(out1["s"], 2.0 * inside.sum(1), rtol=1e-12)
    with pytest.raises(TypeError, match="missing kernel parameter"):
        k({"x": x}, r=0.2)
    with pytest.raises(TypeError, match="unknown kernel parameter"):
        k({"x": x}, r=0.2, power=2, q=1)


CXX_DRIVER = r"""
#include <cstdio>
#include <vector>
#include "wrapper.cpp"
// The generated kernel called from C++ exactly as a program would: the reference
// for "pik.Kernel gives the C++ kernel's results".
int main(int argc, char** argv) {
  const int n = std::atoi(argv[1]);
  std::vector<PikEPI> p(n);
  std::FILE* f = std::fopen(argv[2], "rb");
  if (!f || std::fread(p.data(), sizeof(PikEPI), std::size_t(n), f) != std::size_t(n)) return 3;
  std::fclose(f);
  std::vector<PikFORCE> out(n);
  const PikKernel k(float(std::atof(argv[3])));
  k(p.data(), n, reinterpret_cast<const PikEPJ*>(p.data()), n, out.data());
  f = std::fopen(argv[4], "wb");
  std::fwrite(out.data(), sizeof(PikFORCE), std::size_t(n), f);
  std::fclose(f);
}
"""


def test_bitwise_the_results_of_the_kernel_called_from_cxx(gravity_kernel, rng, tmp_path):
    """The library's kernel and the same generated header compiled into a C++
    program give identical bits (same code, same compiler and flags)."""
    k = gravity_kernel
    n = 777
    p = particles(k, rng, n)
    p.tofile(tmp_path / "p.bin")
    (tmp_path / "driver.cpp").write_text(CXX_DRIVER)
    folder = os.path.dirname(k.library)
    exe = tmp_path / "driver"
    subprocess.run([k.cxx, "-std=c++20", *k.cxxflags, "-I", folder,
                    *[f"-I{d}" for d in pik._paths.paths().include_dirs], str(tmp_path / "driver.cpp"),
                    "-o", str(exe)], check=True)
    eps2 = np.float32(EPS) ** 2
    subprocess.run([str(exe), str(n), str(tmp_path / "p.bin"), repr(float(eps2)), str(tmp_path / "f.bin")],
                   check=True)
    cxx = np.fromfile(tmp_path / "f.bin", dtype=k.force_dtype)
    py = k(p, eps2=eps2, threads=3)
    assert py.tobytes() == cxx.tobytes()


@pytest.mark.parametrize("target", ["reference", "avx2", "avx512"])
def test_every_target_the_host_has(rng, target):
    """Each single-ISA library agrees with float64; an ISA the CPU lacks is refused
    with a message (never run into SIGILL)."""
    from pik.kernel import _ISA_FLAGS
    flags = open("/proc/cpuinfo").read()
    if any(f not in flags.split() for f in _ISA_FLAGS.get(target, ())):
        with pytest.raises(pik.KernelError, match="this CPU lacks"):
            pik.Kernel("gravity.pik", target=target)
        pytest.skip(f"this CPU has no {target}: refusal checked")
    k = pik.Kernel("gravity.pik", target=target)
    p = particles(k, rng, 333)
    f = k(p, eps2=EPS * EPS)
    acc, _ = direct_gravity(p["pos"].astype(np.float64), p["mass"].astype(np.float64), EPS)
    assert np.abs(f["acc"] - acc).max() <= 2e-5 * np.abs(acc).max()
    assert k.isa.lower().replace("-", "") == target.replace("-", "")
