"""Headless CPU rendering of cup scenes by embree ray casting (one ray per pixel).

Everything is built in the camera frame, with rays (x/z, y/z, 1) from the optical centre, so
the hit distance along a ray is directly the depth z.  Cups are shaded with the exact normal
of the surface of revolution (smooth around the axis, sharp at the profile's creases); the
light is fixed in the camera frame, so templates rendered for pose estimation and scenes see
the cup lit in the same way.  Colours are RGB (OpenCV wants BGR: ``rgb[..., ::-1]``).
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING

import cv2
import numpy as np
from embreex import rtcore_scene
from embreex.mesh_construction import TriangleMesh

from sann.vision.camera import Camera, transform_points
from sann.vision.cup import cup_local_normals, cup_mesh, face_is_lid

if TYPE_CHECKING:
    from sann.vision.piles import Box, Pile

BACKGROUND = -1
CUP_SEGMENTS = 48
#: Albedos (RGB, 0-255): a white paper cup, a brown lid, cardboard, a grey table.
CUP_BODY_RGB = np.array([236.0, 232.0, 222.0])
CUP_LID_RGB = np.array([112.0, 72.0, 44.0])
CARDBOARD_RGB = np.array([196.0, 158.0, 108.0])
TABLE_RGB = np.array([118.0, 118.0, 124.0])
#: Directional light in the camera frame (towards the light): from above-left of the sensor.
LIGHT_DIR = np.array([-0.3, -0.5, -1.0]) / np.linalg.norm([-0.3, -0.5, -1.0])
AMBIENT = 0.3
#: Threads for ray casting (the machine has 2 cores; results do not depend on it).
TRACE_THREADS = max(1, min(2, os.cpu_count() or 1))


@dataclass(frozen=True, eq=False)
class RenderResult:
    """Depth (uint16 mm, 0 = nothing), colour (uint8 RGB) and instance ids (int16, -1 = none).

    Instance ids are indices into the list of cup poses that was rendered; the box and the
    table are background (-1).
    """

    depth_mm: np.ndarray
    rgb: np.ndarray
    instance: np.ndarray

    @property
    def mask(self) -> np.ndarray:
        """Boolean image: True where a cup is seen."""
        return self.instance >= 0


@lru_cache(maxsize=4)
def _rays(K_key: tuple, width: int, height: int) -> np.ndarray:
    K = np.array(K_key).reshape(3, 3)
    u, v = np.meshgrid(np.arange(width, dtype=np.float32), np.arange(height, dtype=np.float32))
    d = np.stack([(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1], np.ones_like(u)], axis=-1)
    return np.ascontiguousarray(d.reshape(-1, 3), dtype=np.float32)


@lru_cache(maxsize=4)
def _cup_arrays(segments: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Cup vertices, faces, per-face profile segment and per-face albedo."""
    mesh = cup_mesh(segments)
    albedo = np.where(face_is_lid(segments)[:, None], CUP_LID_RGB, CUP_BODY_RGB)
    albedo = albedo.astype(np.float32)
    return (np.asarray(mesh.vertices), np.asarray(mesh.faces, dtype=np.int32),
            mesh.metadata["segment"], albedo)


def _as_poses(poses: np.ndarray) -> np.ndarray:
    poses = np.asarray(poses, dtype=float)
    if poses.ndim == 2:
        poses = poses[None]
    if poses.ndim != 3 or poses.shape[1:] != (4, 4):
        raise ValueError(f"cup poses must have shape (N, 4, 4), got {poses.shape}")
    return poses


