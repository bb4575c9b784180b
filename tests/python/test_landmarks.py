"""Landmarks of both views (bsv.frontend.landmarks): a landmark not seen confidently in one view is filled in
(from the other view through the calibration, the hand model, the lower threshold) with a warning, a limb
seen in neither view is a typed error naming it, and the joint centres lifted to 3-D lie near the rig's
true joint centres. MediaPipe runs once per image (cached); a landmark's visibility is lowered by wrapping
its result, as a real low-confidence detection would come."""

from __future__ import annotations

import dataclasses
import hashlib
import json

import numpy as np
import pytest

pytest.importorskip("cv2")
pytest.importorskip("mediapipe", reason="mediapipe not installed (pip install -r requirements-frontend.txt)")
bsv = pytest.importorskip("bsv")

from bsv.bodies.joints import rig_joints  # noqa: E402
from bsv.errors import LandmarkMissingError, LimbMissingError, PersonNotFoundError  # noqa: E402
from bsv.frontend import landmarks as lm  # noqa: E402
from bsv.frontend import segment as seg  # noqa: E402
from bsv.frontend.capture import read_capture  # noqa: E402
from bsv.frontend.intrinsics import Intrinsics  # noqa: E402
from bsv.frontend.sex import SEX_MEASUREMENTS  # noqa: E402

SUBJECT, SEED = 1, 5  # a cohort subject the segmentation was not tuned on (seed 1)
_REAL = seg.run_holistic
_CACHE: dict[str, dict] = {}


def _cached(rgb, params=None):
    key = hashlib.sha1(np.ascontiguousarray(rgb).tobytes()).hexdigest()
    if key not in _CACHE:
        _CACHE[key] = _REAL(rgb, params or seg.SegmentParams())
    r = _CACHE[key]
    return {"pose": None if r["pose"] is None else r["pose"].copy(), "hands": list(r["hands"]), "mask": r["mask"]}


@pytest.fixture(scope="module")
def capture(tmp_path_factory):
    """A virtual capture (room, noer) of one cohort subject, its images, cameras and the subject."""
    folder = tmp_path_factory.mktemp("landmarks") / "capture"
    s = bsv.bodies.subject(SUBJECT, SEED)
    bsv.scan(s.body.mesh(), "noer", 0, images=str(folder), room=True)
    data = {v: read_capture(folder / v) for v in seg.VIEWS}
    cams = {v: lm.Camera.from_json(data[v]["intrinsics"], data[v]["meta"]["camera_to_world"]) for v in seg.VIEWS}
    return folder, data, cams, s


def _key(img) -> str:
    return hashlib.sha1(np.ascontiguousarray(img).tobytes()).hexdigest()


def _shown(data, v: str) -> list[np.ndarray]:
    """Every image of view ``v`` MediaPipe may be shown (before mirroring): the colour image as captured and
    brightened, and the subject on the rig's empty room (bsv.frontend.background) with and without the
    floor removed (with and without the camera), as it is and brightened."""
    from bsv.frontend.background import backdrop, on_background, subject_region

    img = np.ascontiguousarray(data[v]["colour"])
    out = [img, seg.stretch_contrast(img)[0]]
    fill = backdrop(v, img.shape[:2])
    for camera in (lm.Camera.from_json(data[v]["intrinsics"], data[v]["meta"]["camera_to_world"]), None):
        region = subject_region(data[v]["depth_m"], camera)
        out += [on_background(img, region, fill), on_background(seg.stretch_contrast(img, region)[0], region, fill)]
    return out


def _lower(monkeypatch, data, where: dict[tuple[str, str], float]) -> None:
    """MediaPipe's result with the visibility of (view, subject landmark) set as given. The view is told by
    the image (front and back differ, and so do their mirror images, which ``flip_average`` detects too; as
    captured and on the backdrop it is shown on);
    the subject's left is on the image right from the front, left from the back (the rule of
    segment._orient), and the other way round in a mirror image."""
    views = {}
    for v in seg.VIEWS:
        for img in _shown(data, v):
            views[_key(img)] = (v, False)
            views[_key(img[:, ::-1])] = (v, True)

    def fake(rgb, params=None):
        r = _cached(rgb, params)
        view, mirrored = views[hashlib.sha1(np.ascontiguousarray(rgb).tobytes()).hexdigest()]
        pose = r["pose"]
        for (v, name), vis in where.items():
            if v != view:
                continue
            joint = name.split("_", 1)[1]
            i, j = seg.POSE_NAMES.index(f"left_{joint}"), seg.POSE_NAMES.index(f"right_{joint}")
            left_is_larger_x = (view == "front") != mirrored
            li = (i if pose[i, 0] > pose[j, 0] else j) if left_is_larger_x else (i if pose[i, 0] < pose[j, 0] else j)
            k = li if name.startswith("left_") else (j if li == i else i)
            pose[k, 2] = vis
        return r

    monkeypatch.setattr(seg, "run_holistic", fake)


