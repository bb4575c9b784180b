#!/usr/bin/env bash
# Runs every test: the Rust workspace (cargo test) and the Python package (pytest).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo test --workspace --exclude bsv-py
.venv/bin/python -m pytest -q tests/python
