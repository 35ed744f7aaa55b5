"""examples/cosmo cosmo_gas restart: a run stopped by --max-steps and continued with
--restart ends with the power spectra and gas statistics of the uninterrupted run (to
rounding: the restart rebuilds the trees and iterates h afresh from the checkpoint's
smoothing lengths), and bad input is refused with a message and a non-zero exit."""
import subprocess
import sys
import tempfile
from pathlib import Path

exe = sys.argv[1]
common = ["--n", "8", "--mesh", "16", "--box", "30", "--steps", "8", "--a-end", "0.1", "--outputs", "0.05,0.1",
          "--checkpoint-every", "0", "--format", "binary"]


def run(*args, ok=True):
    p = subprocess.run([exe, *args], capture_output=True, text=True)
    if ok and p.returncode != 0:
        sys.exit(f"cosmo_gas {' '.join(args)} failed ({p.returncode}):\n{p.stdout}\n{p.stderr}")
    return p


def table(path):
    return [[float(x) for x in line.split()] for line in Path(path).read_text().splitlines() if not line.startswith("#")]


with tempfile.TemporaryDirectory() as d:
    a, b = f"{d}/a", f"{d}/b"
    run(*common, "--out", a)
    run(*common, "--out", b, "--max-steps", "5")
    assert not Path(f"{b}/pk_002.txt").exists(), "the stopped run must not reach a = 0.1"
    run("--restart", f"{b}/checkpoint.pbin", "--out", b)
    pa, pb = table(f"{a}/pk_002.txt"), table(f"{b}/pk_002.txt")
    assert len(pa) == len(pb) > 2
    worst = max(max(abs(x[1] - y[1]) / x[1], abs(x[2] - y[2]) / x[2]) for x, y in zip(pa, pb))
    print(f"restart: P_dm and P_gas at a = 0.1 differ by at most {worst:.2e} (relative)")
    assert worst < 1e-3, worst
    ga, gb = table(f"{a}/gas.txt")[-1], table(f"{b}/gas.txt")[-1]
    assert abs(ga[3] - gb[3]) < 1e-3 * ga[3], (ga, gb)
    print(f"restart: T_gas {ga[3]:.4g} K and {gb[3]:.4g} K")
    for args, msg in [(["--n", "2"], "--n must be"), (["--baryon-fraction", "1.5"], "--baryon-fraction"),
                      (["--lpt", "3"], "--lpt"), (["--gamma", "1"], "--gamma"),
                      (["--restart", f"{d}/nothing.pbin"], "nothing.pbin")]:
        p = run(*args, "--out", f"{d}/bad", ok=False)
        assert p.returncode != 0 and msg in p.stderr, (args, p.returncode, p.stderr)
print("ok")
