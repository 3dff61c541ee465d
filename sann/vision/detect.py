"""Cup detection on an RGB-D frame: LineMod candidates, the Patch-LineMod rule, NMS, ICP.

``detect_cups(rgb, depth_mm, K)`` is the one entry point, for rendered and real frames alike.
Each LineMod match becomes a pose hypothesis without any search: the template knows where the
cup's centre projects relative to its corner and how far behind the surface under each depth
feature the centre lies, so the centre is the matched pixel back-projected at the median of
(measured depth + offset). The template's rotation was rendered with the cup on the optical
axis; turning it by the rotation that takes the optical axis onto the ray through the centre
gives the cup's rotation in the frame. ICP on the depth points then does the fine alignment,
and a refined pose is kept only if the model, projected at that pose, agrees with the measured
depth (``depth_agreement``); for a cup seen from the side, whose two ends LineMod can confuse,
the end-over-end twin is refined as well and the better-agreeing one kept.

``method="linemod"`` is the plain baseline (LineMod matches, NMS, no patch rule, no ICP;
``icp=True`` adds the same refinement and verification without the patch rule);
``method="patch"`` is Patch-LineMod with ICP, as in the paper's pipeline.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from typing import Literal

import numpy as np

from sann.vision.cup import cup_mesh
from sann.vision.icp import IcpResult, ModelCloud, icp_point_to_plane, model_cloud_from_mesh
from sann.vision.linemod import (
    MATCH_OFFSET,
    T_LEVEL0,
    Matches,
    TemplateParams,
    TemplateSet,
    get_templates,
    match_templates,
)
from sann.vision.patch_linemod import (
    PatchRule,
    accept_candidate,
    feature_responses,
    patch_activity,
    spread,
)

__all__ = [
    "MAX_DETECTIONS",
    "DetectConfig",
    "Detection",
    "detect_cups",
    "pose_array",
]

MAX_DETECTIONS = 10
Method = Literal["patch", "linemod"]


@dataclass(frozen=True)
class Detection:
    """A detected cup: centre position (mm, camera frame), cup-to-camera rotation, score."""

    position_mm: np.ndarray
    rotation: np.ndarray
    score: float

    @property
    def axis(self) -> np.ndarray:
        """The cup's symmetry axis (towards the lid) in the camera frame."""
        return self.rotation[:, 2]


@dataclass(frozen=True)
class DetectConfig:
    """Knobs of the detector; the defaults are the SPEC section 6 pipeline."""

    method: Method = "patch"
    templates: TemplateParams = field(default_factory=TemplateParams)
    rule: PatchRule = field(default_factory=PatchRule)
    #: LineMod threshold for the plain baseline (Patch-LineMod uses ``rule.min_score``).
    linemod_threshold: float = 80.0
    #: Candidates closer than this (mm, centre to centre) are one cup; cups touching side by
    #: side are at least a diameter (87 mm) apart, end to end even more.
    nms_radius_mm: float = 45.0
    #: Before ICP, hypotheses are thinned less: a wrong view scoring higher than the right one
    #: on the same cup must not suppress it before verification can tell them apart.
    pre_nms_radius_mm: float = 20.0
    icp: bool | None = None  # None: on for "patch", off for "linemod"
    max_icp_candidates: int = 30
    #: An ICP result is kept only if enough depth points lie within ICP's final gate.
    min_icp_inliers: int = 150
    #: ... and if the refined pose agrees with the depth image (see ``depth_agreement``).
    min_agreement: float = 0.6
    #: A detection this well confirmed suppresses the remaining hypotheses around it.
    sure_agreement: float = 0.85
    #: Views with |cos(axis, line of sight)| below this always try the end-over-end twin
    #: (others only when their own fit is below ``sure_agreement``).
    side_view_cos: float = 0.7
    icp_points: int = 600
    max_detections: int = MAX_DETECTIONS

    def __post_init__(self) -> None:
        if self.method not in ("patch", "linemod"):
            raise ValueError(f"method must be 'patch' or 'linemod', got {self.method!r}")
        if not 1 <= self.max_detections <= MAX_DETECTIONS:
            raise ValueError(f"max_detections must be in 1..{MAX_DETECTIONS}")

    @property
    def use_icp(self) -> bool:
        return self.method == "patch" if self.icp is None else self.icp


