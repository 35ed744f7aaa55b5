#!/usr/bin/python3
"""bench_python: the cost of calling pik from Python, against the same code from C++.

    bench_python.py [--build BUILD] [--n 10000] [--rounds 5] [--tree-log2n 20]
                    [--threads 2] [--skip-tree]

1. pik.Kernel on n x n pairs (kernels/gravity.pik, the kernel's own dtypes, one
   thread) against a C++ program calling the *same* generated header and wrapper
   (compiled with the same compiler and flags) on the same data; the two are
   timed alternately in `rounds` rounds of one run, best of each reported.
2. pik.gravity on 2^tree-log2n particles (cold uniform sphere, theta 0.5, leaf 8,
   group 64, the generated F32 kernel) against bench_tree --kernel generated at the
   same N, theta and threads (mean over its steps 2..4, as pik.gravity's mean over
   calls 2..4; the first call is cold in both).

Prints a table with the CPU model; ratios > 1 mean Python is slower. Needs a
build folder with the Python bindings and bench_tree (`make`).
"""
from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.normpath(os.path.join(HERE, "..", "..", "python")))

DRIVER = r"""
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>
#include "wrapper.cpp"
// The pik.Kernel library's own wrapper (structs of the dtypes + generated kernel),
// called directly: the C++ side of the comparison.
int main(int argc, char** argv) {
  const int n = std::atoi(argv[1]), reps = std::atoi(argv[2]);
  const float eps2 = float(std::atof(argv[3]));
  std::vector<PikEPI> p(n);
  std::FILE* f = std::fopen(argv[4], "rb");  // the same particles as the Python side
  if (!f || std::fread(p.data(), sizeof(PikEPI), n, f) != std::size_t(n)) return 3;
  std::fclose(f);
  std::vector<PikFORCE> out(n);
  const PikKernel k(eps2);
  double best = 1e30;
  for (int r = 0; r < reps; ++r) {
    std::fill(out.begin(), out.end(), PikFORCE{});
    const auto t0 = std::chrono::steady_clock::now();
    k(reinterpret_cast<const PikEPI*>(p.data()), n, reinterpret_cast<const PikEPJ*>(p.data()), n, out.data());
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  double s = 0;
  for (const auto& o : out) s += o.pot;
  std::printf("%.9f %.9g\n", best, s);
}
"""


def cpu_model() -> str:
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        m = re.search(r"Model name:\s*(.*)", out)
        return m.group(1).strip() if m else "unknown CPU"
    except OSError:
        return "unknown CPU"


def bench_kernel(pik, n: int, rounds: int, reps: int) -> tuple[float, float, float, str]:
    k = pik.Kernel("gravity.pik")
    rng = np.random.default_rng(1)
    p = np.zeros(n, k.particle_dtype)
    p["pos"] = rng.normal(size=(n, 3))
    p["mass"] = 1.0 / n
    eps2 = np.float32(1.0 / 4096)
    work = tempfile.mkdtemp(prefix="bench-python-")
    data = os.path.join(work, "p.bin")
    p.tofile(data)
    folder = os.path.dirname(k.library)
    exe = os.path.join(work, "driver")
    with open(os.path.join(work, "driver.cpp"), "w") as f:
        f.write(DRIVER)
    cmd = [k.cxx, "-std=c++20", *k.cxxflags, "-I", folder, *[f"-I{d}" for d in pik._paths.paths().include_dirs],
           os.path.join(work, "driver.cpp"), "-o", exe]
    subprocess.run(cmd, check=True)
    out = k.zeros(n)
    t_py, t_cpp = [], []
    for _ in range(rounds):  # alternate, so both see the same machine state
        r = subprocess.run([exe, str(n), str(reps), repr(float(eps2)), data], capture_output=True, text=True,
                           check=True)
        t_cpp.append(float(r.stdout.split()[0]))
        best = 1e30
        for _ in range(reps):
            out[...] = 0
            t0 = time.perf_counter()
            k(p, p, out, eps2=eps2, threads=1)
            best = min(best, time.perf_counter() - t0)
        t_py.append(best)
        cpp_pot = float(r.stdout.split()[1])
    py_pot = float(out["pot"].astype(np.float64).sum())
    if abs(py_pot - cpp_pot) > 1e-5 * abs(cpp_pot):
        raise SystemExit(f"bench_python: error: Python and C++ results differ ({py_pot} vs {cpp_pot})")
    out[...] = 0
    t0 = time.perf_counter()
    k(p, p, out, eps2=eps2)  # every CPU
    t_all = time.perf_counter() - t0
    return min(t_py), min(t_cpp), t_all, k.isa


