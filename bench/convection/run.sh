#!/usr/bin/env bash
# make bench: the convection benchmark table (bench_convection.py) against this build.
set -euo pipefail
build=${1:-build}
exec /usr/bin/python3 "$(dirname "$0")/bench_convection.py" --build "$build"
