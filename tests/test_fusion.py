"""Fusion: eq. 3 per sequence, eq. 2 per sample, the M x (N+1) array."""

from __future__ import annotations

import numpy as np
import pytest

from sann.fusion import exceeds_one, fuse, logical_column, logical_item, sequence_probability
from sann.tasks.blocks import features, scene_from_blocks
from sann.tasks.planning import plan_scene, t_o_lists

ROW = [
    ("A", 10, (20, 50, 5)), ("B", 10, (35, 50, 5)), ("C", 10, (45, 50, 5)),
    ("D", 5, (46, 51, 12.5)), ("E", 5, (120, 125, 2.5)),
]


def test_eq3_halves_per_step_and_refuses_a_bad_t_o() -> None:
    assert sequence_probability(1) == 1.0
    assert sequence_probability(2) == 0.5
    assert sequence_probability(4) == 0.125
    assert sequence_probability(3, n_dr=3) == pytest.approx(1 / 9)
    for bad in (0, -1, 1.5, True):
        with pytest.raises(ValueError, match="T_o"):
            sequence_probability(bad)


def test_eq2_sums_the_probabilities_of_the_sequences() -> None:
    assert logical_item([]) == 0.0
    assert logical_item([1]) == 1.0
    assert logical_item([3, 3, 2]) == 1.0
    assert logical_item([1, 1]) == 2.0  # two sequences with the target first: above 1
    col = logical_column([[1, 1], [2], []])
    assert col.dtype == np.float32 and col.tolist() == [2.0, 0.5, 0.0]
    assert exceeds_one(col).tolist() == [True, False, False]


def test_fusion_on_hand_built_scene() -> None:
    scene = scene_from_blocks(ROW)
    t_o = t_o_lists(plan_scene(scene))
    col = logical_column([t_o[int(i)] for i in scene.ids])
    # A, D, E free on both pairs: 2 (the tie keeps both grasps); B free along y: grasped at
    # once, nothing else searched (1); C: D comes off, then C is free along y (1/2)
    assert col.tolist() == [2.0, 1.0, 0.5, 2.0, 2.0]
    fused = fuse(features(scene), col)
    assert fused.shape == (5, 14)
    assert np.array_equal(fused[:, :13], features(scene))
    assert np.array_equal(fused[:, 13], col)


def test_fuse_shapes_and_errors() -> None:
    x = np.ones((4, 3), dtype=np.float32)
    assert fuse(x, np.zeros((4, 1))).shape == (4, 4)
    assert fuse(x, np.zeros(4, dtype=np.float32)).dtype == np.float32
    with pytest.raises(ValueError, match="one value per sample"):
        fuse(x, np.zeros(3))
    with pytest.raises(ValueError, match="2-D"):
        fuse(np.zeros(4), np.zeros(4))
