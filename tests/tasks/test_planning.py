"""rules/blocks.soar through the planning driver: known plans, and ours == the real kernel."""

from __future__ import annotations

import re

import numpy as np
import pytest

from sann.fusion import logical_item
from sann.tasks.blocks import (
    FEATURE_NAMES,
    MODES,
    features,
    generate_scene,
    graspable,
    observe_scene,
    scene_from_blocks,
)
from sann.tasks.planning import (
    DEFAULT_HORIZON,
    Planner,
    PlannerConfig,
    parse_sequence,
    plan_scene,
    t_o_lists,
)

# A | B C (B and C touch along x, A is 5 units left of B), D on C, E alone.
ROW = [
    ("A", 10, (20, 50, 5)), ("B", 10, (35, 50, 5)), ("C", 10, (45, 50, 5)),
    ("D", 5, (46, 51, 12.5)), ("E", 5, (120, 125, 2.5)),
]
# a 3 x 3 grid of touching 10-blocks: every block is blocked on both side pairs
GRID = [(chr(ord("A") + 3 * i + j), 10, (40 + 10 * i, 40 + 10 * j, 5))
        for i in range(3) for j in range(3)]
# one column of five: A at the bottom, E on top
COLUMN = [(chr(ord("A") + k), 5, (60, 60, 2.5 + 5 * k)) for k in range(5)]


def _texts(plans: dict) -> dict[str, list[str]]:
    names = "ABCDEFGHIJKLMNOPQRSTUVWXYZ"
    return {names[t - 1]: [f"{s.pair}:{s.t_o}:{s.order}" for s in seqs]
            for t, seqs in plans.items()}


def _sml_or_skip() -> None:
    pytest.importorskip("soar_sml", reason="the real Soar kernel (soar-sml) is not installed")


@pytest.mark.parametrize("engine", ["sann", "soar_sml"])
def test_plans_hand_built_row(engine: str) -> None:
    if engine == "soar_sml":
        _sml_or_skip()
    plans = _texts(plan_scene(scene_from_blocks(ROW), engine=engine))
    assert plans == {
        "A": ["x:1:A", "y:1:A"],  # free along both pairs: the tie is searched, both plans kept
        "B": ["y:1:B"],  # free along y: grasping it now is best, nothing else is tried
        "C": ["y:2:DC"],  # D comes off first, then C is free along y
        "D": ["x:1:D", "y:1:D"],
        "E": ["x:1:E", "y:1:E"],
    }


def test_plans_grid_is_a_dead_end() -> None:
    plans = plan_scene(scene_from_blocks(GRID))
    assert all(seqs == [] for seqs in plans.values())
    assert logical_item(t_o_lists(plans)[5]) == 0.0


def test_column_and_horizon() -> None:
    scene = scene_from_blocks(COLUMN)
    plans = _texts(plan_scene(scene))
    assert plans["A"] == ["x:5:EDCBA", "y:5:EDCBA"]
    assert plans["E"] == ["x:1:E", "y:1:E"]
    short = _texts(plan_scene(scene, horizon=3))
    assert short["A"] == [] and short["B"] == [] and short["C"] == ["x:3:EDC", "y:3:EDC"]


# X in the middle, blockers around it on the table: A, B along x and C, D along y
CROSS = [("X", 10, (50, 50, 5)), ("A", 5, (42.5, 50, 2.5)), ("B", 5, (57.5, 50, 2.5)),
         ("C", 5, (50, 42.5, 2.5)), ("D", 5, (50, 57.5, 2.5))]


