"""Cup piles from MuJoCo: inside the box, at rest, without interpenetration, deterministic."""

import numpy as np
import pytest

from sann.vision.camera import make_pose
from sann.vision.piles import (
    Box,
    DropParams,
    Pile,
    cup_in_box,
    interpenetration,
    make_pile,
    resimulate,
)


@pytest.fixture(scope="module")
def piles():
    return [make_pile(n, seed) for n, seed in ((2, 0), (6, 1), (10, 2), (10, 3))]


def test_every_cup_settles_inside_the_box(piles):
    for pile in piles:
        assert pile.n_cups == pile.requested
        assert len(pile.kinds) == pile.n_cups
        for pose in pile.poses:
            assert cup_in_box(pose, pile.box)
            assert np.allclose(pose[:3, :3] @ pose[:3, :3].T, np.eye(3), atol=1e-6)
        # Resting on the floor or on other cups: the lowest cup centre is a cup radius up.
        assert pile.centres[:, 2].min() > 25.0


def test_piles_are_at_rest(piles):
    for pile in piles[1:3]:
        later = resimulate(pile, seconds=0.3)
        moved = np.linalg.norm(later[:, :3, 3] - pile.centres, axis=1)
        assert moved.max() < 3.0


def test_no_interpenetration(piles):
    for pile in piles:
        assert interpenetration(pile.poses) < 2.0


def test_interpenetration_detects_overlap():
    a = make_pose(np.eye(3), [0, 0, 60])
    b = make_pose(np.eye(3), [30, 0, 60])
    assert interpenetration(np.stack([a, b])) > 10.0


def test_deterministic_for_a_seed(piles):
    again = make_pile(6, 1)
    assert np.array_equal(again.poses, piles[1].poses) and again.kinds == piles[1].kinds
    other = make_pile(6, 2)
    assert not np.allclose(other.poses, again.poses)


def test_orientations_vary(piles):
    axes_z = np.concatenate([p.axes[:, 2] for p in piles])
    assert (axes_z > 0.9).any()  # upright
    assert (axes_z < -0.9).any()  # upside down
    assert (np.abs(axes_z) < 0.3).any()  # lying on the side


def test_box_contains():
    box = Box()
    assert box.contains(np.array([0.0, 0.0, 10.0]))
    assert not box.contains(np.array([box.length, 0.0, 10.0]))
    far = make_pose(np.eye(3), [box.length, 0, 60])
    assert not cup_in_box(far, box)


def test_bad_inputs():
    with pytest.raises(ValueError):
        make_pile(0, 1)
    with pytest.raises(ValueError):
        Box(length=-1)
    with pytest.raises(ValueError):
        make_pile(2, 0, params=DropParams(p_upright=0, p_side=0, p_upside_down=0))


def test_pile_round_trips_through_json(piles):
    import json

    pile = piles[1]
    again = Pile.from_dict(json.loads(json.dumps(pile.to_dict())))
    assert np.array_equal(again.poses, pile.poses) and again.box == pile.box
    assert again.kinds == pile.kinds and again.seed == pile.seed
