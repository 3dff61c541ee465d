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
