"""LineMod templates of the cup: a view sphere rendered, trained in ``cv2.linemod``, cached.

What ``cv2.linemod`` offers from Python (OpenCV 4.12, checked by hand and in the tests):
``addTemplate([rgb, depth], class_id, mask)`` returns the template id and its bounding box;
``getTemplates(class_id, id)`` returns the four (level x modality) templates with their
features ``(x, y, label)``; ``match(sources, threshold, class_ids)`` returns the matches *and*
the quantised orientation images it used, which is what Patch-LineMod needs; ``writeClasses``/
``readClasses`` round-trip the templates through YAML files. The detector itself cannot be
pickled and the bounding boxes are not in the YAML, so a cache file holds the YAML text together
with the metadata this module needs (view rotation, distance, bounding box, depth offsets,
patch labels) in one ``.npz``, written atomically.

The cup is rotationally symmetric, so a view is fixed by where its axis points: a tilt away
from the optical axis and an in-plane rotation, with the in-plane step shrunk by sin(tilt) so
the axis directions cover the sphere evenly, at a few distances.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import tempfile
from dataclasses import asdict, dataclass, field
from functools import cached_property
from pathlib import Path

import cv2
import numpy as np

from sann.vision.camera import Camera, axis_angle, make_pose
from sann.vision.cup import cup_mesh
from sann.vision.patch_linemod import Clustering, cluster_features
from sann.vision.render import render_cup

__all__ = [
    "CLASS_ID",
    "Matches",
    "TemplateParams",
    "TemplateSet",
    "cache_dir",
    "get_templates",
    "template_key",
    "load_templates",
    "match_templates",
    "save_templates",
    "template_views",
    "train_templates",
]

CLASS_ID = "cup"
#: LineMod's T at pyramid level 0 (``getDefaultLINEMOD``); matches are reported T//2 pixels
#: right of and below the top-left corner at which their features were actually evaluated.
T_LEVEL0 = 5
MATCH_OFFSET = T_LEVEL0 // 2 + (T_LEVEL0 % 2 - 1)
CACHE_VERSION = 1


@dataclass(frozen=True)
class TemplateParams:
    """What defines a template set; the cache key is derived from all of it."""

    tilt_step_deg: float = 15.0
    distances_mm: tuple[float, ...] = (520.0, 600.0, 690.0)
    n_patches: int = 6
    clustering: Clustering = "kmeans"
    seed: int = 0

    def __post_init__(self) -> None:
        if not 1.0 <= self.tilt_step_deg <= 90.0:
            raise ValueError(f"tilt_step_deg must be in [1, 90], got {self.tilt_step_deg}")
        if not self.distances_mm or min(self.distances_mm) <= 200.0:
            raise ValueError("distances_mm must be a non-empty tuple of distances above 200 mm")
        if self.n_patches < 3:
            raise ValueError(f"n_patches must be at least 3 (the rule needs 3), got "
                             f"{self.n_patches}")


@dataclass
class TemplateSet:
    """A trained ``cv2.linemod`` detector plus, per template id, what the pose needs."""

    params: TemplateParams
    detector: cv2.linemod.Detector
    rotations: np.ndarray  # (N, 3, 3) cup-to-camera rotation of the view
    distances: np.ndarray  # (N,) depth of the cup centre when rendered (mm)
    origins: np.ndarray  # (N, 2) top-left of the template in its rendering (px)
    sizes: np.ndarray  # (N, 2) width, height of the template (px)
    color_features: list[np.ndarray]  # per template (n, 3): x, y, orientation label
    depth_features: list[np.ndarray]
    depth_offsets: list[np.ndarray]  # per depth feature: centre depth - surface depth (mm)
    color_patches: list[np.ndarray]  # per feature patch label
    depth_patches: list[np.ndarray]
    key: str = field(default="")

    def __len__(self) -> int:
        return len(self.rotations)

    @cached_property
    def stacked(self) -> dict[str, np.ndarray]:
        """The ragged per-template arrays padded into (N, F, ...) arrays for vectorised use.

        Features and patch labels are padded with -1 (label -1 never responds, patch -1
        belongs to no patch), depth offsets with NaN.
        """
        return {
            "color": _padded(self.color_features, -1),
            "depth": _padded(self.depth_features, -1),
            "offsets": _padded([o.astype(np.float64) for o in self.depth_offsets], np.nan),
            "color_patches": _padded(self.color_patches, -1),
            "depth_patches": _padded(self.depth_patches, -1),
        }


def _padded(arrays: list[np.ndarray], fill: float) -> np.ndarray:
    width = max(len(a) for a in arrays)
    out = np.full((len(arrays), width) + arrays[0].shape[1:], fill, dtype=arrays[0].dtype)
    for i, a in enumerate(arrays):
        out[i, : len(a)] = a
    return out


@dataclass(frozen=True)
class Matches:
    """``cv2.linemod`` matches as arrays, plus the quantised images the matcher used."""

    x: np.ndarray  # evaluated top-left corner of the template (px)
    y: np.ndarray
    similarity: np.ndarray
    template_id: np.ndarray
    quantized: tuple[np.ndarray, ...]

    def __len__(self) -> int:
        return len(self.x)


def template_views(tilt_step_deg: float) -> np.ndarray:
    """Cup-to-camera rotations covering all axis directions, about ``tilt_step_deg`` apart.

    Tilt 0 shows the bottom, 180 the lid; in-plane rotation turns the axis around the optical
    axis. The spin about the cup's own axis is invisible and left at zero.
    """
    rotations = []
    n_tilts = int(round(180.0 / tilt_step_deg))
    for tilt in np.linspace(0.0, np.pi, n_tilts + 1):
        n_roll = max(1, int(round(360.0 * np.sin(tilt) / tilt_step_deg)))
        for roll in np.arange(n_roll) * (2.0 * np.pi / n_roll):
            rotations.append(axis_angle([0, 0, 1], roll) @ axis_angle([1, 0, 0], tilt))
    return np.array(rotations)


def _render_view(rotation: np.ndarray, distance: float, camera: Camera) -> tuple[np.ndarray, ...]:
    res = render_cup(make_pose(rotation, np.array([0.0, 0.0, distance])), camera)
    mask = (res.instance >= 0).astype(np.uint8) * 255
    return res.rgb, res.depth_mm, mask


def _features(detector: cv2.linemod.Detector, template_id: int) -> tuple[np.ndarray, np.ndarray]:
    level0 = detector.getTemplates(CLASS_ID, template_id)[:2]
    return tuple(
        np.array([(f.x, f.y, f.label) for f in t.features], dtype=np.int32).reshape(-1, 3)
        for t in level0
    )


def _depth_offsets(feats: np.ndarray, origin: np.ndarray, depth: np.ndarray,
                   distance: float) -> np.ndarray:
    """Centre depth minus the rendered surface depth under each depth feature."""
    z = depth[feats[:, 1] + origin[1], feats[:, 0] + origin[0]].astype(np.float64)
    return np.where(z > 0, distance - z, np.nan)


def train_templates(params: TemplateParams = TemplateParams(),
                    camera: Camera | None = None) -> TemplateSet:
    """Render every view at every distance and train a fresh ``cv2.linemod`` detector.

    Views that LineMod rejects (too few features) are skipped; ids stay contiguous.
    """
    camera = camera or Camera()
    detector = cv2.linemod.getDefaultLINEMOD()
    rots, dists, origins, sizes, offsets = [], [], [], [], []
    for distance in params.distances_mm:
        for rotation in template_views(params.tilt_step_deg):
            rgb, depth, mask = _render_view(rotation, distance, camera)
            tid, bbox = detector.addTemplate([rgb, depth], CLASS_ID, mask)
            if tid < 0:
                continue
            origin = np.array(bbox[:2])
            _, dfeat = _features(detector, tid)
            rots.append(rotation)
            dists.append(distance)
            origins.append(origin)
            sizes.append(bbox[2:])
            offsets.append(_depth_offsets(dfeat, origin, depth, distance))
    if not rots:
        raise RuntimeError("LineMod accepted none of the rendered views")
    return _assemble(params, detector, np.array(rots), np.array(dists), np.array(origins),
                     np.array(sizes), offsets, template_key(params, camera))


def _assemble(params: TemplateParams, detector: cv2.linemod.Detector, rots: np.ndarray,
              dists: np.ndarray, origins: np.ndarray, sizes: np.ndarray,
              offsets: list[np.ndarray], key: str) -> TemplateSet:
    feats = [_features(detector, i) for i in range(len(rots))]
    cfeat, dfeat = [f[0] for f in feats], [f[1] for f in feats]
    patches = tuple(
        [cluster_features(f, params.n_patches, params.clustering, params.seed) for f in fs]
        for fs in (cfeat, dfeat)
    )
    return TemplateSet(params, detector, rots, dists, origins.astype(np.int32),
                       sizes.astype(np.int32), cfeat, dfeat, offsets, patches[0], patches[1],
                       key=key)


def _mesh_hash() -> str:
    mesh = cup_mesh()
    h = hashlib.sha256(np.ascontiguousarray(mesh.vertices, dtype=np.float64).tobytes())
    h.update(np.ascontiguousarray(mesh.faces, dtype=np.int64).tobytes())
    return h.hexdigest()[:16]


def _shading() -> list[float]:
    """The renderer's albedos and light: templates must be re-made when the look changes."""
    from sann.vision import render

    parts = (render.CUP_BODY_RGB, render.CUP_LID_RGB, render.LIGHT_DIR, [render.AMBIENT],
             [render.CUP_SEGMENTS])
    return [round(float(v), 6) for part in parts for v in np.ravel(part)]


