"""The multi-cup experiment (paper Figs. 10-12): DNN vs SANN on poses the pipeline estimated.

Every frame is a synthesised pile seen by the Primesense-like camera; Patch-LineMod + ICP
estimate the poses, the 10 x 13 pose array (+ the target's row) is the DNN's input, and SANN
gets the same plus the logical item that fusion computed from the plans of rules/cups.soar on
the estimated poses. Both are the same ``DeepNet`` (its first layer is a ``ShallowNet``'s),
trained from the same seeds on standardised inputs (training statistics only). Accuracies are
means over seeds with a 95% interval. The detector is scored against the true poses on the
test frames, next to plain LineMod on the same frames.
"""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from sann.nets import DeepNet
from sann.tasks.cups import CupsDataParams, CupsDataset, detection_summary, make_dataset
from sann.train import (
    TrainConfig,
    TrainResult,
    intervals_overlap,
    summarise,
    train_baseline_and_sann,
)
from sann.viz import plots

NETS = ("dnn", "sann")
#: A smaller view sphere (one distance, 20 degree steps: about a hundred templates) for the
#: quick run: trained in seconds when the template cache is cold.
QUICK_TEMPLATES = {"tilt_step_deg": 20.0, "distances_mm": (630.0,)}


@dataclass(frozen=True)
class CupsExperiment:
    """Sizes and settings of one reproduction; ``quick()`` is the small version for tests."""

    n_train_piles: int = 300
    n_test_piles: int = 100
    seeds: int = 5
    data_seed: int = 0
    hidden: tuple[int, ...] = (64, 32, 16)
    #: Chosen on a validation split of the training frames (the last fifth), not on the test
    #: frames: with 131 inputs and ~1,500 samples the deep net overfits without weight decay.
    train: TrainConfig = TrainConfig(epochs=40, batch_size=64, lr=0.001, weight_decay=1e-2)
    data: CupsDataParams = field(default_factory=CupsDataParams)
    cap: int = 8

    def __post_init__(self) -> None:
        for name in ("n_train_piles", "n_test_piles", "seeds", "cap"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"CupsExperiment.{name} must be an integer >= 1, got {value!r}")

    @classmethod
    def quick(cls, seeds: int = 5) -> CupsExperiment:
        return cls(n_train_piles=30, n_test_piles=10, seeds=seeds,
                   train=TrainConfig(epochs=30, batch_size=32, lr=0.003, weight_decay=1e-2),
                   data=CupsDataParams(templates=dict(QUICK_TEMPLATES)))


def with_logical(x: np.ndarray, logical: np.ndarray) -> np.ndarray:
    """The fused M x (N+1) array: pose features plus the logical item column."""
    from sann.fusion import fuse

    return fuse(x.astype(np.float32), logical.astype(np.float32)).astype(np.float32)


def train_pairs(data: CupsDataset, config: CupsExperiment,
                seeds: list[int]) -> list[dict[str, TrainResult]]:
    """Train the DNN and SANN with every seed (each net kind's seeds are trained together,
    see `train_seeds`); one {"dnn", "sann"} pair per seed."""
    fused = (with_logical(data.X_train, data.logical_train),
             with_logical(data.X_test, data.logical_test))
    return train_baseline_and_sann(lambda n: DeepNet(n, hidden=config.hidden), data, fused,
                                   seeds, config.train, "dnn")


def logical_only_accuracy(data: CupsDataset) -> float:
    """The rules alone: call a target graspable when some plan grasps it first (eq. 2 >= 1)."""
    return float(np.mean((data.logical_test >= 1.0).astype(int) == data.y_test))


def run(out: str | Path, config: CupsExperiment = CupsExperiment(),
        progress: bool = False) -> dict:
    """Build the dataset, score the detectors, train DNN and SANN over the seeds, write
    results.json and Figs. 10-12 into ``out``; returns the results."""
    if not isinstance(config, CupsExperiment):
        raise ValueError(f"config must be a CupsExperiment, got {type(config).__name__}")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    data = make_dataset(config.n_train_piles, config.n_test_piles, seed=config.data_seed,
                        params=config.data, cap=config.cap, progress=progress)
    t_data = time.perf_counter() - t0
    t0 = time.perf_counter()
    runs = train_pairs(data, config, list(range(config.seeds)))
    t_train = time.perf_counter() - t0
    accuracy = {net: summarise([r[net].accuracy for r in runs]) for net in NETS}
    results = {
        "config": _jsonable(asdict(config)),
        "dataset": _dataset_info(data),
        "detection": {m: _jsonable(detection_summary(s)) for m, s in data.detection_test.items()},
        "detection_train": {m: _jsonable(detection_summary(s))
                            for m, s in data.detection_train.items()},
        "test_error": {net: [r[net].test_error for r in runs] for net in NETS},
        "accuracy": accuracy,
        "sann_better": bool(accuracy["sann"]["mean"] > accuracy["dnn"]["mean"]),
        "intervals_overlap": intervals_overlap(accuracy["dnn"], accuracy["sann"]),
        "logical_only_accuracy": logical_only_accuracy(data),
        "seconds": {"dataset": t_data, "training": t_train},
    }
    t0 = time.perf_counter()
    results["figures"] = _figures(out, results, data)
    results["seconds"]["figures"] = time.perf_counter() - t0
    (out / "results.json").write_text(json.dumps(results, indent=1))
    return results


