#!/usr/bin/env bash
# The long fuzzing run: EXECS mutated inputs per input path (legacy VTK, XML VTK, settings,
# restart frames, OFF, OBJ, PLY, STL; default 250000 each, 2·10⁶ in all) in-process, on stable
# Rust.
#
#     scripts/fuzz.sh [EXECS_PER_TARGET] [SEED]
#
# Prints the counts per path and executions per second; inputs that panic land in
# fuzz-crashes/ (copy them to tests/data/fuzz/ as regression tests). Exits 1 on any panic.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo run --release --quiet --example fuzz -- "${1:-250000}" "${2:-1}" fuzz-crashes
