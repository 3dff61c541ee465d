"""The takeaway coffee cup of the multi-cup task, as a triangle mesh revolved from a profile.

The profile (SPEC §6) was measured from a rendering of the Doumanoglou cup: pairs (r, z) in mm,
origin at the cup's centre, the axis along +z, the open end of the cup (under the lid) at the
top.  SPEC §6 also states "diameter 137 mm", but the profile's largest radius is 43.5 mm, i.e. a
diameter of 87 mm, which is also what a takeaway cup of 120 mm height looks like; the profile is
the measured object, so it wins and ``CUP_DIAMETER`` is 87 mm.

Besides the watertight mesh, each face carries the index of the profile segment it was swept
from.  The renderer uses it to compute exact smooth normals (smooth around the axis, sharp
across the profile's creases) and to colour the lid differently from the body.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import trimesh

#: (r, z) in mm, from the bottom centre, outwards, up the wall, over the lid, to the lid centre.
CUP_PROFILE: np.ndarray = np.array(
    [
        (0.0, -60.0), (29.5, -60.0), (38.5, 36.0), (40.5, 39.0), (43.5, 42.5), (43.5, 46.0),
        (41.0, 48.5), (39.5, 50.0), (39.5, 58.0), (37.0, 60.0), (31.0, 60.0), (29.0, 56.0),
        (0.0, 55.0),
    ]
)
CUP_HEIGHT: float = 120.0
CUP_RADIUS: float = 43.5
CUP_DIAMETER: float = 2.0 * CUP_RADIUS
CUP_BOTTOM_RADIUS: float = 29.5
#: Profile segments whose lower end lies at or above this height belong to the lid.
LID_START_Z: float = 36.0
MIN_SEGMENTS = 8


def profile_normals() -> np.ndarray:
    """Outward unit normal (n_r, n_z) of each profile segment, shape (len(CUP_PROFILE)-1, 2).

    The profile runs counter-clockwise in the (r, z) half-plane, so the outward normal is the
    segment direction turned clockwise.
    """
    d = np.diff(CUP_PROFILE, axis=0)
    n = np.stack([d[:, 1], -d[:, 0]], axis=1)
    return n / np.linalg.norm(n, axis=1, keepdims=True)


_PROFILE_NORMALS = profile_normals()


def lid_segments() -> np.ndarray:
    """Boolean per profile segment: True for the lid."""
    return CUP_PROFILE[:-1, 1] >= LID_START_Z


@lru_cache(maxsize=8)
def _revolve(segments: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices, faces and per-face profile segment index of the revolved profile."""
    if segments < MIN_SEGMENTS:
        raise ValueError(f"segments must be >= {MIN_SEGMENTS}, got {segments}")
    rings = CUP_PROFILE[1:-1]  # off-axis points, each swept into a ring
    n_rings = len(rings)
    phi = np.arange(segments) * (2.0 * np.pi / segments)
    ring_xyz = np.stack(
        [
            np.outer(rings[:, 0], np.cos(phi)),
            np.outer(rings[:, 0], np.sin(phi)),
            np.repeat(rings[:, 1:2], segments, axis=1),
        ],
        axis=-1,
    ).reshape(-1, 3)
    bottom, top = n_rings * segments, n_rings * segments + 1
    poles = [[0.0, 0.0, CUP_PROFILE[0, 1]], [0.0, 0.0, CUP_PROFILE[-1, 1]]]
    vertices = np.vstack([ring_xyz, poles])

    j = np.arange(segments)
    jn = (j + 1) % segments
    faces = [np.stack([np.full(segments, bottom), jn, j], axis=1)]
    seg_ids = [np.zeros(segments, dtype=np.int32)]
    for k in range(n_rings - 1):
        a, b = k * segments, (k + 1) * segments
        faces.append(np.stack([a + j, a + jn, b + jn], axis=1))
        faces.append(np.stack([a + j, b + jn, b + j], axis=1))
        seg_ids.append(np.full(2 * segments, k + 1, dtype=np.int32))
    last = (n_rings - 1) * segments
    faces.append(np.stack([last + j, last + jn, np.full(segments, top)], axis=1))
    seg_ids.append(np.full(segments, n_rings, dtype=np.int32))
    return vertices, np.vstack(faces).astype(np.int64), np.concatenate(seg_ids)


@lru_cache(maxsize=8)
def cup_mesh(segments: int = 48) -> trimesh.Trimesh:
    """The cup as a watertight trimesh with outward normals (cached; do not modify in place).

    ``mesh.metadata["segment"]`` holds, per face, the index of the profile segment it came from.
    """
    vertices, faces, seg = _revolve(segments)
    mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
    mesh.metadata["segment"] = seg
    mesh.metadata["segments"] = segments
    return mesh


def face_is_lid(segments: int = 48) -> np.ndarray:
    """Boolean per face of ``cup_mesh(segments)``: True where the face belongs to the lid."""
    return lid_segments()[_revolve(segments)[2]]


def cup_local_normals(points: np.ndarray, segment: np.ndarray) -> np.ndarray:
    """Exact smooth surface normals at cup-frame points lying on the given profile segments.

    The surface of revolution has normal (n_r cos φ, n_r sin φ, n_z) with φ the azimuth of the
    point; using it instead of the faceted normal removes the 48 intensity steps around the
    cup, which would otherwise show up as spurious colour gradients for LineMod.
    """
    n_rz = _PROFILE_NORMALS[segment].astype(points.dtype)
    r = np.hypot(points[..., 0], points[..., 1])
    scale = n_rz[..., 0] / np.maximum(r, 1e-9)  # on the axis only flat faces exist (n_r = 0)
    return np.stack([points[..., 0] * scale, points[..., 1] * scale, n_rz[..., 1]], -1)


def _segment_distance(points_rz: np.ndarray) -> np.ndarray:
    """Distance of (r, z) points (N, 2) to the profile (the axis edge is not a surface)."""
    a, b = CUP_PROFILE[:-1], CUP_PROFILE[1:]
    ab = b - a
    ap = points_rz[:, None, :] - a[None]
    s = np.clip(np.einsum("nki,ki->nk", ap, ab) / np.einsum("ki,ki->k", ab, ab), 0.0, 1.0)
    closest = a[None] + s[..., None] * ab[None]
    return np.linalg.norm(points_rz[:, None, :] - closest, axis=-1).min(axis=1)


def _inside_profile(points_rz: np.ndarray) -> np.ndarray:
    """Even-odd test of (r, z) points against the profile closed along the axis."""
    poly = np.vstack([CUP_PROFILE, CUP_PROFILE[:1]])
    a, b = poly[:-1], poly[1:]
    r, z = points_rz[:, 0:1], points_rz[:, 1:2]
    crosses = (a[None, :, 1] > z) != (b[None, :, 1] > z)
    with np.errstate(divide="ignore", invalid="ignore"):
        r_at = a[None, :, 0] + (z - a[None, :, 1]) * (b[None, :, 0] - a[None, :, 0]) / (
            b[None, :, 1] - a[None, :, 1])
    return (np.count_nonzero(crosses & (r < r_at), axis=1) % 2) == 1


def signed_distance(points: np.ndarray) -> np.ndarray:
    """Signed distance (mm, negative inside) of cup-frame points (N, 3) to the true cup surface.

    Exact for the surface of revolution: the nearest surface point of a point lies in its
    meridian plane, so the 3-D distance is the 2-D distance to the profile polygon.
    """
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    rz = np.stack([np.hypot(p[:, 0], p[:, 1]), p[:, 2]], axis=1)
    d = _segment_distance(rz)
    return np.where(_inside_profile(rz), -d, d)
