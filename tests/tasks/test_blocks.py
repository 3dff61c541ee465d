"""Scenes, features and labels of the block world."""

from __future__ import annotations

import numpy as np
import pytest

from sann.tasks.blocks import (
    FEATURE_NAMES,
    MODES,
    TABLE_SIZE,
    BlockWorldParams,
    features,
    generate_scene,
    graspable,
    neighbours,
    observe_scene,
    rests_on_matrix,
    scene_from_blocks,
)
from sann.tasks.blocks.world import _pair_free

N_RANDOM = 150


def _overlaps(scene) -> bool:
    lo, hi = scene.lo(), scene.hi()
    ov = np.minimum(hi[:, None], hi[None]) - np.maximum(lo[:, None], lo[None])
    hit = (ov > 1e-6).all(axis=2)
    np.fill_diagonal(hit, False)
    return bool(hit.any())


@pytest.mark.parametrize("mode", MODES)
def test_generator_invariants(mode: str) -> None:
    for seed in range(N_RANDOM):
        n = 1 + seed % 26
        scene = generate_scene(mode, n, seed)
        assert scene.n == n and len(set(scene.ids.tolist())) == n
        assert set(scene.size.tolist()) <= {5.0, 10.0}
        assert set(scene.color.tolist()) <= {1, 2, 3, 4}
        assert not _overlaps(scene), f"{mode} seed {seed}: blocks overlap"
        assert (rests_on_matrix(scene).sum(axis=0) <= 1).all()  # no block bridges two
        lo, hi = scene.lo(), scene.hi()
        assert (lo[:, :2] >= -1e-6).all() and (hi[:, :2] <= TABLE_SIZE + 1e-6).all()
        # every block rests on the table or on its support, centre over the support's top
        for i, sup in enumerate(scene.support):
            if sup < 0:
                assert lo[i, 2] == pytest.approx(0.0)
            else:
                assert lo[i, 2] == pytest.approx(hi[sup, 2])
                assert (np.abs(scene.centre[i, :2] - scene.centre[sup, :2])
                        <= scene.size[sup] / 2 + 1e-9).all()


def test_c1_nothing_stacked() -> None:
    for seed in range(N_RANDOM):
        scene = generate_scene("C1", 1 + seed % 26, seed)
        assert (scene.support == -1).all()
        assert np.allclose(scene.centre[:, 2], scene.size / 2)


def test_c1_has_touching_blocks() -> None:
    touching = sum(
        (neighbours(s, s.centre)[:, :4] > 0).any()
        for s in (generate_scene("C1", 20, seed) for seed in range(20))
    )
    assert touching >= 15


def test_c2_single_column_exactly_one_graspable() -> None:
    for seed in range(N_RANDOM):
        n = 1 + seed % 26
        scene = generate_scene("C2", n, seed)
        assert (scene.support == -1).sum() == 1
        labels = graspable(scene)
        assert labels.sum() == 1
        top = int(np.argmax(scene.centre[:, 2]))
        assert labels[top]


def test_c3_has_stacks_and_side_blockage() -> None:
    stacked = side = 0
    for seed in range(40):
        scene = generate_scene("C3", 16, seed)
        stacked += (scene.support >= 0).any()
        labels = graspable(scene)
        clear = ~rests_on_matrix(scene).any(axis=1)
        side += (clear & ~labels).any()  # clear but blocked from the sides
    assert stacked == 40
    assert side >= 20


@pytest.mark.parametrize("mode", MODES)
def test_seeds_reproduce(mode: str) -> None:
    a, b = generate_scene(mode, 17, 123), generate_scene(mode, 17, 123)
    c = generate_scene(mode, 17, 124)
    assert np.array_equal(a.centre, b.centre) and np.array_equal(a.ids, b.ids)
    assert not np.array_equal(a.centre, c.centre)
    fa, fb = observe_scene(a, 5).features, observe_scene(b, 5).features
    assert np.array_equal(fa, fb)