def test_the_search_finds_one_plan_per_side_pair() -> None:
    # which pair to free is the real choice (a tie); the order of the blockers is not (the
    # lower id is preferred), and E, on X, comes off first in every plan
    assert _texts(plan_scene(scene_from_blocks(CROSS), targets=[24]))["X"] == [
        "x:3:ABX", "y:3:CDX"]
    covered = CROSS + [("E", 5, (51, 51, 12.5))]
    assert _texts(plan_scene(scene_from_blocks(covered), targets=[24]))["X"] == [
        "x:4:EABX", "y:4:ECDX"]
    # the pairs cost differently: along x only A is in the way, along y C and D on C
    uneven = [("X", 10, (50, 50, 5)), ("A", 5, (42.5, 50, 2.5)), ("C", 10, (50, 40, 5)),
              ("D", 5, (50, 40, 12.5))]
    plans = plan_scene(scene_from_blocks(uneven), targets=[24])
    assert _texts(plans)["X"] == ["x:2:AX", "y:3:DCX"]
    assert logical_item(t_o_lists(plans)[24]) == 0.5 + 0.25
    # A and B 4 units apart (the finger width): each can be grasped, but X is free along y
    row = [("X", 10, (50, 50, 5)), ("A", 5, (42.5, 45.5, 2.5)), ("B", 5, (42.5, 54.5, 2.5)),
           ("C", 5, (57.5, 50, 2.5))]
    assert _texts(plan_scene(scene_from_blocks(row), targets=[24]))["X"] == ["y:1:X"]


def test_side_blockage_comes_from_the_observed_geometry() -> None:
    # 2 units apart: beyond the sensor's neighbour gap, yet A and B pin each other along y and
    # X along x; with C on the right the x pair is a dead end, so only y is planned
    pinned = scene_from_blocks([
        ("X", 10, (50, 50, 5)), ("A", 5, (42.5, 46.5, 2.5)), ("B", 5, (42.5, 53.5, 2.5)),
        ("C", 5, (57.5, 50, 2.5)), ("D", 5, (50, 42.5, 2.5)),
    ])
    feats = features(pinned)
    back, front = FEATURE_NAMES.index("Back"), FEATURE_NAMES.index("Front")
    assert feats[0, back] == feats[1, front] == 0  # the sensor does not list A and B
    assert _texts(plan_scene(feats, targets=[24]))["X"] == ["y:2:DX"]


def test_the_planner_sees_the_observation_not_the_truth() -> None:
    # B stands 4.1 units right of A: the fingers fit (the label says graspable), but the
    # observation puts B 0.2 closer, inside A's slab, and the planner, which sees only the
    # observation, has to clear B first along x (or C, which stands behind A, along y)
    scene = scene_from_blocks([("A", 10, (50, 50, 5)), ("B", 10, (64.1, 50, 5)),
                               ("C", 10, (50, 60, 5))])
    assert graspable(scene)[0]
    observed = scene.centre.copy()
    observed[1, 0] -= 0.2
    plans = _texts(plan_scene(features(scene, observed), targets=[1]))
    assert plans["A"] == ["x:2:BA", "y:2:CA"]
    assert _texts(plan_scene(scene, targets=[1]))["A"] == ["x:1:A"]


def _relations(agent) -> dict[str, dict[int, set[int]]]:
    """carries / xside / yside between block ids, as the rules elaborated them."""
    wmes = list(agent.wmes())
    ident = {w.id: int(str(w.value)) for w in wmes if str(w.attr) == "id"}
    rel: dict[str, dict[int, set[int]]] = {a: {i: set() for i in ident.values()}
                                           for a in ("carries", "xside", "yside")}
    for w in wmes:
        if str(w.attr) in rel:
            rel[str(w.attr)][ident[w.id]].add(ident[w.value])
    return rel


