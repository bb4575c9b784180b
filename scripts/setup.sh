#!/usr/bin/env bash
# Sets up BSV on a fresh machine: a virtualenv in .venv with the bsv Python package (Rust extension built
# by maturin) and the bsv-cli binary. Idempotent; re-running rebuilds only what changed.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
    "$PY" -m venv .venv
fi
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q -r requirements-dev.txt
# The extension (bsv._bsv) in the shared, optimised dev profile, installed editable into .venv.
VIRTUAL_ENV="$PWD/.venv" .venv/bin/maturin develop -q
cargo build -q -p bsv-cli
echo "bsv set up: .venv/bin/python -c 'import bsv', target/debug/bsv-cli"