def test_bad_parameters() -> None:
    with pytest.raises(ValueError, match="1..26"):
        generate_scene("C1", 27, 0)
    with pytest.raises(ValueError, match="1..26"):
        generate_scene("C1", 0, 0)
    with pytest.raises(ValueError, match="C1, C2, C3"):
        generate_scene("C4", 5, 0)
    with pytest.raises(ValueError, match="sensor_noise"):
        BlockWorldParams(sensor_noise=-0.1)
    with pytest.raises(ValueError, match="min_blocks"):
        BlockWorldParams(min_blocks=10, max_blocks=5)
    with pytest.raises(ValueError, match="Generator"):
        generate_scene("C1", 3, "seed")


# --------------------------------------------------------------- hand-built scenes

# A row along x on the table: A | B C (B and C touch, A is 5 units away from B),
# D on top of C, E alone at the back.
ROW = [
    ("A", 10, (20, 50, 5), 1),
    ("B", 10, (35, 50, 5), 2),
    ("C", 10, (45, 50, 5), 3),
    ("D", 5, (46, 51, 12.5), 4),
    ("E", 5, (120, 125, 2.5), 1),
]


def test_labels_hand_built() -> None:
    scene = scene_from_blocks(ROW)
    labels = dict(zip(scene.names, graspable(scene).tolist(), strict=True))
    # A: free along x (5-unit gap >= finger width 2); B: touches C along x, but y is free;
    # C: D rests on it; D: on top, free all round; E: alone.
    assert labels == {"A": True, "B": True, "C": False, "D": True, "E": True}
    assert scene.support.tolist() == [-1, -1, -1, 2, -1]


def test_labels_side_pairs() -> None:
    # X is boxed in along x (L and R touch it); along y, F is 4 units away, B 1 unit.
    box = [
        ("X", 10, (50, 50, 5)), ("L", 10, (40, 50, 5)), ("R", 10, (60, 50, 5)),
        ("F", 10, (50, 36, 5)), ("B", 10, (50, 61, 5)),
    ]
    assert not graspable(scene_from_blocks(box))[scene_from_blocks(box).slot("X")]
    # move B 4 units away (exactly the finger width): the y pair is free
    box[-1] = ("B", 10, (50, 64, 5))
    scene = scene_from_blocks(box)
    assert graspable(scene)[scene.slot("X")]
    # 3 units: beyond the sensor's neighbour gap (Back feature 0), yet the fingers do not fit
    box[-1] = ("B", 10, (50, 63, 5))
    scene = scene_from_blocks(box)
    x = scene.slot("X")
    assert features(scene)[x, FEATURE_NAMES.index("Back")] == 0
    assert not graspable(scene)[x]
    # narrower fingers fit through the 3-unit gap
    assert graspable(scene, BlockWorldParams(gripper_finger_width=3.0))[x]
    assert not graspable(scene, BlockWorldParams(gripper_finger_width=3.5))[x]


def test_hidden_blockage_is_frequent_in_c3() -> None:
    """The point of the clearance > neighbour gap: in C3 a few per cent of the blocks look free
    by their own features (Up = 0 and a side pair with no neighbour) but are not graspable."""
    hidden = total = 0
    for seed in range(60):
        scene = generate_scene("C3", 2 + seed % 25, seed)
        f, labels = features(scene), graspable(scene)
        col = {name: f[:, FEATURE_NAMES.index(name)] for name in FEATURE_NAMES}
        looks_free = (col["Up"] == 0) & (((col["Left"] == 0) & (col["Right"] == 0))
                                          | ((col["Front"] == 0) & (col["Back"] == 0)))
        hidden += int((looks_free & ~labels).sum())
        total += scene.n
    assert 0.01 <= hidden / total <= 0.1