def _reference(rel: dict[str, dict[int, set[int]]], t: int, horizon: int) -> set[str]:
    """The plans a depth-first search over the same choices finds: every branch of every tie
    (the side pair to free; the pair to grasp a target free along both), the preferred grasp
    elsewhere (a block every plan needs before a side blocker, the lower id first)."""
    carries, side = rel["carries"], {"x": rel["xside"], "y": rel["yside"]}
    names = "ABCDEFGHIJKLMNOPQRSTUVWXYZ"
    found: set[str] = set()

    def blocked(n: int, sides: set[int], removed: frozenset) -> bool:
        return bool(sides - removed)

    def group(roots: set[int], removed: frozenset) -> set[int]:
        out, todo = set(), [c for c in roots if c not in removed]
        while todo:
            n = todo.pop()
            if n in out:
                continue
            out.add(n)
            todo += [c for c in carries[n] if c not in removed]
            if blocked(n, side["x"][n], removed) and blocked(n, side["y"][n], removed):
                for a in "xy":
                    if t not in side[a][n]:
                        todo += [c for c in side[a][n] if c not in removed]
        return out

    def search(removed: frozenset, path: str, aim: str | None) -> None:
        depth = len(path)
        free = [a for a in "xy" if not blocked(t, carries[t], removed)
                and not blocked(t, side[a][t], removed)]
        if free:
            found.update(f"{a}:{depth + 1}:{path}{names[t - 1]}" for a in free)
            return
        if depth > horizon - 2:
            return
        top = group(carries[t], removed)
        need = {a: group(side[a][t], removed) if aim in (None, a) else set() for a in "xy"}

        def can(n: int) -> bool:
            return not blocked(n, carries[n], removed) and not (
                blocked(n, side["x"][n], removed) and blocked(n, side["y"][n], removed))

        common = [n for n in top | (need["x"] & need["y"]) if can(n)]
        if common:
            n = min(common)
            search(removed | {n}, path + names[n - 1], aim)
            return
        for a in "xy":
            own = [n for n in need[a] - top - need["xy".replace(a, "")] if can(n)]
            if own:
                n = min(own)
                search(removed | {n}, path + names[n - 1], aim or a)

    search(frozenset(), "", None)
    return found


@pytest.mark.parametrize("mode", MODES)
def test_the_sequences_are_every_plan_the_search_reaches(mode: str) -> None:
    """R of eq. 2 counts the distinct resolutions: the planner's sequences are exactly the
    plans of a depth-first search through every tie, on random observed scenes."""
    ties = 0
    with Planner() as planner:
        for seed in range(25):
            scene = generate_scene(mode, 3 + seed % 10, seed)
            plans = planner.plan(observe_scene(scene, seed).features)
            rel = _relations(planner.agent)
            for t, seqs in plans.items():
                got = [f"{s.pair}:{s.t_o}:{s.order}" for s in seqs]
                assert len(set(got)) == len(got)
                assert set(got) == _reference(rel, t, DEFAULT_HORIZON), (mode, seed, t)
                ties += len(got) > 1
    assert ties > 0


def test_a_c3_trace_has_ties_and_substates_in_both_engines() -> None:
    """The watch-1 trace: operators, impasses, substates -- the same in both engines."""
    _sml_or_skip()
    feats = observe_scene(generate_scene("C3", 8, 3), 3).features
    with Planner(engine="sann") as ours, Planner(engine="soar_sml") as kernel:
        ours_plans, ours_trace = ours.traced(feats)
        kernel_plans, kernel_trace = kernel.traced(feats)
    assert ours_plans == kernel_plans
    assert ours_trace == kernel_trace
    for shown in ("O: O1 (plan-target)", "(operator no-change)", "(operator tie)",
                  "(evaluate-operator)", "(grasp)", "(finish)"):
        assert shown in ours_trace
    assert ours_trace.count("(operator tie)") >= 2


def test_runs_repeat_under_a_seed() -> None:
    """The seed picks among equally good grasps: the same seed, the same trace; another
    seed may pick otherwise, but the plans found are the same."""
    feats = observe_scene(generate_scene("C3", 10, 5), 5).features
    runs = {}
    for seed in (0, 0, 1, 7):
        with Planner(seed=seed) as planner:
            runs.setdefault(seed, []).append(planner.traced(feats))
    assert runs[0][0] == runs[0][1]
    assert all(run[0][0] == runs[0][0][0] for run in (runs[1], runs[7]))


