#!/usr/bin/env bash
# The whole test suite. It first makes the project-local Python environment `.venv/` that the
# tests use to read frames with VTK's own readers (once; again only when requirements.txt
# changes), so it works on a stock Python that refuses `pip install` into the system
# (PEP 668), then runs `cargo test --release` with any arguments given.
set -euo pipefail
cd "$(dirname "$0")/.."
venv="$PWD/.venv"
stamp="$venv/requirements.installed"
if ! cmp -s requirements.txt "$stamp"; then
    rm -rf "$venv"
    # Debian and Ubuntu ship venv without ensurepip unless python3-venv is installed: fall back
    # to a bare environment and fetch pip itself from PyPI.
    if ! python3 -m venv "$venv" >/dev/null 2>&1; then
        rm -rf "$venv"
        python3 -m venv --without-pip "$venv"
        "$venv/bin/python" scripts/bootstrap_pip.py
    fi
    "$venv/bin/python" -m pip install --quiet --disable-pip-version-check -r requirements.txt
    cp requirements.txt "$stamp"
fi
export SHELLSIM_PYTHON="$venv/bin/python"
exec cargo test --release "$@"