class _Scene:
    """Triangles in the camera frame: the cups first (cup i owns faces [i F, (i+1) F)), then
    the static background; one embree mesh, so a hit's primitive id identifies everything."""

    def __init__(self, cam_poses: np.ndarray, background: tuple[np.ndarray, ...] | None,
                 segments: int) -> None:
        verts, faces, self.segment, self.cup_albedo = _cup_arrays(segments)
        self.poses = cam_poses
        self.n_cups = len(cam_poses)
        self.faces_per_cup = len(faces)
        nv = len(verts)
        all_v = [transform_points(p, verts) for p in cam_poses]
        all_f = [faces + i * nv for i in range(self.n_cups)]
        self.bg_colour = np.zeros((0, 3), dtype=np.float32)
        if background is not None:
            bg_v, bg_f, bg_albedo = background
            all_f.append(bg_f + self.n_cups * nv)
            all_v.append(bg_v)
            self.bg_colour = _flat_shading(bg_v, bg_f, bg_albedo)
        self.scene = rtcore_scene.EmbreeScene()
        if all_v:
            TriangleMesh(scene=self.scene,
                         vertices=np.ascontiguousarray(np.vstack(all_v), dtype=np.float32),
                         indices=np.ascontiguousarray(np.vstack(all_f), dtype=np.int32))

    def shade(self, rays: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Trace the rays; depth (mm, 0 = miss), rgb (float) and instance per ray."""
        hit = _trace(self.scene, rays)
        prim = hit["primID"]
        depth = np.where(prim >= 0, hit["tfar"], np.float32(0.0))
        rgb = np.zeros((len(rays), 3), dtype=np.float32)
        instance = np.full(len(rays), BACKGROUND, dtype=np.int16)
        n_cup_faces = self.n_cups * self.faces_per_cup
        cup = np.flatnonzero((prim >= 0) & (prim < n_cup_faces))
        bg = np.flatnonzero(prim >= n_cup_faces)
        rgb[bg] = self.bg_colour[prim[bg] - n_cup_faces]
        if cup.size:
            idx = prim[cup] // self.faces_per_cup
            face = prim[cup] % self.faces_per_cup
            instance[cup] = idx
            rgb[cup] = self._shade_cups(rays[cup] * depth[cup, None], idx, face)
        return depth, rgb, instance

    def _shade_cups(self, points: np.ndarray, idx: np.ndarray, face: np.ndarray) -> np.ndarray:
        """Lambertian colour at camera-frame cup surface points (exact smooth normals)."""
        lambert = np.empty(len(points), dtype=np.float32)
        order = np.argsort(idx, kind="stable")
        bounds = np.searchsorted(idx[order], np.arange(self.n_cups + 1))
        for k in range(self.n_cups):
            sel = order[bounds[k]:bounds[k + 1]]
            if sel.size == 0:
                continue
            r = self.poses[k, :3, :3].astype(np.float32)
            t = self.poses[k, :3, 3].astype(np.float32)
            local = (points[sel] - t) @ r
            light_local = r.T @ LIGHT_DIR.astype(np.float32)  # light in the cup's frame
            lambert[sel] = cup_local_normals(local, self.segment[face[sel]]) @ light_local
        # The inside of the cup is never seen (the lid closes it), so normals face the viewer.
        np.clip(lambert, 0.0, 1.0, out=lambert)
        return self.cup_albedo[face] * (AMBIENT + (1.0 - AMBIENT) * lambert)[:, None]


_POOLS: dict[int, ThreadPoolExecutor] = {}


def _pool() -> ThreadPoolExecutor:
    """The tracing threads of this process (a forked worker must not inherit dead ones)."""
    pid = os.getpid()
    if pid not in _POOLS:
        _POOLS.clear()
        _POOLS[pid] = ThreadPoolExecutor(max_workers=TRACE_THREADS)
    return _POOLS[pid]


def _trace(scene: rtcore_scene.EmbreeScene, rays: np.ndarray) -> dict[str, np.ndarray]:
    """Intersect camera-frame rays from the origin; in chunks on threads (embree drops the GIL)."""
    if len(rays) < 4096 or TRACE_THREADS == 1:
        return scene.run(np.zeros_like(rays), rays, output=1)
    chunks = np.array_split(rays, TRACE_THREADS)
    parts = list(_pool().map(lambda r: scene.run(np.zeros_like(r), r, output=1), chunks))
    return {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}


def _flat_shading(vertices: np.ndarray, faces: np.ndarray, albedo: np.ndarray) -> np.ndarray:
    """Per-face colour of planar camera-frame faces, each seen from the camera's side."""
    tri = vertices[faces]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    normal *= np.sign(np.einsum("ni,ni->n", normal, -tri.mean(axis=1)))[:, None]
    lambert = np.clip(normal @ LIGHT_DIR, 0.0, 1.0)
    return (albedo * (AMBIENT + (1.0 - AMBIENT) * lambert)[:, None]).astype(np.float32)


def _pack(depth: np.ndarray, rgb: np.ndarray, instance: np.ndarray, shape: tuple[int, int],
          ) -> RenderResult:
    return RenderResult(
        depth_mm=np.clip(np.rint(depth), 0, 65535).astype(np.uint16).reshape(shape),
        rgb=np.clip(np.rint(rgb), 0, 255).astype(np.uint8).reshape(shape + (3,)),
        instance=instance.reshape(shape),
    )


def _background_in_camera(box: Box | None, camera: Camera, table: bool):
    if box is None and not table:
        return None
    from sann.vision.piles import background_mesh

    verts, faces, albedo = background_mesh(box, table)
    return transform_points(camera.world_to_camera, verts), faces, albedo


_BACKGROUND_CACHE: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}


