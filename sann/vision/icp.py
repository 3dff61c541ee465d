"""Point-to-plane ICP refinement of a cup pose on the measured depth points.

LineMod places a template to within a few pixels and one template step of rotation; the
10 x 13 pose array needs millimetres and degrees. Aligning the model surface to the depth points
the camera measured closes that gap. Point-to-plane converges in a handful of iterations on
smooth surfaces such as a cup, and a KD-tree over the model (built once, in the model frame)
keeps every iteration to one vectorised query.

Pose convention everywhere in ``sann.vision``: a model point ``p`` is seen at ``R @ p + t`` in
the camera frame (millimetres).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

__all__ = [
    "IcpResult",
    "ModelCloud",
    "backproject",
    "icp_point_to_plane",
    "model_cloud_from_mesh",
]


@dataclass(frozen=True)
class ModelCloud:
    """Surface samples of a model with outward unit normals, in the model frame.

    Nearest-neighbour queries go through a voxel grid that stores, per cell, the sample nearest
    to the cell's centre: one rounding and one gather per query point instead of a tree walk.
    The answer is the true nearest sample up to half a cell diagonal, which point-to-plane ICP
    does not notice because it measures along the sample's normal.
    """

    points: np.ndarray
    normals: np.ndarray
    tree: cKDTree
    grid_origin: np.ndarray
    grid_step: float
    grid: np.ndarray  # (nx, ny, nz) int32 index of the nearest sample

    def nearest(self, local: np.ndarray, max_distance: float) -> tuple[np.ndarray, np.ndarray]:
        """(distance, index) of the nearest sample per point; inf where beyond the gate/grid."""
        cell = np.floor((local - self.grid_origin) / self.grid_step).astype(np.int64)
        shape = np.array(self.grid.shape)
        inside = np.all((cell >= 0) & (cell < shape), axis=1)
        idx = np.zeros(len(local), dtype=np.int64)
        c = cell[inside]
        idx[inside] = self.grid[c[:, 0], c[:, 1], c[:, 2]]
        dist = np.linalg.norm(local - self.points[idx], axis=1)
        dist[~inside | (dist > max_distance)] = np.inf
        return dist, idx


def _nearest_grid(points: np.ndarray, tree: cKDTree, step: float,
                  margin: float) -> tuple[np.ndarray, np.ndarray]:
    lo = points.min(axis=0) - margin
    n = np.ceil((points.max(axis=0) + margin - lo) / step).astype(int)
    axes = [lo[k] + step * (np.arange(n[k]) + 0.5) for k in range(3)]
    centres = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    _, idx = tree.query(centres)
    return lo, idx.reshape(tuple(n)).astype(np.int32)


@dataclass(frozen=True)
class IcpResult:
    """Refined pose and how well the scene supports it."""

    rotation: np.ndarray
    translation: np.ndarray
    rmse: float
    inlier_fraction: float
    n_inliers: int
    iterations: int


def model_cloud_from_mesh(
    vertices: np.ndarray, faces: np.ndarray, n_points: int = 4000, seed: int = 0,
    grid_step: float = 2.0, grid_margin: float = 25.0,
) -> ModelCloud:
    """Sample ``n_points`` uniformly by area over a triangle mesh.

    Face normals (not vertex normals) are used because the cup profile has sharp creases at the
    lid, where averaged vertex normals would tilt the tangent planes.
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3:
        raise ValueError("expected vertices (n, 3) and triangle faces (m, 3)")
    if n_points < 10:
        raise ValueError(f"n_points must be at least 10, got {n_points}")
    tri = vertices[faces]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = np.linalg.norm(cross, axis=1)
    keep = area > 1e-12
    tri, cross, area = tri[keep], cross[keep], area[keep]
    rng = np.random.default_rng(seed)
    idx = rng.choice(len(tri), size=n_points, p=area / area.sum())
    u, v = rng.random(n_points), rng.random(n_points)
    flip = u + v > 1.0
    u[flip], v[flip] = 1.0 - u[flip], 1.0 - v[flip]
    t = tri[idx]
    points = t[:, 0] + u[:, None] * (t[:, 1] - t[:, 0]) + v[:, None] * (t[:, 2] - t[:, 0])
    normals = cross[idx] / area[idx, None]
    tree = cKDTree(points)
    origin, grid = _nearest_grid(points, tree, grid_step, grid_margin)
    return ModelCloud(points, normals, tree, origin, grid_step, grid)


