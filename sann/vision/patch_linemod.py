"""Patch-LineMod: reject LineMod matches whose support is not spread over the whole template.

Plain LineMod sums the responses of all template features into one score, so in a pile a
template can score high by straddling two touching cups: half of its features on one cup, half
on the other. Patch-LineMod (the SANN authors' fork, paper Fig. 10) clusters each template's
features into spatial patches and keeps a match only when most patches, in both modalities,
respond on their own.

``cv2.linemod`` reports one similarity per match, not per feature, but ``Detector.match``
returns the quantised orientation images it used. The per-feature responses are recomputed
here from those images exactly as LineMod does (spread over T x T, then the similarity table:
4 for the same orientation, 3 for a neighbouring one, 0 otherwise), only at the candidates'
features, so it costs a gather rather than a convolution.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from sklearn.cluster import KMeans
from sklearn.manifold import TSNE

__all__ = [
    "Clustering",
    "PatchRule",
    "accept_candidate",
    "cluster_features",
    "feature_responses",
    "patch_activity",
    "spread",
]

Clustering = Literal["kmeans", "tsne+kmeans"]

#: Largest response of one feature in the LineMod similarity table.
MAX_RESPONSE = 4.0


@dataclass(frozen=True)
class PatchRule:
    """Thresholds of the acceptance rule (SPEC section 6 defaults)."""

    active_ratio: float = 0.7
    min_fraction: float = 0.6
    min_patches: int = 3
    min_score: float = 70.0


def _feature_descriptor(features: np.ndarray) -> np.ndarray:
    """(x, y) plus the orientation on a circle scaled to pixels, for t-SNE's neighbourhoods."""
    xy = features[:, :2].astype(np.float64)
    angle = features[:, 2].astype(np.float64) * (np.pi / 8.0)
    scale = max(float(np.ptp(xy, axis=0).max()), 1.0) * 0.1
    return np.hstack([xy, scale * np.cos(angle)[:, None], scale * np.sin(angle)[:, None]])


def cluster_features(
    features: np.ndarray, n_patches: int, method: Clustering = "kmeans", seed: int = 0
) -> np.ndarray:
    """Patch label (0..n_patches-1) of every feature ``(x, y, orientation)`` of a template.

    ``kmeans`` clusters the feature positions directly; ``tsne+kmeans`` first embeds position
    and orientation in 2-D with t-SNE, as the authors' fork does, then clusters the embedding.
    Labels are renumbered by first appearance so equal inputs give equal outputs.
    """
    features = np.asarray(features)
    if features.ndim != 2 or features.shape[1] != 3:
        raise ValueError(f"features must be (n, 3) rows of x, y, label, got {features.shape}")
    if n_patches < 1:
        raise ValueError(f"n_patches must be positive, got {n_patches}")
    n = len(features)
    if n < n_patches:
        raise ValueError(f"cannot make {n_patches} patches from {n} features")
    if method == "kmeans":
        data = features[:, :2].astype(np.float64)
    elif method == "tsne+kmeans":
        perplexity = float(min(30.0, max(2.0, (n - 1) / 3.0)))
        data = TSNE(
            n_components=2, perplexity=perplexity, init="pca", random_state=seed, max_iter=500
        ).fit_transform(_feature_descriptor(features))
    else:
        raise ValueError(f"unknown clustering {method!r}; use 'kmeans' or 'tsne+kmeans'")
    raw = KMeans(n_clusters=n_patches, n_init=4, random_state=seed).fit_predict(data)
    _, first = np.unique(raw, return_index=True)
    order = np.argsort(np.argsort(first))
    return order[raw].astype(np.int32)


