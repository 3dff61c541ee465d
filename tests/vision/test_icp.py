"""Point-to-plane ICP on the cup: recovery of known transforms, back-projection, bad input."""

import numpy as np
import pytest

from sann.vision.camera import K_PRIMESENSE, axis_angle, make_pose, rotation_to
from sann.vision.cup import cup_mesh
from sann.vision.detect import cup_model_cloud
from sann.vision.icp import backproject, icp_point_to_plane, model_cloud_from_mesh
from sann.vision.render import render_cup

TRUE_R = rotation_to(np.array([0.3, -0.8, 0.5]), 0.3)
TRUE_T = np.array([30.0, 20.0, 600.0])


@pytest.fixture(scope="module")
def scene_points():
    """Depth points of one cup as the camera sees it (front side only)."""
    res = render_cup(make_pose(TRUE_R, TRUE_T))
    return backproject(res.depth_mm, K_PRIMESENSE)


def _axis_error_deg(R):
    return np.degrees(np.arccos(np.clip(R[:, 2] @ TRUE_R[:, 2], -1.0, 1.0)))


@pytest.mark.parametrize(
    ("angle_deg", "shift"), [(3.0, (2.0, -1.0, 3.0)), (10.0, (6.0, -5.0, 8.0))]
)
def test_icp_recovers_a_known_small_transform(scene_points, angle_deg, shift):
    R0 = axis_angle([1.0, 0.5, 0.0], np.radians(angle_deg)) @ TRUE_R
    res = icp_point_to_plane(cup_model_cloud(), scene_points, R0, TRUE_T + np.array(shift))
    assert np.linalg.norm(res.translation - TRUE_T) < 1.0
    assert _axis_error_deg(res.rotation) < 1.0
    assert res.inlier_fraction > 0.95
    assert np.allclose(res.rotation @ res.rotation.T, np.eye(3), atol=1e-9)


def test_icp_without_scene_points_returns_the_start_pose():
    res = icp_point_to_plane(cup_model_cloud(), np.zeros((0, 3)), TRUE_R, TRUE_T)
    assert res.n_inliers == 0 and np.array_equal(res.translation, TRUE_T)


def test_model_cloud_samples_lie_on_the_cup_with_outward_normals():
    mesh = cup_mesh()
    cloud = model_cloud_from_mesh(np.asarray(mesh.vertices), np.asarray(mesh.faces), 2000, 3)
    assert cloud.points.shape == (2000, 3) and cloud.normals.shape == (2000, 3)
    assert np.allclose(np.linalg.norm(cloud.normals, axis=1), 1.0)
    assert np.all(np.abs(cloud.points[:, 2]) <= 60.0 + 1e-9)
    # Outward: stepping along the normal leaves the (star-shaped) cup, away from its centre.
    moved = cloud.points + 2.0 * cloud.normals
    assert np.mean(np.linalg.norm(moved, axis=1) > np.linalg.norm(cloud.points, axis=1)) > 0.95
    # The grid lookup agrees with the exact nearest sample up to half a cell diagonal.
    q = cloud.points[:200] + np.random.default_rng(0).normal(0.0, 3.0, (200, 3))
    d_grid, _ = cloud.nearest(q, np.inf)
    d_tree, _ = cloud.tree.query(q)
    assert np.all(d_grid - d_tree <= np.sqrt(3.0) * cloud.grid_step + 1e-9)


def test_backproject_round_trips_pixels():
    depth = np.zeros((480, 640), dtype=np.uint16)
    depth[100, 200] = 700
    depth[300, 500] = 1000
    pts = backproject(depth, K_PRIMESENSE)
    uv = pts[:, :2] / pts[:, 2:] * np.diag(K_PRIMESENSE)[:2] + K_PRIMESENSE[:2, 2]
    assert np.allclose(sorted(map(tuple, np.rint(uv))), [(200, 100), (500, 300)])
    assert len(backproject(depth, K_PRIMESENSE, mask=np.zeros_like(depth, bool))) == 0


def test_bad_input_is_rejected():
    with pytest.raises(ValueError):
        icp_point_to_plane(cup_model_cloud(), np.zeros((5, 2)), TRUE_R, TRUE_T)
    with pytest.raises(ValueError):
        backproject(np.zeros(10), K_PRIMESENSE)
    with pytest.raises(ValueError):
        model_cloud_from_mesh(np.zeros((3, 2)), np.zeros((1, 3), int))