@dataclass(frozen=True)
class Candidates:
    """Pose hypotheses from matches (arrays over candidates)."""

    match_index: np.ndarray
    score: np.ndarray
    position: np.ndarray  # (m, 3)
    rotation: np.ndarray  # (m, 3, 3)
    template_id: np.ndarray
    window: np.ndarray  # (m, 4): x0, y0, x1, y1 of the template in the frame


@lru_cache(maxsize=1)
def cup_model_cloud() -> ModelCloud:
    """Surface samples of the cup for ICP (cached: the KD-tree is built once)."""
    mesh = cup_mesh()
    return model_cloud_from_mesh(np.asarray(mesh.vertices), np.asarray(mesh.faces), 6000, 0)


def patch_filter(templates: TemplateSet, matches: Matches, rule: PatchRule) -> np.ndarray:
    """Boolean per match: does it pass the Patch-LineMod rule?"""
    if len(matches) == 0:
        return np.zeros(0, dtype=bool)
    st = templates.stacked
    offsets = np.stack([matches.x, matches.y], axis=1)
    tid = matches.template_id
    active = []
    for modality, quantized in (("color", matches.quantized[0]), ("depth", matches.quantized[1])):
        resp = feature_responses(spread(quantized, T_LEVEL0), st[modality][tid], offsets)
        labels = st[modality + "_patches"][tid]
        active.append(
            patch_activity(resp, labels, templates.params.n_patches, rule.active_ratio)
        )
    return accept_candidate(active[0], active[1], matches.similarity, rule)


def _ray_rotation(ray: np.ndarray) -> np.ndarray:
    """(m, 3, 3) smallest rotations taking the optical axis onto each unit ray."""
    z = np.array([0.0, 0.0, 1.0])
    axis = np.cross(z, ray)
    s = np.linalg.norm(axis, axis=1)
    c = ray[:, 2]
    k = np.divide(axis, s[:, None], out=np.zeros_like(axis), where=s[:, None] > 1e-12)
    kx = np.zeros((len(ray), 3, 3))
    kx[:, 0, 1], kx[:, 0, 2], kx[:, 1, 2] = -k[:, 2], k[:, 1], -k[:, 0]
    kx -= kx.transpose(0, 2, 1)
    return np.eye(3) + s[:, None, None] * kx + (1.0 - c)[:, None, None] * (kx @ kx)


def coarse_poses(templates: TemplateSet, matches: Matches, index: np.ndarray,
                 depth_mm: np.ndarray, K: np.ndarray) -> Candidates:
    """Pose hypotheses of the matches ``index``; those without depth support are dropped."""
    st = templates.stacked
    tid = matches.template_id[index]
    # A match's corner lies 0..T-1 px above-left of the true one (see match_templates); the
    # middle of that range is the unbiased estimate.
    x, y = matches.x[index] + MATCH_OFFSET, matches.y[index] + MATCH_OFFSET
    feats = st["depth"][tid]
    h, w = depth_mm.shape
    fx = np.clip(x[:, None] + feats[..., 0], 0, w - 1)
    fy = np.clip(y[:, None] + feats[..., 1], 0, h - 1)
    measured = depth_mm[fy, fx].astype(np.float64)
    valid = (measured > 0) & (feats[..., 2] >= 0)
    centre_z = np.where(valid, measured + st["offsets"][tid], np.nan)
    with np.errstate(all="ignore"):
        z = np.nanmedian(np.where(np.isfinite(centre_z), centre_z, np.nan), axis=1)
    keep = np.isfinite(z) & (valid.sum(axis=1) >= 8)
    tid, x, y, z, index = tid[keep], x[keep], y[keep], z[keep], index[keep]
    origin = templates.origins[tid]
    u = x + (K[0, 2] - origin[:, 0])
    v = y + (K[1, 2] - origin[:, 1])
    ray = np.stack([(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1], np.ones_like(u)], axis=1)
    position = ray * z[:, None]
    unit = ray / np.linalg.norm(ray, axis=1, keepdims=True)
    rotation = _ray_rotation(unit) @ templates.rotations[tid]
    size = templates.sizes[tid]
    window = np.stack([x, y, x + size[:, 0], y + size[:, 1]], axis=1)
    return Candidates(index, matches.similarity[index], position, rotation, tid, window)


