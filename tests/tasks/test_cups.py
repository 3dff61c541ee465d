"""rules/cups.soar and the cup samples: known plans, ours == the real kernel == a reference of
the documented search, labels from the true poses, samples built from estimated poses."""

from __future__ import annotations

import re

import numpy as np
import pytest

from sann.fusion import logical_item
from sann.tasks.cups import (
    CUP_NAMES,
    FEATURE_NAMES,
    CupPlanner,
    CupScene,
    CupsDataParams,
    build_split,
    detections_from_array,
    label_detections,
    make_dataset,
    observe_pile,
    parse_sequence,
    pile_spec,
    plan_cups,
)
from sann.vision.camera import axis_angle, make_pose, rotation_to
from sann.vision.detect import Detection
from sann.vision.piles import make_pile

#: The quick experiment's small view sphere: trained once, then loaded from the cache.
PARAMS = CupsDataParams(templates={"tilt_step_deg": 20.0, "distances_mm": (630.0,)})


def _scene(n: int, over_pairs: list[tuple[int, int]], on_pairs: tuple = ()) -> CupScene:
    over = np.zeros((n, n), dtype=bool)
    on = np.zeros((n, n), dtype=bool)
    for a, b in over_pairs:
        over[a, b] = True
    for a, b in on_pairs:
        on[a, b] = over[a, b] = True
    pos = np.column_stack([np.arange(n) * 100.0, np.zeros(n), np.full(n, 60.0)])
    return CupScene(pos, np.tile([0.0, 0.0, 1.0], (n, 1)), np.full(n, 90.0), over, on)


def _texts(plans: dict) -> dict[str, list[str]]:
    return {CUP_NAMES[t]: [f"{s.t_o}:{s.order}" for s in seqs] for t, seqs in plans.items()}


def _reference(scene: CupScene, target: int) -> list[str]:
    """The plans of the search the rule file's header documents, in plain Python: a depth-first
    search through every branch of every tie (free cups over the same cup as the first free
    cup), the first free cup elsewhere."""
    cover = scene.over | scene.on
    found: set[str] = set()

    def search(removed: frozenset, path: str) -> None:
        needed, covered, stack = {target}, set(), [target]
        while stack:
            x = stack.pop()
            for a in map(int, np.flatnonzero(cover[:, x])):
                if a in removed:
                    continue
                covered.add(x)
                if a not in needed:
                    needed.add(a)
                    stack.append(a)
        if target not in covered:
            found.add(f"{len(path) + 1}:{path}{CUP_NAMES[target]}")
            return
        free = sorted(x for x in needed if x != target and x not in covered)
        if not free:
            return  # a dead end: a cycle of the relations
        first = free[0]
        below = {x for x in needed if cover[first, x]}
        for c in free:
            if c == first or any(cover[c, x] for x in below):
                search(removed | {c}, path + CUP_NAMES[c])

    search(frozenset(), "")
    return sorted(found, key=lambda s: (int(s.split(":")[0]), s))


def _sml_or_skip() -> None:
    pytest.importorskip("soar_sml", reason="the real Soar kernel (soar-sml) is not installed")


# --------------------------------------------------------------------------- known plans


@pytest.mark.parametrize("engine", ["sann", "soar_sml"])
def test_plans_hand_built_pile(engine: str) -> None:
    if engine == "soar_sml":
        _sml_or_skip()
    # D rests on B, B lies over A, C lies over A; E stands alone. C and D lie over different
    # cups: their order is no choice, C (the lower index) goes first.
    scene = _scene(5, [(1, 0), (2, 0)], on_pairs=((3, 1),))
    assert _texts(plan_cups(scene, engine=engine)) == {
        "A": ["4:CDBA"],
        "B": ["2:DB"],
        "C": ["1:C"],
        "D": ["1:D"],
        "E": ["1:E"],
    }


