"""MediaPipe prepared on a background thread while `bsv process` loads the PDF renderer
(`bsv.frontend.segment.warming_up`): the graph is ready afterwards, the body's errors come through, the
stderr the warm-up captures is the process's own again when the block ends, and what the rest of the
process printed meanwhile is replayed without MediaPipe's start-up log."""

from __future__ import annotations

import os

import numpy as np
import pytest

pytest.importorskip("mediapipe", reason="mediapipe not installed (pip install -r requirements-frontend.txt)")

from bsv.frontend import segment as seg


def _fd2() -> tuple[int, int]:
    st = os.fstat(2)
    return st.st_dev, st.st_ino


def test_the_graph_is_built_and_stderr_is_restored() -> None:
    before = _fd2()
    prm = seg.DEFAULT_PARAMS["front"]
    with seg.warming_up() as wait:
        wait()  # the with target waits for the thread: the graph is there inside the block already
        made = seg._MODELS.get((prm.model_complexity, float(prm.min_detection_confidence)))
        assert made is not None and made[0] == os.getpid()
    assert _fd2() == before


def test_an_error_in_the_body_propagates_after_the_warm_up() -> None:
    before = _fd2()
    with pytest.raises(RuntimeError, match="the body failed"), seg.warming_up():
        raise RuntimeError("the body failed")
    assert _fd2() == before


def test_an_unknown_or_bad_parameter_is_left_to_the_segmentation() -> None:
    with seg.warming_up(no_such_parameter=1) as wait:
        wait()
    with seg.warming_up(model_complexity=7) as wait:
        wait()
    with pytest.raises(seg.SegmentationError, match="no_such_parameter"):
        seg.detect(np.zeros((32, 32, 3), np.uint8), "front", no_such_parameter=1)


def test_captured_stderr_is_replayed_without_mediapipes_log(capfd) -> None:
    captured: list[str] = []
    with seg._native_stderr_captured(captured):
        os.write(2, b"INFO: Created TensorFlow Lite XNNPACK delegate for CPU.\n")
        os.write(2, b"W0000 00:00:1796314194.740015   13600 inference_feedback_manager.cc:114] Feedback manager\n")
        os.write(2, b"a warning of the main thread\n")  # what sys.stderr does in a process (fd 2)
    assert capfd.readouterr().err == ""  # nothing reached the real stderr meanwhile
    seg._replay(captured)
    assert capfd.readouterr().err == "a warning of the main thread\n"


def test_then_runs_on_the_thread_once_the_graph_is_ready() -> None:
    import threading

    seen: list[tuple[str, bool]] = []
    prm = seg.DEFAULT_PARAMS["front"]
    key = (prm.model_complexity, float(prm.min_detection_confidence))

    def then() -> None:
        seen.append((threading.current_thread().name, key in seg._MODELS))
        raise RuntimeError("a failing warm-up step is not the body's error")

    with seg.warming_up(then=then) as wait:
        wait()
    assert seen == [("bsv-mediapipe-warm-up", True)]