def nms_3d(positions: np.ndarray, scores: np.ndarray, radius: float, limit: int) -> np.ndarray:
    """Indices of the best-scoring candidates with no better one within ``radius`` (greedy)."""
    order = np.argsort(-scores, kind="stable")
    kept: list[int] = []
    for i in order:
        if kept and np.min(np.linalg.norm(positions[kept] - positions[i], axis=1)) < radius:
            continue
        kept.append(int(i))
        if len(kept) >= limit:
            break
    return np.array(kept, dtype=np.int64)


def _scene_points(depth_mm: np.ndarray, K: np.ndarray, window: np.ndarray,
                  centre_z: float) -> np.ndarray:
    """Depth points inside the template window, within a cup's reach of the centre depth."""
    h, w = depth_mm.shape
    x0, y0 = max(int(window[0]), 0), max(int(window[1]), 0)
    x1, y1 = min(int(window[2]), w), min(int(window[3]), h)
    patch = depth_mm[y0:y1, x0:x1].astype(np.float64)
    vv, uu = np.nonzero((patch > 0) & (np.abs(patch - centre_z) < 100.0))
    z = patch[vv, uu]
    return np.stack([(uu + x0 - K[0, 2]) * z / K[0, 0], (vv + y0 - K[1, 2]) * z / K[1, 1], z], 1)


def depth_agreement(model: ModelCloud, rotation: np.ndarray, translation: np.ndarray,
                    depth_mm: np.ndarray, K: np.ndarray, tolerance: float = 8.0) -> float:
    """How well a pose explains the depth image: agreeing / (agreeing + contradicting) points.

    The model's surface points facing the camera are projected into the image. A point agrees
    when the measured depth is within ``tolerance`` of it, is occluded (neutral) when something
    lies in front of it, and contradicts when the camera sees past it (farther, or no reading).
    A cup put where there is none, or the right cup turned end over end, contradicts a lot.
    """
    pts = model.points @ rotation.T + translation
    nrm = model.normals @ rotation.T
    facing = np.einsum("ij,ij->i", nrm, pts) < 0.0
    pts = pts[facing]
    h, w = depth_mm.shape
    u = np.rint(pts[:, 0] * K[0, 0] / pts[:, 2] + K[0, 2]).astype(np.int64)
    v = np.rint(pts[:, 1] * K[1, 1] / pts[:, 2] + K[1, 2]).astype(np.int64)
    inside = (u >= 0) & (u < w) & (v >= 0) & (v < h)
    if not inside.any():
        return 0.0
    measured = depth_mm[v[inside], u[inside]].astype(np.float64)
    z = pts[inside, 2]
    agree = np.abs(measured - z) <= tolerance
    contradict = (measured == 0) | (measured > z + tolerance)
    n = agree.sum() + contradict.sum()
    return float(agree.sum() / n) if n else 0.0


def _flipped(rotation: np.ndarray) -> np.ndarray:
    """The same cup turned end over end (axis reversed, centre kept)."""
    return rotation @ np.diag([1.0, -1.0, -1.0])


def _refine(cands: Candidates, order: np.ndarray, depth_mm: np.ndarray, K: np.ndarray,
            config: DetectConfig) -> list[Detection]:
    """ICP from each hypothesis (best LineMod score first); keep the ones the depth confirms.

    A cup seen from the side is nearly symmetric end to end (a slightly tapered cylinder), so
    LineMod sometimes picks the reversed view and ICP, being local, cannot turn it over: the
    end-over-end twin is refined too and the better-verified one kept.
    Hypotheses next to a cup already confirmed beyond doubt are not refined again.
    """
    model = cup_model_cloud()
    out: list[Detection] = []
    sure: list[np.ndarray] = []
    for i in order:
        if sure and np.min(np.linalg.norm(np.array(sure) - cands.position[i], axis=1)) < \
                config.nms_radius_mm:
            continue
        pts = _scene_points(depth_mm, K, cands.window[i], cands.position[i, 2])
        if len(pts) < config.min_icp_inliers:
            continue
        best = _verified_icp(model, pts, cands.rotation[i], cands.position[i], depth_mm, K,
                             config)
        if best is None:
            continue
        fit, res = best
        out.append(Detection(res.translation, res.rotation, float(cands.score[i] * fit)))
        if fit >= config.sure_agreement:
            sure.append(res.translation)
    return out