@pytest.mark.parametrize("engine", ["sann", "soar_sml"])
def test_cups_over_the_same_cup_tie_and_every_order_is_found(engine: str) -> None:
    if engine == "soar_sml":
        _sml_or_skip()
    # B, C and D lie over A: which comes off A first is a real choice, and so on below.
    three = _texts(plan_cups(_scene(4, [(1, 0), (2, 0), (3, 0)]), targets=[0], engine=engine))
    assert three["A"] == ["4:BCDA", "4:BDCA", "4:CBDA", "4:CDBA", "4:DBCA", "4:DCBA"]
    # B and D over A, C on B: C and D lie over different cups, C goes first; then B and D
    # are both free on A, and which comes off first is a real choice.
    stack = _scene(4, [(1, 0), (3, 0)], on_pairs=((2, 1),))
    assert _texts(plan_cups(stack, targets=[0], engine=engine))["A"] == ["4:CBDA", "4:CDBA"]
    # two stacks over A (C on B, E on D): B and D are never free together, so no order is a
    # choice: one plan, the lower index first.
    stacks = _scene(5, [(1, 0), (3, 0)], on_pairs=((2, 1), (4, 3)))
    assert _texts(plan_cups(stacks, targets=[0], engine=engine))["A"] == ["5:CBEDA"]


def test_the_fusion_sum_counts_the_orders_found() -> None:
    plans = plan_cups(_scene(5, [(1, 0), (2, 0), (3, 0), (4, 0)]), targets=[0])[0]
    assert len(plans) == 24 and {s.t_o for s in plans} == {5}
    assert len({s.order for s in plans}) == 24
    assert logical_item(s.t_o for s in plans) == pytest.approx(24 * 0.5**4)


def test_cycle_is_a_dead_end_and_only_its_victims_fail() -> None:
    # A over B over C over A (estimated poses can do that), D over A, E alone under nothing
    scene = _scene(5, [(0, 1), (1, 2), (2, 0), (3, 0)])
    plans = plan_cups(scene)
    assert all(plans[t] == [] for t in (0, 1, 2))
    assert logical_item(s.t_o for s in plans[0]) == 0.0
    assert _texts(plans)["D"] == ["1:D"] and _texts(plans)["E"] == ["1:E"]


@pytest.mark.parametrize("engine", ["sann", "soar_sml"])
def test_a_cycle_over_the_target_ends_the_search_without_a_plan(engine: str) -> None:
    """Runaway protection: seven free cups over a two-cup cycle could be taken in 7! orders,
    every one a dead end; a target whose needed cups hold a cycle gives up at once instead."""
    if engine == "soar_sml":
        _sml_or_skip()
    # B and C lie over each other, both over A; D..J all lie over B (they would tie).
    pairs = [(1, 0), (2, 0), (1, 2), (2, 1)] + [(k, 1) for k in range(3, 10)]
    scene = _scene(10, pairs)
    with CupPlanner(engine) as planner:
        plans, trace = planner.traced(scene)
    assert plans[0] == plans[1] == plans[2] == []
    assert all(_texts(plans)[CUP_NAMES[k]] == [f"1:{CUP_NAMES[k]}"] for k in range(3, 10))
    assert "(operator tie)" not in trace and trace.count("(give-up)") == 3
    decisions = [int(line.split(":")[0]) for line in trace.splitlines()
                 if line.strip()[:1].isdigit()]
    # per target: plan-target, its substate, one give-up or grasp; then finish
    assert "(finish)" in trace and max(decisions) == 3 * 10 + 1


@pytest.mark.parametrize("engine", ["sann", "soar_sml"])
def test_free_cups_over_a_cycle_elsewhere_are_still_planned(engine: str) -> None:
    """A cycle blocks only the targets that need a cup of it: E, over the cycle, and F, over
    the same cup D as E, are planned (and tie on D); D itself is not."""
    if engine == "soar_sml":
        _sml_or_skip()
    # A and B over each other, both over C; D over C too; E and F over D; G alone.
    scene = _scene(7, [(0, 1), (1, 0), (0, 2), (1, 2), (3, 2), (4, 3), (5, 3), (4, 0)])
    texts = _texts(plan_cups(scene, engine=engine))
    assert texts["A"] == texts["B"] == texts["C"] == []
    assert texts["D"] == ["3:EFD", "3:FED"]
    assert texts["E"] == ["1:E"] and texts["F"] == ["1:F"] and texts["G"] == ["1:G"]


