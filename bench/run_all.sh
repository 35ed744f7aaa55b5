#!/usr/bin/env bash
# Run every benchmark and print its table: bench/<dir>/run.sh when the folder has
# one (e.g. bench/mpi runs under mpirun), otherwise each BUILD/bin/bench_<dir>*.
set -euo pipefail
build=${1:-build}
here=$(cd "$(dirname "$0")" && pwd)
shopt -s nullglob
for dir in "$here"/*/; do
  name=$(basename "$dir")
  if [ -f "$dir/run.sh" ]; then
    echo "== bench/$name/run.sh"
    bash "$dir/run.sh" "$build"
    continue
  fi
  for b in "$build"/bin/bench_"$name"*; do
    echo "== $(basename "$b")"
    "$b"
  done
done
