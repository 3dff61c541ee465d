"""Patch-LineMod: feature clustering, LineMod's responses recomputed, the activity rule."""

import cv2
import numpy as np
import pytest

from sann.vision.patch_linemod import (
    MAX_RESPONSE,
    PatchRule,
    accept_candidate,
    cluster_features,
    feature_responses,
    patch_activity,
    spread,
)


def _blobs(seed=0):
    """Features in three well separated groups of 20, with random orientations."""
    rng = np.random.default_rng(seed)
    centres = np.array([[10, 10], [80, 15], [40, 90]])
    xy = np.vstack([c + rng.integers(-5, 6, (20, 2)) for c in centres])
    return np.hstack([xy, rng.integers(0, 8, (60, 1))]).astype(np.int32)


@pytest.mark.parametrize("method", ["kmeans", "tsne+kmeans"])
def test_clustering_shapes_and_determinism(method):
    feats = _blobs()
    labels = cluster_features(feats, 3, method, seed=5)
    assert labels.shape == (60,) and labels.dtype == np.int32
    assert set(labels.tolist()) == {0, 1, 2}
    assert np.array_equal(labels, cluster_features(feats, 3, method, seed=5))
    assert labels[0] == 0  # renumbered by first appearance


def test_kmeans_patches_are_spatial_groups():
    labels = cluster_features(_blobs(), 3, "kmeans")
    for g in range(3):
        assert len(set(labels[20 * g: 20 * (g + 1)].tolist())) == 1


def test_clustering_rejects_bad_input():
    with pytest.raises(ValueError):
        cluster_features(_blobs()[:2], 3)
    with pytest.raises(ValueError):
        cluster_features(_blobs(), 3, "dbscan")
    with pytest.raises(ValueError):
        cluster_features(np.zeros((10, 2)), 3)


def test_spread_ors_the_block_below_right():
    q = np.zeros((20, 20), dtype=np.uint8)
    q[10, 10] = 4
    s = spread(q, 5)
    ys, xs = np.nonzero(s)
    assert set(ys.tolist()) == set(range(6, 11)) and set(xs.tolist()) == set(range(6, 11))
    assert np.all(s[ys, xs] == 4)


def test_similarity_table_and_bounds():
    img = np.zeros((10, 10), dtype=np.uint8)
    img[2, 3] = 1 << 5  # orientation 5
    feats = np.array([[3, 2, 5], [3, 2, 4], [3, 2, 6], [3, 2, 1], [3, 2, -1]])
    assert feature_responses(img, feats, [[0, 0]]).tolist() == [[4, 3, 3, 0, 0]]
    assert feature_responses(img, feats[:1], [[20, 0], [-5, 0]]).tolist() == [[0], [0]]
    # Orientation 0 and 7 are neighbours: the circle closes.
    img[2, 3] = 1 << 7
    assert feature_responses(img, np.array([[3, 2, 0]]), [[0, 0]]).tolist() == [[3]]


