"""Block-task benchmark, dataset half: build D1-C3 (12,000 samples, planning included).

Usage::

    .venv/bin/python benchmarks/blocks.py [--mode C3] [--n-train 10000] [--n-test 2000]
                                          [--engines sann,soar_sml] [--seed 0] [--workers 2]

In one process it times, on the same seeds and without the cache:

- the anchor: generating and observing the scenes alone (no planning), the dataset's
  geometry cost;
- ``make_dataset("D1", mode)`` with each engine (rules/blocks.soar planning every block);

and prints wall seconds, samples per second, the ratio to the anchor, and the CPU seconds
(this process and its workers: on a shared machine the wall time also counts other users).
The target for D1-C3 with our engine is <= 60 s on this 2-core machine, goal 30 s. Both
engines must produce the same arrays (checked here too). The training half (the nets) lives
in functions added below by the networks work; keep the two halves in separate functions.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from sann.tasks.blocks import BlockWorldParams, make_dataset, observe_scene
from sann.tasks.blocks.dataset import _dataset_scene

TARGET_SECONDS = 60.0
GOAL_SECONDS = 30.0
FULL_SAMPLES = 12_000  # the D1-C3 dataset of the paper: 10,000 train + 2,000 test


def time_scene_generation(mode: str, n_samples: int, seed: int, params: BlockWorldParams
                          ) -> tuple[float, int]:
    """Seconds to generate and observe the scenes of a D1 split (no planning); scene count."""
    t0 = time.perf_counter()
    count = index = 0
    while count < n_samples:
        scene, rng = _dataset_scene("D1", mode, "train", index, seed, params,
                                    n_samples - count)
        observe_scene(scene, rng, params)
        count += scene.n
        index += 1
    return time.perf_counter() - t0, index


def _cpu_seconds() -> float:
    """CPU time of this process and of its finished children (the planning workers)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def time_dataset(engine: str, mode: str, n_train: int, n_test: int, seed: int,
                 workers: int = 1):
    """Build D1 without the cache; returns (wall seconds, CPU seconds, dataset)."""
    t0, c0 = time.perf_counter(), _cpu_seconds()
    data = make_dataset("D1", mode, n_train=n_train, n_test=n_test, seed=seed, engine=engine,
                        use_cache=False, workers=workers)
    return time.perf_counter() - t0, _cpu_seconds() - c0, data


def dataset_benchmark(mode: str, n_train: int, n_test: int, seed: int,
                      engines: list[str], workers: int = 1) -> dict[str, float]:
    """Print and return the dataset-building figures."""
    params = BlockWorldParams()
    n = n_train + n_test
    anchor, scenes = time_scene_generation(mode, n, seed, params)
    print(f"D1-{mode}: {n} samples from about {scenes} scenes, {workers} worker process(es)")
    print(f"  anchor (scenes + features + labels, no planning): {anchor:7.2f} s")
    results: dict[str, float] = {"anchor": anchor}
    built = {}
    for engine in engines:
        seconds, cpu, data = time_dataset(engine, mode, n_train, n_test, seed, workers)
        results[engine] = seconds
        results[f"{engine}_cpu"] = cpu
        built[engine] = data
        print(f"  make_dataset with {engine:8s}: {seconds:7.2f} s  "
              f"({n / seconds:7.0f} samples/s, {seconds / anchor:5.1f}x the anchor; "
              f"{cpu:.1f} CPU s)")
    if "sann" in results:
        full = results["sann"] * FULL_SAMPLES / n
        verdict = ("goal met" if full <= GOAL_SECONDS else
                   "target met" if full <= TARGET_SECONDS else "TARGET MISSED")
        scaled = "" if n == FULL_SAMPLES else f" (scaled to {FULL_SAMPLES} samples)"
        print(f"  ours: {full:.1f} s{scaled} against the {TARGET_SECONDS:.0f} s target "
              f"(goal {GOAL_SECONDS:.0f} s): {verdict}")
    if "sann" in built and "soar_sml" in built:
        ratio = results["sann"] / results["soar_sml"]
        same = all(np.array_equal(getattr(built["sann"], k), getattr(built["soar_sml"], k))
                   for k in ("X_train", "logical_train", "y_train", "X_test", "logical_test"))
        print(f"  ours / soar_sml: {ratio:.2f}x; identical datasets: {same}")
        results["identical"] = float(same)
    return results