def _images(data):
    return {v: {"colour": data[v]["colour"], "depth_m": data[v]["depth_m"]} for v in seg.VIEWS}


def test_camera_projects_back_what_it_deprojects():
    k = Intrinsics(640, 480, 600.0, 610.0, 319.5, 239.5)
    r = np.array([[1.0, 0, 0], [0, -1, 0], [0, 0, -1]])
    cam = lm.Camera(k, r, np.array([0.1, 1.0, 2.0]))
    uv = np.array([[10.0, 20.0], [320.0, 240.0], [600.5, 470.25]])
    xyz = cam.deproject(uv, np.array([1.5, 2.0, 2.5]))
    assert np.allclose(cam.project(xyz), uv, atol=1e-6)
    assert np.allclose(xyz[1], [0.1 + 0.5 / 600 * 2.0, 1.0 - 0.5 / 610 * 2.0, 0.0])  # 2 m in front, along -z
    assert np.allclose(cam.axis(), [0, 0, -1])


def test_a_low_wrist_in_one_view_comes_from_the_other(capture, monkeypatch):
    _, data, cams, _ = capture
    _lower(monkeypatch, data, {})
    clean = lm.segment_views(_images(data), cams)
    assert clean["back"].warnings == () and clean["front"].warnings == ()
    _lower(monkeypatch, data, {("back", "left_wrist"): 0.3})
    segs = lm.segment_views(_images(data), cams)
    assert segs["back"].sources == {"left_wrist": "other view"}
    assert segs["front"].sources == {}
    (w,) = segs["back"].warnings
    assert "left_wrist" in w and "back" in w and "other view" in w
    # the wrist projected from the front view lands near MediaPipe's own back-view wrist
    got, own = segs["back"].landmark("left_wrist"), clean["back"].landmark("left_wrist")
    assert np.hypot(*(got[:2] - own[:2])) < 12.0, (got, own)
    # and the labels barely move
    same = (segs["back"].labels == clean["back"].labels).mean()
    assert same > 0.99


def test_single_view_hand_model_then_lower_threshold(capture, monkeypatch):
    _, data, _, _ = capture
    _lower(monkeypatch, data, {("front", "left_wrist"): 0.3, ("front", "right_knee"): 0.6})
    s = seg.segment_image(data["front"]["colour"], "front", data["front"]["depth_m"])
    assert s.hands_found[0], "the hand model should find the left hand of this render"
    assert s.sources == {"left_wrist": "hand model", "right_knee": "low visibility"}
    assert any("right_knee" in w and "0.50" in w for w in s.warnings)
    _lower(monkeypatch, data, {("front", "right_knee"): 0.3})
    with pytest.raises(LandmarkMissingError, match="right_knee") as e:
        seg.segment_image(data["front"]["colour"], "front")
    assert e.value.missing == ["right_knee"]


def test_a_limb_missing_in_both_views_is_a_typed_error(capture, monkeypatch):
    _, data, cams, _ = capture
    _lower(monkeypatch, data, {("front", "left_knee"): 0.2, ("back", "left_knee"): 0.1})
    with pytest.raises(LimbMissingError, match="left leg") as e:
        lm.segment_views(_images(data), cams)
    msg = str(e.value)
    assert "left_knee" in msg and "front" in msg and "back" in msg and "step back" in msg and "light" in msg
    assert e.value.limbs == ["left leg"] and e.value.missing == ["left_knee"]
    assert isinstance(e.value, LandmarkMissingError)


