#!/usr/bin/env bash
# Static checks, all of which must pass: rustfmt, clippy (warnings are errors), ruff and mypy.
# Needs the .venv of scripts/setup.sh (ruff and mypy come from requirements-dev.txt).
set -euo pipefail
cd "$(dirname "$0")/.."
echo "lint: cargo fmt --check"
cargo fmt --all -- --check
echo "lint: cargo clippy"
PYO3_PYTHON="$PWD/.venv/bin/python" cargo clippy -q --workspace --all-targets -- -D warnings
echo "lint: ruff check"
.venv/bin/ruff check python tests benchmarks scripts
echo "lint: mypy"
.venv/bin/mypy
echo "lint: clean"
