#!/usr/bin/env bash
# The long fuzzing run, in-process on stable Rust: EXECS mutated inputs per input path (default
# 80000 each, about 10⁶ in all) over thirteen paths: the readers (legacy VTK, XML VTK, settings,
# restart frames, OFF, OBJ, PLY, STL) and the commands' own inputs (frames drawn by render, logs
# drawn by plot, mesh's arguments through the real parser, sweep files checked and counted,
# MorphoShell settings through import-morphoshell). 80000 per path: 1 040 000 executions in
# 29 s on one core, 5 800–410 000 per second by path (mesh slowest, PLY fastest), no panic, no
# abort, at most 8 MB resident (seeds 1 and 2).
#
#     scripts/fuzz.sh [EXECS_PER_TARGET] [SEED]
#
# Prints the counts per path and executions per second; inputs that panic land in
# fuzz-crashes/ (copy them to tests/data/fuzz/ as regression tests). Exits 1 on any panic.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo run --release --quiet --example fuzz -- "${1:-80000}" "${2:-1}" fuzz-crashes
