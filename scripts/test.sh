#!/usr/bin/env bash
# Runs every check and test: static checks (scripts/lint.sh: rustfmt, clippy, ruff, mypy), the Rust
# workspace (cargo test) and the Python package (pytest).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/lint.sh
cargo test --workspace --exclude bsv-py
.venv/bin/python -m pytest -q tests/python
