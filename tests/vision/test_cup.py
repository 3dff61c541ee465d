"""The cup mesh: dimensions, watertightness, orientation, the analytic normals and distance."""

import numpy as np
import pytest

from sann.vision.cup import (
    CUP_DIAMETER,
    CUP_HEIGHT,
    CUP_PROFILE,
    cup_local_normals,
    cup_mesh,
    face_is_lid,
    signed_distance,
)


def test_dimensions_follow_the_profile():
    mesh = cup_mesh()
    lo, hi = mesh.bounds
    assert hi[2] - lo[2] == pytest.approx(CUP_HEIGHT) == 120.0
    assert lo[2] == pytest.approx(-60.0) and hi[2] == pytest.approx(60.0)
    assert hi[0] - lo[0] == pytest.approx(CUP_DIAMETER) == 87.0
    assert np.allclose((lo + hi)[:2], 0.0)


def test_watertight_and_outward():
    mesh = cup_mesh()
    assert mesh.is_watertight and mesh.is_winding_consistent
    # Positive volume means outward normals; a cone frustum + lid is about 0.46 litre.
    assert 400_000 < mesh.volume < 520_000
    assert mesh.is_volume
    # The outer wall's normals point away from the axis.
    centres = mesh.triangles_center
    wall = mesh.metadata["segment"] == 1
    assert np.all(np.einsum("ni,ni->n", mesh.face_normals[wall, :2], centres[wall, :2]) > 0)


def test_mesh_is_cached_and_resolution_checked():
    assert cup_mesh(48) is cup_mesh(48)
    assert len(cup_mesh(24).faces) == 24 * 2 * (len(CUP_PROFILE) - 2)
    with pytest.raises(ValueError):
        cup_mesh(3)


def test_analytic_normals_agree_with_the_facets():
    mesh = cup_mesh(96)
    analytic = cup_local_normals(mesh.triangles_center, mesh.metadata["segment"])
    assert np.allclose(np.linalg.norm(analytic, axis=1), 1.0)
    assert np.einsum("ni,ni->n", analytic, mesh.face_normals).min() > 0.99


def test_lid_is_the_top_part():
    lid = face_is_lid()
    z = cup_mesh().triangles_center[:, 2]
    assert z[lid].min() > 35.0 and z[~lid].max() < 37.0
    assert 0.2 < lid.mean() < 0.95


def test_signed_distance():
    points = np.array([[0, 0, 0], [50, 0, 44], [0, 0, 58], [0, 0, -61], [0, 29, -59]])
    d = signed_distance(points)
    # Nearest surface of the centre: the conical wall, radius 35.125 at z = 0.
    assert d[0] == pytest.approx(-35.125 * 96 / np.hypot(96, 9))
    assert d[1] == pytest.approx(6.5)
    assert d[2] == pytest.approx(3.0, abs=0.01)  # above the recess (z = 55), below the rim
    assert d[3] == pytest.approx(1.0)
    assert -1.0 < d[4] < 0.0
    # Every mesh vertex lies on the surface.
    assert np.abs(signed_distance(cup_mesh().vertices)).max() < 1e-6