def backproject(depth_mm: np.ndarray, K: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
    """Camera-frame points (mm) of the valid (non-zero) depth pixels, optionally masked."""
    depth = np.asarray(depth_mm)
    if depth.ndim != 2:
        raise ValueError(f"depth must be a 2-D image, got shape {depth.shape}")
    valid = depth > 0
    if mask is not None:
        valid &= np.asarray(mask, dtype=bool)
    v, u = np.nonzero(valid)
    z = depth[v, u].astype(np.float64)
    K = np.asarray(K, dtype=np.float64)
    x = (u - K[0, 2]) * z / K[0, 0]
    y = (v - K[1, 2]) * z / K[1, 1]
    return np.stack([x, y, z], axis=1)


def _skew_exp(omega: np.ndarray) -> np.ndarray:
    """Rotation matrix of the axis-angle vector ``omega`` (Rodrigues)."""
    angle = float(np.linalg.norm(omega))
    if angle < 1e-12:
        return np.eye(3)
    k = omega / angle
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(angle) * kx + (1.0 - np.cos(angle)) * (kx @ kx)


def _step(
    model: ModelCloud, scene: np.ndarray, R: np.ndarray, t: np.ndarray, max_distance: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """One linearised point-to-plane update; returns (R, t, inlier mask, rmse)."""
    local = (scene - t) @ R
    dist, idx = model.nearest(local, max_distance)
    inl = np.isfinite(dist)
    if inl.sum() < 6:
        return R, t, inl, float("inf")
    # Linearise about the cup's centre, not the camera's: rotations about a point 600 mm away
    # would be nearly indistinguishable from translations and the system ill-conditioned.
    m = model.points[idx[inl]] @ R.T
    n = model.normals[idx[inl]] @ R.T
    s = scene[inl] - t
    a = np.empty((len(m), 6))
    a[:, 0] = m[:, 1] * n[:, 2] - m[:, 2] * n[:, 1]  # m x n, without np.cross's overhead
    a[:, 1] = m[:, 2] * n[:, 0] - m[:, 0] * n[:, 2]
    a[:, 2] = m[:, 0] * n[:, 1] - m[:, 1] * n[:, 0]
    a[:, 3:] = n
    b = np.einsum("ij,ij->i", s - m, n)
    # The cup is symmetric about its axis: that spin is unconstrained, so a small ridge keeps
    # the normal equations well posed instead of letting it wander.
    ata = a.T @ a
    ata += 1e-6 * np.diag(np.repeat([np.trace(ata[:3, :3]), np.trace(ata[3:, 3:])], 3))
    x = np.linalg.solve(ata, a.T @ b)
    dR = _skew_exp(x[:3])
    rmse = float(np.sqrt(np.mean(dist[inl] ** 2)))
    return dR @ R, t + x[3:], inl, rmse


def icp_point_to_plane(
    model: ModelCloud,
    scene_points: np.ndarray,
    rotation: np.ndarray,
    translation: np.ndarray,
    iterations: int = 20,
    max_distance: float = 20.0,
    min_distance: float = 5.0,
    tolerance: float = 0.02,
) -> IcpResult:
    """Refine ``(rotation, translation)`` so the model surface meets ``scene_points``.

    Correspondences farther than the current gate are ignored; the gate shrinks geometrically
    from ``max_distance`` to ``min_distance`` so that neighbouring cups in a pile, touching this
    one, stop pulling once the pose is close.
    """
    scene = np.asarray(scene_points, dtype=np.float64)
    if scene.ndim != 2 or scene.shape[1] != 3:
        raise ValueError(f"scene_points must be (n, 3), got {scene.shape}")
    R = np.asarray(rotation, dtype=np.float64).copy()
    t = np.asarray(translation, dtype=np.float64).reshape(3).copy()
    if len(scene) == 0:
        return IcpResult(R, t, float("inf"), 0.0, 0, 0)
    decay = (min_distance / max_distance) ** (1.0 / max(iterations // 2, 1))
    gate = max_distance
    done = 0
    while done < iterations:
        done += 1
        R_new, t_new, _, _ = _step(model, scene, R, t, gate)
        # The spin about the cup's axis is unobservable: judge convergence by centre and axis.
        moved = np.linalg.norm(t_new - t) + 100.0 * np.linalg.norm(R_new[:, 2] - R[:, 2])
        R, t = R_new, t_new
        gate = max(min_distance, gate * decay)
        if moved < tolerance and gate <= min_distance:
            break
    local = (scene - t) @ R
    dist, _ = model.nearest(local, min_distance)
    inl = np.isfinite(dist)
    rmse = float(np.sqrt(np.mean(dist[inl] ** 2))) if inl.any() else float("inf")
    u, _, vt = np.linalg.svd(R)
    R = u @ vt
    return IcpResult(R, t, rmse, float(inl.mean()), int(inl.sum()), done)