def test_responses_reproduce_opencv_similarity():
    """Our per-feature responses, summed, give the score cv2.linemod reports.

    Exactly in most cases; OpenCV's local refinement sometimes scores one feature one unit
    differently (its linear memories read a neighbouring grid cell), so one unit is allowed.
    """
    h, w = 240, 320
    yy, xx = np.mgrid[:h, :w]

    def disc(cx, cy, rad, angle):
        r = np.hypot(xx - cx, yy - cy)
        depth = np.where(r < rad, 700 - np.sqrt(np.maximum(rad**2 - r**2, 0)), 0)
        rgb = np.zeros((h, w, 3), np.uint8)
        rgb[r < rad] = (200, 180, 50)
        rgb[r < rad / 2] = (20, 40, 200)
        stripe = np.abs((xx - cx) * np.cos(angle) + (yy - cy) * np.sin(angle)) < 5
        rgb[stripe & (r < rad)] = (0, 255, 0)
        return rgb, depth.astype(np.uint16), (r < rad).astype(np.uint8) * 255

    det = cv2.linemod.getDefaultLINEMOD()
    rgb, depth, mask = disc(120, 110, 50, 0.0)
    assert det.addTemplate([rgb, depth], "c", mask)[0] == 0
    templ = det.getTemplates("c", 0)
    checked, exact = 0, 0
    for rad, angle in [(44, 0.0), (55, 0.0), (47, 0.6)]:
        rgb, depth, _ = disc(170, 130, rad, angle)
        matches, quantized = det.match([rgb, depth], 30.0)
        for m in matches[:2]:
            total, count = 0.0, 0
            for k in range(2):
                feats = np.array([(f.x, f.y, f.label) for f in templ[k].features])
                # LineMod reports positions 2 px (T=5) right of/below the evaluated corner.
                resp = feature_responses(spread(quantized[k], 5), feats, [[m.x - 2, m.y - 2]])
                total, count = total + resp.sum(), count + len(feats)
            unit = 100.0 / (MAX_RESPONSE * count)
            ours = 100.0 * total / (MAX_RESPONSE * count)
            assert ours == pytest.approx(m.similarity, abs=unit + 1e-3)
            exact += abs(ours - m.similarity) < 1e-3
            checked += 1
    assert checked >= 3 and exact >= checked - 1


def _responses(patch_means, per_patch=4):
    """Hand-built responses: each patch's features alternate to give the wanted mean."""
    labels = np.repeat(np.arange(len(patch_means)), per_patch)
    return np.repeat(np.asarray(patch_means, float), per_patch)[None], labels


def test_a_patch_is_active_only_above_70_percent_of_its_maximum():
    resp, labels = _responses([4.0, 3.0, 2.8, 2.0, 0.0])
    active = patch_activity(resp, labels, 5, 0.7)
    assert active.tolist() == [[True, True, False, False, False]]  # 2.8 = 70%: not above


def test_activity_with_padding_and_per_candidate_labels():
    resp = np.array([[4.0, 4.0, 0.0, 0.0], [0.0, 4.0, 4.0, 4.0]])
    labels = np.array([[0, 0, 1, -1], [0, 1, 1, 2]])
    active = patch_activity(resp, labels, 3)
    assert active.tolist() == [[True, False, False], [False, True, True]]
    with pytest.raises(ValueError):
        patch_activity(resp, labels, 2)


@pytest.mark.parametrize(
    ("n_active_color", "n_active_depth", "n_patches", "score", "kept"),
    [
        (4, 4, 6, 80.0, True),  # 67% > 60% in both
        (4, 3, 6, 80.0, False),  # depth only 50%
        (3, 3, 5, 80.0, False),  # exactly 60% is not more than 60%
        (3, 3, 4, 80.0, True),  # 75% and 3 patches
        (2, 2, 3, 90.0, False),  # 67% but fewer than 3 patches
        (6, 6, 6, 70.0, False),  # score must exceed 70
        (6, 6, 6, 70.5, True),
    ],
)
def test_acceptance_rule(n_active_color, n_active_depth, n_patches, score, kept):
    color = (np.arange(n_patches) < n_active_color)[None]
    depth = (np.arange(n_patches) < n_active_depth)[None]
    assert accept_candidate(color, depth, np.array([score]), PatchRule()).tolist() == [kept]


def test_small_tsne_preserves_neighbourhoods_and_groups():
    from sklearn.manifold import trustworthiness

    from sann.vision.patch_linemod import tsne_small

    rng = np.random.default_rng(1)
    centres = np.array([[0, 0, 0, 0], [10, 0, 0, 0], [0, 10, 0, 0], [5, 5, 8, 0]])
    x = np.vstack([c + rng.normal(size=(16, 4)) for c in centres])
    y = tsne_small(x, 15.0)
    assert y.shape == (64, 2) and np.all(np.isfinite(y))
    assert trustworthiness(x, y, n_neighbors=5) > 0.95
    assert np.array_equal(y, tsne_small(x, 15.0))
    labels = cluster_features(_blobs(), 3, "tsne+kmeans")
    for g in range(3):
        assert len(set(labels[20 * g: 20 * (g + 1)].tolist())) == 1
