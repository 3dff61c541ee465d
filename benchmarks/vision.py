"""Vision benchmark: scene synthesis (piles, rendering, labels) and pose estimation.

Usage::

    .venv/bin/python benchmarks/vision.py [--frames 30] [--piles 10] [--seed 0]

Scene part (this file's ``scene_part``), in one process on the same inputs:

(a) render: median time of ``render`` for a 10-cup pile at 640 x 480 (depth, colour,
    instance ids), after a first cold frame that also renders and caches the empty box.
    Target <= 50 ms.  Also the single-cup template render (``render_cup``), target <= 10 ms.
(b) piles: wall time of ``make_pile`` for 10 cups (MuJoCo), over several seeds; target
    about a second at most.  Also the ground-truth labels of a pile (``label_pile``).

Every time is also printed as a ratio to an anchor measured in the same run: sorting 10^6
float64 numbers with ``np.sort`` (seeded), so figures from different machines or loads can be
compared.  The pose-estimation part lives in its own function and is appended to the report.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable

import numpy as np

from sann.vision.camera import default_camera, make_pose, rotation_to
from sann.vision.labels import label_pile
from sann.vision.piles import make_pile
from sann.vision.render import render, render_cup

RENDER_TARGET_S = 0.050
CUP_TARGET_S = 0.010
PILE_TARGET_S = 1.0


def timed(fn: Callable[[], object], repeat: int) -> list[float]:
    """Wall times (s) of ``repeat`` calls."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return times


def anchor_time(repeat: int = 7) -> float:
    """Median time of np.sort on 10^6 seeded float64: the machine/load yardstick."""
    data = np.random.default_rng(0).random(1_000_000)
    return statistics.median(timed(lambda: np.sort(data), repeat))


def report(name: str, seconds: float, anchor: float, target: float | None = None) -> None:
    verdict = "" if target is None else (" ok" if seconds <= target else " OVER TARGET")
    goal = "" if target is None else f"  (target {target * 1e3:.0f} ms{verdict})"
    print(f"  {name:<38} {seconds * 1e3:8.1f} ms  = {seconds / anchor:6.2f} x anchor{goal}")


def scene_part(frames: int, piles: int, seed: int, anchor: float) -> dict[str, float]:
    """Render, template-render, pile and label timings; returns the medians in seconds."""
    camera = default_camera()
    pile_times: list[float] = []
    made = []
    for k in range(piles):
        start = time.perf_counter()
        made.append(make_pile(10, seed + k))
        pile_times.append(time.perf_counter() - start)
    pile = made[0]
    cold = timed(lambda: render(pile, camera), 1)[0]
    warm = statistics.median(timed(lambda: render(pile, camera), frames))
    rng = np.random.default_rng(seed)
    views = [make_pose(rotation_to(rng.normal(size=3), rng.uniform(0, 2 * np.pi)),
                       [0.0, 0.0, rng.uniform(450.0, 1000.0)]) for _ in range(frames)]
    cup = statistics.median([timed(lambda v=v: render_cup(v), 1)[0] for v in views])
    rendered = render(pile, camera)
    labels = statistics.median(timed(lambda: label_pile(pile, camera, rendered), 3))
    out = {
        "render_10_cups": warm,
        "render_cold": cold,
        "render_cup": cup,
        "pile_10_cups_median": statistics.median(pile_times),
        "pile_10_cups_max": max(pile_times),
        "labels": labels,
    }
    print(f"scene synthesis: {frames} frames, {piles} piles of 10 cups, "
          f"{sum(p.n_cups for p in made)} cups placed, {sum(p.redrops for p in made)} re-drops")
    report("render 10-cup pile 640x480 (median)", warm, anchor, RENDER_TARGET_S)
    report("render first frame (caches the box)", cold, anchor)
    report("render one cup, template (median)", cup, anchor, CUP_TARGET_S)
    report("make_pile(10) (median)", out["pile_10_cups_median"], anchor, PILE_TARGET_S)
    report("make_pile(10) (max)", out["pile_10_cups_max"], anchor, PILE_TARGET_S)
    report("label_pile (median)", labels, anchor)
    return out


POSE_TARGET_S = 1.5
POSE_GOAL_S = 0.3


def _wall_and_cpu(calls: list[Callable[[], object]]) -> tuple[float, float]:
    """Median wall time and median process CPU time (s) of single calls."""
    wall, cpu = [], []
    for call in calls:
        w0, c0 = time.perf_counter(), time.process_time()
        call()
        wall.append(time.perf_counter() - w0)
        cpu.append(time.process_time() - c0)
    return statistics.median(wall), statistics.median(cpu)