def test_a_landmark_weak_in_both_views_comes_from_the_view_that_sees_it_at_the_lower_threshold(capture, monkeypatch):
    """The front view's ankles under the lower threshold and the back view's between it and the confident one
    (a heavy body's, 0.47 and 0.6, once lost its capture): the back view uses its own at the lower threshold,
    the front view takes the back view's through the calibration, both with a warning, and no error."""
    _, data, cams, _ = capture
    _lower(monkeypatch, data, {})
    clean = lm.segment_views(_images(data), cams)
    _lower(monkeypatch, data, {("front", "left_ankle"): 0.45, ("front", "right_ankle"): 0.45,
                               ("back", "left_ankle"): 0.6, ("back", "right_ankle"): 0.6})
    segs = lm.segment_views(_images(data), cams)
    for name in ("left_ankle", "right_ankle"):
        assert segs["front"].sources[name] == "other view" and segs["back"].sources[name] == "low visibility"
        assert any(name in w and "other view" in w and "0.50" in w for w in segs["front"].warnings)
        got, own = segs["front"].landmark(name), clean["front"].landmark(name)
        assert np.hypot(*(got[:2] - own[:2])) < 12.0, (name, got, own)
    # a view under the lower threshold while the other is under it too still loses the limb
    _lower(monkeypatch, data, {("front", "left_ankle"): 0.45, ("back", "left_ankle"): 0.4})
    with pytest.raises(LimbMissingError, match="left leg"):
        lm.segment_views(_images(data), cams)


def test_joint_centres_near_the_rig(capture, monkeypatch):
    _, data, cams, s = capture
    _lower(monkeypatch, data, {})
    segs = lm.segment_views(_images(data), cams)
    joints = lm.joint_centres(segs, {v: data[v]["depth_m"] for v in seg.VIEWS}, cams)
    truth = rig_joints(s.phenotype, s.pose)
    assert set(joints) == set(lm.JOINTS)
    err = {j: float(np.linalg.norm(joints[j].xyz - truth[j])) * 1000 for j in joints}
    # measured 13 mm median, 20 mm worst (the knees); the target is a median of 15 mm over a cohort
    assert np.median(list(err.values())) < 16.0, err
    assert max(err.values()) < 35.0, err
    raw = lm.joint_centres(segs, {v: data[v]["depth_m"] for v in seg.VIEWS}, cams, correct=False)
    raw_err = [float(np.linalg.norm(raw[j].xyz - truth[j])) * 1000 for j in raw]
    assert np.median(raw_err) > np.median(list(err.values())), "the learned offsets should help a held-out subject"
    for j in joints.values():
        assert 0.0 <= j.confidence <= 1.0 and j.source == "front+back"
        assert json.loads(json.dumps(j.to_json()))["source"] == "front+back"


def test_a_view_whose_landmark_is_not_repeatable_is_left_out(capture, monkeypatch):
    """The back view's left ankle detected 12 px off, its image and mirror-image detections 30 px apart
    (``pose_spread``): the joint comes from the front view's landmark and both views' depth, near the
    rig's; taken at face value
    (no spread known: the plain front/back mean) the same wrong landmark moves the joint further."""
    import dataclasses

    _, data, cams, s = capture
    _lower(monkeypatch, data, {})
    segs = lm.segment_views(_images(data), cams)
    depths = {v: data[v]["depth_m"] for v in seg.VIEWS}
    truth = rig_joints(s.phenotype, s.pose)["ankle_l"]
    i = seg.POSE_NAMES.index("left_ankle")
    bad_pose = segs["back"].pose.copy()
    bad_pose[i, 0] += 12.0
    spread = np.full(33, 1.0)
    spread[i] = 30.0
    front = dataclasses.replace(segs["front"], pose_spread=np.full(33, 1.0))
    flagged = {"front": front, "back": dataclasses.replace(segs["back"], pose=bad_pose, pose_spread=spread)}
    joint = lm.joint_centres(flagged, depths, cams)["ankle_l"]
    assert joint.source.startswith("front") and "back: left out" in joint.source, joint.source
    err = float(np.linalg.norm(joint.xyz - truth)) * 1000
    assert err < 35.0, err
    # Its depth: midway between the front surface under the kept landmark and the back surface behind it
    # (the left-out view's depth image at the kept point's projection), not the back's wrong landmark.
    depth_err = abs(float((joint.xyz - truth) @ cams["front"].axis())) * 1000
    assert depth_err < 20.0, depth_err
    unflagged = {"front": dataclasses.replace(segs["front"], pose_spread=None),
                 "back": dataclasses.replace(segs["back"], pose=bad_pose, pose_spread=None)}
    plain = lm.joint_centres(unflagged, depths, cams)["ankle_l"]
    assert plain.source == "front+back"
    assert float(np.linalg.norm(plain.xyz - truth)) * 1000 > err + 5.0


