"""The camera path's cut lines moved once the joint centres are known, in one place for ``bsv process`` and
``bsv bench synth``: the thigh / shin lines by the body's proportions (:mod:`bsv.frontend.kneelines`), then the
upper-arm / forearm lines by the elbows' bend (:mod:`bsv.frontend.elbowlines`)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from .elbowlines import recut_elbow_lines
from .kneelines import with_proportional_knee_lines
from .segment import Segmentation


def lines_after_joints(segs: Mapping[str, Segmentation], joints: Mapping[str, Any], cameras: Mapping[str, Any],
                       **params: Any) -> dict[str, Segmentation]:
    """Each view's segmentation with its knee and elbow lines moved for the capture's joint centres (``joints``)
    and calibrated ``cameras``; ``params``: the segmentation parameters the views were drawn with."""
    return recut_elbow_lines(with_proportional_knee_lines(segs, joints, cameras, **params), joints, cameras, **params)


__all__ = ["lines_after_joints"]
