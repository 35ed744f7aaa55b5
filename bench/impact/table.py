"""Prints the table of bench/impact/run.sh from the collide runs' outputs."""
import os
import re
import sys

import numpy as np

work, sizes = sys.argv[1], sys.argv[2:]
splits, cpus = [], []
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
    sp = re.search(r"split: density walk ([\d.]+) s, hydro walk ([\d.]+) s, short-range tree refresh\+moments ([\d.]+) s, "
                   r"gravity tree build\+moments ([\d.]+) s, gravity walk ([\d.]+) s, density passes/evaluation ([\d.]+), "
                   r"groups walked per pass ([\d.]+)", txt)
    if sp:
        splits.append((ntot, int(steps), *(float(x) for x in sp.groups())))
    cp = re.search(r"cpu: process ([\d.]+) s, density ([\d.]+) s, eos ([\d.]+) s, hydro ([\d.]+) s, gravity ([\d.]+) s", txt)
    log = np.loadtxt(f"{work}/collide_{n}/log.txt")
    dt = np.median(log[1:, 2])
    steps24 = 86400 / dt
    if cp:
        cpus.append((ntot, int(steps), dt, steps24, *(float(x) for x in cp.groups())))
    print(f"{ntot:>8} {int(steps):>6} {wall / steps:>8.3f} {dens / steps:>8.3f} {hydro / steps:>7.3f} "
          f"{grav / steps:>8.3f} {tree / steps:>6.3f} {pps:>10.3g} {dt:>7.2f} {steps24:>11.0f} "
          f"{steps24 * wall / steps / 60:>8.0f} min")
print("density/hydro/gravity include their trees' builds; 'tree' is the sum of the three trees' build times.")
if splits:
    print()
    print("per step (s): the walks (kernels included), the short-range trees' refreshes and cell moments, the gravity "
          "tree's build; passes per force evaluation; fraction of the i-groups walked per density pass")
    print(f"{'N':>8} {'dens walk':>9} {'hydro walk':>10} {'sr refresh':>10} {'grav build':>10} {'grav walk':>9} "
          f"{'passes':>6} {'groups':>6}")
    for ntot, steps, dw, hw, rf, gb, gw, passes, groups in splits:
        print(f"{ntot:>8} {dw / steps:>9.3f} {hw / steps:>10.3f} {rf / steps:>10.3f} {gb / steps:>10.3f} "
              f"{gw / steps:>9.3f} {passes:>6.2f} {groups:>6.2f}")
if cpus:
    print()
    print("CPU time (all threads, independent of the machine's other jobs) per step (s); particle-steps per CPU "
          "second; the wall time to 24 h of an idle machine whose threads each get a whole core, CPU/threads "
          f"(threads: OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS', 'all')})")
    print(f"{'N':>8} {'cpu/step':>8} {'density':>8} {'hydro':>7} {'gravity':>8} {'p-steps/cpu-s':>13} "
          f"{'24 h: cpu':>10} {'24 h idle wall':>14}")
    thr = int(os.environ.get("OMP_NUM_THREADS", os.cpu_count() or 1))
    for ntot, steps, dt, steps24, proc, dens, eos, hydro, grav in cpus:
        per = (dens + eos + hydro + grav) / (steps + 1)  # steps + the initial force evaluation
        if per <= 0:  # the cpu: line has 10 ms resolution
            print(f"{ntot:>8} too short to time (the CPU times round to 0 s): raise PIK_BENCH_STEPS")
            continue
        print(f"{ntot:>8} {per:>8.3f} {dens / (steps + 1):>8.3f} {hydro / (steps + 1):>7.3f} {grav / (steps + 1):>8.3f} "
              f"{ntot / per:>13.3g} {steps24 * per / 3600:>8.2f} h {steps24 * per / thr / 60:>10.0f} min")
