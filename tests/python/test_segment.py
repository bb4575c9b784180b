"""MediaPipe body segmentation on the virtual scanner's colour renders (front and back cameras) of a few
synthetic bodies, scored against the scanner's ground-truth label images; clear errors for an empty
image and for a subject whose legs are out of the frame."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

cv2 = pytest.importorskip("cv2")
pytest.importorskip("mediapipe", reason="mediapipe not installed (pip install -r requirements-frontend.txt)")
bsv = pytest.importorskip("bsv")

from bsv.frontend import errors  # noqa: E402
from bsv.frontend import segment as seg  # noqa: E402
from bsv.frontend.capture import read_capture  # noqa: E402

VIEWS = ("front", "back")
COHORT_SEED = 3  # not the cohort the defaults were tuned on (seed 1)


@pytest.fixture(scope="module")
def scans(tmp_path_factory):
    """Scanner folders of the default body and two cohort subjects, segmented once (colour only)."""
    root = tmp_path_factory.mktemp("segment")
    bodies = [("default", bsv.bodies.make_body())]
    bodies += [(f"cohort{s.index}", s.body) for s in bsv.bodies.cohort(2, COHORT_SEED)]
    out = {}
    for name, body in bodies:
        folder = root / name
        bsv.scan(body.mesh(), "noer", 0, images=str(folder))
        result = seg.segment_capture(folder, use_depth=False)
        for view in VIEWS:
            truth = cv2.imread(str(folder / view / "labels.png"), cv2.IMREAD_UNCHANGED)
            out[(name, view)] = (folder, result[view], truth)
    return out


def test_landmarks_found_and_sides_match_the_truth(scans):
    for (name, view), (_, s, truth) in scans.items():
        assert s.landmarks.shape == (71, 3) and len(s.names) == 71 and len(set(s.names)) == 71
        assert s.hands_found == (True, True), f"{name} {view}: hands {s.hands_found}"
        assert np.isfinite(s.landmarks[:, :2]).all()
        h, w = truth.shape
        for lm in seg.REQUIRED_LANDMARKS:
            x, y, vis = s.landmark(lm)
            assert vis >= 0.75 and 0 <= x < w and 0 <= y < h, f"{name} {view}: {lm} at {x, y} visibility {vis}"
        # the subject's left is on the image right from the front and on the image left from the back
        dx = s.landmark("left_shoulder")[0] - s.landmark("right_shoulder")[0]
        assert dx > 0 if view == "front" else dx < 0
        # each knee and wrist landmark lies on (or next to) its own side's segments in the truth
        for lm, ids in (("left_knee", (9, 11)), ("right_knee", (10, 12)), ("left_wrist", (5, 7)), ("right_wrist", (6, 8)),
                        ("left_elbow", (3, 5)), ("right_elbow", (4, 6))):
            x, y = (round(c) for c in s.landmark(lm)[:2])
            window = truth[max(y - 6, 0):y + 7, max(x - 6, 0):x + 7]
            assert np.isin(window, ids).any(), f"{name} {view}: {lm} not on {ids}: {np.unique(window)}"


def test_label_accuracy_against_rendered_truth(scans):
    accs = {v: [] for v in VIEWS}
    for (name, view), (_, s, truth) in scans.items():
        r = seg.label_accuracy(s.labels, truth)
        accs[view].append(r["accuracy"])
        ious = " ".join(f"{k}={v:.2f}" for k, v in r["iou"].items())
        print(f"{name:8s} {view:5s} accuracy {r['accuracy']:.3f} mask IoU {r['mask_iou']:.3f} | {ious}")
        assert r["accuracy"] >= 0.90, f"{name} {view}: accuracy {r['accuracy']:.3f}"
        assert r["mask_iou"] >= 0.90, f"{name} {view}: mask IoU {r['mask_iou']:.3f}"
        assert all(v >= 0.5 for v in r["iou"].values()), f"{name} {view}: a segment is badly placed: {r['iou']}"
        assert set(np.unique(s.labels)) == set(range(15))
    for v in VIEWS:
        print(f"mean accuracy {v}: {np.mean(accs[v]):.3f}")


def test_medial_and_transverse_corrections(scans):
    """Left leg labels only on the subject's left of the medial line (through the mid-hips along the body
    axis), thighs only above the knee line."""
    for (name, view), (_, s, _) in scans.items():
        def mid(a, s=s):
            return (s.landmark(f"left_{a}")[:2] + s.landmark(f"right_{a}")[:2]) / 2
        h_mid, axis = mid("hip"), mid("hip") - mid("shoulder")
        knee_y = mid("knee")[1]
        ys, xs = np.nonzero(s.labels)
        lab = s.labels[ys, xs]
        across = (xs - h_mid[0]) * axis[1] - (ys - h_mid[1]) * axis[0]  # > 0: image right of the medial line
        left_side = across > 0 if view == "front" else across < 0
        legs_l, legs_r = np.isin(lab, (9, 11, 13)), np.isin(lab, (10, 12, 14))
        assert left_side[legs_l].all() and not left_side[legs_r].any(), f"{name} {view}"
        assert (ys[np.isin(lab, (9, 10))] < knee_y + 0.2 * (ys.max() - knee_y)).all()
        assert (ys[np.isin(lab, (11, 12))] > knee_y - 5).all()


def test_segment_capture_writes_files(scans):
    folder, s, _ = scans[("default", "front")]
    written = cv2.imread(str(folder / "front" / "segmentation.png"), cv2.IMREAD_UNCHANGED)
    assert written.dtype == np.uint8 and np.array_equal(written, s.labels)
    meta = json.loads((folder / "front" / "landmarks.json").read_text())
    assert meta["view"] == "front" and len(meta["landmarks_px"]) == 71
    assert meta["segments"]["foot_r"] == 14 and sum(meta["counts"].values()) == int(s.mask.sum())
    assert (cv2.imread(str(folder / "front" / "mask.png"), cv2.IMREAD_UNCHANGED) > 0).sum() == s.mask.sum()
    from bsv.palette import colourise

    preview = cv2.cvtColor(cv2.imread(str(folder / "front" / "segmentation_preview.png")), cv2.COLOR_BGR2RGB)
    assert np.array_equal(preview, colourise(s.labels))  # the raw ids in the segment palette, beside them


def test_depth_refines_the_mask(scans):
    folder, s, truth = scans[("cohort0", "back")]
    data = read_capture(folder / "back")
    refined = seg.refine_mask_with_depth(s.mask, data["depth_m"])
    iou = lambda m: ((m & (truth > 0)).sum() / (m | (truth > 0)).sum())  # noqa: E731
    print(f"mask IoU colour only {iou(s.mask):.4f}, refined with depth {iou(refined):.4f}")
    assert iou(refined) > 0.99 > iou(s.mask)  # the scanner's background has no depth


def test_depth_completes_a_limb_the_colour_mask_lost():
    """A shin whose lower half MediaPipe's mask dropped (a dark leg over a brown floor in dim light) comes
    back from the depth image; the wall behind stays out, and a limb absent from the mask is not invented."""
    h, w = 300, 240
    depth = np.full((h, w), 3.0)  # a wall 3 m away
    depth[100:200, 90:111] = 2.0  # the left shin, knee (100, 100) to ankle (100, 200), 2 m away
    depth[100:200, 150:171] = 2.0  # the right shin, not in the mask at all
    depth[120:130, 95:105] = 0.0  # a hole without depth stays a hole
    pose = np.full((33, 3), np.nan)
    pose[25] = (100.0, 100.0, 1.0)  # left knee
    pose[27] = (100.0, 200.0, 1.0)  # left ankle
    pose[26] = (160.0, 100.0, 1.0)  # right knee
    pose[28] = (160.0, 200.0, 1.0)  # right ankle
    mask = np.zeros((h, w), bool)
    mask[100:150, 90:111] = True  # the upper half of the left shin only
    mask[120:130, 95:105] = False
    done = seg.complete_limbs_with_depth(mask, depth, pose)
    shin = depth == 2.0
    left = np.zeros((h, w), bool)
    left[:, :130] = True
    assert (done & shin & left).sum() == (shin & left).sum()  # the whole left shin
    assert not (done & (depth == 3.0)).any()  # no wall
    assert not (done & ~left).any()  # the right shin had nothing to anchor its depth: left out
    assert not done[120:130, 95:105].any()
    assert not seg.complete_limbs_with_depth(mask, depth, pose, width=0.0)[150:200].any()
    with pytest.raises(errors.SegmentationError, match="limb_fill_width"):
        seg.SegmentParams(limb_fill_width=1.5)


def test_an_ankle_height_outside_its_range_is_refused():
    """SegmentParams.ankle_height is a fraction of the stature: a value in millimetres or metres is refused
    with the range and what 0 means."""
    for bad in (75.0, -0.01, 0.5):
        with pytest.raises(errors.SegmentationError, match=r"ankle_height must lie in \[0, 0.2\]"):
            seg.SegmentParams(ankle_height=bad)
    assert seg.SegmentParams(ankle_height=0.0).ankle_height == 0.0


def test_blank_image_has_no_person():
    with pytest.raises(errors.PersonNotFoundError, match="no person"):
        seg.segment_image(np.full((1024, 768, 3), 128, np.uint8), "front")


def test_a_dim_subject_on_black_is_found_with_its_contrast_stretched(tmp_path):
    """A studio capture (no wall behind the subject, so a black background) whose back view is lit only by a
    weak fill light: MediaPipe finds nobody in the image as captured nor in its mirror image. Brightened, it
    does, and the detection says how it was found; on the neutral background of the capture's depth it is
    found as it is, and segmented as well as a lit view."""
    from bsv.bench.synth import STUDIO, scan_seed

    s = bsv.bodies.subject(5, 0)
    folder = tmp_path / "studio"
    bsv.scan(s.body.mesh(), "noer", scan_seed(0, 5), images=str(folder), room=dict(STUDIO))
    back = read_capture(folder / "back")["colour"]
    for img in (back, np.ascontiguousarray(back[:, ::-1])):  # the failure this guards against
        assert seg.run_holistic(img, seg.DEFAULT_PARAMS["back"])["pose"] is None
    det = seg.detect(back, "back")
    assert len(det.notes) == 1 and "brightness scaled 2.2x" in det.notes[0], det.notes
    assert det.spread is not None  # the mirror image of the brightened image is averaged in as usual
    # With its depth, the capture shows MediaPipe the subject on a neutral grey (bsv.frontend.background),
    # against which the dim subject stands out: found without brightening.
    result = seg.segment_capture(folder, write=False)
    assert not any("brightness" in w for w in (*result["back"].warnings, *result["front"].warnings))
    darker = (back.astype(np.float64) * 0.2).astype(np.uint8)  # gain 11: still found
    assert "brightness scaled 11." in seg.detect(darker, "back").notes[0]
    truth = cv2.imread(str(folder / "back" / "labels.png"), cv2.IMREAD_UNCHANGED)
    r = seg.label_accuracy(result["back"].labels, truth)
    assert r["accuracy"] >= 0.90 and r["mask_iou"] >= 0.90, r


def test_stretch_contrast_brightens_a_dim_image_only():
    dim = np.zeros((40, 30, 3), np.uint8)
    dim[10:30, 10:20] = (100, 60, 40)
    out, gain = seg.stretch_contrast(dim)
    assert gain == pytest.approx(2.55)
    assert tuple(out[15, 15]) == (255, 153, 102) and out.dtype == np.uint8 and not out[0, 0].any()
    bright = dim.copy()
    bright[10:30, 10:20] = (255, 200, 10)
    same, one = seg.stretch_contrast(bright)
    assert one == 1.0 and same is bright
    black = np.zeros((8, 8, 3), np.uint8)
    assert seg.stretch_contrast(black)[1] == seg.STRETCH_MAX_GAIN  # capped: noise is not amplified without end


def test_legs_cropped_names_the_ankles(scans):
    folder, _, truth = scans[("default", "front")]
    colour = read_capture(folder / "front")["colour"]
    rows = np.nonzero((truth == 11) | (truth == 12))[0]
    cut = int(rows.min() + 0.6 * (rows.max() - rows.min()))  # through the shins: the ankles are out of frame
    with pytest.raises(errors.LandmarkMissingError, match="ankle") as e:
        seg.segment_image(np.ascontiguousarray(colour[:cut]), "front")
    assert "left_ankle" in e.value.missing and "right_ankle" in e.value.missing
    assert not any("wrist" in m for m in e.value.missing)


def test_bad_arguments_are_clear_errors():
    img = np.zeros((64, 48, 3), np.uint8)
    with pytest.raises(errors.SegmentationError, match="view"):
        seg.segment_image(img, "side")
    with pytest.raises(errors.SegmentationError, match="RGB uint8"):
        seg.segment_image(img.astype(np.float32), "front")
    with pytest.raises(errors.SegmentationError, match="model_complexity"):
        seg.segment_image(img, "front", model_complexity=5)
    with pytest.raises(errors.SegmentationError, match="unknown segmentation parameter"):
        seg.segment_image(img, "front", no_such_knob=1)


def test_label_accuracy_counts():
    truth = np.zeros((4, 6), np.uint8)
    truth[:, :3] = 2
    truth[:, 3:] = 9
    pred = truth.copy()
    pred[0, :] = 0  # 6 pixels outside the predicted mask
    pred[1, 3] = 10  # one wrong pixel
    r = seg.label_accuracy(pred, truth)
    assert r["n_pixels"] == 18 and r["accuracy"] == pytest.approx(17 / 18)
    assert r["mask_iou"] == pytest.approx(18 / 24)
    assert r["iou"]["torso"] == 1.0 and r["iou"]["thigh_l"] == pytest.approx(8 / 9) and r["iou"]["thigh_r"] == 0.0
    assert math.isnan(r["iou"]["head"])
    with pytest.raises(errors.SegmentationError, match="shape"):
        seg.label_accuracy(pred, truth[:3])


def test_coarse_hands_when_the_hand_model_misses(scans):
    """Without the hand model's landmarks, the pose's wrist-knuckle-thumb points still give the hands (the
    hand/forearm cut is the wrist line either way; the hand bones only decide which limb a pixel is on)."""
    for key in (("default", "front"), ("cohort0", "back")):
        _, s, truth = scans[key]
        full = seg.label_accuracy(s.labels, truth)
        coarse = seg.label_accuracy(seg.label_pixels(s.mask, s.pose, [None, None], seg.DEFAULT_PARAMS[key[1]]), truth)
        print(f"{key}: hand IoU with hand landmarks {full['iou']['hand_l']:.2f}/{full['iou']['hand_r']:.2f}, "
              f"pose only {coarse['iou']['hand_l']:.2f}/{coarse['iou']['hand_r']:.2f}")
        assert coarse["accuracy"] > full["accuracy"] - 0.02
        assert min(coarse["iou"]["hand_l"], coarse["iou"]["hand_r"]) > 0.7


def test_write_segmentation_refuses_to_overwrite(scans, tmp_path):
    from bsv.errors import OutputExistsError

    folder, s, _ = scans[("default", "front")]
    before = (folder / "front" / "landmarks.json").read_text()
    with pytest.raises(OutputExistsError, match="overwrite"):
        seg.write_segmentation(s, folder / "front")
    assert (folder / "front" / "landmarks.json").read_text() == before
    seg.write_segmentation(s, folder / "front", overwrite=True)
    seg.write_segmentation(s, tmp_path / "new" / "front")  # a new folder is created
    assert (tmp_path / "new" / "front" / "segmentation.png").is_file()


def test_flip_average_is_the_mean_of_both_oriented_detections(monkeypatch):
    """``flip_average``: the view is detected on the image and on its mirror image; the mirror's landmarks
    are mapped back (x -> w - 1 - x), both are oriented to the subject's left/right, and the result is their
    mean (positions, visibilities, hands, soft masks). A fake MediaPipe that answers the mirror image with
    the true landmarks plus 4 px and 0.2 visibility shows it."""
    h, w = 60, 80
    img = np.zeros((h, w, 3), np.uint8)
    img[:, : w // 2] = 50  # the mirror image differs from the image
    truth = np.column_stack([np.linspace(5, 70, 33), np.linspace(5, 50, 33), np.full(33, 0.6)])
    hand = np.column_stack([np.full(21, 60.0), np.linspace(20, 40, 21)])
    mask = np.zeros((h, w), np.float32)
    mask[10:50, 20:40] = 1.0

    def fake(rgb, params=None):
        mirrored = bool(rgb[0, -1, 0] == 50)
        if not mirrored:
            return {"pose": truth.copy(), "hands": [hand.copy(), None], "mask": mask.copy()}
        pose = truth.copy()
        pose[:, 0] = w - 1 - (pose[:, 0] + 4.0)  # the mirror's x of (truth + 4 px)
        pose[:, 2] += 0.2
        return {"pose": pose, "hands": [None, None], "mask": mask[:, ::-1] * 0.5}

    monkeypatch.setattr(seg, "run_holistic", fake)
    one = seg.detect(img, "front", flip_average=False)
    both = seg.detect(img, "front", flip_average=True)
    assert np.allclose(both.pose[:, 0], one.pose[:, 0] + 2.0)
    assert np.allclose(both.pose[:, 1], one.pose[:, 1])
    assert np.allclose(both.pose[:, 2], one.pose[:, 2] + 0.1)
    assert [hd is None for hd in both.hands] == [hd is None for hd in one.hands]  # a hand seen once is kept
    assert both.mask_soft is not None and np.allclose(both.mask_soft, 0.75 * mask)


def test_bone_distances_are_the_exact_point_to_segment_distances():
    """label_pixels compares the distance of every person pixel to the nearest bone of each group
    (bsv._bsv.nearest_segment_distances): the same numbers as the point-to-segment formula in numpy."""
    rng = np.random.default_rng(3)
    p = rng.uniform(0, 640, (5000, 2))
    bones = [(rng.uniform(0, 640, 2), rng.uniform(0, 640, 2)) for _ in range(25)] + [(np.array([5.0, 5.0]),) * 2]

    def reference(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        ab = b - a
        den = float(ab @ ab)
        t = np.zeros(len(p)) if den <= 1e-12 else np.clip((p - a) @ ab / den, 0.0, 1.0)
        q = a + t[:, None] * ab
        return np.hypot(p[:, 0] - q[:, 0], p[:, 1] - q[:, 1])

    expected = np.min([reference(a, b) for a, b in bones], axis=0)
    np.testing.assert_allclose(seg._bones_dist(p, bones), expected, rtol=1e-12, atol=1e-9)
    assert np.isinf(seg._bones_dist(p, [])).all()
    with pytest.raises(bsv.errors.InputError, match=r"segments must have shape \(N, 4\)") as e:
        bsv._bsv.nearest_segment_distances(p, np.zeros((3, 2, 2)))
    assert e.value.argument == "segments"


def _drawn_arm(half: float, offset: float = 0.0, torso_from: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A mask with one upper arm drawn as a band of half-width ``half`` around the segment (100, 100) ->
    (260, 220) (shoulder to elbow, pixels), the bone given ``offset`` pixels off the band's axis; with
    ``torso_from``, a torso filling the image below the line y = x + torso_from (left of the arm)."""
    h, w = 400, 400
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    sh, el = np.array([100.0, 100.0]), np.array([260.0, 220.0])
    axis = (el - sh) / np.hypot(*(el - sh))
    normal = np.array([-axis[1], axis[0]])
    rel_x, rel_y = xx - sh[0], yy - sh[1]
    along = rel_x * axis[0] + rel_y * axis[1]
    across = rel_x * normal[0] + rel_y * normal[1]
    mask = (np.abs(across) <= half) & (along >= -40) & (along <= 240)
    if torso_from is not None:
        mask |= yy > xx + torso_from
    return mask, sh + offset * normal, el + offset * normal


