"""Precision and recall of cup detections against the true poses of a pile.

A detection is correct when its centre lies within 15 mm of a true cup's centre and its axis
within 15 degrees of that cup's axis. The cup is rotationally symmetric, so only the axis is
observable; its two ends differ (bottom vs lid), so axes are compared with their sign. Each
true cup is claimed by at most one detection (best score first), so a duplicate counts
against precision.

Recall is measured over the *visible* cups: those with at least ``min_visible`` of their
silhouette unoccluded (a cup buried under others cannot be found from the image). Precision is
over all detections, and a detection of a mostly hidden cup still counts as correct.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from sann.vision.camera import Camera
from sann.vision.detect import Detection
from sann.vision.render import render_cup

__all__ = [
    "FrameScore",
    "axis_angle_deg",
    "evaluate_frame",
    "match_detections",
    "summarize",
    "visible_fractions",
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


def visible_fractions(instance: np.ndarray, world_poses: np.ndarray, camera: Camera) -> np.ndarray:
    """Per cup: pixels seen in the scene's instance image / pixels of the cup rendered alone."""
    world_poses = np.asarray(world_poses, dtype=np.float64).reshape(-1, 4, 4)
    seen = np.bincount(instance[instance >= 0].ravel(), minlength=len(world_poses))
    alone = np.array([(render_cup(p, camera, frame="world").instance >= 0).sum()
                      for p in world_poses])
    return seen[: len(world_poses)] / np.maximum(alone, 1)
