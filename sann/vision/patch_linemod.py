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

__all__ = [
    "Clustering",
    "PatchRule",
    "accept_candidate",
    "cluster_features",
    "feature_descriptor",
    "feature_responses",
    "patch_activity",
    "spread",
    "tsne_small",
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


def feature_descriptor(features: np.ndarray) -> np.ndarray:
    """(x, y) plus the orientation on a circle scaled to pixels, for t-SNE's neighbourhoods."""
    xy = features[:, :2].astype(np.float64)
    angle = features[:, 2].astype(np.float64) * (np.pi / 8.0)
    scale = max(float(np.ptp(xy, axis=0).max()), 1.0) * 0.1
    return np.hstack([xy, scale * np.cos(angle)[:, None], scale * np.sin(angle)[:, None]])


def _row_affinities(d2: np.ndarray, perplexity: float) -> np.ndarray:
    """Conditional Gaussian affinities with each row's bandwidth set to the perplexity."""
    n = len(d2)
    beta, lo, hi = np.ones(n), np.zeros(n), np.full(n, np.inf)
    target = np.log(perplexity)
    off = ~np.eye(n, dtype=bool)
    # Distances relative to each row's nearest neighbour: the same affinities, no underflow.
    d = d2 - np.min(np.where(off, d2, np.inf), axis=1, keepdims=True)
    d[~off] = 0.0
    for _ in range(60):
        p = np.exp(-d * beta[:, None]) * off
        sp = p.sum(axis=1)
        entropy = np.log(sp) + beta * (d * p).sum(axis=1) / sp
        wide = entropy > target  # too flat: narrow the kernel
        lo = np.where(wide, beta, lo)
        hi = np.where(wide, hi, beta)
        beta = np.where(np.isinf(hi), beta * 2.0, 0.5 * (lo + hi))
    return p / sp[:, None]


def tsne_small(data: np.ndarray, perplexity: float, n_iter: int = 500) -> np.ndarray:
    """Exact 2-D t-SNE (van der Maaten & Hinton 2008) for the few dozen features of a template.

    scikit-learn's TSNE takes about half a second per call whatever the size, which over a
    thousand templates would make training take many minutes; for 63 points the exact
    gradient is a 63 x 63 array operation, so this version takes milliseconds. It follows the
    reference optimiser: early exaggeration 12 for 250 iterations, momentum 0.5 then 0.8,
    adaptive gains, and a PCA initialisation, which also makes it deterministic.
    """
    x = np.asarray(data, dtype=np.float64)
    n = len(x)
    x = x - x.mean(axis=0)
    d2 = np.sum((x[:, None] - x[None]) ** 2, axis=-1)
    d2 /= max(float(np.median(d2)), 1e-12)
    p = _row_affinities(d2, perplexity)
    p = np.maximum((p + p.T) / (2.0 * n), 1e-12)
    _, _, vt = np.linalg.svd(x, full_matrices=False)
    y = x @ vt[:2].T
    y *= 1e-4 / max(float(np.std(y[:, 0])), 1e-12)
    lr = max(n / 12.0 / 4.0, 50.0)
    velocity, gains = np.zeros_like(y), np.ones_like(y)
    for it in range(n_iter):
        exaggeration, momentum = (12.0, 0.5) if it < 250 else (1.0, 0.8)
        sq = np.sum(y**2, axis=1)
        num = 1.0 / (1.0 + np.maximum(sq[:, None] + sq[None] - 2.0 * y @ y.T, 0.0))
        np.fill_diagonal(num, 0.0)
        q = np.maximum(num / num.sum(), 1e-12)
        w = (exaggeration * p - q) * num
        grad = 4.0 * (w.sum(axis=1)[:, None] * y - w @ y)
        same = np.sign(grad) == np.sign(velocity)
        gains = np.maximum(np.where(same, gains * 0.8, gains + 0.2), 0.01)
        velocity = momentum * velocity - lr * gains * grad
        y = y + velocity
    return y


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
        data = tsne_small(feature_descriptor(features), perplexity)
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