def pose_part(piles: int, seed: int, anchor: float) -> dict[str, float]:
    """Pose estimation: speed on 10-cup piles and precision/recall on mixed piles.

    Speed: ``detect_cups`` (Patch-LineMod + ICP) per 640 x 480 frame with the default template
    set (>= 300 templates), and its ratio to plain ``cv2.linemod`` matching of the same frame
    with the same templates (the brief's anchor). Accuracy on the same piles: plain LineMod,
    Patch-LineMod, and ablations separating the patch rule from the ICP/verification back end.
    """
    from sann.vision.camera import K_PRIMESENSE
    from sann.vision.detect import DetectConfig, detect_cups
    from sann.vision.evaluate import evaluate_methods, make_frames
    from sann.vision.linemod import TemplateParams, get_templates, match_templates

    params = TemplateParams()
    start = time.perf_counter()
    templates = get_templates(params, K_PRIMESENSE)
    load = time.perf_counter() - start
    config = DetectConfig(templates=params)
    busy = make_frames(max(3, piles // 3), seed + 7, cups=(10, 10))
    detect_cups(busy[0].rgb, busy[0].depth_mm, K_PRIMESENSE, config, templates)  # warm caches
    match, match_cpu = _wall_and_cpu(
        [lambda f=f: match_templates(templates, f.rgb, f.depth_mm, 70.0) for f in busy])
    full, full_cpu = _wall_and_cpu(
        [lambda f=f: detect_cups(f.rgb, f.depth_mm, K_PRIMESENSE, config, templates)
         for f in busy])
    print(f"pose estimation: {len(templates)} templates ({params.tilt_step_deg:g} deg steps, "
          f"distances {params.distances_mm} mm), loaded/trained in {load:.1f} s")
    report("cv2.linemod match, 10-cup frame", match, anchor)
    report("detect_cups Patch-LineMod+ICP", full, anchor, POSE_TARGET_S)
    print(f"  {'detect_cups / cv2.linemod match':<38} {full / match:8.2f} x   "
          f"(goal {POSE_GOAL_S * 1e3:.0f} ms: {'met' if full <= POSE_GOAL_S else 'not met'})")
    print(f"  {'CPU time (all threads): match, detect':<38} {match_cpu * 1e3:8.1f} ms, "
          f"{full_cpu * 1e3:.1f} ms  (ratio {full_cpu / match_cpu:.2f}; robust to a loaded "
          f"machine)")
    frames = make_frames(piles, seed)
    # Ablations: the patch rule without the ICP/verification back end, and the back end
    # without the patch rule at the plain threshold (80) and at Patch-LineMod's (70).
    configs = {
        "linemod": DetectConfig(method="linemod", templates=params),
        "patch, no icp": DetectConfig(method="patch", templates=params, icp=False),
        "linemod+icp": DetectConfig(method="linemod", templates=params, icp=True),
        "linemod70+icp": DetectConfig(method="linemod", templates=params, icp=True,
                                      linemod_threshold=70.0),
        "patch-linemod": config,
    }
    scores = evaluate_methods(frames, configs, K_PRIMESENSE)
    print(f"  accuracy on {len(frames)} piles of 2-10 cups, {scores['linemod']['visible_cups']} "
          f"visible cups (15 mm, 15 deg):")
    for name, s in scores.items():
        print(f"    {name:<14} precision {s['precision']:6.1%}  recall {s['recall']:6.1%}  "
              f"median error {s['median_position_error_mm']:5.2f} mm "
              f"{s['median_axis_error_deg']:5.2f} deg  {s['seconds_per_frame'] * 1e3:6.0f} ms")
    out = {"pose_templates": float(len(templates)), "pose_linemod_match": match,
           "pose_detect": full, "pose_ratio_to_match": full / match,
           "pose_linemod_match_cpu": match_cpu, "pose_detect_cpu": full_cpu}
    for name, s in scores.items():
        out[f"{name}_precision"] = s["precision"]
        out[f"{name}_recall"] = s["recall"]
    return out


def main(argv: list[str] | None = None) -> dict[str, float]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--piles", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--pose-piles", type=int, default=30,
                        help="piles for the pose-estimation accuracy (0 skips that part)")
    args = parser.parse_args(argv)
    anchor = anchor_time()
    print(f"anchor: np.sort of 10^6 float64 = {anchor * 1e3:.1f} ms")
    results = {"anchor": anchor}
    results.update(scene_part(args.frames, args.piles, args.seed, anchor))
    if args.pose_piles > 0:
        results.update(pose_part(args.pose_piles, args.seed, anchor))
    return results


if __name__ == "__main__":
    main()