def _assert_back_took_the_fronts(segs, clean, data, cams, names, why: str, tol_px: float) -> None:
    """The back view's ``names`` came from the front view through the calibration, a warning each saying
    ``why``; each lies within ``tol_px`` of MediaPipe's own clean back-view landmark (not where the faked
    detection put it), the back view's labels are the clean ones, and the joint centres take those joints
    from the front view alone."""
    assert segs["back"].sources == dict.fromkeys(names, "other view")
    assert segs["front"].sources == {}
    assert len(segs["back"].warnings) == len(names) and all(why in w for w in segs["back"].warnings)
    for name in names:
        got, own = segs["back"].landmark(name), clean["back"].landmark(name)
        assert np.hypot(*(got[:2] - own[:2])) < tol_px, (name, got, own)
    assert (segs["back"].labels == clean["back"].labels).mean() > 0.99
    joints = lm.joint_centres(segs, {v: data[v]["depth_m"] for v in seg.VIEWS}, cams)
    for name in names:
        side, kind = name.split("_", 1)
        assert joints[f"{kind}_{side[0]}"].source == "front", name


def _back_mirror_lowered(monkeypatch, data, cams, names) -> tuple[dict, dict]:
    """Both views segmented as captured, then again with the back view's ``names`` detected 60 px lower in its
    mirror image than in the image (not repeatable there): the clean and the faked segmentations."""
    _lower(monkeypatch, data, {})
    clean = lm.segment_views(_images(data), cams)
    mirrored_back = {_key(x[:, ::-1]) for x in _shown(data, "back")}
    rows = [seg.POSE_NAMES.index(n) for n in names]

    def fake(rgb, params=None):
        r = _cached(rgb, params)
        if _key(rgb) in mirrored_back:
            r["pose"][rows, 1] += 60.0
        return r

    monkeypatch.setattr(seg, "run_holistic", fake)
    return clean, lm.segment_views(_images(data), cams)


def test_a_landmark_one_view_does_not_repeat_is_labelled_from_the_other(capture, monkeypatch):
    """The back view's elbows detected 60 px lower in its mirror image than in the image (a dim back lit
    from one side does that; the front's two detections agree): the back view's labels take the front's
    elbows through the calibration, each a warning, and come out as with the clean detection."""
    _, data, cams, _ = capture
    clean, segs = _back_mirror_lowered(monkeypatch, data, cams, ("left_elbow", "right_elbow"))
    _assert_back_took_the_fronts(segs, clean, data, cams, ("left_elbow", "right_elbow"), "not repeatable", 12.0)


def test_shoulders_and_hips_taken_from_the_other_view_land_on_the_body(capture, monkeypatch):
    """The back view's shoulders and hips detected 60 px lower in its mirror image (bumps on the skin did that
    on a hard-cohort subject): the front's stand in, through the calibration, at the middle of the body's cross-
    section between the front surface and the back surface behind it, so each lies near MediaPipe's own clean
    back-view landmark. (Pushed from the front surface by the mask's width across the limb, which at a shoulder
    or a hip runs on into the torso, they landed 30-40 px off the body, and with them the shoulder boundary.)"""
    _, data, cams, _ = capture
    names = ("left_shoulder", "right_shoulder", "left_hip", "right_hip")
    clean, segs = _back_mirror_lowered(monkeypatch, data, cams, names)
    assert segs["back"].sources == dict.fromkeys(names, "other view")
    for name in names:
        got, own = segs["back"].landmark(name), clean["back"].landmark(name)
        assert np.hypot(*(got[:2] - own[:2])) < 12.0, (name, got, own)
        assert segs["back"].mask[round(float(got[1])), round(float(got[0]))], name


def test_a_leg_landmark_the_views_place_at_different_heights_is_taken_from_the_plausible_view(capture, monkeypatch):
    """The back view's knees detected 25 px (about 9 cm) up the thighs in both its image and its mirror image
    (repeatably wrong: a dark lower leg against a dark floor does that): the two views' knees then lie at
    heights that cannot both be right, the back's is farther from the knee height the stature gives, so the
    back view's labels take the front's knees through the calibration, each a warning, and the joint
    centres take the knees from the front view alone."""
    _, data, cams, _ = capture
    _lower(monkeypatch, data, {})
    clean = lm.segment_views(_images(data), cams)
    back = {_key(im) for x in _shown(data, "back") for im in (x, x[:, ::-1])}
    knees = [seg.POSE_NAMES.index("left_knee"), seg.POSE_NAMES.index("right_knee")]

    def fake(rgb, params=None):
        r = _cached(rgb, params)
        if hashlib.sha1(np.ascontiguousarray(rgb).tobytes()).hexdigest() in back:
            r["pose"][knees, 1] -= 25.0
        return r

    monkeypatch.setattr(seg, "run_holistic", fake)
    segs = lm.segment_views(_images(data), cams)
    _assert_back_took_the_fronts(segs, clean, data, cams, ("left_knee", "right_knee"),
                                 "above the front view's, farther from the", 10.0)
    assert all("the body's proportions give" in w for w in segs["back"].warnings)