def _dataset_info(data: CupsDataset) -> dict:
    from sann.fusion import exceeds_one

    info = {k: v for k, v in data.meta.items() if k != "params"}
    info.update(
        inputs_dnn=int(data.X_train.shape[1]), inputs_sann=int(data.X_train.shape[1] + 1),
        train_frames_with_detections=int(len(np.unique(data.image_train))),
        test_frames_with_detections=int(len(np.unique(data.image_test))),
        cups_per_frame_mean=float(np.concatenate([data.frames_train[:, 0],
                                                  data.frames_test[:, 0]]).mean()),
        logical_exceeds_one=float(exceeds_one(data.logical_train).mean()),
        logical_zero=float((data.logical_train == 0).mean()),
        detections_unmatched=float(np.mean(_unmatched(data))),
    )
    return _jsonable(info)


def _unmatched(data: CupsDataset) -> np.ndarray:
    """Per test frame: detections that match no true cup (they are labelled not graspable)."""
    frames = data.detection_test["patch"]["frames"]
    return frames[:, 0] - frames[:, 1]


def _figures(out: Path, results: dict, data: CupsDataset) -> dict[str, str]:
    import matplotlib.pyplot as plt

    names = {"fig10": "fig10_patches.png", "fig11": "fig11_estimated_poses.png",
             "fig12": "fig12_test_error.png"}
    fig = _fig10(data)
    fig.savefig(out / names["fig10"], dpi=110, bbox_inches="tight")
    plt.close(fig)
    fig = _fig11(data)
    fig.savefig(out / names["fig11"], dpi=110, bbox_inches="tight")
    plt.close(fig)
    acc = results["accuracy"]
    title = (f"Fig. 12: test error, cups (DNN {acc['dnn']['mean']:.1%}, "
             f"SANN {acc['sann']['mean']:.1%} accuracy)")
    plt.close(plots.error_curves(results["test_error"], title, out / names["fig12"]))
    return names


def _fig10(data: CupsDataset):
    """A side view template's colour features clustered into patches: k-means on the feature
    positions, and the authors' t-SNE + k-means."""
    import matplotlib.pyplot as plt

    from sann.vision.evaluate import draw_patches
    from sann.vision.linemod import get_templates

    templates = get_templates(data.params.template_params(), data.params.camera().K)
    side = int(np.argmin(np.abs(templates.rotations[:, 2, 2])))
    fig, axes = plt.subplots(2, 2, figsize=(8, 7))
    for row, method in zip(axes, ("kmeans", "tsne+kmeans"), strict=True):
        draw_patches(row[0], row[1], templates, side, "color", method)
    fig.suptitle(f"Fig. 10: template {side} of {len(templates)}, features clustered into "
                 "patches")
    fig.tight_layout()
    return fig


def _fig11(data: CupsDataset):
    """The test frame with the most detections: estimated poses over its depth image."""
    import matplotlib.pyplot as plt

    from sann.vision.evaluate import draw_detections

    n_train = int(data.meta["train_piles"])
    counts = data.frames_test[:, 1]
    image = n_train + int(np.argmax(counts))
    pile, _, seen = data.frame(image)
    camera = data.params.camera()
    detections = data.detections(image)
    fig, ax = plt.subplots(figsize=(7, 5.4))
    draw_detections(ax, seen.depth_mm, detections, camera.K,
                    true_poses=camera.world_to_camera @ pile.poses)
    ax.set_title(f"Fig. 11: {len(detections)} cups found in a pile of {pile.n_cups} "
                 "(Patch-LineMod + ICP; x: true centres)")
    return fig


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, float) and not np.isfinite(value):
        return None
    if isinstance(value, str | int | float | bool) or value is None:
        return value
    return str(value)
