#!/usr/bin/env bash
# The giant-impact benchmark of docs/impact.md: the canonical impact (0.9 + 0.11 M_E,
# 45 deg, v_imp = v_esc) at several resolutions for a fixed number of steps through
# contact; prints the time per step split into SPH density, hydro forces, gravity and
# tree builds, particle-steps per second, and the projection to 24 simulated hours.
#   bash bench/impact/run.sh [BUILD] [N_TARGET...]   (default N: 10000 45000 90000)
#   PIK_BENCH_STEPS (60), PIK_BENCH_TIME_STEPS (global|block), PIK_BENCH_THETA (0.7, the program's default), PIK_BENCH_CFL (0.3;
#   0.4 is SWIFT's demo setting, docs/impact.md "Session 7"), PIK_BENCH_GRAVITY_EVERY (auto: gravity once per 4 SPH
#   steps, docs/impact.md "Gravity on a longer step"); --max-steps counts the driver's steps, and the tables' "per
#   step" is per driver step: a block with block steps, a gravity step (up to 4 SPH steps) with --gravity-every;
#   the summary line of collide_N.txt gives the figures per force evaluation
set -euo pipefail
build=${1:-build}
shift || true
sizes=("${@:-10000 45000 90000}")
bin=$build/bin/impact
work=${PIK_BENCH_DIR:-$build/bench_impact}
mkdir -p "$work"
echo "# $(lscpu | grep 'Model name' | sed 's/  */ /g'), OMP_NUM_THREADS=${OMP_NUM_THREADS:-all}"
for n in ${sizes[@]}; do
  ni=$((n * 11 / 90))
  t=$work/target_$n.pbin
  i=$work/impactor_$n.pbin
  # Short relaxations: the benchmark times the impact, not the bodies' quality.
  [ -f "$t" ] || "$bin" planet --mass 0.9 --n "$n" --body "$t" --out "$work/relax_t_$n" --format binary \
                   --relax-time 600 --snapshots 0 > "$work/planet_t_$n.txt"
  [ -f "$i" ] || "$bin" planet --mass 0.11 --n "$ni" --body "$i" --out "$work/relax_i_$n" --format binary \
                   --relax-time 600 --snapshots 0 > "$work/planet_i_$n.txt"
  "$bin" collide --target "$t" --impactor "$i" --out "$work/collide_$n" --format binary --snapshots 0 \
    --max-steps ${PIK_BENCH_STEPS:-60} --checkpoint-every 0 --time-steps ${PIK_BENCH_TIME_STEPS:-global} \
    --theta ${PIK_BENCH_THETA:-0.7} --cfl ${PIK_BENCH_CFL:-0.3} --gravity-every ${PIK_BENCH_GRAVITY_EVERY:-auto} \
    > "$work/collide_$n.txt"
done
/usr/bin/python3 "$(dirname "$0")/table.py" "$work" ${sizes[@]}