def _verified_icp(model: ModelCloud, pts: np.ndarray, rotation: np.ndarray,
                  position: np.ndarray, depth_mm: np.ndarray, K: np.ndarray,
                  config: DetectConfig) -> tuple[float, IcpResult] | None:
    """The best (depth agreement, ICP result) over the hypothesis and its end-over-end twin.

    The twin is skipped only when the hypothesis is seen along its axis and already fits
    beyond doubt.
    """
    stride = max(1, len(pts) // config.icp_points)
    ray = position / np.linalg.norm(position)
    side_view = abs(float(rotation[:, 2] @ ray)) < config.side_view_cos
    best = None
    for rot in (rotation, _flipped(rotation)):
        if rot is not rotation and not side_view and best is not None \
                and best[0] >= config.sure_agreement:
            break  # a clear fit seen along the axis: the twin cannot do better
        res = icp_point_to_plane(model, pts[::stride], rot, position)
        if res.n_inliers * stride < config.min_icp_inliers:
            continue
        if np.linalg.norm(res.translation - position) > config.nms_radius_mm:
            continue
        fit = depth_agreement(model, res.rotation, res.translation, depth_mm, K)
        if best is None or fit > best[0]:
            best = (fit, res)
    if best is None or best[0] < config.min_agreement:
        return None
    return best


def detect_cups(rgb: np.ndarray, depth_mm: np.ndarray, K: np.ndarray,
                config: DetectConfig | None = None,
                templates: TemplateSet | None = None) -> list[Detection]:
    """Up to ``config.max_detections`` (10) cups in an RGB-D frame, best first.

    ``rgb`` is (H, W, 3) uint8, ``depth_mm`` (H, W) uint16 with 0 for no reading, ``K`` the
    3x3 intrinsics (the templates are rendered with the same ``K``).
    """
    config = config or DetectConfig()
    K = np.asarray(K, dtype=np.float64)
    if K.shape != (3, 3):
        raise ValueError(f"K must be 3x3, got {K.shape}")
    templates = templates or get_templates(config.templates, K)
    patch = config.method == "patch"
    threshold = config.rule.min_score if patch else config.linemod_threshold
    matches = match_templates(templates, rgb, depth_mm, threshold)
    index = np.arange(len(matches))
    if patch:
        index = index[patch_filter(templates, matches, config.rule)]
    cands = coarse_poses(templates, matches, index, np.asarray(depth_mm), K)
    limit = config.max_icp_candidates if config.use_icp else config.max_detections
    radius = config.pre_nms_radius_mm if config.use_icp else config.nms_radius_mm
    order = nms_3d(cands.position, cands.score, radius, limit)
    if not config.use_icp:
        return [Detection(cands.position[i], cands.rotation[i], float(cands.score[i]))
                for i in order]
    refined = _refine(cands, order, np.asarray(depth_mm), K, config)
    if not refined:
        return []
    pos = np.array([d.position_mm for d in refined])
    keep = nms_3d(pos, np.array([d.score for d in refined]), config.nms_radius_mm,
                  config.max_detections)
    return [refined[i] for i in keep]


def pose_array(detections: list[Detection]) -> np.ndarray:
    """The paper's 10 x 13 array: position (3), rotation row-major (9), score (1) per row.

    Rows follow the detections' order (best first); missing rows are zero.
    """
    if len(detections) > MAX_DETECTIONS:
        raise ValueError(f"at most {MAX_DETECTIONS} detections fit, got {len(detections)}")
    out = np.zeros((MAX_DETECTIONS, 13))
    for row, det in zip(out, detections, strict=False):
        row[:3] = det.position_mm
        row[3:12] = np.asarray(det.rotation).reshape(9)
        row[12] = det.score
    return out
