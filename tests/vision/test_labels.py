"""Labels on hand-built piles: relations, corridor, reachability, visibility."""

import numpy as np
import pytest

from sann.vision.camera import Camera, default_camera, look_at, make_pose, rotation_to
from sann.vision.labels import (
    LabelParams,
    cup_relations,
    graspability,
    label_pile,
    visible_fractions,
)
from sann.vision.piles import Box, interpenetration, make_pile

UPRIGHT = np.eye(3)


def _lying(yaw: float = 0.0) -> np.ndarray:
    return rotation_to([np.cos(yaw), np.sin(yaw), 0.0])


def _cup_lying_on_an_upright_cup() -> np.ndarray:
    lower = make_pose(UPRIGHT, [0, 0, 60])
    # The lying cup rests on the lower cup's lid (top at z = 120), a 1 mm gap at the closest.
    upper = make_pose(_lying(), [0, 0, 120 + 40])
    return np.stack([lower, upper])


def test_hand_built_pile_is_physically_sound():
    assert interpenetration(_cup_lying_on_an_upright_cup()) < 1.0


def test_one_cup_on_another():
    poses = _cup_lying_on_an_upright_cup()
    rel = cup_relations(poses)
    assert rel.pairs("on") == [(1, 0)] and rel.pairs("over") == [(1, 0)]
    assert 0.0 <= rel.gap[1, 0] <= 2.0 and np.isinf(rel.gap[0, 1])
    labels = graspability(poses, visible_fraction=np.ones(2), box=Box())
    assert labels.free.tolist() == [False, True]
    assert labels.graspable.tolist() == [False, True]
    assert labels.blockers == ((1,), ())


def test_over_but_not_on():
    poses = _cup_lying_on_an_upright_cup()
    poses[1, 2, 3] += 40.0  # lifted: still over, no longer touching
    rel = cup_relations(poses)
    assert rel.pairs("over") == [(1, 0)] and rel.pairs("on") == []
    assert rel.gap[1, 0] == pytest.approx(40.0, abs=3.0)


def test_cups_side_by_side_are_independent():
    for gap in (0.5, 3.0):  # rims touching, almost
        poses = np.stack([make_pose(UPRIGHT, [-43.5 - gap / 2, 0, 60]),
                          make_pose(UPRIGHT, [43.5 + gap / 2, 0, 60])])
        rel = cup_relations(poses)
        assert not rel.over.any()
        labels = graspability(poses, np.ones(2), box=Box())
        assert labels.graspable.all()
    lying = np.stack([make_pose(_lying(), [0, -40, 38]), make_pose(_lying(np.pi), [0, 40, 38])])
    assert not cup_relations(lying).over.any()


def test_a_taller_neighbour_overhanging_blocks_the_corridor():
    lying = make_pose(_lying(np.pi / 2), [0, 0, 38])
    # An upright cup beside it whose lid rim reaches over the lying cup's flank.
    upright = make_pose(UPRIGHT, [75, 0, 60])
    assert interpenetration(np.stack([lying, upright])) < 1.0
    labels = graspability(np.stack([lying, upright]), np.ones(2), box=Box())
    assert labels.free.tolist() == [False, True]


def test_estimated_overlapping_poses_give_one_direction():
    poses = _cup_lying_on_an_upright_cup()
    poses[1, 2, 3] -= 8.0  # an estimate that sinks the upper cup into the lower one
    rel = cup_relations(poses, LabelParams(over_tolerance_mm=15.0))
    assert rel.pairs("over") == [(1, 0)]


def test_reachable_and_visible():
    box = Box()
    inside = make_pose(UPRIGHT, [0, 0, 60])
    outside = make_pose(UPRIGHT, [box.length, 0, 60])
    labels = graspability(np.stack([inside, outside]), np.array([0.9, 0.2]), box=box)
    assert labels.reachable.tolist() == [True, False]
    assert labels.visible.tolist() == [True, False]
    assert labels.graspable.tolist() == [True, False]
    too_high = make_pose(UPRIGHT, [0, 0, 400])
    assert not graspability(too_high[None], np.ones(1), box=None).reachable[0]
    with pytest.raises(ValueError):
        graspability(np.stack([inside, outside]), np.ones(3), box=box)


def test_visible_fractions():
    cam = Camera(pose=look_at([0, 0, 700], [0, 0, 0]))
    poses = _cup_lying_on_an_upright_cup()
    frac = visible_fractions(poses, cam, box=Box())
    assert frac[1] == pytest.approx(1.0)
    assert 0.0 < frac[0] < 0.6  # the lying cup hides most of the lower cup's lid
    alone = visible_fractions(poses[:1], cam, box=Box())
    assert alone[0] == pytest.approx(1.0)


def test_label_a_dropped_pile():
    pile = make_pile(8, 4)
    labels = label_pile(pile, default_camera())
    g = labels.grasp
    assert g.graspable.any()  # the topmost cup is always free
    top = int(np.argmax(pile.centres[:, 2]))
    assert g.free[top]
    # A cup that another rests on is never free.
    for upper, lower in labels.relations.pairs("on"):
        assert not g.free[lower] and upper in g.blockers[lower]
    assert np.all((g.visible_fraction >= 0) & (g.visible_fraction <= 1.0 + 1e-9))


def test_bad_input():
    with pytest.raises(ValueError):
        cup_relations(np.zeros((2, 3, 3)))
    with pytest.raises(ValueError):
        LabelParams(min_visible_fraction=2.0)
