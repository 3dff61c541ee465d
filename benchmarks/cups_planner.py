"""Cup planner benchmark: the searching rules/cups.soar against the budgeted planner it
replaced (benchmarks/data/cups-budgeted.soar, ^cap 8), in our engine and in the real kernel.

Usage::

    .venv/bin/python benchmarks/cups_planner.py [--piles 40] [--views 5] [--seed 0]
                                                [--rounds 3] [--cache cups-test-....npz]

The scenes are what the rules see of a pile: by default simulated piles (``make_pile``) whose
true poses are moved as an estimator moves them (about 5 mm, up to 10 degrees) with some cups
missed, relations from those poses (as tests/tasks/test_cups.py builds them); with
``--cache`` the pose arrays of a built cups split (``sann.cache``), i.e. real detections.
Every cup of a scene is a target. Per planner and engine it prints the median (over rounds)
of the milliseconds per scene, the ratio to our engine's budgeted planner measured in the same
run (the anchor), and the sequences per target (mean, max, and the share of targets with more
than one). It checks that both engines give the same plans with each rule file.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

from sann import RULES
from sann.tasks.backends import SannBackend, SmlBackend
from sann.tasks.cups import CupScene, CupsDataParams, _cup_items, detections_from_array

BUDGETED = Path(__file__).resolve().parent / "data" / "cups-budgeted.soar"
SEARCH = RULES / "cups.soar"
CAP = 8


def estimated_scenes(piles: int, views: int, seed: int) -> list[CupScene]:
    """Simulated piles seen as an estimator sees them (seeded)."""
    from sann.vision.camera import axis_angle, make_pose
    from sann.vision.piles import make_pile

    rng = np.random.default_rng(seed)
    scenes = []
    for k in range(piles):
        pile = make_pile(int(rng.integers(4, 11)), 1000 * seed + k)
        for _ in range(views):
            keep = rng.permutation(pile.n_cups)[: int(rng.integers(2, pile.n_cups + 1))]
            poses = [make_pose(axis_angle(rng.normal(size=3), np.radians(rng.uniform(0, 10)))
                               @ p[:3, :3], p[:3, 3] + rng.normal(0.0, 5.0, size=3))
                     for p in pile.poses[keep]]
            scenes.append(CupScene.from_world_poses(np.array(poses),
                                                    rng.uniform(70, 100, len(poses))))
    return scenes


def cached_scenes(path: Path) -> list[CupScene]:
    """The detections of a built cups split, moved to the world frame."""
    camera = CupsDataParams().camera()
    arrays = np.load(path)["poses"]
    return [CupScene.from_detections(detections_from_array(a), camera) for a in arrays
            if a[:, 12].max() > 0]


def _orders(found: list) -> list[tuple[int, str]]:
    """(target, order) of each output sequence: a symbol target:T_o:order (the search) or an
    identifier with ^target ^order (the budgeted planner)."""
    out = []
    for value in found:
        if isinstance(value, str):
            target, _, order = value.split(":")
            out.append((int(target), order))
        else:
            out.append((int(value["target"]), value["order"]))
    return sorted(out)


def run(backend, scenes: list[CupScene], budgeted: bool) -> tuple[float, list]:
    """Seconds for planning every scene (every cup a target), and the plans."""
    plans = []
    t0 = time.perf_counter()
    for scene in scenes:
        items = _cup_items(scene, range(scene.n))
        if budgeted:
            items = [("cap", CAP), *items]
        plans.append(_orders(backend.run(items, seed=0)))
    return time.perf_counter() - t0, plans


def counts(scenes: list[CupScene], plans: list) -> list[int]:
    """Sequences per target, over every target of every scene."""
    return [sum(1 for t, _ in p if t == target) for s, p in zip(scenes, plans, strict=True)
            for target in range(s.n)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--piles", type=int, default=40)
    ap.add_argument("--views", type=int, default=5)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--cache", type=Path, default=None)
    args = ap.parse_args()
    scenes = (cached_scenes(args.cache) if args.cache
              else estimated_scenes(args.piles, args.views, args.seed))
    print(f"{len(scenes)} scenes, {sum(s.n for s in scenes)} targets")
    setups = {(rules, engine): (SannBackend(path) if engine == "sann"
                                else SmlBackend(path, f"cups{rules}"))
              for rules, path in (("budgeted", BUDGETED), ("search", SEARCH))
              for engine in ("sann", "soar_sml")}
    seconds: dict = {key: [] for key in setups}
    plans: dict = {}
    for _ in range(args.rounds):
        for key, backend in setups.items():
            s, plans[key] = run(backend, scenes, key[0] == "budgeted")
            seconds[key].append(s)
    for rules in ("budgeted", "search"):
        assert plans[(rules, "sann")] == plans[(rules, "soar_sml")], f"{rules}: engines differ"
    anchor = statistics.median(seconds[("budgeted", "sann")])
    print(f"{'planner':9s} {'engine':9s} {'ms/scene':>9s} {'ratio':>6s} {'seq/target':>10s} "
          f"{'max':>4s} {'>1':>6s}")
    for (rules, engine), secs in seconds.items():
        med = statistics.median(secs)
        n = np.array(counts(scenes, plans[(rules, engine)]))
        print(f"{rules:9s} {engine:9s} {1000 * med / len(scenes):9.2f} {med / anchor:6.2f} "
              f"{n.mean():10.3f} {n.max():4d} {np.mean(n > 1):6.1%}")
    old, new = (np.array(counts(scenes, plans[(r, "sann")])) for r in ("budgeted", "search"))
    print(f"targets where the search finds fewer / the same / more sequences than the budget: "
          f"{np.sum(new < old)} / {np.sum(new == old)} / {np.sum(new > old)}; "
          f"no sequence: {np.sum(old == 0)} budgeted, {np.sum(new == 0)} search")
    for backend in setups.values():
        backend.close()


if __name__ == "__main__":
    main()