def test_ankles_are_placed_at_the_height_the_stature_gives(capture, monkeypatch):
    """Both views' ankles detected 20 px (about 7 cm) up the shins, in the image and its mirror image alike
    (so the views agree and nothing flags them): place_ankles moves them back to the height the stature
    gives, so the ankles and the labels come out as with the clean detection; with ankle_height 0 the
    ankles stay where MediaPipe put them."""
    _, data, cams, _ = capture
    _lower(monkeypatch, data, {})
    clean = lm.segment_views(_images(data), cams)
    ankles = [seg.POSE_NAMES.index("left_ankle"), seg.POSE_NAMES.index("right_ankle")]

    def fake(rgb, params=None):
        r = _cached(rgb, params)
        r["pose"][ankles, 1] -= 20.0
        return r

    monkeypatch.setattr(seg, "run_holistic", fake)
    segs = lm.segment_views(_images(data), cams)
    for v in seg.VIEWS:
        assert segs[v].warnings == clean[v].warnings
        for name in ("left_ankle", "right_ankle"):
            got, own = segs[v].landmark(name), clean[v].landmark(name)
            assert np.hypot(*(got[:2] - own[:2])) < 4.0, (v, name, got, own)
        assert (segs[v].labels == clean[v].labels).mean() > 0.998
    fixed = {v: dataclasses.replace(seg.DEFAULT_PARAMS[v], ankle_height=0.0) for v in seg.VIEWS}
    monkeypatch.setattr(seg, "DEFAULT_PARAMS", fixed)
    raw = lm.segment_views(_images(data), cams)
    for v in seg.VIEWS:
        for name in ("left_ankle", "right_ankle"):
            got, own = raw[v].landmark(name), clean[v].landmark(name)
            # left 20 px up (and not placed); the clean ankle is itself placed, by up to about 12 px
            assert 8.0 < own[1] - got[1] < 34.0, (v, name, got, own)


def test_a_views_ankles_up_the_shins_with_no_person_under_them_come_from_the_other_view(capture, monkeypatch):
    """The back view's ankles detected at mid-shin (120 px up, in the image and its mirror image alike) where
    MediaPipe's mask lost the lower legs, so neither the mask nor the depth lifts them (a colour sensor's
    noise once did this to a back view and took half of both shins away): the height of their pixels' rays
    at the front view's depth judges them implausible, they are taken from the front view with a warning,
    and the back view's shins are labelled about as with the clean detection."""
    _, data, cams, _ = capture
    _lower(monkeypatch, data, {})
    clean = lm.segment_views(_images(data), cams)
    ankles = [seg.POSE_NAMES.index("left_ankle"), seg.POSE_NAMES.index("right_ankle")]
    back = {_key(img) for img in _shown(data, "back")}
    back |= {_key(np.ascontiguousarray(img[:, ::-1])) for img in _shown(data, "back")}

    def fake(rgb, params=None):
        r = _cached(rgb, params)
        if _key(rgb) not in back:
            return r
        r["pose"][ankles, 1] -= 120.0
        mask = np.array(r["mask"], copy=True)
        lowest = int(r["pose"][ankles, 1].min())  # the lower legs lost from the moved ankles down
        mask[lowest - 15:] = 0.0
        r["mask"] = mask
        return r

    monkeypatch.setattr(seg, "run_holistic", fake)
    segs = lm.segment_views(_images(data), cams)
    assert segs["front"].warnings == clean["front"].warnings
    for name in ("left_ankle", "right_ankle"):
        assert segs["back"].sources.get(name) == "other view", segs["back"].sources
        assert any(name in w and "above the front view's" in w for w in segs["back"].warnings), segs["back"].warnings
        got, own = segs["back"].landmark(name), clean["back"].landmark(name)
        assert np.hypot(*(got[:2] - own[:2])) < 12.0, (name, got, own)
    for shin in ("shin_l", "shin_r"):
        k = bsv.SEGMENT_IDS[shin]
        n_clean, n_got = int((clean["back"].labels == k).sum()), int((segs["back"].labels == k).sum())
        assert abs(n_got - n_clean) < 0.2 * n_clean, (shin, n_got, n_clean)