def test_relations_from_true_poses_feed_the_plan() -> None:
    # A upright on the floor, B lying across A's lid, C upright far away
    a = make_pose(np.eye(3), np.array([0.0, 0.0, 60.0]))
    b = make_pose(rotation_to([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 120.0 + 43.6]))
    c = make_pose(np.eye(3), np.array([250.0, 0.0, 60.0]))
    scene = CupScene.from_world_poses(np.array([a, b, c]), [90.0, 85.0, 80.0])
    assert scene.over[1, 0] and scene.on[1, 0] and scene.over.sum() == 1
    assert _texts(plan_cups(scene)) == {"A": ["2:BA"], "B": ["1:B"], "C": ["1:C"]}


def test_planner_rejects_bad_input(tmp_path) -> None:
    scene = _scene(2, [(1, 0)])
    with pytest.raises(ValueError, match="not rows"):
        plan_cups(scene, targets=[2])
    with pytest.raises(ValueError, match="engine"):
        CupPlanner(engine="clips")
    with pytest.raises(ValueError, match="seed"):
        CupPlanner(seed=-1)
    with pytest.raises(ValueError, match="target:T_o:order"):
        parse_sequence("0:DA")
    with pytest.raises(ValueError, match="not found"):
        CupPlanner(rules=tmp_path / "missing.soar")
    with pytest.raises(ValueError, match="shape"):
        CupScene(np.zeros((2, 3)), np.zeros((2, 3)), np.zeros(3), np.zeros((2, 2), bool),
                 np.zeros((2, 2), bool))
    with pytest.raises(ValueError, match="itself"):
        CupScene(np.zeros((1, 3)), np.zeros((1, 3)), np.zeros(1), np.ones((1, 1), bool),
                 np.zeros((1, 1), bool))
    with pytest.raises(ValueError, match="0..10"):
        _scene(11, [])
    assert plan_cups(_scene(0, [])) == {}


# --------------------------------------------------------------------------- ours == kernel


def _estimated_scenes(n_piles: int = 5, per_pile: int = 10) -> list[CupScene]:
    """Pose sets as an estimator returns them: true pile poses moved by up to ~10 mm / 10 deg,
    some cups missed, rows in a random order; relations from those poses."""
    rng = np.random.default_rng(7)
    scenes = []
    for k in range(n_piles):
        pile = make_pile(int(rng.integers(5, 11)), 500 + k)
        for _ in range(per_pile):
            keep = rng.permutation(pile.n_cups)[: int(rng.integers(2, pile.n_cups + 1))]
            poses = []
            for pose in pile.poses[keep]:
                turn = axis_angle(rng.normal(size=3), np.radians(rng.uniform(0, 10)))
                poses.append(make_pose(turn @ pose[:3, :3],
                                       pose[:3, 3] + rng.normal(0.0, 5.0, size=3)))
            scenes.append(CupScene.from_world_poses(np.array(poses),
                                                    rng.uniform(70, 100, len(poses))))
    return scenes


def _random_relation_scenes(n: int = 20) -> list[CupScene]:
    """Arbitrary relations, cycles included: the rules must not depend on geometry."""
    rng = np.random.default_rng(11)
    out = []
    for _ in range(n):
        k = int(rng.integers(1, 11))
        over = rng.random((k, k)) < rng.uniform(0.05, 0.35)
        np.fill_diagonal(over, False)
        on = over & (rng.random((k, k)) < 0.5)
        out.append(CupScene(rng.normal(0, 100, (k, 3)), np.tile([0.0, 0.0, 1.0], (k, 1)),
                            rng.uniform(70, 100, k), over, on))
    return out


