"""Precision and recall of cup detections against the true poses of a pile.

A detection is correct when its centre lies within 15 mm of a true cup's centre and its axis
within 15 degrees of that cup's axis. The cup is rotationally symmetric, so only the axis is
observable; its two ends differ (bottom vs lid), so axes are compared with their sign. Each
true cup is claimed by at most one detection (best score first), so a duplicate counts
against precision.

Recall is measured over the *visible* cups: those with at least half of their silhouette
unoccluded (``LabelParams.min_visible_fraction``, the same rule as the graspability labels; a
cup buried under others cannot be found from the image). Precision is over all detections,
and a detection of a mostly hidden cup still counts as correct.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from sann.vision.camera import Camera, default_camera
from sann.vision.detect import DetectConfig, Detection, detect_cups
from sann.vision.labels import LabelParams, visible_fractions
from sann.vision.linemod import get_templates
from sann.vision.piles import make_pile
from sann.vision.render import SensorNoise, add_sensor_noise, render

__all__ = [
    "FrameScore",
    "axis_angle_deg",
    "evaluate_frame",
    "match_detections",
    "summarize",
    "Frame",
    "make_frames",
    "evaluate_methods",
    "draw_patches",
    "draw_detections",
]

POSITION_TOL_MM = 15.0
AXIS_TOL_DEG = 15.0


@dataclass(frozen=True)
class FrameScore:
    """Counts of one frame."""

    n_detections: int
    n_correct: int  # detections matched to a true cup
    n_visible: int  # true cups counted for recall
    n_found: int  # visible true cups matched by a detection
    position_errors: tuple[float, ...] = ()  # mm, of the correct detections
    axis_errors: tuple[float, ...] = ()  # degrees, of the correct detections


def axis_angle_deg(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle (degrees) between unit axes, broadcasting over leading dimensions."""
    cos = np.sum(np.asarray(a) * np.asarray(b), axis=-1)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def match_detections(
    detections: Sequence[Detection],
    true_poses: np.ndarray,
    position_tol: float = POSITION_TOL_MM,
    axis_tol: float = AXIS_TOL_DEG,
) -> np.ndarray:
    """Index of the true cup each detection claims, or -1 (greedy, best score first).

    ``true_poses`` are cup-to-camera 4x4 poses, shape (n, 4, 4).
    """
    true_poses = np.asarray(true_poses, dtype=np.float64).reshape(-1, 4, 4)
    claimed = np.full(len(detections), -1, dtype=np.int64)
    free = np.ones(len(true_poses), dtype=bool)
    order = np.argsort([-d.score for d in detections], kind="stable")
    for i in order:
        det = detections[i]
        dist = np.linalg.norm(true_poses[:, :3, 3] - det.position_mm, axis=1)
        angle = axis_angle_deg(true_poses[:, :3, 2], det.axis)
        ok = free & (dist <= position_tol) & (angle <= axis_tol)
        if ok.any():
            j = int(np.argmin(np.where(ok, dist, np.inf)))
            claimed[i] = j
            free[j] = False
    return claimed


def evaluate_frame(
    detections: Sequence[Detection],
    true_poses: np.ndarray,
    visible: np.ndarray,
    position_tol: float = POSITION_TOL_MM,
    axis_tol: float = AXIS_TOL_DEG,
) -> FrameScore:
    """Score one frame; ``visible`` marks the true cups that count for recall."""
    true_poses = np.asarray(true_poses, dtype=np.float64).reshape(-1, 4, 4)
    visible = np.asarray(visible, dtype=bool)
    if visible.shape != (len(true_poses),):
        raise ValueError(f"need one visibility flag per true cup, got {visible.shape}")
    claimed = match_detections(detections, true_poses, position_tol, axis_tol)
    hit = claimed >= 0
    pos_err = [float(np.linalg.norm(detections[i].position_mm - true_poses[j, :3, 3]))
               for i, j in enumerate(claimed) if j >= 0]
    ang_err = [float(axis_angle_deg(detections[i].axis, true_poses[j, :3, 2]))
               for i, j in enumerate(claimed) if j >= 0]
    return FrameScore(
        n_detections=len(detections),
        n_correct=int(hit.sum()),
        n_visible=int(visible.sum()),
        n_found=int(visible[claimed[hit]].sum()),
        position_errors=tuple(pos_err),
        axis_errors=tuple(ang_err),
    )