def test_a_view_whose_pose_covers_a_part_of_the_person_is_replaced_by_the_other_view(capture, monkeypatch):
    """The back view's pose shrunk to a quarter about its nose, mirror image and all, with a mask of the upper
    back only (a bright back view on a floor of the skin's colour once gave a head-and-shoulders skeleton at
    visibility 1.0, and every volume of the capture went wrong): detect refuses it against the person's height
    in the depth image (PoseTooSmallError), and segment_views takes the back view from the front one, saying
    so, with its legs labelled about as with the clean detection."""
    from bsv.errors import PersonNotFoundError as NotFound
    from bsv.errors import PoseTooSmallError

    _, data, cams, _ = capture
    _lower(monkeypatch, data, {})
    clean = lm.segment_views(_images(data), cams)
    back = {_key(img) for img in _shown(data, "back")}
    back |= {_key(np.ascontiguousarray(img[:, ::-1])) for img in _shown(data, "back")}
    nose = seg.POSE_NAMES.index("nose")

    def fake(rgb, params=None):
        r = _cached(rgb, params)
        if _key(rgb) not in back:
            return r
        pose = r["pose"]
        pose[:, :2] = pose[nose, :2] + 0.25 * (pose[:, :2] - pose[nose, :2])
        mask = np.zeros_like(r["mask"])
        y = int(pose[:, 1].max())
        mask[max(0, y - 60):y] = r["mask"][max(0, y - 60):y]
        r["mask"] = mask
        return r

    monkeypatch.setattr(seg, "run_holistic", fake)
    with pytest.raises(PoseTooSmallError, match="spans") as e:
        seg.detect(data["back"]["colour"], "back", depth=data["back"]["depth_m"], camera=cams["back"])
    assert isinstance(e.value, NotFound) and 0.05 < e.value.span < seg.MIN_SKELETON_SPAN
    segs = lm.segment_views(_images(data), cams)
    assert segs["front"].warnings == clean["front"].warnings
    assert any("spans" in w and "front view's through the calibration" in w for w in segs["back"].warnings)
    # the stood-in view's boundaries are less certain: its intervals widen (the front view's do not)
    assert all(segs["back"].extra_sd[k] >= sd for k, sd in lm.STAND_IN_SD.items())
    assert "upper_arm_l" not in segs["front"].extra_sd
    for part in ("thigh_l", "thigh_r", "shin_l", "shin_r"):
        k = bsv.SEGMENT_IDS[part]
        n_clean, n_got = int((clean["back"].labels == k).sum()), int((segs["back"].labels == k).sum())
        assert abs(n_got - n_clean) < 0.25 * n_clean, (part, n_got, n_clean)


def test_skeleton_span_is_the_required_landmarks_height_over_the_persons():
    region = np.zeros((100, 50), dtype=bool)
    region[10:91, 20:30] = True  # the person: rows 10-90
    pose = np.zeros((len(seg.POSE_NAMES), 3))
    pose[:, 1] = 50.0
    pose[seg.POSE_NAMES.index("left_shoulder"), 1] = 25.0
    pose[seg.POSE_NAMES.index("right_ankle"), 1] = 85.0
    pose[seg.POSE_NAMES.index("nose"), 1] = 0.0  # not a required landmark
    assert seg.skeleton_span(pose, region) == pytest.approx(60.0 / 80.0)
    assert seg.skeleton_span(pose, np.zeros_like(region)) is None
    pose[seg.POSE_NAMES.index("left_knee"), 1] = np.nan
    assert seg.skeleton_span(pose, region) is None


def test_the_stature_is_read_from_the_depth_of_the_person(capture, monkeypatch):
    """person_stature: the top of the head above the floor, within 3 cm of the body's true height (the mask's
    spill onto the wall behind the head does not raise it)."""
    _, data, cams, s = capture
    _lower(monkeypatch, data, {})
    dets = {v: seg.detect(data[v]["colour"], v) for v in seg.VIEWS}
    height = lm.person_stature(dets, cams, {v: data[v]["depth_m"] for v in seg.VIEWS})
    v = np.asarray(s.body.mesh().vertices)
    assert abs(height - (v[:, 1].max() - v[:, 1].min())) < 0.03, height


def _lose(monkeypatch, data, views) -> None:
    """MediaPipe finds nobody in any image of ``views``: the image, its mirror image and both brightened."""
    lost = {_key(im) for v in views for x in _shown(data, v) for im in (x, x[:, ::-1])}

    def fake(rgb, params=None):
        if hashlib.sha1(np.ascontiguousarray(rgb).tobytes()).hexdigest() in lost:
            return {"pose": None, "hands": [None, None], "mask": None}
        return _cached(rgb, params)

    monkeypatch.setattr(seg, "run_holistic", fake)


