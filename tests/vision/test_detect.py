"""detect_cups end to end, the 10 x 13 pose array, and the evaluation's matching rule."""

import numpy as np
import pytest

from sann.vision.camera import K_PRIMESENSE, axis_angle, default_camera, make_pose
from sann.vision.detect import (
    MAX_DETECTIONS,
    DetectConfig,
    Detection,
    cup_model_cloud,
    depth_agreement,
    detect_cups,
    pose_array,
)
from sann.vision.evaluate import evaluate_frame, match_detections, summarize
from sann.vision.labels import visible_fractions
from sann.vision.linemod import TemplateParams, get_templates
from sann.vision.piles import make_pile
from sann.vision.render import render, render_cup

#: A reduced view sphere (106 templates, one distance) keeps the tests to seconds; it is
#: trained once and then loaded from the cache.
PARAMS = TemplateParams(tilt_step_deg=20.0, distances_mm=(630.0,))
CONFIG = DetectConfig(templates=PARAMS)


@pytest.fixture(scope="module")
def templates():
    return get_templates(PARAMS)


def _axis_error_deg(a, b):
    return float(np.degrees(np.arccos(np.clip(np.dot(a, b), -1.0, 1.0))))


@pytest.mark.parametrize(
    ("tilt", "roll", "position"),
    [(50, 37, (40, -30, 610)), (100, 200, (-60, 25, 632)), (160, 290, (10, 50, 625)),
     (75, 130, (-20, -40, 618))],
)
def test_a_single_cup_is_found_within_5_mm_and_5_degrees(templates, tilt, roll, position):
    R = (axis_angle([0, 0, 1], np.radians(roll)) @ axis_angle([1, 0, 0], np.radians(tilt))
         @ axis_angle([0, 0, 1], 0.4))
    position = np.array(position, dtype=float)
    res = render_cup(make_pose(R, position))
    found = detect_cups(res.rgb, res.depth_mm, K_PRIMESENSE, CONFIG, templates)
    assert len(found) == 1
    assert np.linalg.norm(found[0].position_mm - position) < 5.0
    assert _axis_error_deg(found[0].axis, R[:, 2]) < 5.0
    assert 70.0 < found[0].score <= 100.0


def test_plain_linemod_gives_a_coarse_pose(templates):
    R = axis_angle([1, 0, 0], np.radians(100)) @ axis_angle([0, 0, 1], 1.0)
    position = np.array([25.0, -10.0, 630.0])
    res = render_cup(make_pose(R, position))
    found = detect_cups(res.rgb, res.depth_mm, K_PRIMESENSE, DetectConfig("linemod", PARAMS),
                        templates)
    assert len(found) >= 1
    assert np.linalg.norm(found[0].position_mm - position) < 20.0
    assert _axis_error_deg(found[0].axis, R[:, 2]) < 20.0


def test_an_empty_frame_has_no_cups(templates):
    rgb = np.full((480, 640, 3), 120, np.uint8)
    depth = np.full((480, 640), 700, np.uint16)
    assert detect_cups(rgb, depth, K_PRIMESENSE, CONFIG, templates) == []


def test_the_clearly_visible_cups_of_a_small_pile_are_found(templates):
    cam = default_camera()
    scores = []
    for seed in (0, 2, 3):
        pile = make_pile(4, seed)
        res = render(pile, cam)
        visible = visible_fractions(pile, cam, res) >= 0.9
        true = cam.world_to_camera @ pile.poses
        found = detect_cups(res.rgb, res.depth_mm, K_PRIMESENSE, CONFIG, templates)
        scores.append(evaluate_frame(found, true, visible))
    summary = summarize(scores)
    assert summary["visible_cups"] >= 10
    assert summary["recall"] >= 0.9 and summary["precision"] >= 0.9


def test_depth_agreement_tells_the_right_pose_from_a_turned_one():
    R = axis_angle([1, 0, 0], np.radians(90))
    t = np.array([0.0, 0.0, 620.0])
    depth = render_cup(make_pose(R, t)).depth_mm
    model = cup_model_cloud()
    assert depth_agreement(model, R, t, depth, K_PRIMESENSE) > 0.9
    turned = R @ np.diag([1.0, -1.0, -1.0])  # end over end
    assert depth_agreement(model, turned, t, depth, K_PRIMESENSE) < 0.6
    assert depth_agreement(model, R, t + [150.0, 0, 0], depth, K_PRIMESENSE) < 0.1


def _det(pos, axis, score):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    helper = np.array([1.0, 0, 0]) if abs(axis[0]) < 0.9 else np.array([0, 1.0, 0])
    x = np.cross(helper, axis)
    x /= np.linalg.norm(x)
    return Detection(np.asarray(pos, float), np.stack([x, np.cross(axis, x), axis], 1), score)


def test_pose_array_shape_order_and_zero_padding():
    dets = [_det([1, 2, 600], [0, 0, 1], 90.0), _det([-5, 7, 640], [1, 0, 0], 80.0)]
    arr = pose_array(dets)
    assert arr.shape == (MAX_DETECTIONS, 13)
    assert np.allclose(arr[0, :3], [1, 2, 600]) and arr[0, 12] == 90.0
    assert np.allclose(arr[1, 3:12], dets[1].rotation.reshape(9))
    assert np.allclose(arr[1, 3:12].reshape(3, 3)[:, 2], [1, 0, 0])
    assert np.all(arr[2:] == 0.0)
    assert np.all(pose_array([]) == 0.0)
    with pytest.raises(ValueError):
        pose_array(dets * 6)


def test_matching_uses_15_mm_15_degrees_signed_axes_and_one_claim_per_cup():
    true = np.stack([make_pose(np.eye(3), np.array([0.0, 0.0, 600.0])),
                     make_pose(axis_angle([1, 0, 0], np.pi / 2), np.array([100.0, 0, 600]))])
    tilt = np.sin(np.radians(14.0)), np.cos(np.radians(14.0))
    dets = [
        _det([10, 0, 605], [0, tilt[0], tilt[1]], 90.0),  # 11 mm, 14 degrees: correct
        _det([0, 0, 600], [0, 0, 1], 85.0),  # duplicate of cup 0: wrong
        _det([100, 0, 600], [0, 1, 0], 80.0),  # cup 1 turned end over end: wrong
        _det([300, 0, 600], [0, 0, 1], 99.0),  # nothing there
    ]
    assert match_detections(dets, true).tolist() == [0, -1, -1, -1]
    score = evaluate_frame(dets, true, np.array([True, True]))
    assert (score.n_correct, score.n_found, score.n_visible) == (1, 1, 2)
    assert summarize([score])["precision"] == 0.25 and summarize([score])["recall"] == 0.5
    with pytest.raises(ValueError):
        evaluate_frame(dets, true, np.array([True]))


def test_bad_input_is_rejected(templates):
    rgb = np.zeros((480, 640, 3), np.uint8)
    depth = np.zeros((480, 640), np.uint16)
    with pytest.raises(ValueError):
        detect_cups(rgb, depth, np.eye(4), CONFIG, templates)
    with pytest.raises(ValueError):
        detect_cups(rgb, depth.astype(np.float32), K_PRIMESENSE, CONFIG, templates)
    with pytest.raises(ValueError):
        DetectConfig(method="ppf")
