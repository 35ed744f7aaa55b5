#!/usr/bin/env bash
# make bench: the Python-vs-C++ table of bench_python.py against this build.
set -euo pipefail
build=${1:-build}
exec /usr/bin/python3 "$(dirname "$0")/bench_python.py" --build "$build"