def summarize(scores: Sequence[FrameScore]) -> dict[str, float]:
    """Precision, recall and error statistics pooled over frames."""
    n_det = sum(s.n_detections for s in scores)
    n_vis = sum(s.n_visible for s in scores)
    pos = np.concatenate([np.asarray(s.position_errors, dtype=float) for s in scores] or [[]])
    ang = np.concatenate([np.asarray(s.axis_errors, dtype=float) for s in scores] or [[]])
    return {
        "frames": len(scores),
        "detections": n_det,
        "visible_cups": n_vis,
        "precision": sum(s.n_correct for s in scores) / n_det if n_det else 0.0,
        "recall": sum(s.n_found for s in scores) / n_vis if n_vis else 0.0,
        "median_position_error_mm": float(np.median(pos)) if pos.size else float("nan"),
        "median_axis_error_deg": float(np.median(ang)) if ang.size else float("nan"),
    }


@dataclass(frozen=True)
class Frame:
    """A test frame: the images, the true cup-to-camera poses and which cups count as visible."""

    rgb: np.ndarray
    depth_mm: np.ndarray
    true_poses: np.ndarray
    visible: np.ndarray
    n_cups: int


def make_frames(n_piles: int, seed: int, camera: Camera | None = None,
                cups: tuple[int, int] = (2, 10),
                min_visible: float = LabelParams().min_visible_fraction,
                noise: SensorNoise | None = None) -> list[Frame]:
    """Rendered piles of ``cups[0]..cups[1]`` cups (seeded) with their ground truth.

    With ``noise`` the images get the Primesense-like sensor noise (seeded per frame); the
    visible fractions always come from the clean rendering.
    """
    if n_piles < 1 or not 1 <= cups[0] <= cups[1]:
        raise ValueError(f"need n_piles >= 1 and 1 <= cups[0] <= cups[1], got {n_piles}, {cups}")
    camera = camera or default_camera()
    rng = np.random.default_rng(seed)
    frames = []
    for k in range(n_piles):
        pile = make_pile(int(rng.integers(cups[0], cups[1] + 1)), seed * 1000 + k)
        res = render(pile, camera)
        fraction = visible_fractions(pile, camera, res)
        if noise is not None:
            res = add_sensor_noise(res, seed * 1000 + k, noise)
        frames.append(Frame(res.rgb, res.depth_mm, camera.world_to_camera @ pile.poses,
                            fraction >= min_visible, pile.n_cups))
    return frames


def evaluate_methods(frames: Sequence[Frame], configs: dict[str, DetectConfig],
                     K: np.ndarray) -> dict[str, dict[str, float]]:
    """Precision/recall (and mean time per frame) of each detector configuration."""
    out = {}
    for name, config in configs.items():
        templates = get_templates(config.templates, K)
        scores, times = [], []
        for f in frames:
            start = time.perf_counter()
            found = detect_cups(f.rgb, f.depth_mm, K, config, templates)
            times.append(time.perf_counter() - start)
            scores.append(evaluate_frame(found, f.true_poses, f.visible))
        out[name] = summarize(scores) | {"seconds_per_frame": float(np.mean(times))}
    return out