def test_label_overhang_and_finger_pads() -> None:
    # a 10-block centred on a 5-block overhangs it: the 5-block is covered. C stands beside the
    # column under the overhang: the overhang is above C's height, so C's x fingers fit.
    scene = scene_from_blocks([
        ("A", 5, (50, 50, 2.5)), ("B", 10, (50, 50, 10)), ("C", 5, (42, 50, 2.5)),
    ])
    labels = dict(zip(scene.names, graspable(scene).tolist(), strict=True))
    assert labels == {"A": False, "B": True, "C": True}
    assert _pair_free(scene, 0, 2.0)[scene.slot("C")]
    # E touches C's left face, D its back face: both pairs blocked
    walled = scene_from_blocks([
        ("A", 5, (50, 50, 2.5)), ("B", 10, (50, 50, 10)), ("C", 5, (42, 50, 2.5)),
        ("D", 5, (42, 55, 2.5)), ("E", 5, (37, 50, 2.5)),
    ])
    assert not graspable(walled)[walled.slot("C")]
    # a corner grazing the finger slab by less than the pad margin does not block it
    grazed = scene_from_blocks([
        ("A", 10, (50, 50, 5)), ("B", 10, (61, 59.5, 5)), ("C", 10, (39, 40.5, 5)),
        ("D", 10, (50, 61, 5)), ("E", 10, (50, 39, 5)),
    ])
    assert _pair_free(grazed, 0, 2.0, 1.0)[0] and not _pair_free(grazed, 0, 2.0, 0.0)[0]
    assert graspable(grazed)[0]


def test_features_hand_built() -> None:
    scene = scene_from_blocks(ROW)
    f = features(scene)  # true positions
    assert f.shape == (5, 13) and len(FEATURE_NAMES) == 13
    row = {name: dict(zip(FEATURE_NAMES, f[i].tolist(), strict=True))
           for i, name in enumerate(scene.names)}
    assert row["A"]["X"] == 20 and row["A"]["Z"] == 5 and row["A"]["Target"] == 1
    assert row["A"]["Distance"] == pytest.approx(np.hypot(np.hypot(45, 50), 5))
    assert row["E"]["Distance"] == 130  # clipped
    assert row["A"]["Right"] == 0  # 5 units away: beyond the neighbour gap
    assert row["B"]["Right"] == 3 and row["C"]["Left"] == 2
    assert row["C"]["Up"] == 4 and row["D"]["Down"] == 3 and row["D"]["Up"] == 0
    assert row["D"]["Left"] == 0  # D sits above B's top: no z overlap
    assert row["C"]["Color"] == 3 and row["D"]["Size"] == 5


def test_features_noise_is_small_and_seeded() -> None:
    scene = scene_from_blocks(ROW)
    o1, o2 = observe_scene(scene, 1), observe_scene(scene, 1)
    assert np.array_equal(o1.features, o2.features)
    assert np.abs(o1.features[:, :3] - scene.centre).max() < 2.0
    assert np.array_equal(o1.features[:, 7:], features(scene)[:, 7:])  # relations survive
    exact = observe_scene(scene, 1, BlockWorldParams(sensor_noise=0.0))
    assert np.array_equal(exact.features, features(scene))


# --------------------------------------------------------------- datasets


@pytest.fixture()
def tmp_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("SANN_CACHE", str(tmp_path))
    return tmp_path