def test_rules_match_the_kernel_and_the_reference_on_estimated_poses() -> None:
    """Many estimated pose sets and arbitrary relations: ours == the kernel == the search the
    header documents, with ties searched on a good share of the targets."""
    _sml_or_skip()
    scenes = _estimated_scenes(8) + _random_relation_scenes(40)
    assert len(scenes) >= 100
    covered = tied = 0
    with CupPlanner("sann") as ours, CupPlanner("soar_sml") as kernel:
        for k, scene in enumerate(scenes):
            mine, theirs = ours.plan(scene), kernel.plan(scene)
            assert mine == theirs, k
            for t in range(scene.n):
                assert [f"{s.t_o}:{s.order}" for s in mine[t]] == _reference(scene, t), (k, t)
            covered += sum(1 for seqs in mine.values() if seqs and seqs[0].t_o > 1)
            tied += sum(1 for seqs in mine.values() if len(seqs) > 1)
    assert covered > 80 and tied > 15  # plenty of targets with cups over them, and of ties


def test_a_trace_of_a_pile_with_cups_over_the_target_has_ties_and_substates() -> None:
    """The watch-1 trace of a generated pile whose target has >= 2 cups over it: proposals,
    an operator no-change substate, a tie impasse and its evaluations, in both engines."""
    _sml_or_skip()
    scene, target = next((s, t) for s in _estimated_scenes() for t in range(s.n)
                         if s.over[:, t].sum() >= 2 and len(_reference(s, t)) > 1)
    with CupPlanner("sann") as ours, CupPlanner("soar_sml") as kernel:
        ours_plans, ours_trace = ours.traced(scene, [target])
        kernel_plans, kernel_trace = kernel.traced(scene, [target])
    assert ours_plans == kernel_plans and len(ours_plans[target]) > 1
    for trace in (ours_trace, kernel_trace):
        for shown in ("O: O1 (plan-target)", "(operator no-change)", "(operator tie)",
                      "(evaluate-operator)", "(grasp)", "(finish)"):
            assert shown in trace
    assert _shape(ours_trace) == _shape(kernel_trace)


def _shape(trace: str) -> str:
    """A watch-1 trace without the numbers of its identifiers."""
    return re.sub(r"\b([OSC])\d+\b", r"\1", trace)


def test_the_seed_changes_the_picks_not_the_plans() -> None:
    scene = _scene(5, [(1, 0), (2, 0), (3, 0)], on_pairs=((4, 1),))
    runs = {}
    for seed in (0, 0, 1, 7):
        with CupPlanner(seed=seed) as planner:
            runs.setdefault(seed, []).append(planner.traced(scene))
    assert runs[0][0] == runs[0][1]
    assert all(run[0][0] == runs[0][0][0] for run in (runs[1], runs[7]))


# --------------------------------------------------------------------------- labels


def _det(position, axis, score=90.0) -> Detection:
    return Detection(np.asarray(position, float), rotation_to(axis), score)


def test_labels_come_from_the_matched_true_cup() -> None:
    true = np.array([make_pose(np.eye(3), np.array([0.0, 0.0, 600.0])),
                     make_pose(np.eye(3), np.array([200.0, 0.0, 600.0]))])
    graspable = np.array([True, False])
    dets = [
        _det([1.0, 2.0, 601.0], [0, 0, 1]),  # cup 0, graspable
        _det([200.0, 5.0, 600.0], [0, 0.1, 1]),  # cup 1, blocked
        _det([40.0, 0.0, 600.0], [0, 0, 1]),  # 40 mm off: no cup
        _det([0.0, 0.0, 600.0], [0, 0, -1]),  # cup 0 turned end over end: no cup (and a dup)
    ]
    matched, labels = label_detections(dets, true, graspable)
    assert matched.tolist() == [0, 1, -1, -1]
    assert labels.tolist() == [1, 0, 0, 0]
    loose, _ = label_detections(dets[2:3], true, graspable, match_mm=50.0)
    assert loose.tolist() == [0]
    with pytest.raises(ValueError, match="labels for"):
        label_detections(dets, true, graspable[:1])


# --------------------------------------------------------------------------- samples


@pytest.fixture(scope="module")
def planner():
    with CupPlanner() as p:
        yield p


@pytest.fixture(scope="module")
def observed(planner):
    n, pile_seed, noise_seed = pile_spec(0, "test", 3, PARAMS)
    pile = make_pile(n, pile_seed)
    return pile, observe_pile(pile, PARAMS.camera(), PARAMS, planner, noise_seed,
                              ("patch", "linemod"))


