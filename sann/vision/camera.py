"""The Primesense-like RGB-D camera of the multi-cup task, rigid transforms and projections.

Conventions: lengths in mm; poses are 4x4 homogeneous matrices; ``Camera.pose`` maps camera
coordinates to world coordinates; the camera frame is OpenCV's (x right, y down, z forward),
so a pixel (u, v) with depth z sees the camera-frame point ((u - cx) z / fx, (v - cy) z / fy, z).
The world frame of the scenes has z up, its origin on the top face of the box's floor.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

WIDTH, HEIGHT = 640, 480
K_PRIMESENSE = np.array([[550.0, 0.0, 316.0], [0.0, 540.0, 244.0], [0.0, 0.0, 1.0]])
#: The depth range of the Doumanoglou dataset (mm): the box lies 400-1100 mm from the sensor.
DEPTH_RANGE_MM = (400.0, 1100.0)


def make_pose(rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    """4x4 pose from a 3x3 rotation and a translation (mm)."""
    rotation = np.asarray(rotation, dtype=float)
    translation = np.asarray(translation, dtype=float)
    if rotation.shape != (3, 3) or translation.shape != (3,):
        raise ValueError(f"need a 3x3 rotation and a 3-vector, got {rotation.shape}, "
                         f"{translation.shape}")
    pose = np.eye(4)
    pose[:3, :3] = rotation
    pose[:3, 3] = translation
    return pose


def invert_pose(pose: np.ndarray) -> np.ndarray:
    """Inverse of a rigid 4x4 pose (cheaper and exacter than a general inverse)."""
    r, t = pose[:3, :3], pose[:3, 3]
    return make_pose(r.T, -r.T @ t)


def transform_points(pose: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Apply a 4x4 pose to points of shape (..., 3)."""
    return points @ pose[:3, :3].T + pose[:3, 3]


def axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix of ``angle`` radians about ``axis`` (Rodrigues)."""
    a = np.asarray(axis, dtype=float)
    norm = np.linalg.norm(a)
    if norm == 0:
        raise ValueError("rotation axis must be non-zero")
    x, y, z = a / norm
    k = np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * (k @ k)


def rotation_to(z_axis: np.ndarray, yaw: float = 0.0) -> np.ndarray:
    """A rotation whose third column is ``z_axis``, then turned by ``yaw`` about that axis.

    For the rotationally symmetric cup this is all of its pose's rotation that is observable.
    """
    z = np.asarray(z_axis, dtype=float)
    z = z / np.linalg.norm(z)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    base = np.stack([x, np.cross(z, x), z], axis=1)
    return base @ axis_angle([0, 0, 1], yaw)


def look_at(eye: np.ndarray, target: np.ndarray, up: np.ndarray = (0.0, 0.0, 1.0)) -> np.ndarray:
    """Camera-to-world pose of an OpenCV camera at ``eye`` looking at ``target``.

    Image "up" (-y) is the projection of ``up``; when looking along ``up`` the world +y axis
    is used instead, so a camera straight above the scene has image x along world x.
    """
    eye = np.asarray(eye, dtype=float)
    z = np.asarray(target, dtype=float) - eye
    if np.linalg.norm(z) == 0:
        raise ValueError("eye and target coincide")
    z /= np.linalg.norm(z)
    up = np.asarray(up, dtype=float)
    if np.linalg.norm(np.cross(z, up)) < 1e-6:
        up = np.array([0.0, 1.0, 0.0])
    x = np.cross(z, up)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return make_pose(np.stack([x, y, z], axis=1), eye)


@dataclass(frozen=True)
class Camera:
    """A pinhole camera: intrinsics ``K``, image size, and camera-to-world ``pose``."""

    K: np.ndarray = field(default_factory=lambda: K_PRIMESENSE.copy())
    width: int = WIDTH
    height: int = HEIGHT
    pose: np.ndarray = field(default_factory=lambda: np.eye(4))

    def __post_init__(self) -> None:
        if np.shape(self.K) != (3, 3) or np.shape(self.pose) != (4, 4):
            raise ValueError("K must be 3x3 and pose 4x4")
        if self.width <= 0 or self.height <= 0:
            raise ValueError("image size must be positive")

    @property
    def world_to_camera(self) -> np.ndarray:
        """The extrinsic matrix: world coordinates to camera coordinates."""
        return invert_pose(self.pose)

    @property
    def position(self) -> np.ndarray:
        """The optical centre in world coordinates."""
        return self.pose[:3, 3].copy()

    def project(self, points: np.ndarray, frame: str = "world") -> tuple[np.ndarray, np.ndarray]:
        """Pixel coordinates (..., 2) as floats, and depth z (...) of points (..., 3).

        ``frame`` is ``"world"`` or ``"camera"``.  Points behind the camera get z <= 0 and
        meaningless pixel coordinates; callers filter on z.
        """
        p = self._to_camera(np.asarray(points, dtype=float), frame)
        z = p[..., 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            u = self.K[0, 0] * p[..., 0] / z + self.K[0, 2]
            v = self.K[1, 1] * p[..., 1] / z + self.K[1, 2]
        return np.stack([u, v], axis=-1), z

    def ray_directions(self) -> np.ndarray:
        """Camera-frame ray per pixel centre, (H, W, 3), with z = 1 (so t along it is depth)."""
        return pixel_rays(self.K, self.width, self.height)

    def backproject(self, depth_mm: np.ndarray, frame: str = "camera") -> np.ndarray:
        """Points (H, W, 3) in mm of a depth image; pixels with depth 0 give NaN."""
        return backproject(depth_mm, self.K, self.pose if frame == "world" else None)

    def _to_camera(self, points: np.ndarray, frame: str) -> np.ndarray:
        if frame == "camera":
            return points
        if frame == "world":
            return transform_points(self.world_to_camera, points)
        raise ValueError(f"frame must be 'world' or 'camera', got {frame!r}")


def pixel_rays(K: np.ndarray, width: int, height: int) -> np.ndarray:
    """Camera-frame direction (x/z, y/z, 1) through each pixel's centre, shape (H, W, 3)."""
    u, v = np.meshgrid(np.arange(width, dtype=float), np.arange(height, dtype=float))
    return np.stack(
        [(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1], np.ones_like(u)], axis=-1
    )


def backproject(
    depth_mm: np.ndarray, K: np.ndarray, pose: np.ndarray | None = None
) -> np.ndarray:
    """Points (H, W, 3) of a depth image in the camera frame, or the world frame given the pose.

    Depth 0 means "no reading" (the sensor's convention) and yields NaN points.
    """
    depth = np.asarray(depth_mm)
    if depth.ndim != 2:
        raise ValueError(f"depth must be a 2-D image, got shape {depth.shape}")
    z = depth.astype(float)
    z[depth == 0] = np.nan
    points = pixel_rays(np.asarray(K, dtype=float), depth.shape[1], depth.shape[0]) * z[..., None]
    return points if pose is None else transform_points(pose, points)


def default_camera(distance: float = 700.0, tilt_deg: float = 10.0) -> Camera:
    """The scene camera: above the box's centre, the box floor ``distance`` mm away.

    A small tilt (about the world x axis) keeps the view general, as in the dataset, where
    the sensor looked into the box from above at a slight angle.
    """
    if not DEPTH_RANGE_MM[0] <= distance <= DEPTH_RANGE_MM[1]:
        raise ValueError(f"distance {distance} outside the dataset's range {DEPTH_RANGE_MM}")
    tilt = np.radians(tilt_deg)
    eye = distance * np.array([0.0, -np.sin(tilt), np.cos(tilt)])
    return Camera(pose=look_at(eye, np.zeros(3)))