def training_benchmark(mode: str, n_train: int, n_test: int, seed: int, anchor: float) -> None:
    """Training half: the SANN shallow net on D1-<mode> (dataset from the cache), the time to
    reach >= 99% test accuracy (the epoch where the eq. 4 curve first drops to 1%), and the
    whole default training run; ratios against the scene-generation anchor."""
    from sann.experiments.blocks import BlocksExperiment, with_logical
    from sann.nets import ShallowNet
    from sann.train import train

    data = make_dataset("D1", mode, n_train, n_test, seed=seed, workers=None)
    config = BlocksExperiment().train
    start = time.perf_counter()
    run = train(lambda n: ShallowNet(n, hidden=5), with_logical(data.X_train, data.logical_train),
                data.y_train, with_logical(data.X_test, data.logical_test), data.y_test,
                seed=0, config=config)
    seconds = time.perf_counter() - start
    reached = next((i + 1 for i, e in enumerate(run.test_error) if e <= 0.01), None)
    print(f"SANN D1-{mode}: {config.epochs} epochs in {seconds:.1f} s, final accuracy "
          f"{run.accuracy:.4f}, {seconds / anchor:.1f}x the anchor")
    if reached is None:
        print("  never reached 99% test accuracy")
    else:
        to_99 = seconds * reached / config.epochs
        verdict = "met" if to_99 <= 20 else "MISSED"
        print(f"  >= 99% first at epoch {reached}: {to_99:.1f} s (target <= 20 s: {verdict}, "
              f"goal 10 s), {to_99 / anchor:.1f}x the anchor")


def quick_reproduce_benchmark() -> None:
    """`python -m sann reproduce blocks --quick` from an empty cache (target <= 3 min)."""
    import subprocess
    import sys
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, SANN_CACHE=os.path.join(tmp, "cache"), TQDM_DISABLE="1")
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "sann", "reproduce", "blocks", "--quick",
                        "--out", os.path.join(tmp, "out")], check=True, env=env)
        seconds = time.perf_counter() - start
    verdict = "met" if seconds <= 180 else "MISSED"
    print(f"reproduce blocks --quick, empty cache: {seconds:.1f} s (target <= 180 s: {verdict})")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mode", default="C3", choices=["C1", "C2", "C3"])
    parser.add_argument("--n-train", type=int, default=10_000)
    parser.add_argument("--n-test", type=int, default=2_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--engines", default="sann,soar_sml")
    parser.add_argument("--workers", type=int, default=2,
                        help="planning processes (the machine has 2 cores)")
    parser.add_argument("--skip-datasets", action="store_true",
                        help="only the training half (datasets from the cache)")
    parser.add_argument("--quick-reproduce", action="store_true",
                        help="also time `reproduce blocks --quick` from an empty cache")
    args = parser.parse_args(argv)
    engines = [e for e in args.engines.split(",") if e]
    if not args.skip_datasets:
        dataset_benchmark(args.mode, args.n_train, args.n_test, args.seed, engines, args.workers)
    anchor, _ = time_scene_generation(args.mode, args.n_train + args.n_test, args.seed,
                                      BlockWorldParams())
    print(f"anchor (scene generation, {args.n_train + args.n_test} samples): {anchor:.2f} s")
    training_benchmark(args.mode, args.n_train, args.n_test, args.seed, anchor)
    if args.quick_reproduce:
        quick_reproduce_benchmark()


if __name__ == "__main__":
    main()
