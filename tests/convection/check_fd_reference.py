#!/usr/bin/env python3
"""bench/convection/fd_reference.py, the finite-difference cross-check of the convection docs:
case 1a (Ra = 1e4, isoviscous) on 24 intervals reaches Blankenbach et al.'s (1989) v_rms 42.864947
within 0.5 % (measured -0.12 %) and Nu 4.884409 within 6 % (measured +5.0 %: the one-sided wall
gradient is the coarse part) with Nu top = bottom; bad input is refused with a message.

    check_fd_reference.py FD_REFERENCE_PY OUT_DIR
"""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

NU_1A, VRMS_1A = 4.884409, 42.864947


def main() -> int:
    script, out = sys.argv[1], Path(sys.argv[2])
    out.mkdir(parents=True, exist_ok=True)
    cmd = [sys.executable, script, "--n", "24", "--contrast", "1", "--t-end", "0.3", "--dt", "1e-3",
           "--save", str(out / "case1a.npz"), "--profiles"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"FAIL: {' '.join(cmd)} exited {p.returncode}\n{p.stdout}\n{p.stderr}")
    m = re.search(r"Nu top ([\d.]+) bottom ([\d.]+)\s+v_rms ([\d.]+)\s+<T> ([\d.]+)", p.stdout)
    if not m:
        sys.exit(f"FAIL: no final line in\n{p.stdout}")
    nut, nub, vrms, tm = (float(g) for g in m.groups())
    print(f"case 1a, 24 intervals: Nu {nut:.4f} / {nub:.4f} ({100 * (nut / NU_1A - 1):+.2f} %), "
          f"v_rms {vrms:.3f} ({100 * (vrms / VRMS_1A - 1):+.2f} %), <T> {tm:.4f}")
    if abs(vrms / VRMS_1A - 1) > 0.005 or abs(nut / NU_1A - 1) > 0.06 or abs(nut - nub) > 1e-3 * nut:
        sys.exit("FAIL: case 1a is not reproduced")
    if abs(tm - 0.5) > 1e-3:  # the isoviscous cell is symmetric about T = 1/2
        sys.exit("FAIL: the isoviscous mean temperature is not 1/2")
    if not (out / "case1a.npz").exists():
        sys.exit("FAIL: --save wrote nothing")
    bad = [(["--n", "2"], "--n must be at least 4"), (["--n", "8", "--contrast", "0.5"], "--contrast must be at least 1"),
           (["--n", "8", "--dt", "0"], "must be positive"), (["--n", "8", "--init", str(out / "missing.npz")], "cannot read T")]
    for args, want in bad:
        p = subprocess.run([sys.executable, script, *args], capture_output=True, text=True)
        if p.returncode == 0 or want not in p.stderr:
            sys.exit(f"FAIL: {args} gave exit {p.returncode}, wanted a non-zero exit and '{want}':\n{p.stderr}")
        print(f"refused {args}: {p.stderr.strip()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
