"""The subject shown to MediaPipe on one background, whatever the room behind it.

MediaPipe's pose landmarks move with what surrounds the subject, not only with the subject's own pixels: on
the rig's renders of the same 20 bodies (seeds 1 and 3, noer; the subject's pixels identical to the digit),
the knee joint lifted from the clinic room's image lies 2.6 mm low, from the same subject on black 11.8 mm
low, and the shoulder moves 3 mm the other way (benchmarks/BENCH.md, round 2 session 34). The cut lines and
joint offsets learned in one room then misplace the boundaries in another, and a lab's background (a wall, a
curtain, a black studio) should not move a volume between two visits. So every capture is shown to MediaPipe
on the same background: by default the rig's empty clinic room (:func:`backdrop`, the room the cut lines and
offsets were learned in), or a uniform grey (:data:`BACKGROUND_GREY`). On either, the same bodies' landmarks
agree between the room and the studio to a fraction of a pixel.

The depth image says which pixels are the subject: the valid pixels above the floor (the calibrated world
frame has the floor at y = 0; :data:`FLOOR_MARGIN_M`) within :data:`SUBJECT_DEPTH_M` behind the nearest
surface of the image's central region (the subject stands between the cameras: nothing else is nearer
there), in the parts of that set that reach the central region; small holes (depth dropouts on the body) are
filled. Everything else is replaced, up to the depth's own silhouette (:data:`GROW_PX`: MediaPipe reads even
a one-pixel rim of the room).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from importlib import resources
from typing import TYPE_CHECKING

import numpy as np

from ..extras import require
from .errors import SegmentationError

if TYPE_CHECKING:
    from .landmarks import Camera

#: The grey every non-subject pixel becomes with the ``"grey"`` background (sRGB, each channel).
BACKGROUND_GREY = 128
#: The empty clinic room of the ``"room"`` background, per view: files of ``bsv/data`` made by
#: ``benchmarks/make_backdrop.py`` from the rig's own renders (the room the cut lines were learned in).
BACKDROP_FILES: dict[str, str] = {"front": "backdrop_front.png", "back": "backdrop_back.png"}
#: A pixel whose world point lies less than this above the floor (y = 0 of the calibrated world) is floor.
FLOOR_MARGIN_M = 0.03
#: How far behind the nearest surface of the central region a pixel may lie and still be the subject: a body's
#: depth from its front to its back with the arms held out, and some room.
SUBJECT_DEPTH_M = 0.8
#: The central region of the image where the subject stands: columns and rows as fractions of the image.
CENTRAL_COLUMNS = (0.3, 0.7)
CENTRAL_ROWS = (0.15, 0.7)
#: The percentile of the central region's depths taken as the subject's nearest surface (a few flying
#: pixels nearer than the body do not move it).
NEAREST_PERCENTILE = 5.0
#: A part of the candidate region smaller than this fraction of the largest part is dropped (a speck of the
#: room at the subject's depth).
MIN_PART_FRACTION = 0.01
#: A hole in the subject's region smaller than this fraction of the region's area is filled (a depth dropout
#: on the body); larger ones (the space enclosed by an arm and the trunk) stay background.
MAX_HOLE_FRACTION = 0.005
#: Pixels the subject's region is grown by. None: MediaPipe reads even a one-pixel rim of the room around the
#: subject. On the rig's renders of three bodies in the room and in the studio (both views, knees, hips,
#: shoulders, elbows) the landmarks agree within 0.4 px with no rim, and move by up to 2.3 px with a 1-px rim
#: and 5.5 px with a 3-px rim, as much as on the images as captured (benchmarks/BENCH.md, round 2 session 34).
#: A sensor whose depth silhouette is wider than the subject (stereo edge fattening) lets such a rim in.
GROW_PX = 0
#: With the ``"auto"`` background, the depth around the subject is a void (a black studio, a background out of
#: the sensor's range) when fewer than this share of the pixels outside the subject's region have depth; a
#: room the sensor sees (its walls and floor return depth nearly everywhere) is left as captured.
VOID_DEPTH_FRACTION = 0.1
#: More than this share of an image with depth is a room whatever the subject covers (:func:`sees_room`).
ROOM_DEPTH_FRACTION = 0.5
#: The smallest share of the image the subject's region must cover to be used: less means the depth does not
#: show the subject (no depth, a wrong calibration) and the image is shown as captured.
MIN_REGION_FRACTION = 0.01


def _world_heights(depth: np.ndarray, valid: np.ndarray, camera: Camera) -> np.ndarray:
    """The world y (metres above the calibrated floor) of every valid pixel, NaN elsewhere."""
    v, u = np.nonzero(valid)
    xyz = camera.deproject(np.column_stack([u, v]).astype(np.float64), depth[v, u])
    out = np.full(depth.shape, np.nan)
    out[v, u] = xyz[:, 1]
    return out


def subject_region(depth_m: np.ndarray, camera: Camera | None = None) -> np.ndarray | None:
    """The pixels of the subject by depth (bool, the image's shape), or None when the depth does not show a
    subject (see :data:`MIN_REGION_FRACTION`). ``camera``: the calibrated camera whose world frame has the
    floor at y = 0; without it the floor is not removed."""
    cv2 = require("cv2")

    d = np.asarray(depth_m, dtype=np.float64)
    h, w = d.shape
    cand = (d > 0) & np.isfinite(d)
    if camera is not None and cand.any():
        cand &= ~(_world_heights(d, cand, camera) < FLOOR_MARGIN_M)
    r0, r1 = int(CENTRAL_ROWS[0] * h), int(CENTRAL_ROWS[1] * h)
    c0, c1 = int(CENTRAL_COLUMNS[0] * w), int(CENTRAL_COLUMNS[1] * w)
    central = d[r0:r1, c0:c1][cand[r0:r1, c0:c1]]
    if central.size < MIN_REGION_FRACTION * h * w * 0.1:
        return None
    nearest = float(np.percentile(central, NEAREST_PERCENTILE))
    cand &= d < nearest + SUBJECT_DEPTH_M
    n, lab, stats, _ = cv2.connectedComponentsWithStats(cand.astype(np.uint8), connectivity=8)
    if n <= 1:
        return None
    in_centre = np.zeros(n, dtype=bool)
    in_centre[np.unique(lab[r0:r1, c0:c1])] = True
    sizes = stats[:, cv2.CC_STAT_AREA].astype(np.float64)
    sizes[0] = 0.0
    keep = in_centre & (sizes >= MIN_PART_FRACTION * sizes.max())
    keep[0] = False
    region = keep[lab]
    area = int(region.sum())
    if area < MIN_REGION_FRACTION * h * w:
        return None
    # Holes: background parts not touching the image's border; the small ones are dropouts on the body.
    _, blab, bstats, _ = cv2.connectedComponentsWithStats((~region).astype(np.uint8), connectivity=4)
    border = np.unique(np.concatenate([blab[0], blab[-1], blab[:, 0], blab[:, -1]]))
    small = bstats[:, cv2.CC_STAT_AREA] < MAX_HOLE_FRACTION * area
    small[border] = False
    small[0] = False  # label 0: the region itself
    region |= small[blab] & ~region
    if GROW_PX > 0:
        k = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * GROW_PX + 1, 2 * GROW_PX + 1))
        region = cv2.dilate(region.astype(np.uint8), k) > 0
    return region


@functools.cache
def _backdrop_file(view: str) -> np.ndarray:
    """The packaged empty room of a view (RGB uint8), read once."""
    cv2 = require("cv2")

    name = BACKDROP_FILES.get(view)
    if name is None:
        raise SegmentationError(f"no backdrop for the view {view!r}: the views are {', '.join(BACKDROP_FILES)}")
    data = resources.files("bsv") / "data" / name
    img = cv2.imdecode(np.frombuffer(data.read_bytes(), dtype=np.uint8), cv2.IMREAD_COLOR)
    if img is None:
        raise SegmentationError(f"the packaged backdrop {name} could not be read: reinstall bsv")
    return np.ascontiguousarray(img[:, :, ::-1])


def backdrop(view: str, shape: tuple[int, int]) -> np.ndarray:
    """The empty clinic room seen by the ``view`` camera (:data:`BACKDROP_FILES`), scaled to cover an image of
    ``shape`` (height, width) and cropped at its centre when the proportions differ (RGB uint8)."""
    cv2 = require("cv2")

    img = _backdrop_file(view)
    h, w = shape
    k = max(h / img.shape[0], w / img.shape[1])
    size = (max(w, round(img.shape[1] * k)), max(h, round(img.shape[0] * k)))
    big = img if size == (img.shape[1], img.shape[0]) else cv2.resize(img, size, interpolation=cv2.INTER_LINEAR)
    y0, x0 = (big.shape[0] - h) // 2, (big.shape[1] - w) // 2
    return big[y0:y0 + h, x0:x0 + w]


def sees_room(depth_m: np.ndarray) -> bool:
    """Whether the depth surely shows a room (more than :data:`ROOM_DEPTH_FRACTION` of all pixels have depth,
    more than a standing subject covers): the cheap test ``"auto"`` makes before looking for the subject."""
    d = np.asarray(depth_m)
    return float(np.count_nonzero(d > 0)) > ROOM_DEPTH_FRACTION * d.size


def void_around(depth_m: np.ndarray, region: np.ndarray) -> bool:
    """Whether the depth around the subject's ``region`` is a void: fewer than :data:`VOID_DEPTH_FRACTION` of
    the other pixels have depth (nothing behind or under the subject returns it)."""
    d = np.asarray(depth_m)
    outside = ~region
    n = int(outside.sum())
    return n == 0 or float(((d > 0) & np.isfinite(d) & outside).sum()) < VOID_DEPTH_FRACTION * n


def on_background(colour_rgb: np.ndarray, region: np.ndarray | None, fill: np.ndarray | None = None) -> np.ndarray:
    """``colour_rgb`` with every pixel outside ``region`` taken from ``fill`` (an image of the same shape: a
    :func:`backdrop`) or, without it, set to :data:`BACKGROUND_GREY`; the image itself when ``region`` is
    None."""
    if region is None:
        return np.asarray(colour_rgb)
    around = np.asarray(BACKGROUND_GREY, dtype=np.uint8) if fill is None else np.asarray(fill, dtype=np.uint8)
    # one pass over the pixels (a boolean-mask assignment took 40-70 ms of a 1024 x 768 image)
    return np.where(np.asarray(region, dtype=bool)[..., None], np.asarray(colour_rgb, dtype=np.uint8), around)


@dataclass(frozen=True)
class Showing:
    """What MediaPipe is shown of one view: the subject's ``region`` (None: the image as captured), the
    ``fill`` outside it (a :func:`backdrop`; None: :data:`BACKGROUND_GREY`) and, when the requested background
    could not be made, a ``note`` saying why (a warning of the segmentation)."""

    region: np.ndarray | None = None
    fill: np.ndarray | None = None
    note: str | None = None

    @property
    def background(self) -> str:
        """What surrounds the subject in :meth:`image`: "as_captured", "room" or "grey"."""
        return "as_captured" if self.region is None else "grey" if self.fill is None else "room"

    def image(self, colour_rgb: np.ndarray) -> np.ndarray:
        """``colour_rgb`` as MediaPipe is shown it (:func:`on_background`)."""
        return on_background(colour_rgb, self.region, self.fill)


def showing(background: str, view: str, shape: tuple[int, int], depth_m: np.ndarray | None,
            camera: Camera | None = None) -> Showing:
    """What MediaPipe is shown of the ``view`` image of ``shape`` for the ``background`` setting
    (:attr:`bsv.frontend.segment.SegmentParams.background`): nothing changes without depth or
    ``"as_captured"``, nor with ``"auto"`` where the depth shows a room (:func:`sees_room`,
    :func:`void_around`); otherwise the subject's region on the backdrop (``"room"``, ``"auto"``) or grey."""
    if background == "as_captured" or depth_m is None or (background == "auto" and sees_room(depth_m)):
        return Showing()
    region = subject_region(depth_m, camera)
    if region is None or region.shape != shape:
        return Showing(note="the depth does not set the subject apart from the room, so MediaPipe saw the image as "
                            "captured (its landmarks then move with the background: check the depth image)")
    if background == "auto" and not void_around(depth_m, region):
        return Showing()  # the sensor sees a room: MediaPipe sees it too, as the cut lines were learned
    return Showing(region, backdrop(view, shape) if background in ("room", "auto") else None)


def neutral_background(colour_rgb: np.ndarray, depth_m: np.ndarray, camera: Camera | None = None,
                       view: str | None = None) -> np.ndarray | None:
    """``colour_rgb`` outside :func:`subject_region` replaced by the ``view`` camera's :func:`backdrop` (without
    a view: :data:`BACKGROUND_GREY`), or None when the depth does not show the subject (the caller then uses
    the image as captured)."""
    shape = np.asarray(colour_rgb).shape[:2]
    show = showing("grey" if view is None else "room", view or "front", (shape[0], shape[1]), depth_m, camera)
    return None if show.region is None else show.image(colour_rgb)


__all__ = [
    "BACKDROP_FILES",
    "BACKGROUND_GREY",
    "CENTRAL_COLUMNS",
    "CENTRAL_ROWS",
    "FLOOR_MARGIN_M",
    "GROW_PX",
    "MAX_HOLE_FRACTION",
    "MIN_PART_FRACTION",
    "MIN_REGION_FRACTION",
    "NEAREST_PERCENTILE",
    "ROOM_DEPTH_FRACTION",
    "SUBJECT_DEPTH_M",
    "VOID_DEPTH_FRACTION",
    "Showing",
    "backdrop",
    "neutral_background",
    "on_background",
    "sees_room",
    "showing",
    "subject_region",
    "void_around",
]
