"""examples/cosmo restart: a run stopped by --max-steps and continued with --restart
ends with the power spectrum and halo list of the uninterrupted run (to rounding:
the restart rebuilds the tree from the checkpoint's positions), and bad input is
refused with a message and a non-zero exit."""
import subprocess
import sys
import tempfile
from pathlib import Path

exe = sys.argv[1]
common = ["--n", "16", "--box", "24", "--steps", "12", "--outputs", "0.5,1", "--checkpoint-every", "0"]


def run(*args, ok=True):
    p = subprocess.run([exe, *args], capture_output=True, text=True)
    if ok and p.returncode != 0:
        sys.exit(f"cosmo {' '.join(args)} failed ({p.returncode}):\n{p.stdout}\n{p.stderr}")
    return p


def table(path):
    return [[float(x) for x in line.split()] for line in Path(path).read_text().splitlines() if not line.startswith("#")]


with tempfile.TemporaryDirectory() as d:
    a, b = f"{d}/a", f"{d}/b"
    run(*common, "--out", a)
    run(*common, "--out", b, "--max-steps", "5")
    assert not Path(f"{b}/pk_002.txt").exists(), "the stopped run must not reach a = 1"
    run("--restart", f"{b}/checkpoint.pbin", "--out", b)
    pa, pb = table(f"{a}/pk_002.txt"), table(f"{b}/pk_002.txt")
    assert len(pa) == len(pb) > 4
    worst = max(abs(x[1] - y[1]) / x[1] for x, y in zip(pa, pb))
    print(f"restart: P(k) at a = 1 differs by at most {worst:.2e} (relative)")
    assert worst < 1e-3, worst
    ha, hb = table(f"{a}/fof_002.txt"), table(f"{b}/fof_002.txt")
    assert len(ha) == len(hb) > 0, (len(ha), len(hb))
    print(f"restart: {len(ha)} haloes in both runs")
    for args, msg in [(["--n", "1"], "--n must be"), (["--omega-m", "2"], "--omega-m"),
                      (["--spectrum", "cdm"], "--spectrum"), (["--a-start", "2"], "--a-start"),
                      (["--restart", f"{d}/nothing.pbin"], "nothing.pbin")]:
        p = run(*args, "--out", f"{d}/bad", ok=False)
        assert p.returncode != 0 and msg in p.stderr, (args, p.returncode, p.stderr)
print("ok")