def test_observe_pile_uses_estimated_poses(observed) -> None:
    pile, obs = observed
    camera = PARAMS.camera()
    dets = detections_from_array(obs.pose_array)
    assert 1 <= obs.n_detections == len(dets) <= pile.n_cups
    assert np.all(obs.pose_array[obs.n_detections:] == 0)
    # the rules' scene is the detections moved to the world frame, not the true poses
    for det, pos in zip(dets, obs.scene.positions, strict=True):
        assert np.allclose(camera.pose[:3, :3] @ det.position_mm + camera.pose[:3, 3], pos)
    assert not any(np.allclose(obs.scene.positions[0], c) for c in pile.centres)
    cam_true = camera.world_to_camera @ pile.poses
    matched, labels = label_detections(dets, cam_true, obs.true_graspable)
    assert np.array_equal(matched, obs.matched) and np.array_equal(labels, obs.labels)
    assert obs.labels.sum() <= obs.true_graspable.sum()
    for plans, value in zip(obs.plans, obs.logical, strict=True):
        t_os = [int(p.split(":")[0]) for p in plans.split()]
        assert value == pytest.approx(logical_item(t_os))
    assert set(obs.scores) == {"patch", "linemod"}
    assert obs.scores["patch"].n_detections == obs.n_detections


def test_build_split_rows_and_determinism(planner) -> None:
    first = build_split("train", 1, 5, PARAMS, planner)
    again = build_split("train", 1, 5, PARAMS, planner)
    for key in first:
        if key.startswith("det_") and not key.endswith("errors"):
            assert np.array_equal(first[key][:, :4], again[key][:, :4])  # column 4: seconds
        elif key != "seconds":
            assert np.array_equal(first[key], again[key]), key
    X, target, image = first["X"], first["target"], first["image"]
    assert X.shape == (len(first["y"]), len(FEATURE_NAMES)) == (len(target), 131)
    for row, t, i in zip(X, target, image, strict=True):
        assert np.array_equal(row[:130], first["poses"][i].ravel().astype(np.float32))
        assert row[130] == t < first["frames"][i, 1]
    assert np.all(image == 0) and len(image) == first["frames"][0, 1] > 0
    assert set(np.unique(first["y"])) <= {0, 1}
    assert first["det_patch"].shape == (1, 5)


def test_make_dataset_caches_and_regenerates_frames(tmp_path, monkeypatch) -> None:
    from sann import cache

    monkeypatch.setattr(cache, "cache_dir", lambda: tmp_path)  # datasets only, not templates
    ds = make_dataset(1, 1, seed=3, params=PARAMS)
    assert ds.meta["cache_hit"] == {"train": False, "test": False}
    hit = make_dataset(1, 1, seed=3, params=PARAMS)
    assert hit.meta["cache_hit"] == {"train": True, "test": True}
    assert np.array_equal(ds.X_train, hit.X_train) and np.array_equal(ds.y_test, hit.y_test)
    assert set(ds.detection_test) == {"patch", "linemod"} and set(ds.detection_train) == {"patch"}
    assert np.all(ds.image_test == 1) and np.all(ds.image_train == 0)
    pile, clean, seen = ds.frame(1)
    assert pile.n_cups == ds.frames_test[0, 0]
    assert seen.depth_mm.shape == clean.depth_mm.shape == (480, 640)
    with pytest.raises(ValueError, match="not a frame"):
        ds.pile(2)
    with pytest.raises(ValueError, match="positive integer"):
        make_dataset(0, 1)
    with pytest.raises(ValueError, match="min_cups"):
        CupsDataParams(min_cups=5, max_cups=3)


def test_cache_key_follows_the_vision_code_not_its_prose() -> None:
    from sann.tasks.cups import _code_dump, vision_sha256

    plain = _code_dump("def f(x):\n    return x + 1\n")
    documented = '"""Module."""\ndef f(x):\n    """Doc."""\n    return x + 1  # note\n'
    assert _code_dump(documented) == plain
    assert _code_dump("def f(x):\n    return x + 2\n") != plain
    assert vision_sha256() == vision_sha256()