def test_upper_arm_half_width_of_a_drawn_arm():
    """The half-width across the shoulder-elbow bone (the upper arm's girth for the nearest-bone rule) is the
    band's, wherever the bone lies inside it; cross-sections where the arm lies against the torso are left
    out, and an arm against the torso all along has no girth."""
    for half in (8.0, 14.0, 22.0):
        for offset in (0.0, 5.0, -6.0):
            mask, sh, el = _drawn_arm(half, offset)
            got = seg.upper_arm_half_width(mask, sh, el)
            assert got is not None and abs(got - half) <= 1.0, (half, offset, got)
    # the torso touches the arm's lower side near the shoulder: the sections there are skipped
    mask, sh, el = _drawn_arm(12.0, torso_from=60.0)
    assert abs(seg.upper_arm_half_width(mask, sh, el) - 12.0) <= 1.0
    mask, sh, el = _drawn_arm(12.0, torso_from=-20.0)  # the whole arm lies on the torso
    assert seg.upper_arm_half_width(mask, sh, el) is None
    assert seg.upper_arm_half_width(np.zeros((50, 50), bool), np.array([10.0, 10.0]), np.array([30.0, 30.0])) is None
    assert seg.upper_arm_half_width(mask, np.array([5.0, 5.0]), np.array([5.5, 5.0])) is None  # no bone
    assert seg.upper_arm_half_width(mask, np.array([np.nan, 5.0]), np.array([50.0, 50.0])) is None  # not placed