def template_key(params: TemplateParams, camera: Camera | None = None) -> str:
    """Cache key: the parameters, the mesh, the shading, the camera and the OpenCV version."""
    camera = camera or Camera()
    blob = json.dumps(
        {"params": asdict(params), "mesh": _mesh_hash(), "K": np.asarray(camera.K).tolist(),
         "size": [camera.width, camera.height], "cv2": cv2.__version__,
         "shading": _shading(), "version": CACHE_VERSION},
        sort_keys=True,
    )
    return hashlib.sha256(blob.encode()).hexdigest()[:20]


def cache_dir() -> Path:
    """``$SANN_CACHE`` or ``.sann-cache/`` at the repository root."""
    env = os.environ.get("SANN_CACHE")
    return Path(env) if env else Path(__file__).resolve().parents[2] / ".sann-cache"


def _ragged(arrays: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    lengths = np.array([len(a) for a in arrays], dtype=np.int64)
    return np.concatenate(arrays, axis=0), lengths


def _unragged(flat: np.ndarray, lengths: np.ndarray) -> list[np.ndarray]:
    return list(np.split(flat, np.cumsum(lengths)[:-1]))


def save_templates(templates: TemplateSet, path: Path) -> None:
    """Write the template set to ``path`` (``.npz``) atomically: temp file, then rename."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        templates.detector.writeClasses(str(Path(tmp) / "%s.yml"))
        yml = (Path(tmp) / f"{CLASS_ID}.yml").read_text()
    arrays = {}
    for name in ("color_features", "depth_features", "depth_offsets", "color_patches",
                 "depth_patches"):
        arrays[name], arrays[name + "_len"] = _ragged(getattr(templates, name))
    buf = io.BytesIO()
    np.savez_compressed(
        buf, yml=np.array(yml), params=np.array(json.dumps(asdict(templates.params))),
        key=np.array(templates.key), rotations=templates.rotations,
        distances=templates.distances, origins=templates.origins, sizes=templates.sizes,
        **arrays,
    )
    fd, tmp_path = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(buf.getvalue())
        os.replace(tmp_path, path)
    except BaseException:
        Path(tmp_path).unlink(missing_ok=True)
        raise


def load_templates(path: Path) -> TemplateSet:
    """Read a template set written by :func:`save_templates`."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no template file at {path}")
    with np.load(path, allow_pickle=False) as z:
        data = {k: z[k] for k in z.files}
    raw = json.loads(str(data["params"]))
    raw["distances_mm"] = tuple(raw["distances_mm"])
    params = TemplateParams(**raw)
    detector = cv2.linemod.getDefaultLINEMOD()
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / f"{CLASS_ID}.yml").write_text(str(data["yml"]))
        detector.readClasses([CLASS_ID], str(Path(tmp) / "%s.yml"))
    if detector.numTemplates() != len(data["rotations"]):
        raise ValueError(f"{path}: {detector.numTemplates()} templates in the detector but "
                         f"{len(data['rotations'])} views in the metadata")
    ragged = {
        name: _unragged(data[name], data[name + "_len"])
        for name in ("color_features", "depth_features", "depth_offsets", "color_patches",
                     "depth_patches")
    }
    return TemplateSet(
        params, detector, data["rotations"], data["distances"], data["origins"],
        data["sizes"], ragged["color_features"], ragged["depth_features"],
        ragged["depth_offsets"], ragged["color_patches"], ragged["depth_patches"],
        key=str(data["key"]),
    )