def _background_image(camera: Camera, box: Box | None, table: bool,
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Flat depth and rgb of the empty scene, cached: the box and the camera rarely change."""
    key = (camera.K.tobytes(), camera.pose.tobytes(), camera.width, camera.height, box, table)
    if key not in _BACKGROUND_CACHE:
        if len(_BACKGROUND_CACHE) >= 8:
            _BACKGROUND_CACHE.pop(next(iter(_BACKGROUND_CACHE)))
        sc = _Scene(np.zeros((0, 4, 4)), _background_in_camera(box, camera, table), CUP_SEGMENTS)
        depth, rgb, _ = sc.shade(_camera_rays(camera))
        _BACKGROUND_CACHE[key] = (depth, rgb)
    return _BACKGROUND_CACHE[key]


def _camera_rays(camera: Camera) -> np.ndarray:
    return _rays(tuple(np.asarray(camera.K, float).ravel()), camera.width, camera.height)


def render(
    scene: Pile | np.ndarray,
    camera: Camera,
    box: Box | None = None,
    table: bool = True,
    segments: int = CUP_SEGMENTS,
    exhaustive: bool = False,
) -> RenderResult:
    """Render cups (a ``Pile``, or world poses of shape (N, 4, 4)) with the box and the table.

    A ``Pile`` brings its own box; for bare poses pass ``box`` (or None for no box).  The empty
    scene is rendered once per camera and box; afterwards only the pixels inside the cups'
    projected outlines are traced (against cups, box and table, so walls occlude).
    ``exhaustive=True`` traces every pixel instead: the slow reference for the fast path.
    """
    poses = getattr(scene, "poses", scene)
    box = getattr(scene, "box", box)
    cam_poses = camera.world_to_camera @ _as_poses(poses)
    bg_depth, bg_rgb = _background_image(camera, box, table)
    depth, rgb = bg_depth.copy(), bg_rgb.copy()
    instance = np.full(camera.width * camera.height, BACKGROUND, dtype=np.int16)
    pixels = _cup_pixels(cam_poses, camera, segments)
    if exhaustive:
        pixels = np.arange(camera.width * camera.height)
    if pixels.size:
        sc = _Scene(cam_poses, _background_in_camera(box, camera, table), segments)
        depth[pixels], rgb[pixels], instance[pixels] = sc.shade(_camera_rays(camera)[pixels])
    return _pack(depth, rgb, instance, (camera.height, camera.width))


def render_cup(
    pose: np.ndarray,
    camera: Camera | None = None,
    frame: str = "camera",
    segments: int = CUP_SEGMENTS,
) -> RenderResult:
    """One cup at ``pose`` against an empty background (depth 0, black, instance -1).

    Meant for template rendering: ``pose`` is cup-to-camera by default (``frame="world"`` for
    a cup-to-world pose and ``camera.pose``).  Only the rays inside the cup's projected
    bounding rectangle are cast, which makes it a few milliseconds per view.
    """
    camera = camera or Camera()
    pose = _as_poses(pose)[0]
    if frame == "world":
        pose = camera.world_to_camera @ pose
    elif frame != "camera":
        raise ValueError(f"frame must be 'camera' or 'world', got {frame!r}")
    h, w = camera.height, camera.width
    depth = np.zeros(h * w, dtype=np.float32)
    rgb = np.zeros((h * w, 3), dtype=np.float32)
    instance = np.full(h * w, BACKGROUND, dtype=np.int16)
    pixels = _cup_pixels(pose[None], camera, segments)
    if pixels.size:
        sc = _Scene(pose[None], None, segments)
        depth[pixels], rgb[pixels], instance[pixels] = sc.shade(_camera_rays(camera)[pixels])
    return _pack(depth, rgb, instance, (h, w))


def _cup_pixels(cam_poses: np.ndarray, camera: Camera, segments: int) -> np.ndarray:
    """Flat indices of the pixels that may see a cup: the convex hulls of the cups' projected
    vertices (the faceted cup lies inside them), grown by a pixel for rounding."""
    inside = np.zeros((camera.height, camera.width), dtype=np.uint8)
    verts = _cup_arrays(segments)[0]
    for pose in cam_poses:
        p = transform_points(pose, verts)
        if np.any(p[:, 2] <= 1.0):
            raise ValueError("every cup must lie entirely in front of the camera")
        uv, _ = camera.project(p, frame="camera")
        lo, hi = uv.min(axis=0), uv.max(axis=0)
        if hi[0] < -2 or hi[1] < -2 or lo[0] > camera.width + 2 or lo[1] > camera.height + 2:
            continue
        hull = cv2.convexHull(np.round(uv * 16).astype(np.int32))
        cv2.fillConvexPoly(inside, hull, 1, lineType=cv2.LINE_8, shift=4)
    inside = cv2.dilate(inside, _KERNEL)
    return np.flatnonzero(inside)


_KERNEL = np.ones((3, 3), dtype=np.uint8)


@dataclass(frozen=True)
class SensorNoise:
    """A Primesense-like sensor's imperfections (off unless asked for).

    Depth noise grows with the square of the distance (Khoshelham & Elberink 2012: sigma about
    1.4 mm at 1 m); readings are missing where the depth jumps (the projector's shadow and
    mixed pixels at object boundaries); colour gets Gaussian noise.
    """

    depth_sigma_at_1m: float = 1.425
    edge_jump_mm: float = 15.0
    edge_dropout: float = 0.5
    rgb_sigma: float = 2.0


def add_sensor_noise(result: RenderResult, seed: int,
                     noise: SensorNoise | None = None) -> RenderResult:
    """A noisy copy of a rendering (instance ids untouched); deterministic for a seed."""
    noise = noise or SensorNoise()
    rng = np.random.default_rng(seed)
    depth = result.depth_mm.astype(np.float64)
    valid = depth > 0
    sigma = noise.depth_sigma_at_1m * (depth / 1000.0) ** 2
    depth = np.where(valid, depth + rng.normal(size=depth.shape) * sigma, 0.0)
    jump = np.zeros_like(valid)
    d = result.depth_mm.astype(np.int32)
    jump[:, 1:] |= np.abs(np.diff(d, axis=1)) > noise.edge_jump_mm
    jump[:, :-1] |= jump[:, 1:].copy()
    rows = np.abs(np.diff(d, axis=0)) > noise.edge_jump_mm
    jump[1:] |= rows
    jump[:-1] |= rows
    depth[jump & (rng.random(depth.shape) < noise.edge_dropout)] = 0.0
    rgb = result.rgb + rng.normal(size=result.rgb.shape) * noise.rgb_sigma
    return RenderResult(
        depth_mm=np.clip(np.rint(depth), 0, 65535).astype(np.uint16),
        rgb=np.clip(np.rint(rgb), 0, 255).astype(np.uint8),
        instance=result.instance.copy(),
    )