def test_the_upper_arms_reach_follows_their_girth(scans):
    """With arm_girth_power upper arms thicker than arm_girth_ref (for the body's height in the image) take
    more of the pixels between their bones and the torso, thinner ones fewer; at the reference girth (the
    arms' mean), or with the power 0, the plain nearest-bone rule. Forearms and every other segment are
    untouched."""
    _, s, _ = scans[("default", "front")]
    # the nearest-bone rule alone (no shoulder line from the armpit, which decides above the armpit)
    prm = dataclasses.replace(seg.DEFAULT_PARAMS["front"], arm_girth_power=0.0, armpit_angle=None)
    plain = seg.label_pixels(s.mask, s.pose, [None, None], prm)
    P = {n: s.pose[i, :2] for i, n in enumerate(seg.POSE_NAMES)}
    height = float(np.hypot(*(P["nose"] - (P["left_ankle"] + P["right_ankle"]) / 2)))
    girth = {side: seg.upper_arm_half_width(s.mask, P[f"{side}_shoulder"], P[f"{side}_elbow"]) / height
             for side in ("left", "right")}
    assert all(0.02 < g < 0.05 for g in girth.values()), girth
    ua = [seg.SEGMENT_IDS["upper_arm_l"], seg.SEGMENT_IDS["upper_arm_r"]]
    counts = {}
    for ref in (0.5, 1.0, 2.0):
        # one reference for both arms: the mean of their girths, scaled
        p = dataclasses.replace(prm, arm_girth_power=0.5, arm_girth_ref=ref * float(np.mean(list(girth.values()))))
        lab = seg.label_pixels(s.mask, s.pose, [None, None], p)
        counts[ref] = int(np.isin(lab, ua).sum())
        others = ~np.isin(plain, [*ua, seg.SEGMENT_IDS["torso"], seg.SEGMENT_IDS["head"]])
        assert (lab[others] == plain[others]).all()  # only the upper arms and the torso trade pixels
    base = int(np.isin(plain, ua).sum())
    assert counts[0.5] > base + 20 and counts[2.0] < base - 20, (counts, base)
    assert counts[1.0] == base
    assert seg.DEFAULT_PARAMS["front"].arm_girth_power == 0.5 and seg.DEFAULT_PARAMS["back"].arm_girth_power == 0.5
    for bad in ({"arm_girth_power": -0.5}, {"arm_girth_power": 3.0}, {"arm_girth_ref": 0.0}, {"arm_girth_ref": 0.5}):
        with pytest.raises(errors.SegmentationError, match="arm_girth"):
            seg.SegmentParams(**bad)


