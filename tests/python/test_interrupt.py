"""A fit can be stopped: Ctrl-C (SIGINT) ends a Python ``bsv.register`` within an iteration or so, with
KeyboardInterrupt, instead of after the whole schedule."""

from __future__ import annotations

import signal
import subprocess
import sys
import time

SCRIPT = r"""
import sys
import bsv
t = bsv.default_template()
c = bsv.scan(t, "noer", seed=0)
def tick(it):
    if it["iteration"] == 0:
        print("started", flush=True)
try:
    bsv.register(c, progress=tick, schedule="m2p:100000", stop_motion_mm=0)
except KeyboardInterrupt:
    print("interrupted", flush=True)
    sys.exit(42)
print("finished", flush=True)
"""


def test_ctrl_c_stops_a_long_fit_at_the_next_iteration() -> None:
    # 100,000 iterations take about an hour; the interrupt must end the fit at the next iteration.
    # The child gets the default SIGINT disposition: an ignored SIGINT is inherited across exec, and an
    # earlier test's cluster may leave the test process ignoring it (Python then never installs its handler).
    proc = subprocess.Popen([sys.executable, "-c", SCRIPT], stdout=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert proc.stdout is not None
    try:
        assert proc.stdout.readline().strip() == "started"
        time.sleep(0.5)
        # Ctrl-C, repeated every 5 s as a user would.
        out = ""
        for _ in range(24):
            proc.send_signal(signal.SIGINT)
            try:
                out, _ = proc.communicate(timeout=5)
                break
            except subprocess.TimeoutExpired:
                continue
    finally:
        proc.kill()
    assert proc.returncode == 42 and "interrupted" in out
