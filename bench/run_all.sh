#!/usr/bin/env bash
# Run every benchmark built under BUILD/bin/bench_* and print their tables.
set -euo pipefail
build=${1:-build}
shopt -s nullglob
for b in "$build"/bin/bench_*; do
  echo "== $(basename "$b")"
  "$b"
done