def _drawn_body(gap: bool = True, hole: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """A mask with a torso (columns 150-250 from row 100 down) and a right arm from the shoulder (245, 110)
    down and out to the elbow (365, 230), 15 px half-width (the armpit where its lower edge leaves the torso's
    side); without ``gap`` the arm hangs against the torso (its band widened to the hip); with ``hole`` a
    depth drop-out inside the torso. Returns the mask and the elbow."""
    h, w = 400, 420
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    mask = (xx >= 150) & (xx <= 250) & (yy >= 100)
    sh, el = np.array([245.0, 110.0]), np.array([365.0, 230.0])
    axis = (el - sh) / np.hypot(*(el - sh))
    normal = np.array([-axis[1], axis[0]])
    along = (xx - sh[0]) * axis[0] + (yy - sh[1]) * axis[1]
    across = (xx - sh[0]) * normal[0] + (yy - sh[1]) * normal[1]
    mask |= (np.abs(across) <= 15.0) & (along >= -10) & (along <= 200)
    if not gap:
        mask |= (xx >= 150) & (xx <= 370) & (yy >= 100)
    if hole:
        mask[150:170, 230:245] = False
    return mask, el


def test_the_armpit_is_the_top_of_the_gap_under_the_arm():
    """The armpit is where the arm's lower edge leaves the torso's side (the arm's lower edge, y = x - 135 +
    15 * sqrt(2), meets x = 250 at y = 136.2); a hole inside the torso does not move it; an arm hanging
    against the torso has none."""
    mask, el = _drawn_body()
    a = seg.armpit_point(mask, el, centre_x=200.0, top_y=110.0, bottom_y=390.0)
    assert a is not None and abs(a[1] - 136.2) <= 2.0 and 250.0 <= a[0] <= 255.0, a
    holed, _ = _drawn_body(hole=True)
    assert np.allclose(seg.armpit_point(holed, el, 200.0, 110.0, 390.0), a)
    closed, _ = _drawn_body(gap=False)
    assert seg.armpit_point(closed, el, 200.0, 110.0, 390.0) is None
    assert seg.armpit_point(mask, np.array([np.nan, 200.0]), 200.0, 110.0, 390.0) is None  # no elbow


def _cut_against_rule(s, truth: np.ndarray, prm, off: dict, ids: list[int], wrong: dict[str, int]) -> tuple[np.ndarray, np.ndarray]:
    """A segmentation's mask and pose labelled with ``prm`` (its cut line) and with the fields ``off`` set (the rule
    alone): adds to ``wrong`` ("rule", "line") how many pixels of the true ``ids`` each labels as another of
    ``ids``, checks that only ``ids`` trade pixels, and returns both label images (rule, line)."""
    rule = seg.label_pixels(s.mask, s.pose, [None, None], dataclasses.replace(prm, **off))
    line = seg.label_pixels(s.mask, s.pose, [None, None], prm)
    both = np.isin(truth, ids)
    for k, lab in (("rule", rule), ("line", line)):
        wrong[k] += int((both & np.isin(lab, ids) & (lab != truth)).sum())
    others = ~np.isin(rule, ids)
    assert (line[others] == rule[others]).all()
    return rule, line


def test_the_shoulder_line_from_the_armpit_labels_the_shoulders_closer_to_the_truth(scans):
    """On the rig's renders (the default body and two cohort subjects, both views) the shoulder line from
    the armpit (the defaults) mislabels fewer of the true torso's and upper arms' pixels than the
    nearest-bone rule alone; leaning it further towards the midline gives the arms more pixels; only the
    torso and the upper arms trade pixels."""
    ua = [seg.SEGMENT_IDS["upper_arm_l"], seg.SEGMENT_IDS["upper_arm_r"]]
    torso = seg.SEGMENT_IDS["torso"]
    wrong = {"rule": 0, "line": 0}
    for (_, view), (_, s, truth) in scans.items():
        prm = seg.DEFAULT_PARAMS[view]
        assert prm.armpit_angle is not None
        _, line = _cut_against_rule(s, truth, prm, {"armpit_angle": None}, [torso, *ua], wrong)
        leaning = seg.label_pixels(s.mask, s.pose, [None, None],
                                   dataclasses.replace(prm, armpit_angle=prm.armpit_angle + 10.0))
        assert np.isin(leaning, ua).sum() > np.isin(line, ua).sum()
    assert wrong["line"] < 0.8 * wrong["rule"], wrong


def test_shoulder_line_parameters_outside_their_ranges_are_refused():
    for bad in ({"armpit_angle": 75.0}, {"armpit_arm_slope": 3.0}, {"armpit_sex_slope": -25.0}, {"armpit_reach": 0.0}):
        with pytest.raises(errors.SegmentationError, match="armpit"):
            seg.SegmentParams(**bad)


def _drawn_legs(gap: bool = True, hole: bool = False) -> np.ndarray:
    """A mask with a torso (columns 100-300, rows 50-200) and two legs (columns 100-190 and 210-300, down to
    the bottom): the crotch at (200, 201). Without ``gap`` the legs touch all the way down; with ``hole`` a depth
    drop-out between the thighs above the crotch."""
    h, w = 420, 400
    yy, xx = np.mgrid[0:h, 0:w]
    mask = (xx >= 100) & (xx <= 300) & (yy >= 50)
    if gap:
        mask &= ~((xx > 190) & (xx < 210) & (yy > 200))
    if hole:
        mask[170:190, 192:208] = False
    return mask


def test_the_crotch_is_the_top_of_the_gap_between_the_legs():
    """The crotch is the top of the gap between the legs, midway across it; a hole between the thighs does not
    move it; legs touching down to the knees have none."""
    knees = np.array([145.0, 380.0]), np.array([255.0, 380.0])
    c = seg.crotch_point(_drawn_legs(), *knees, top_y=120.0)
    assert c is not None and abs(c[1] - 201.0) <= 1.0 and abs(c[0] - 200.0) <= 1.0, c
    assert np.allclose(seg.crotch_point(_drawn_legs(hole=True), *knees, top_y=120.0), c)
    assert seg.crotch_point(_drawn_legs(gap=False), *knees, top_y=120.0) is None
    assert seg.crotch_point(_drawn_legs(), np.array([np.nan, 380.0]), knees[1], 120.0) is None  # no knee


def test_groin_line_parameters_outside_their_ranges_are_refused():
    for bad in ({"groin_angle": 85.0}, {"groin_angle": -15.0}, {"groin_reach": 0.0}, {"groin_offset": 0.5}):
        with pytest.raises(errors.SegmentationError, match="groin"):
            seg.SegmentParams(**bad)


def _legs_pose() -> np.ndarray:
    """Pose landmarks (33, 3; subject's left on the image right, a front view) for :func:`_drawn_legs`: hips at
    row 190, knees at row 380 (the hip-knee distance 190 px)."""
    pose = np.full((33, 3), np.nan)
    at = {"left_shoulder": (270, 60), "right_shoulder": (130, 60), "left_hip": (250, 190), "right_hip": (150, 190),
          "left_knee": (255, 380), "right_knee": (145, 380)}
    for name, xy in at.items():
        pose[seg.POSE_NAMES.index(name)] = (*xy, 1.0)
    return pose


def test_the_two_views_crotches_agree():
    """A gap between the legs only shows lower than the crotch: when one view's gap starts far lower than the
    other's (depths below the hips differing by more than CROTCH_VIEWS_DISAGREE of the hip-knee distance),
    its crotch moves up to the other's depth; views that agree keep their own; a view with no gap takes the
    other's depth at the midline. A gap deeper than the expected crotch by more than CROTCH_TOUCH_MARGIN (the
    thighs touch) puts that view's crotch at its expected depth (a woman's lower than a man's) and moves the
    other view's up to its own expected depth when deeper, each with a warning for the touching view."""
    pose = _legs_pose()
    open_, closed = _drawn_legs(), _drawn_legs()
    closed[200:260, 185:215] = True  # the thighs touch down to row 260 (depth 0.37 against 0.06)
    spread = math.degrees(math.atan2(5.0, 190.0))  # each knee 5 px outward of its hip
    c, notes = seg.agreeing_crotches({"front": open_, "back": closed}, {"front": pose, "back": pose})
    assert list(notes) == ["back"] and "the thighs touch" in notes["back"] and "expected depth" in notes["back"], notes
    assert c["front"] is not None and c["back"] is not None  # the open view keeps its own: above its expected
    want = 190.0 + 190.0 * seg.expected_crotch_depth("back", 0.0, spread)
    assert abs(c["front"][1] - 201.0) <= 1.0 and abs(c["back"][1] - want) <= 0.5, c
    lowish = _drawn_legs()
    lowish[200:250, 185:215] = True  # the other view's gap opens below the touching thighs too: up to expected
    c, notes = seg.agreeing_crotches({"front": lowish, "back": closed}, {"front": pose, "back": pose})
    want_front = 190.0 + 190.0 * seg.expected_crotch_depth("front", 0.0, spread)
    assert list(notes) == ["back"] and abs(c["front"][1] - want_front) <= 0.5, (c, notes)
    near = _drawn_legs()
    near[200:205, 185:215] = True  # 4 px lower: within the views' agreement, kept
    c, notes = seg.agreeing_crotches({"front": open_, "back": near}, {"front": pose, "back": pose})
    assert notes == {}
    assert c["back"] is not None and abs(c["back"][1] - 205.0) <= 1.0, c
    together = _drawn_legs(gap=False)
    c, notes = seg.agreeing_crotches({"front": open_, "back": together}, {"front": pose, "back": pose})
    assert c["back"] is not None and abs(c["back"][1] - 201.0) <= 1.5 and abs(c["back"][0] - 200.0) <= 1.0, c
    deep = _drawn_legs()
    deep[200:320, 185:215] = True  # both views' gaps start at depth 0.69: the thighs touch above it
    assert seg.thigh_angle_deg(np.array([250.0, 190.0]), np.array([255.0, 380.0]), np.array([0.0, 1.0]),
                               np.array([1.0, 0.0])) == pytest.approx(spread)
    for sex in (-1.0, 0.0, 1.0):
        c, notes = seg.agreeing_crotches({"front": deep, "back": deep}, {"front": pose, "back": pose}, sex)
        assert sorted(notes) == ["back", "front"] and all("expected depth" in n for n in notes.values()), notes
        for v in ("front", "back"):
            want = 190.0 + 190.0 * seg.expected_crotch_depth(v, sex, spread)
            assert c[v] is not None and abs(c[v][1] - want) <= 0.5 and abs(c[v][0] - 200.0) <= 0.5, (sex, v, c)
    assert seg.expected_crotch_depth("front", 1.0, spread) > seg.expected_crotch_depth("front", -1.0, spread)
    assert seg.expected_crotch_depth("back", 0.0, 10.0) < seg.expected_crotch_depth("back", 0.0, 0.0)
    assert all(seg.expected_crotch_depth(v, 0.0, spread) + seg.CROTCH_TOUCH_MARGIN < 0.37 for v in ("front", "back"))


def _arms_pose(left_deg: float, right_deg: float) -> np.ndarray:
    """Pose landmarks (33, 3; a front view: the subject's left on the image right) with each arm's elbow 100 px
    from its shoulder at the given angle below the horizontal."""
    pose = np.full((33, 3), np.nan)
    at = {"left_shoulder": (270.0, 60.0), "right_shoulder": (130.0, 60.0), "left_hip": (250.0, 190.0),
          "right_hip": (150.0, 190.0)}
    for side, sign, deg in (("left", 1.0, left_deg), ("right", -1.0, right_deg)):
        sx, sy = at[f"{side}_shoulder"]
        a = math.radians(deg)
        at[f"{side}_elbow"] = (sx + sign * 100.0 * math.cos(a), sy + 100.0 * math.sin(a))
    for name, xy in at.items():
        pose[seg.POSE_NAMES.index(name)] = (*xy, 1.0)
    return pose


def test_two_views_that_disagree_on_an_arms_angle_are_warned_about():
    """A front view whose left arm reads 63 degrees below the horizontal where the back view reads 49 (the
    bumps subject of round 2 session 32: its front shoulder landmarks lay high) is a warning naming that arm and
    both angles; views within ARM_ANGLE_VIEWS_DISAGREE_DEG of each other, or a view missing, are not."""
    front, back = _arms_pose(63.0, 50.0), _arms_pose(49.0, 47.0)
    assert seg.arm_angle_deg(front[seg.POSE_NAMES.index("left_shoulder"), :2],
                             front[seg.POSE_NAMES.index("left_elbow"), :2],
                             np.array([0.0, 1.0]), np.array([1.0, 0.0])) == pytest.approx(63.0)
    notes = seg.disagreeing_arm_angles({"front": front, "back": back})
    assert list(notes) == ["front"], notes
    assert "left arm's angle reads 63 degrees" in notes["front"] and "49 in the back" in notes["front"], notes
    assert "right arm" not in notes["front"], notes
    assert seg.disagreeing_arm_angles({"front": _arms_pose(46.0, 52.0), "back": _arms_pose(49.0, 54.0)}) == {}
    assert seg.disagreeing_arm_angles({"front": front}) == {}
    hidden = front.copy()
    hidden[seg.POSE_NAMES.index("left_elbow")] = np.nan
    assert seg.disagreeing_arm_angles({"front": hidden, "back": back}) == {}


def test_the_groin_line_from_the_crotch_labels_the_hips_closer_to_the_truth(scans):
    """On the rig's renders (the default body and two cohort subjects, both views) the groin line from the
    crotch at the defaults' lean, unshifted (the pixel-true line learned from the rig's labels; the defaults
    move it up for the volume the registration carries), mislabels far fewer of the true torso's and thighs'
    pixels than the torso polygon alone; only the torso and the thighs trade pixels; moving the line up gives
    the thighs more pixels. Segmented without depth, the torso polygon stands."""
    thighs = [seg.SEGMENT_IDS["thigh_l"], seg.SEGMENT_IDS["thigh_r"]]
    torso = seg.SEGMENT_IDS["torso"]
    wrong = {"rule": 0, "line": 0}
    for (_, view), (folder, colour_only, truth) in scans.items():
        if view == "front":
            with_depth = seg.segment_capture(folder, write=False)  # the crotch is found in the depth's mask
        s = with_depth[view]
        # colour only: MediaPipe's mask closes the gap's top, and no groin line is drawn
        lm = colour_only.landmarks[:, :2]
        hands = [lm[29:50] if colour_only.hands_found[0] else None, lm[50:71] if colour_only.hands_found[1] else None]
        polygon = seg.label_pixels(colour_only.mask, colour_only.pose, hands,
                                   dataclasses.replace(seg.DEFAULT_PARAMS[view], groin_angle=None))
        assert (colour_only.labels == polygon).all()
        prm = dataclasses.replace(seg.DEFAULT_PARAMS[view], groin_offset=0.0)
        assert prm.groin_angle is not None
        rule, line = _cut_against_rule(s, truth, prm, {"groin_angle": None}, [torso, *thighs], wrong)
        no_crotch = seg.label_pixels(s.mask, s.pose, [None, None], prm, crotch=np.full(2, np.nan))
        assert (no_crotch == rule).all()  # a NaN crotch: no groin line, the torso polygon
        higher = seg.label_pixels(s.mask, s.pose, [None, None],
                                  dataclasses.replace(prm, groin_offset=prm.groin_offset + 0.05))
        assert np.isin(higher, thighs).sum() > np.isin(line, thighs).sum()
    assert wrong["line"] < 0.6 * wrong["rule"], wrong
