"""MediaPipe prepared on a background thread while `bsv process` loads the PDF renderer
(`bsv.frontend.segment.warming_up`): the graph is ready afterwards, the body's errors come through, and the
stderr the warm-up silences is the process's own again when the block ends."""

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
    with seg.warming_up():
        pass
    assert _fd2() == before
    prm = seg.DEFAULT_PARAMS["front"]
    made = seg._MODELS.get((prm.model_complexity, float(prm.min_detection_confidence)))
    assert made is not None and made[0] == os.getpid()


def test_an_error_in_the_body_propagates_after_the_warm_up() -> None:
    before = _fd2()
    with pytest.raises(RuntimeError, match="the body failed"), seg.warming_up():
        raise RuntimeError("the body failed")
    assert _fd2() == before


def test_an_unknown_or_bad_parameter_is_left_to_the_segmentation() -> None:
    with seg.warming_up(no_such_parameter=1):
        pass
    with seg.warming_up(model_complexity=7):
        pass
    with pytest.raises(seg.SegmentationError, match="no_such_parameter"):
        seg.detect(np.zeros((32, 32, 3), np.uint8), "front", no_such_parameter=1)
