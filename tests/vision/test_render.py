"""Rendering: depth and silhouettes against geometry computed by hand; fast path vs reference."""

import numpy as np
import pytest

from sann.vision.camera import Camera, default_camera, look_at, make_pose, rotation_to
from sann.vision.piles import Box
from sann.vision.render import CUP_LID_RGB, add_sensor_noise, render, render_cup


def _lid_towards_camera(distance: float) -> np.ndarray:
    return make_pose(rotation_to([0, 0, -1]), [0, 0, distance])


def test_single_cup_depth_and_silhouette():
    res = render_cup(_lid_towards_camera(600.0))
    assert res.depth_mm.dtype == np.uint16 and res.rgb.dtype == np.uint8
    assert res.instance.dtype == np.int16
    # The principal ray hits the lid's recess (z = 55 in the cup frame): depth 600 - 55.
    assert res.depth_mm[244, 316] == 545
    # The widest ring (r = 43.5) is nearest at cup z = 46, i.e. depth 554.
    half_width = 550 * 43.5 / 554
    row = np.flatnonzero(res.mask[244])
    assert abs(len(row) - 2 * half_width) <= 2
    assert abs(row.mean() - 316) <= 1
    col = np.flatnonzero(res.mask[:, 316])
    assert abs(len(col) - 2 * 540 * 43.5 / 554) <= 2
    # Outside the cup: nothing.
    assert (res.depth_mm[~res.mask] == 0).all() and (res.rgb[~res.mask] == 0).all()
    assert (res.depth_mm[res.mask] > 0).all()


def test_lid_is_brown_and_body_is_white():
    top = render_cup(_lid_towards_camera(600.0))
    bottom = render_cup(make_pose(np.eye(3), [0, 0, 600.0]))
    lid = top.rgb[244, 316].astype(float)
    assert np.allclose(lid / np.linalg.norm(lid), CUP_LID_RGB / np.linalg.norm(CUP_LID_RGB),
                       atol=0.02)
    white = bottom.rgb[244, 316]
    assert white.min() > 150 and bottom.depth_mm[244, 316] == 540


def test_world_frame_pose_and_occlusion():
    cam = Camera(pose=look_at([0, 0, 700], [0, 0, 0]))
    near = make_pose(np.eye(3), [0, 0, 300])
    far = make_pose(np.eye(3), [60, 0, 60])  # partly hidden by the near cup
    res = render(np.stack([far, near]), cam, box=Box())
    assert res.instance[244, 316] == 1
    assert res.depth_mm[244, 316] == 700 - 355  # the near cup's lid recess (cup z = 55)
    alone = render_cup(far, cam, frame="world")
    assert alone.mask.sum() > (res.instance == 0).sum() > 0


def test_fast_path_matches_the_exhaustive_trace():
    cam = default_camera()
    rng = np.random.default_rng(3)
    poses = [make_pose(rotation_to(rng.normal(size=3), rng.uniform(0, 6)),
                       [rng.uniform(-100, 100), rng.uniform(-80, 80), rng.uniform(45, 150)])
             for _ in range(6)]
    fast = render(np.stack(poses), cam, box=Box())
    slow = render(np.stack(poses), cam, box=Box(), exhaustive=True)
    assert np.array_equal(fast.instance, slow.instance)
    assert np.array_equal(fast.depth_mm, slow.depth_mm)
    diff = np.abs(fast.rgb.astype(int) - slow.rgb).max(axis=-1)
    assert diff[fast.mask].max() <= 1
    # Rays exactly on a box edge may pick either face (a tie broken by the BVH): a few pixels.
    assert np.count_nonzero(diff > 1) <= 10
    # The box and the table fill the rest of the frame within the dataset's depth range.
    assert (fast.depth_mm > 0).all() and fast.depth_mm.max() < 1100


def test_bad_inputs():
    with pytest.raises(ValueError):
        render_cup(make_pose(np.eye(3), [0, 0, -100]))
    with pytest.raises(ValueError):
        render(np.zeros((2, 3, 3)), Camera())
    with pytest.raises(ValueError):
        render_cup(_lid_towards_camera(600), frame="robot")


def test_sensor_noise():
    clean = render_cup(_lid_towards_camera(700.0))
    noisy = add_sensor_noise(clean, seed=5)
    again = add_sensor_noise(clean, seed=5)
    assert np.array_equal(noisy.depth_mm, again.depth_mm) and np.array_equal(noisy.rgb, again.rgb)
    assert np.array_equal(noisy.instance, clean.instance)
    assert (noisy.depth_mm[clean.depth_mm == 0] == 0).all()  # no reading stays no reading
    both = (noisy.depth_mm > 0) & (clean.depth_mm > 0)
    err = noisy.depth_mm[both].astype(float) - clean.depth_mm[both]
    assert 0.3 < err.std() < 2.0 and abs(err.mean()) < 0.2
    lost = (clean.depth_mm > 0) & (noisy.depth_mm == 0)
    assert lost.any()
    # Readings are lost only next to a depth jump (here: the silhouette).
    d = np.pad(clean.depth_mm.astype(int), 1, mode="edge")
    centre = d[1:-1, 1:-1]
    jump = np.max([np.abs(centre - d[:-2, 1:-1]), np.abs(centre - d[2:, 1:-1]),
                   np.abs(centre - d[1:-1, :-2]), np.abs(centre - d[1:-1, 2:])], axis=0)
    assert (jump[lost] > 15).all()