@pytest.mark.parametrize("lost", ["back", "front"])
def test_a_view_without_a_person_is_stood_in_for_by_the_other(capture, monkeypatch, lost):
    """MediaPipe finds nobody in one view (even mirrored, even brightened): that view's landmarks come from
    the other view through the calibration, its person mask from its depth, with a warning; its labels stay
    close to the truth and its landmarks to where MediaPipe put them when it saw the person."""
    folder, data, cams, _ = capture
    _lower(monkeypatch, data, {})
    clean = lm.segment_views(_images(data), cams)
    _lose(monkeypatch, data, [lost])
    segs = lm.segment_views(_images(data), cams)
    other = "front" if lost == "back" else "back"
    assert segs[lost].warnings[0].startswith(f"{lost} image: no person found in it")
    assert f"the {other} view's through the calibration" in segs[lost].warnings[0]
    assert not any("no person" in w for w in segs[other].warnings)
    from PIL import Image

    truth = np.asarray(Image.open(folder / lost / "labels.png"))
    got, own = seg.label_accuracy(segs[lost].labels, truth), seg.label_accuracy(clean[lost].labels, truth)
    assert got["mask_iou"] >= 0.93 and got["accuracy"] >= 0.90, (got, own)  # measured 0.96 / 0.94-0.95
    for name in seg.REQUIRED_LANDMARKS:
        if name in clean[lost].sources:  # MediaPipe's own was already replaced from the other view
            continue
        d = np.hypot(*(segs[lost].landmark(name)[:2] - clean[lost].landmark(name)[:2]))
        assert d < 20.0, (name, d)  # measured 1-15 px


def test_process_keeps_a_capture_whose_back_view_shows_no_person(capture, monkeypatch, tmp_path):
    folder, data, _, s = capture
    _lose(monkeypatch, data, ["back"])
    from bsv.pipeline import process

    process(folder, folder / "calibration.json", tmp_path / "out", progress=False)
    vols = json.loads((tmp_path / "out" / "volumes.json").read_text())
    assert vols["warnings"][0].startswith("back image: no person found in it")
    assert "no person found in it" in (tmp_path / "out" / "report.html").read_text()
    truth = s.volumes_l()
    err = 100 * (vols["volumes_l"]["trunk_limbs"] - truth["trunk_limbs"]) / truth["trunk_limbs"]
    assert abs(err) < 1.0, err  # measured -0.25 % (the limbs within 6 %: degraded, said so)
    # and its intervals say so too: every quantity the stood-in view's boundaries move is widened
    assert all(k in vols["intervals"]["method"] for k in ("upper_arm_l", "shin_r", "asymmetry_shin_pct"))


def test_process_says_when_the_crotch_was_not_seen_and_widens_the_thighs(capture, monkeypatch, tmp_path):
    """No hip-loop target (the crotch not seen, as where the thighs touch): bsv process says so, keeps no
    boundary target and widens the thighs' intervals (bsv.frontend.groin.NO_TARGET_SD), not the arms'."""
    folder, _, _, _ = capture
    from bsv.frontend import groin
    from bsv.pipeline import process

    process(folder, folder / "calibration.json", tmp_path / "seen", progress=False)
    seen = json.loads((tmp_path / "seen" / "volumes.json").read_text())
    assert seen["boundaries_m"] and groin.NO_TARGET_WARNING not in seen["warnings"]
    monkeypatch.setattr(groin, "hip_loop_targets", lambda *a, **k: {})
    process(folder, folder / "calibration.json", tmp_path / "unseen", progress=False)
    unseen = json.loads((tmp_path / "unseen" / "volumes.json").read_text())
    assert groin.NO_TARGET_WARNING in unseen["warnings"] and unseen["boundaries_m"] == {}
    assert "thigh_l" in unseen["intervals"]["method"]

    def width(v: dict, name: str) -> float:
        lo, hi = v["intervals"]["volumes_l"][name]
        return (hi - lo) / v["volumes_l"][name]

    assert width(unseen, "thigh_l") > 1.15 * width(seen, "thigh_l")
    assert width(unseen, "forearm_l") == pytest.approx(width(seen, "forearm_l"), rel=0.05)


def test_no_person_in_either_view_is_a_typed_error(capture, monkeypatch):
    _, data, cams, _ = capture
    _lose(monkeypatch, data, seg.VIEWS)
    with pytest.raises(PersonNotFoundError, match="no person found in either camera's image"):
        lm.segment_views(_images(data), cams)