def test_targets_per_run_does_not_change_plans() -> None:
    scene = generate_scene("C3", 12, 3)
    feats = observe_scene(scene, 3).features
    with Planner(targets_per_run=1) as one, Planner() as all_at_once:
        assert one.plan(feats) == all_at_once.plan(feats)


def test_planner_bad_input() -> None:
    with pytest.raises(ValueError, match="engine"):
        PlannerConfig(engine="clips")
    with pytest.raises(ValueError, match="horizon"):
        PlannerConfig(horizon=0)
    with pytest.raises(ValueError, match="seed"):
        PlannerConfig(seed=-1)
    with pytest.raises(ValueError, match="target:pair:T_o:order"):
        parse_sequence("3:y:DC")
    with pytest.raises(ValueError, match="rules file"):
        PlannerConfig(rules="/nonexistent/blocks.soar")
    scene = scene_from_blocks(ROW)
    with Planner() as p:
        with pytest.raises(ValueError, match="not blocks of the scene"):
            p.plan(features(scene), [26])
        with pytest.raises(ValueError, match=r"\(n, 13\)"):
            p.plan(np.zeros((3, 5)))


@pytest.mark.parametrize("mode", MODES)
def test_ours_agrees_with_soar_sml(mode: str) -> None:
    """>= 200 random scenes per mode, every block a target: the same sequences."""
    _sml_or_skip()
    with Planner(engine="sann") as ours, Planner(engine="soar_sml") as kernel:
        for seed in range(200):
            n = 2 + seed % 7
            scene = generate_scene(mode, n, seed)
            feats = observe_scene(scene, seed).features
            assert ours.plan(feats) == kernel.plan(feats), f"{mode} seed {seed}"


def test_planning_prints_nothing_and_keeps_the_transcript(
    capfd: pytest.CaptureFixture[str],
) -> None:
    """The planner's agent halts once per scene; a chapter that plans thousands of scenes would
    show as many "System halted." lines if the agent wrote to standard output."""
    with Planner() as planner:
        planner.plan(features(scene_from_blocks(ROW)))
        transcript = planner._backend.transcript.getvalue()
    assert capfd.readouterr().out == ""
    assert "System halted." in transcript


def _shape(trace: str) -> str:
    """A watch-1 trace without the numbers of its identifiers."""
    return re.sub(r"\b([OSC])\d+\b", r"\1", trace)


@pytest.mark.xfail(strict=True, reason=(
    "measured: at decision 31 the kernel opens a state no-change below the evaluation state "
    "S6 (a dead end, scored failure) where ours has scored S6 with the numeric value 6 and "
    "evaluates the other tied grasp; the plans found are the same"))
def test_the_search_of_one_c3_scene_differs_in_one_evaluation() -> None:
    _sml_or_skip()
    feats = observe_scene(generate_scene("C3", 13, 9), 9).features
    with Planner(engine="sann") as ours, Planner(engine="soar_sml") as kernel:
        ours_plans, ours_trace = ours.traced(feats)
        kernel_plans, kernel_trace = kernel.traced(feats)
    assert ours_plans == kernel_plans
    assert _shape(ours_trace) == _shape(kernel_trace)


@pytest.mark.xfail(strict=True, reason=(
    "measured: the same decisions, but the kernel numbers the grasp operator chosen after the "
    "tie of target W O20 where ours numbers it O19 (proposals of one wave made in another "
    "order)"))
def test_one_trace_numbers_two_operators_the_other_way() -> None:
    _sml_or_skip()
    feats = features(generate_scene("C3", 10, 4))
    with Planner(engine="sann") as ours, Planner(engine="soar_sml") as kernel:
        ours_trace, kernel_trace = ours.traced(feats, [23])[1], kernel.traced(feats, [23])[1]
    assert _shape(ours_trace) == _shape(kernel_trace)
    assert ours_trace == kernel_trace
