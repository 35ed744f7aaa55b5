"""Prints the table of bench/impact/run.sh from the collide runs' outputs."""
import re
import sys

import numpy as np

work, sizes = sys.argv[1], sys.argv[2:]
print(f"{'N':>8} {'steps':>6} {'s/step':>8} {'density':>8} {'hydro':>7} {'gravity':>8} {'tree':>6} "
      f"{'p-steps/s':>10} {'dt (s)':>7} {'24 h: steps':>11} {'24 h: wall':>10}")
for n in sizes:
    txt = open(f"{work}/collide_{n}.txt").read()
    m = re.search(r"steps (\d+), t = ([\d.e+-]+) s, wall ([\d.]+) s: density ([\d.]+) s .*?eos ([\d.]+) s, hydro "
                  r"([\d.]+) s, gravity ([\d.]+) s, tree builds ([\d.]+) s; ([\d.e+]+) particle-steps/s", txt)
    head = re.search(r"target [\d.]+ M_E \((\d+) particles.*impactor [\d.]+ M_E \((\d+),", txt)
    if not m or not head:
        sys.exit(f"cannot parse {work}/collide_{n}.txt")
    steps, t, wall, dens, eos, hydro, grav, tree, pps = (float(x) for x in m.groups())
    ntot = int(head.group(1)) + int(head.group(2))
    log = np.loadtxt(f"{work}/collide_{n}/log.txt")
    dt = np.median(log[1:, 2])
    steps24 = 86400 / dt
    print(f"{ntot:>8} {int(steps):>6} {wall / steps:>8.3f} {dens / steps:>8.3f} {hydro / steps:>7.3f} "
          f"{grav / steps:>8.3f} {tree / steps:>6.3f} {pps:>10.3g} {dt:>7.2f} {steps24:>11.0f} "
          f"{steps24 * wall / steps / 60:>8.0f} min")
print("density/hydro/gravity include their trees' builds; 'tree' is the sum of the three trees' build times.")
