"""Camera model: intrinsics, projection round trip, poses."""

import numpy as np
import pytest

from sann.vision.camera import (
    K_PRIMESENSE,
    Camera,
    axis_angle,
    backproject,
    default_camera,
    invert_pose,
    look_at,
    make_pose,
    rotation_to,
    transform_points,
)


def test_primesense_intrinsics():
    cam = Camera()
    assert (cam.width, cam.height) == (640, 480)
    assert np.array_equal(cam.K, [[550, 0, 316], [0, 540, 244], [0, 0, 1]])
    uv, z = cam.project(np.array([[0.0, 0.0, 700.0], [70.0, -54.0, 700.0]]), frame="camera")
    assert np.allclose(uv, [[316, 244], [371, 202.3428571]]) and np.allclose(z, 700)


def test_projection_round_trip_through_a_depth_image():
    rng = np.random.default_rng(0)
    cam = default_camera()
    u = rng.integers(0, cam.width, 200)
    v = rng.integers(0, cam.height, 200)
    depth = np.zeros((cam.height, cam.width), dtype=np.uint16)
    depth[v, u] = rng.integers(400, 1100, 200)
    world = cam.backproject(depth, frame="world")
    uv, z = cam.project(world[v, u])
    assert np.allclose(uv, np.stack([u, v], 1), atol=1e-6)
    assert np.allclose(z, depth[v, u])
    assert np.isnan(world[depth == 0]).all()


def test_backproject_camera_frame():
    depth = np.full((480, 640), 1000, dtype=np.uint16)
    pts = backproject(depth, K_PRIMESENSE)
    assert np.allclose(pts[244, 316], [0, 0, 1000])
    assert np.allclose(pts[244, 316 + 55], [100, 0, 1000])
    with pytest.raises(ValueError):
        backproject(np.zeros(5), K_PRIMESENSE)


def test_poses_and_rotations():
    rng = np.random.default_rng(1)
    r = axis_angle(rng.normal(size=3), 0.7)
    assert np.allclose(r @ r.T, np.eye(3)) and np.isclose(np.linalg.det(r), 1)
    pose = make_pose(r, [1.0, 2.0, 3.0])
    p = rng.normal(size=(5, 3))
    assert np.allclose(transform_points(invert_pose(pose), transform_points(pose, p)), p)
    axis = np.array([0.2, -0.5, 0.8])
    q = rotation_to(axis, yaw=1.0)
    assert np.allclose(q[:, 2], axis / np.linalg.norm(axis)) and np.allclose(q @ q.T, np.eye(3))
    with pytest.raises(ValueError):
        make_pose(np.eye(2), [0, 0, 0])


def test_look_at_and_default_camera():
    pose = look_at([0, 0, 800], [0, 0, 0])
    assert np.allclose(pose[:3, 2], [0, 0, -1])  # optical axis straight down
    cam = default_camera(distance=700)
    uv, z = cam.project(np.zeros(3))
    assert np.allclose(uv, [316, 244]) and np.isclose(z, 700)
    # World +y (the far wall) appears towards the top of the image.
    uv2, _ = cam.project(np.array([0.0, 100.0, 0.0]))
    assert uv2[1] < 244
    with pytest.raises(ValueError):
        default_camera(distance=200)
    with pytest.raises(ValueError):
        cam.project(np.zeros(3), frame="robot")