def bench_tree(pik, build: str, log2n: int, threads: int) -> tuple[float, float]:
    exe = os.path.join(build, "bin", "bench_tree")
    if not os.path.exists(exe):
        raise SystemExit(f"bench_python: error: {exe} not built (cmake --build {build} --target bench_tree)")
    env = dict(os.environ, OMP_WAIT_POLICY="passive")
    r = subprocess.run([exe, "--min-log2n", str(log2n), "--max-log2n", str(log2n), "--kernel", "generated",
                        "--threads", str(threads), "--steps", "3", "--sample", "10",
                        # pik.gravity's leaf and group below (bench_tree's defaults are 12 / 128)
                        "--leaf", "8", "--group", "64"],
                       capture_output=True, text=True, check=True, env=env)
    row = [ln for ln in r.stdout.splitlines() if ln.strip().startswith(str(1 << log2n))][0]
    t_cpp = float(row.split()[1])
    # the same cold uniform sphere (distribution, not the same random numbers)
    n = 1 << log2n
    rng = np.random.default_rng(12345)
    x = rng.uniform(-1, 1, size=(2 * n, 3))
    x = x[(x ** 2).sum(1) <= 1][:n]
    m = np.full(n, 1.0 / n)
    times = []
    for _ in range(4):
        t0 = time.perf_counter()
        pik.gravity(x, m, eps=1 / 64, theta=0.5, leaf=8, group=64, threads=threads)
        times.append(time.perf_counter() - t0)
    return float(np.mean(times[1:])), t_cpp


def main() -> int:
    ap = argparse.ArgumentParser(prog="bench_python.py", description=__doc__.splitlines()[0])
    ap.add_argument("--build", default=os.environ.get("PIK_BUILD_DIR", os.path.join(HERE, "..", "..", "build")))
    ap.add_argument("--n", type=int, default=10000, help="i and j particles of the kernel call (default 10^4)")
    ap.add_argument("--rounds", type=int, default=5, help="alternating rounds (default 5)")
    ap.add_argument("--reps", type=int, default=3, help="calls per round, best kept (default 3)")
    ap.add_argument("--tree-log2n", type=int, default=20, help="log2 N of the tree step (default 20)")
    ap.add_argument("--threads", type=int, default=2, help="threads of the tree step (default 2)")
    ap.add_argument("--skip-tree", action="store_true", help="only the kernel call")
    a = ap.parse_args()
    os.environ["PIK_BUILD_DIR"] = os.path.abspath(a.build)
    import pik
    print(f"bench_python: {cpu_model()}, {os.cpu_count()} CPUs; times in seconds, best of each")
    t_py, t_cpp, t_all, isa = bench_kernel(pik, a.n, a.rounds, a.reps)
    print(f"{'what':44} {'C++ [s]':>10} {'Python [s]':>11} {'Py/C++':>7}")
    print(f"{f'gravity.pik {a.n}x{a.n} pairs, 1 thread ({isa})':44} {t_cpp:10.4f} {t_py:11.4f} {t_py / t_cpp:7.3f}")
    print(f"{f'  same, pik.Kernel threads={os.cpu_count()}':44} {'':>10} {t_all:11.4f}")
    if not a.skip_tree:
        g_py, g_cpp = bench_tree(pik, a.build, a.tree_log2n, a.threads)
        label = f"tree step N=2^{a.tree_log2n} theta 0.5, {a.threads} threads"
        print(f"{label:44} {g_cpp:10.4f} {g_py:11.4f} {g_py / g_cpp:7.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
