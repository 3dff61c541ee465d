"""The datasets D1 and D2 of the blocks world: observed scenes planned by the rules, cached.

Every scene of a dataset has its own seed (from the dataset seed, kind, mode, split and
index), so :meth:`BlockDataset.scene` regenerates any of them and the arrays do not depend
on how many processes planned them.
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import asdict, dataclass

import numpy as np

from .features import observe_scene
from .world import (
    FEATURE_NAMES,
    MAX_BLOCKS,
    MODES,
    NAMES,
    BlockWorldParams,
    Scene,
    check_mode,
    generate_scene,
)

DATASET_VERSION = "blocks-dataset-4"  # bump when generation, features or labels change
KINDS = ("D1", "D2")
_SPLITS = ("train", "test")


@dataclass
class BlockDataset:
    """D1 or D2 of one mode, split into train and test (scenes never straddle the split).

    D1 (one sample per block): ``X`` = the 13 Table-1 features + the image id (14 columns).
    D2 (one sample per scene): ``X`` = 26 x 13 features, one row of 13 per block id (A first;
    zeros for blocks not in the scene), flattened, + the designated target's id (339 columns).
    The D2 target is a graspable block with probability 1/2 and a blocked one otherwise (when
    the scene has both kinds), so D2 labels are about balanced; D1 keeps the natural rates
    (C1 mostly graspable, C2 one block per scene, C3 about a quarter to a third).
    ``logical``: the fusion column (eq. 2 over the plans of the sample's target); ``y``: 1 if
    the target is graspable now (true geometry), else 0. ``image``: the scene index of each
    sample (train scenes 0..S-1, test scenes numbered on from S). ``plans``: the sequences of
    the sample's target, as text ``"x:3:DCA y:2:DA"`` (pair:T_o:order). :meth:`scene`
    regenerates any scene of the dataset, e.g. for drawing.
    """

    kind: str
    mode: str
    X_train: np.ndarray
    logical_train: np.ndarray
    y_train: np.ndarray
    X_test: np.ndarray
    logical_test: np.ndarray
    y_test: np.ndarray
    image_train: np.ndarray
    image_test: np.ndarray
    plans_train: np.ndarray
    plans_test: np.ndarray
    feature_names: list[str]
    meta: dict

    def scene(self, image: int) -> Scene:
        """The scene of ``image`` (a value of ``image_train``/``image_test``)."""
        n_train_scenes = int(self.meta["train_scenes"])
        split, index = ("train", image) if image < n_train_scenes else (
            "test", image - n_train_scenes)
        params = BlockWorldParams(**self.meta["params"])
        seed = int(self.meta["seed"])
        jobs = _scene_jobs(self.kind, self.mode, split, int(self.meta[f"{split}_samples"]),
                           seed, params)
        if not 0 <= index < len(jobs):
            raise ValueError(f"image {image} is not a scene of this dataset")
        return _dataset_scene(self.kind, self.mode, split, index, seed, params,
                              jobs[index][1])[0]

    @property
    def test_scenes(self) -> list[Scene]:
        """Every test scene, in image order."""
        return [self.scene(int(i)) for i in np.unique(self.image_test)]


def feature_names_for(kind: str) -> list[str]:
    """Column names of ``X`` for D1 or D2."""
    if kind == "D1":
        return [*FEATURE_NAMES, "Image"]
    return [f"{name}.{f}" for name in NAMES for f in FEATURE_NAMES] + ["TargetId"]


def _scene_rng(kind: str, mode: str, split: str, index: int, seed: int) -> np.random.Generator:
    return np.random.default_rng(
        [seed, KINDS.index(kind), MODES.index(mode), _SPLITS.index(split), index])


def _dataset_scene(kind: str, mode: str, split: str, index: int, seed: int,
                   params: BlockWorldParams, max_blocks: int | None
                   ) -> tuple[Scene, np.random.Generator]:
    """Scene ``index`` of a split: its block count, layout and noise all come from one rng."""
    rng = _scene_rng(kind, mode, split, index, seed)
    n = int(rng.integers(params.min_blocks, params.max_blocks + 1))
    if max_blocks is not None:
        n = min(n, max_blocks)
    return generate_scene(mode, n, rng, params), rng


def _choose_target(labels: np.ndarray, rng: np.random.Generator) -> int:
    """D2 target slot: with probability 1/2 a graspable block, else a blocked one (when the
    scene has one of that kind), so that D2 labels are balanced where the scene allows."""
    want = rng.random() < 0.5
    pool = np.flatnonzero(labels == want)
    if len(pool) == 0:
        pool = np.arange(len(labels))
    return int(rng.choice(pool))


def _plan_text(seqs: list) -> str:
    return " ".join(f"{s.pair}:{s.t_o}:{s.order}" for s in seqs)


def _scene_jobs(kind: str, mode: str, split: str, n_samples: int, seed: int,
                params: BlockWorldParams) -> list[tuple[int, int | None]]:
    """(scene index, block-count cap) of every scene of a split. D1 draws scenes until the
    samples are reached; the last scene is cut to the samples still missing."""
    if kind == "D2":
        return [(index, None) for index in range(n_samples)]
    jobs: list[tuple[int, int | None]] = []
    count = 0
    while count < n_samples:
        index = len(jobs)
        n = int(_scene_rng(kind, mode, split, index, seed).integers(params.min_blocks,
                                                                      params.max_blocks + 1))
        cap = n_samples - count
        jobs.append((index, cap))
        count += min(n, cap)
    return jobs


def _scene_samples(kind: str, mode: str, split: str, index: int, cap: int | None,
                   first_image: int, seed: int, params: BlockWorldParams, planner) -> tuple:
    """The samples of one scene: (X rows, logical, labels, image ids, plan texts)."""
    from sann.fusion import logical_item

    scene, rng = _dataset_scene(kind, mode, split, index, seed, params, cap)
    obs = observe_scene(scene, rng, params)
    image = first_image + index
    if kind == "D1":
        plans = planner.plan(obs.features)
        rows = np.column_stack([obs.features, np.full(scene.n, image)])
        slots = list(range(scene.n))
    else:
        slot = _choose_target(obs.labels, rng)
        plans = planner.plan(obs.features, [int(scene.ids[slot])])
        padded = np.zeros((MAX_BLOCKS, len(FEATURE_NAMES)))
        padded[scene.ids - 1] = obs.features
        rows = np.append(padded.ravel(), scene.ids[slot])[None, :]
        slots = [slot]
    seqs = [plans[int(scene.ids[slot])] for slot in slots]
    return (rows, [logical_item(s.t_o for s in q) for q in seqs],
            [int(obs.labels[slot]) for slot in slots], [image] * len(slots),
            [_plan_text(q) for q in seqs])


_PLANNERS: dict = {}


def _planner(config):
    """One planner per configuration (and rule text) in a process, made before any pool forks
    so that the workers inherit it: sourcing the rules costs about a second per process."""
    from sann import cache
    from sann.tasks.planning import Planner

    key = (config, cache.file_sha256(config.rules))
    if key not in _PLANNERS:
        _PLANNERS[key] = Planner(config)
    return _PLANNERS[key]


def _worker_chunk(args: tuple) -> list[tuple]:
    kind, mode, split, jobs, first_image, seed, params, config = args
    planner = _planner(config)
    return [_scene_samples(kind, mode, split, index, cap, first_image, seed, params, planner)
            for index, cap in jobs]


def _collect(split: str, parts: list[tuple]) -> dict[str, np.ndarray]:
    rows, logical, labels, images, plans = ([], [], [], [], [])
    for r, lg, lb, im, pl in parts:
        rows.append(r)
        logical += lg
        labels += lb
        images += im
        plans += pl
    return {
        f"X_{split}": np.concatenate(rows).astype(np.float32),
        f"logical_{split}": np.asarray(logical, dtype=np.float32),
        f"y_{split}": np.asarray(labels, dtype=np.int64),
        f"image_{split}": np.asarray(images, dtype=np.int64),
        f"plans_{split}": np.asarray(plans, dtype=str),
    }


def _run_jobs(kind: str, mode: str, split: str, jobs: list, first_image: int, seed: int,
              params: BlockWorldParams, config, workers: int, bar) -> list[tuple]:
    """Plan the scenes of ``jobs`` in this process or in a pool; results in scene order."""
    parts: list[tuple] = []
    planner = _planner(config)
    if workers == 1:
        for index, cap in jobs:
            part = _scene_samples(kind, mode, split, index, cap, first_image, seed, params,
                                  planner)
            parts.append(part)
            if bar is not None:
                bar.update(len(part[2]))
        return parts
    import multiprocessing as mp

    size = max(1, min(25, len(jobs) // (4 * workers)))
    chunks = [(kind, mode, split, jobs[i:i + size], first_image, seed, params, config)
              for i in range(0, len(jobs), size)]
    ctx = mp.get_context("fork")
    with ctx.Pool(workers) as pool:
        for chunk in pool.imap(_worker_chunk, chunks):
            parts += chunk
            if bar is not None:
                bar.update(sum(len(p[2]) for p in chunk))
    return parts


def _check_workers(workers: object) -> int:
    if workers is None:
        return max(1, os.cpu_count() or 1)
    if isinstance(workers, bool) or not isinstance(workers, int | np.integer) or workers < 1:
        raise ValueError(f"workers must be a positive integer or None, got {workers!r}")
    return int(workers)


def _check_count(value: object, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value <= 0:
        raise ValueError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


def make_dataset(
    kind: str,
    mode: str,
    n_train: int = 10_000,
    n_test: int = 2_000,
    seed: int = 0,
    params: BlockWorldParams | None = None,
    engine: str = "sann",
    rules: str | os.PathLike[str] | None = None,
    progress: bool = False,
    horizon: int | None = None,
    use_cache: bool = True,
    workers: int | None = 1,
) -> BlockDataset:
    """Build (or load from the cache) dataset ``kind`` (D1/D2) of ``mode`` (C1/C2/C3).

    Every scene is planned by ``rules`` in ``engine``; the fusion column is eq. 2 over the
    target's sequences. The cache key covers every argument except ``engine``, ``progress``
    and ``use_cache`` (the engines give identical plans: tests/tasks/test_planning.py checks
    it), plus the sha256 of the rule file's code (``sann.cache.soar_code_sha256``: comments do
    not count) and ``DATASET_VERSION``. ``workers`` processes plan the
    scenes (None: one per CPU core); every scene has its own seed, so the arrays do not depend
    on it. ``horizon`` defaults to the planner's (T_o <= 8).
    """
    from sann import cache
    from sann.tasks.planning import DEFAULT_HORIZON, DEFAULT_RULES, PlannerConfig

    if kind not in KINDS:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    mode = check_mode(mode)
    n_train, n_test = _check_count(n_train, "n_train"), _check_count(n_test, "n_test")
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ValueError(f"seed must be an integer >= 0, got {seed!r}")
    params = params or BlockWorldParams()
    if not isinstance(params, BlockWorldParams):
        raise ValueError(f"params must be a BlockWorldParams, got {type(params).__name__}")
    config = PlannerConfig(engine=engine, rules=rules or DEFAULT_RULES,
                           horizon=DEFAULT_HORIZON if horizon is None else horizon,
                           clearance=float(params.gripper_finger_width),
                           margin=float(params.finger_margin))
    rules_code = cache.soar_code_sha256(config.rules)
    description = {
        "kind": kind, "mode": mode, "n_train": n_train, "n_test": n_test, "seed": int(seed),
        "params": asdict(params), "rules_code_sha256": rules_code,
        "horizon": config.horizon, "z_tolerance": config.z_tolerance, "version": DATASET_VERSION,
    }

    n_workers = _check_workers(workers)

    def build() -> dict[str, np.ndarray]:
        return _build_arrays(kind, mode, n_train, n_test, int(seed), params, config, progress,
                             n_workers)

    t0 = time.perf_counter()
    arrays, hit = cache.get_or_build(f"blocks-{kind}-{mode}", description, build,
                                     use_cache=use_cache)
    meta = {**description, **json.loads(str(arrays.pop("meta")))}
    meta.update(cache_hit=hit, seconds=time.perf_counter() - t0,
                rules_sha256=cache.file_sha256(config.rules))
    return BlockDataset(kind=kind, mode=mode, feature_names=feature_names_for(kind), meta=meta,
                        **arrays)


def _build_arrays(kind: str, mode: str, n_train: int, n_test: int, seed: int,
                  params: BlockWorldParams, config, progress: bool, workers: int
                  ) -> dict[str, np.ndarray]:
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=n_train + n_test, desc=f"{kind}-{mode}", unit="sample")
    t0 = time.perf_counter()
    train_jobs = _scene_jobs(kind, mode, "train", n_train, seed, params)
    test_jobs = _scene_jobs(kind, mode, "test", n_test, seed, params)
    try:
        train = _run_jobs(kind, mode, "train", train_jobs, 0, seed, params, config, workers,
                          bar)
        test = _run_jobs(kind, mode, "test", test_jobs, len(train_jobs), seed, params, config,
                         workers, bar)
    finally:
        if bar is not None:
            bar.close()
    meta = {"train_scenes": len(train_jobs), "test_scenes": len(test_jobs),
            "engine": config.engine, "build_seconds": time.perf_counter() - t0,
            "train_samples": n_train, "test_samples": n_test, "workers": workers}
    return {**_collect("train", train), **_collect("test", test),
            "meta": np.array(json.dumps(meta))}