def spread(quantized: np.ndarray, T: int) -> np.ndarray:
    """OR of the orientation bits over the T x T block below-right of each pixel (LineMod)."""
    q = np.asarray(quantized, dtype=np.uint8)
    if q.ndim != 2:
        raise ValueError(f"quantized image must be 2-D, got {q.shape}")
    h, w = q.shape
    rows = q.copy()
    for r in range(1, T):
        rows[: h - r] |= q[r:]
    out = rows.copy()
    for c in range(1, T):
        out[:, : w - c] |= rows[:, c:]
    return out


def _similarity_table() -> np.ndarray:
    """(8, 256) response of a feature with orientation ``l`` to a spread bit mask."""
    table = np.zeros((8, 256), dtype=np.float32)
    masks = np.arange(256)
    for label in range(8):
        near = (1 << ((label + 1) % 8)) | (1 << ((label - 1) % 8))
        table[label] = np.where(masks & (1 << label), 4.0, np.where(masks & near, 3.0, 0.0))
    return table


_TABLE = _similarity_table()


def feature_responses(
    spread_image: np.ndarray, features: np.ndarray, offsets: np.ndarray
) -> np.ndarray:
    """Responses (0, 3 or 4) of template features placed at many offsets.

    ``features`` is (n, 3) rows of x, y, orientation label shared by all placements, or
    (m, n, 3) with one feature list per placement (label -1 marks padding, responding 0);
    ``offsets`` is (m, 2), the template's top-left corner in the image. Returns (m, n).
    Features falling outside the image respond 0.
    """
    features = np.asarray(features)
    if features.ndim == 2:
        features = features[None]
    if features.ndim != 3 or features.shape[2] != 3:
        raise ValueError(f"features must be (n, 3) or (m, n, 3), got {features.shape}")
    offsets = np.atleast_2d(np.asarray(offsets))
    h, w = spread_image.shape
    x = offsets[:, :1] + features[..., 0]
    y = offsets[:, 1:2] + features[..., 1]
    label = features[..., 2]
    valid = (x >= 0) & (x < w) & (y >= 0) & (y < h) & (label >= 0)
    bits = spread_image[np.clip(y, 0, h - 1), np.clip(x, 0, w - 1)]
    resp = _TABLE[np.clip(label, 0, 7), bits]
    return np.where(valid, resp, 0.0)


def patch_activity(
    responses: np.ndarray, labels: np.ndarray, n_patches: int, active_ratio: float = 0.7
) -> np.ndarray:
    """Whether each patch is active: its mean response exceeds ``active_ratio`` of the maximum.

    ``responses`` is (m, n) for m candidates and n features; ``labels`` is (n,) when all
    candidates share a template, or (m, n) when each has its own, with -1 marking padding.
    Returns (m, n_patches) booleans. A patch's maximum is what it would score with every
    feature at full response; a patch without features is never active.
    """
    responses = np.atleast_2d(np.asarray(responses, dtype=np.float64))
    labels = np.broadcast_to(np.asarray(labels), responses.shape)
    if labels.max(initial=-1) >= n_patches:
        raise ValueError(f"patch labels must be below n_patches={n_patches}")
    onehot = labels[..., None] == np.arange(n_patches)
    counts = onehot.sum(axis=1)
    total = np.einsum("mn,mnp->mp", responses, onehot)
    mean = np.divide(total, counts, out=np.zeros_like(total), where=counts > 0)
    return (mean > active_ratio * MAX_RESPONSE) & (counts > 0)


def accept_candidate(
    active_color: np.ndarray, active_depth: np.ndarray, score: np.ndarray, rule: PatchRule
) -> np.ndarray:
    """The Patch-LineMod rule, vectorised over candidates.

    Kept when the score exceeds ``min_score`` and, in each modality, more than ``min_fraction``
    of the patches and at least ``min_patches`` are active.
    """
    ok = np.asarray(score) > rule.min_score
    for active in (np.atleast_2d(active_color), np.atleast_2d(active_depth)):
        n_active = active.sum(axis=1)
        ok &= (n_active > rule.min_fraction * active.shape[1]) & (n_active >= rule.min_patches)
    return ok