def test_process_keeps_the_capture_and_records_the_warning(capture, monkeypatch, tmp_path):
    folder, data, _, _ = capture
    _lower(monkeypatch, data, {("back", "right_wrist"): 0.7})
    from bsv.pipeline import process

    res = process(folder, folder / "calibration.json", tmp_path / "out", progress=False)
    vols = json.loads((tmp_path / "out" / "volumes.json").read_text())
    assert len(vols["warnings"]) == 1 and "right_wrist" in vols["warnings"][0]
    assert res.warnings == vols["warnings"]
    assert set(vols["joints_m"]) == set(lm.JOINTS)
    assert vols["joints_m"]["wrist_r"]["source"] == "front"  # the back view's wrist came from the front
    assert "right_wrist" in (tmp_path / "out" / "report.html").read_text()
    assert vols["volumes_l"]["trunk_limbs"] > 0
    # the sex was not given: read from the capture, recorded, and the template's build follows it
    assert vols["sex"]["source"] == "inferred" and vols["template"]["gender"] == vols["sex"]["template_gender"]
    assert "Sex: not given; read from the capture" in (tmp_path / "out" / "report.html").read_text()


def test_the_sex_is_read_from_the_capture_or_taken_as_given(capture, monkeypatch):
    """This man is read as a man (both views hold the same estimate); a sex given as a score is taken as it is
    and moves the knee lines: a woman's lie lower, so her shins have fewer pixels."""
    _, data, cams, s = capture
    _lower(monkeypatch, data, {})
    segs = lm.segment_views(_images(data), cams)
    est = segs["front"].sex
    assert s.sex == "male" and est is segs["back"].sex
    assert est.source == "inferred" and est.p_female < 0.5 and est.score < 0
    assert set(est.measurements) == set(SEX_MEASUREMENTS) and all(np.isfinite(list(est.measurements.values())))
    woman = lm.segment_views(_images(data), cams, sex_score=1.0)
    man = lm.segment_views(_images(data), cams, sex_score=-1.0)
    assert woman["front"].sex.sex == "female" and man["back"].sex.source == "given"
    for v in seg.VIEWS:
        shins = [int(np.isin(x[v].labels, [seg.SEGMENT_IDS["shin_l"], seg.SEGMENT_IDS["shin_r"]]).sum())
                 for x in (woman, segs, man)]
        assert shins[0] < shins[2] and shins[0] <= shins[1] <= shins[2], (v, shins)  # the man read as one: ~ -1


def test_bsv_process_names_the_missing_limb_and_writes_nothing(capture, monkeypatch, tmp_path, capsys):
    from bsv.pipeline import main_process

    folder, data, _, _ = capture
    _lower(monkeypatch, data, {("front", "right_elbow"): 0.1, ("back", "right_elbow"): 0.2})
    out = tmp_path / "out"
    assert main_process([str(folder), "-c", str(folder / "calibration.json"), "-o", str(out), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "right arm" in err and "right_elbow" in err and "step back" in err and "Traceback" not in err
    assert not out.exists() or not any(out.rglob("*"))


def test_the_ankle_plane_labels_the_shins_and_feet_closer_to_the_truth(capture, monkeypatch):
    """segment_views cuts each leg's shin from its foot by the 3-D ankle plane (cut_feet_at_ankle_plane): on
    the rendered capture, the leg pixels labelled shin where the truth says foot or the other way round are
    fewer than half as many as with the 2-D line through the ankle landmark alone (the plane turned off)."""
    folder, data, cams, _ = capture
    from PIL import Image

    _lower(monkeypatch, data, {})
    planed = lm.segment_views(_images(data), cams)
    monkeypatch.setattr(lm, "cut_feet_at_ankle_plane", lambda labels, *a, **k: np.array(labels, copy=True))
    lined = lm.segment_views(_images(data), cams)

    def wrong(segs) -> int:
        n = 0
        for v in seg.VIEWS:
            truth = np.asarray(Image.open(folder / v / "labels.png"))
            for side in "lr":
                ids = (seg.SEGMENT_IDS["shin_" + side], seg.SEGMENT_IDS["foot_" + side])
                both = np.isin(truth, ids) & np.isin(segs[v].labels, ids)
                n += int((both & (truth != segs[v].labels)).sum())
        return n

    assert wrong(planed) < 0.6 * wrong(lined), (wrong(planed), wrong(lined))
    for v in seg.VIEWS:  # nothing but the legs' shin / foot pixels changes
        moved = planed[v].labels != lined[v].labels
        legs = np.isin(lined[v].labels, [seg.SEGMENT_IDS[f"{k}_{s}"] for k in ("shin", "foot") for s in "lr"])
        assert moved.any() and not (moved & ~legs).any()
