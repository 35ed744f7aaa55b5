#!/usr/bin/env bash
# The tables of docs/parallel.md: Barnes-Hut at N = 2^20 on 2 ranks x 1 thread vs
# 1 rank x 2 threads and weak scaling at 2^17 particles per rank for np = 1, 2, 4, 8;
# the same for the neighbour search (2^18; 2^16 per rank). Barnes-Hut runs with the
# generated AVX-512 kernel and the offset criterion, as bench_tree's FDPS comparison.
# Every run is unbound (--bind-to none): mpirun would otherwise pin a lone rank to one
# core, and its two threads would share it.
#   bash bench/mpi/run.sh [BUILD]
set -euo pipefail
build=${1:-build}
bin=$build/bin/bench_mpi
# Ranks waiting in MPI yield the core (Open MPI polls otherwise, taking time from the
# rank being waited for whenever cores are shared, as under oversubscription or load).
flags=(--oversubscribe --bind-to none --mca mpi_yield_when_idle 1 -x OMP_NUM_THREADS -x OMP_WAIT_POLICY)
export OMP_WAIT_POLICY=passive  # waiting threads sleep (cpu/thr counts work, not spinning)
bh=(--kernel generated --opening offset)
[ "$(id -u)" = 0 ] && flags+=(--allow-run-as-root)
echo "## N = 2^20, theta 0.5, leaf 8, group 64"
OMP_NUM_THREADS=2 mpirun "${flags[@]}" -np 1 "$bin" --log2n 20 "${bh[@]}" --header
OMP_NUM_THREADS=1 mpirun "${flags[@]}" -np 2 "$bin" --log2n 20 "${bh[@]}"
echo
echo "## weak scaling, 2^17 particles per rank, 1 thread per rank (oversubscribed beyond 2)"
first=--header
for np in 1 2 4 8; do
  OMP_NUM_THREADS=1 mpirun "${flags[@]}" -np $np "$bin" --log2n-per-rank 17 "${bh[@]}" $first
  first=
done
echo
echo "## neighbour search (gather, 50 neighbours, periodic cube), N = 2^18"
OMP_NUM_THREADS=2 mpirun "${flags[@]}" -np 1 "$bin" --log2n 18 --neighbours 50 --header
OMP_NUM_THREADS=1 mpirun "${flags[@]}" -np 2 "$bin" --log2n 18 --neighbours 50
echo
echo "## neighbour search weak scaling, 2^16 particles per rank, 1 thread per rank"
first=--header
for np in 1 2 4 8; do
  OMP_NUM_THREADS=1 mpirun "${flags[@]}" -np $np "$bin" --log2n-per-rank 16 --neighbours 50 $first
  first=
done