_MEMORY: dict[str, TemplateSet] = {}


def get_templates(params: TemplateParams = TemplateParams(),
                  K: np.ndarray | None = None) -> TemplateSet:
    """Templates for ``params`` and intrinsics ``K`` (default: the Primesense-like camera).

    From memory, else the cache file, else trained and saved: training takes tens of seconds,
    loading well under one.
    """
    camera = Camera() if K is None else Camera(K=np.asarray(K, dtype=np.float64))
    key = template_key(params, camera)
    if key in _MEMORY:
        return _MEMORY[key]
    path = cache_dir() / f"linemod-{key}.npz"
    if path.is_file():
        templates = load_templates(path)
    else:
        templates = train_templates(params, camera)
        save_templates(templates, path)
    _MEMORY[key] = templates
    return templates


def match_templates(templates: TemplateSet, rgb: np.ndarray, depth_mm: np.ndarray,
                    threshold: float = 70.0) -> Matches:
    """Plain ``cv2.linemod`` matching over the whole frame, as arrays.

    Positions are moved back by LineMod's reporting offset, so that ``(x, y) + feature`` is
    the pixel where the feature was scored.
    """
    rgb, depth_mm = _check_frame(rgb, depth_mm)
    found, quantized = templates.detector.match([rgb, depth_mm], float(threshold), [CLASS_ID])
    n = len(found)
    x = np.fromiter((m.x for m in found), dtype=np.int32, count=n) - MATCH_OFFSET
    y = np.fromiter((m.y for m in found), dtype=np.int32, count=n) - MATCH_OFFSET
    sim = np.fromiter((m.similarity for m in found), dtype=np.float64, count=n)
    tid = np.fromiter((m.template_id for m in found), dtype=np.int32, count=n)
    return Matches(x, y, sim, tid, tuple(quantized))


def _check_frame(rgb: np.ndarray, depth_mm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    rgb = np.asarray(rgb)
    depth_mm = np.asarray(depth_mm)
    if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.dtype != np.uint8:
        raise ValueError(f"rgb must be (H, W, 3) uint8, got {rgb.shape} {rgb.dtype}")
    if depth_mm.shape != rgb.shape[:2] or depth_mm.dtype != np.uint16:
        raise ValueError(f"depth must be (H, W) uint16 mm matching rgb, got {depth_mm.shape} "
                         f"{depth_mm.dtype}")
    return np.ascontiguousarray(rgb), np.ascontiguousarray(depth_mm)