def test_d1_dataset(tmp_cache) -> None:
    from sann.fusion import logical_item
    from sann.tasks.blocks import make_dataset

    d = make_dataset("D1", "C3", n_train=120, n_test=40, seed=1)
    assert d.X_train.shape == (120, 14) and d.X_test.shape == (40, 14)
    assert d.X_train.dtype == np.float32 and d.y_train.dtype == np.int64
    assert d.logical_train.dtype == np.float32 and d.logical_test.shape == (40,)
    assert d.feature_names == [*FEATURE_NAMES, "Image"]
    assert np.array_equal(d.X_train[:, 13], d.image_train)
    assert set(d.image_train) .isdisjoint(set(d.image_test))  # scenes do not straddle
    assert 0 < d.y_train.mean() < 1
    # the fusion column is eq. 2 over the recorded plans
    for text, value in zip(d.plans_test, d.logical_test, strict=True):
        t_o = [int(p.split(":")[1]) for p in text.split()]
        assert value == pytest.approx(logical_item(t_o))
    # a regenerated test scene is the one the samples came from
    image = int(d.image_test[0])
    scene = d.scene(image)
    rows = d.X_test[d.image_test == image]
    assert sorted(rows[:, 6].astype(int).tolist()) == scene.ids.tolist()
    assert np.array_equal(graspable(scene)[np.searchsorted(scene.ids, rows[:, 6].astype(int))],
                          d.y_test[d.image_test == image].astype(bool))
    last = int(d.image_train[-1])  # the last scene of a split is cut to the samples missing
    assert d.scene(last).n == int((d.image_train == last).sum())
    assert d.meta["rules_sha256"] and d.meta["train_samples"] == 120
    assert not d.meta["cache_hit"]


def test_d2_dataset(tmp_cache) -> None:
    from sann.tasks.blocks import make_dataset

    d = make_dataset("D2", "C2", n_train=60, n_test=20, seed=2)
    assert d.X_train.shape == (60, 26 * 13 + 1) and len(d.feature_names) == 339
    assert d.meta["train_scenes"] == 60
    # balanced by construction where scenes allow (C2 always has a graspable top)
    assert 0.25 < d.y_train.mean() < 0.75
    x = d.X_test[0]
    target = int(x[-1])
    rows = x[:-1].reshape(26, 13)
    present = rows[:, 6] > 0
    assert (rows[present, 6] == np.flatnonzero(present) + 1).all()  # row k is block id k+1
    assert not rows[~present].any()  # padding is zeros
    assert present[target - 1]


def test_dataset_determinism_and_cache(tmp_cache) -> None:
    from sann.tasks.blocks import make_dataset

    a = make_dataset("D1", "C1", n_train=50, n_test=20, seed=7)
    b = make_dataset("D1", "C1", n_train=50, n_test=20, seed=7)
    c = make_dataset("D1", "C1", n_train=50, n_test=20, seed=7, use_cache=False)
    assert b.meta["cache_hit"] and not c.meta["cache_hit"]
    for name in ("X_train", "logical_train", "y_train", "X_test", "logical_test", "y_test"):
        assert np.array_equal(getattr(a, name), getattr(b, name))
        assert np.array_equal(getattr(a, name), getattr(c, name))
    assert a.plans_test.tolist() == c.plans_test.tolist()
    d = make_dataset("D1", "C1", n_train=50, n_test=20, seed=7, use_cache=False, workers=2)
    assert np.array_equal(a.X_train, d.X_train) and np.array_equal(a.logical_test, d.logical_test)
    other = make_dataset("D1", "C1", n_train=50, n_test=20, seed=8)
    assert not np.array_equal(a.X_train, other.X_train)


def test_dataset_bad_parameters(tmp_cache) -> None:
    from sann.tasks.blocks import make_dataset

    with pytest.raises(ValueError, match="C1, C2, C3"):
        make_dataset("D1", "C4")
    with pytest.raises(ValueError, match="kind"):
        make_dataset("D3", "C1")
    with pytest.raises(ValueError, match="n_train"):
        make_dataset("D1", "C1", n_train=0)
    with pytest.raises(ValueError, match="n_test"):
        make_dataset("D1", "C1", n_test=-5)
    with pytest.raises(ValueError, match="max_blocks"):
        make_dataset("D1", "C1", params=BlockWorldParams(max_blocks=27))
    with pytest.raises(ValueError, match="sensor_noise"):
        make_dataset("D1", "C1", params=BlockWorldParams(sensor_noise=-1.0))
    with pytest.raises(ValueError, match="engine"):
        make_dataset("D1", "C1", engine="clips")
    with pytest.raises(ValueError, match="workers"):
        make_dataset("D1", "C1", workers=0)
    assert not list(tmp_cache.iterdir())