def draw_patches(ax_image, ax_embedding, templates, template_id: int, modality: str = "color",
                 method: str | None = None) -> np.ndarray:
    """Fig. 10: a template's features on its rendering, coloured by patch; and the 2-D space
    the patches were cut in (feature positions for k-means, the t-SNE embedding otherwise).

    ``method`` overrides the template set's clustering (to show both on the same template).
    Returns the patch labels drawn.
    """
    from sann.vision.camera import make_pose
    from sann.vision.patch_linemod import cluster_features, feature_descriptor, tsne_small
    from sann.vision.render import render_cup

    params = templates.params
    method = method or params.clustering
    feats = (templates.color_features if modality == "color"
             else templates.depth_features)[template_id]
    labels = cluster_features(feats, params.n_patches, method, params.seed)
    pose = make_pose(templates.rotations[template_id],
                     np.array([0.0, 0.0, templates.distances[template_id]]))
    x0, y0 = templates.origins[template_id]
    w, h = templates.sizes[template_id]
    crop = render_cup(pose).rgb[y0: y0 + h + 1, x0: x0 + w + 1]
    ax_image.imshow(crop)
    ax_image.scatter(feats[:, 0], feats[:, 1], c=labels, cmap="tab10", s=28,
                     vmin=0, vmax=9, edgecolors="black", linewidths=0.5)
    ax_image.set_title(f"{method}: {params.n_patches} patches of {len(feats)} {modality} features")
    ax_image.set_axis_off()
    if ax_embedding is not None:
        if method == "kmeans":
            space, name = feats[:, :2].astype(float) * [1, -1], "feature position"
        else:
            perplexity = float(min(30.0, max(2.0, (len(feats) - 1) / 3.0)))
            space, name = tsne_small(feature_descriptor(feats), perplexity), "t-SNE embedding"
        ax_embedding.scatter(space[:, 0], space[:, 1], c=labels, cmap="tab10", s=20, vmin=0,
                             vmax=9)
        ax_embedding.set_title(f"clustered in: {name}")
        ax_embedding.set_xticks([])
        ax_embedding.set_yticks([])
    return labels


def draw_detections(ax, depth_mm: np.ndarray, detections: Sequence[Detection], K: np.ndarray,
                    true_poses: np.ndarray | None = None, n_points: int = 600) -> None:
    """Fig. 11: estimated poses drawn over the depth image.

    Each detection is shown as its cup's surface points facing the camera, projected at the
    estimated pose, with its axis (bottom to lid) and its rank and score; true cups, when
    given, are marked by a white cross at their centre.
    """
    from sann.vision.detect import cup_model_cloud

    K = np.asarray(K, dtype=np.float64)
    depth = np.asarray(depth_mm, dtype=np.float64)
    valid = depth > 0
    lo, hi = (np.percentile(depth[valid], [1, 99]) if valid.any() else (0.0, 1.0))
    ax.imshow(np.where(valid, depth, hi), cmap="gray", vmin=lo, vmax=hi)
    model = cup_model_cloud()
    pick = np.linspace(0, len(model.points) - 1, n_points).astype(int)

    def project(p):
        return p[..., 0] * K[0, 0] / p[..., 2] + K[0, 2], p[..., 1] * K[1, 1] / p[..., 2] + K[1, 2]

    colours = plt_colours(len(detections))
    for rank, (det, colour) in enumerate(zip(detections, colours, strict=True)):
        pts = model.points[pick] @ det.rotation.T + det.position_mm
        nrm = model.normals[pick] @ det.rotation.T
        facing = np.einsum("ij,ij->i", nrm, pts) < 0
        u, v = project(pts[facing])
        ax.scatter(u, v, s=2, color=colour)
        ends = det.position_mm + np.outer([-60.0, 60.0], det.axis)
        eu, ev = project(ends)
        ax.annotate("", xy=(eu[1], ev[1]), xytext=(eu[0], ev[0]),
                    arrowprops={"arrowstyle": "->", "color": colour, "lw": 1.5})
        cu, cv = project(det.position_mm)
        ax.text(cu, cv, f"{rank + 1}:{det.score:.0f}", color="white", fontsize=7,
                ha="center", va="center", bbox={"facecolor": colour, "alpha": 0.7, "pad": 1})
    if true_poses is not None and len(true_poses):
        tu, tv = project(np.asarray(true_poses)[:, :3, 3])
        ax.scatter(tu, tv, marker="x", color="white", s=30)
    ax.set_xlim(0, depth.shape[1])
    ax.set_ylim(depth.shape[0], 0)
    ax.set_axis_off()


def plt_colours(n: int) -> list:
    """``n`` distinct colours (tab10, cycled)."""
    import matplotlib

    cmap = matplotlib.colormaps["tab10"]
    return [cmap(i % 10) for i in range(n)]
