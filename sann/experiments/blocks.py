"""The multi-block experiment (paper Figs. 8, 9, 13, 14) with the baselines a reviewer asks for.

For every dataset (D1/D2 x C1/C2/C3) and every data seed, five predictors are scored on the
same test samples:

- ``majority``: the training set's more frequent label, predicted for every test sample.
- ``rules``: the planner alone. A sample is called graspable when some logical sequence of its
  target has ``T_o = 1`` (a plan grasps the target first). In the fusion column this is a term
  of eq. 3 equal to 1; it is read from the plans themselves, because eq. 2 can also reach 1
  with two ``T_o = 2`` sequences.
- ``ann``: the paper's shallow net (inputs -> 5 tanh units -> 2) on the features.
- ``sann``: the same net on the features plus the logical item (eq. 2).
- ``control``: the same net on the features plus :func:`free_now_column`, a 0/1 column that
  numpy computes straight from the sample's feature rows, without the planner: the target has
  no block on it (no Up neighbour, no block listing it as Down) and one of its side pairs has
  no other block's observed box in its finger slabs (the gripper's clearance, less the pad's
  margin along the face, over the target's height range shrunk by the z tolerance). That is
  the information the rules get — every block's feature row (observed centre and size, hence
  its box, and the neighbour ids) and the gripper's clearance — turned into the one-step test
  the rules apply before they search. If SANN beats the ANN but not this control, what helped
  was the extra scene-level input, not the planning (the sequences, their search, the eq.-3
  weights).

Intervals. The test samples of one scene are not independent (D1 has about 14 per scene), so
every interval is a percentile bootstrap that resamples, in each replicate, the data seeds,
the test scenes of each data seed and the initialisation seeds, all with replacement
(:func:`bootstrap`). The difference SANN - ANN gets its own interval from the same replicates.

Learning curves. ANN and SANN are trained on the first ``k`` training samples (whole scenes,
in scene order, the last one cut) for each ``k`` of ``curve_sizes`` up to ``n_train``; every
size gets at least ``min_steps`` optimiser steps (a 30-sample set has one mini-batch per
epoch), and is scored on the full test set. The rules do not learn: their curve is flat.

Every (dataset, data seed) evaluation is cached (:mod:`sann.cache`: atomic, keyed on the
configuration, the rule file, the dataset version and the sha256 of the code that computes
it), so ``reproduce blocks`` resumes after a failure and the book reads a finished full-size
run without computing it (:func:`cached_results`).
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np
from sklearn.manifold import TSNE
from threadpoolctl import threadpool_limits

from sann.nets import ShallowNet
from sann.tasks.blocks import (
    DATASET_VERSION,
    FEATURE_NAMES,
    MAX_BLOCKS,
    BlockWorldParams,
    make_dataset,
)
from sann.train import TrainConfig, TrainResult, train_groups
from sann.viz import plots

KINDS = ("D1", "D2")
MODES = ("C1", "C2", "C3")
METHODS = ("majority", "rules", "ann", "sann", "control")
NETS = ("ann", "sann", "control")
CURVE_NETS = ("ann", "sann")
_CODE = [Path(__file__).resolve().parents[1] / name
         for name in ("experiments/blocks.py", "train.py", "fusion.py", "nets.py")]
_COL = {name: i for i, name in enumerate(FEATURE_NAMES)}


@dataclass(frozen=True)
class BlocksExperiment:
    """Sizes and settings of one reproduction; `quick()` is the small version for tests.
    ``seeds`` initialisation seeds are trained on each of the ``data_seeds`` datasets.
    ``tsne_points=0`` leaves out the t-SNE figures (13-14), e.g. where another part of the
    book draws them. ``workers``: processes that plan the scenes (None: one per core)."""

    n_train: int = 10_000
    n_test: int = 2_000
    seeds: int = 5
    data_seeds: tuple[int, ...] = (0, 1, 2)
    hidden: int = 5
    train: TrainConfig = TrainConfig(epochs=60, batch_size=64, lr=0.01)
    curve_sizes: tuple[int, ...] = (30, 100, 300, 1_000, 3_000, 10_000)
    min_steps: int = 1_500
    resamples: int = 1_000
    tsne_points: int = 1_000
    workers: int | None = None

    def __post_init__(self) -> None:
        for name in ("n_train", "n_test", "seeds", "hidden", "min_steps", "resamples"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"BlocksExperiment.{name} must be an integer >= 1, "
                                 f"got {value!r}")
        if not self.data_seeds or len(set(self.data_seeds)) != len(self.data_seeds):
            raise ValueError(f"BlocksExperiment.data_seeds must be distinct seeds, "
                             f"got {self.data_seeds!r}")
        if any(k < 1 for k in self.curve_sizes):
            raise ValueError(f"curve sizes must be >= 1, got {self.curve_sizes!r}")

    @property
    def data_seed(self) -> int:
        """The first data seed (the dataset of single-seed figures such as t-SNE)."""
        return self.data_seeds[0]

    @property
    def sizes(self) -> list[int]:
        """The learning curve's training sizes: ``curve_sizes`` up to ``n_train``, which
        always closes the curve."""
        return sorted({k for k in self.curve_sizes if k < self.n_train} | {self.n_train})

    @classmethod
    def quick(cls, seeds: int = 2) -> BlocksExperiment:
        return cls(n_train=150, n_test=120, seeds=seeds, data_seeds=(0, 1),
                   train=TrainConfig(epochs=15, batch_size=64, lr=0.02),
                   curve_sizes=(30, 100), min_steps=100, resamples=500, tsne_points=150)


# --------------------------------------------------------------------------- the predictors


def with_logical(x: np.ndarray, logical: np.ndarray) -> np.ndarray:
    """The fused M x (N+1) array: features plus the logical item column."""
    return np.hstack([x, logical.reshape(-1, 1)]).astype(np.float32)


def rules_verdict(plans: np.ndarray) -> np.ndarray:
    """1 where some sequence of the sample's target has T_o = 1, else 0. ``plans`` holds the
    dataset's plan texts (``"x:3:DCA y:1:A"``: pair:T_o:order per sequence)."""
    return np.array([int(any(part.split(":")[1] == "1" for part in text.split()))
                     for text in plans], dtype=np.int64)


def free_now(rows: np.ndarray, params: BlockWorldParams | None = None) -> np.ndarray:
    """For each (n, 13) feature row of one scene: nothing rests on it (neighbour features)
    and one of its side pairs is free of other blocks' observed boxes (see the module doc)."""
    from sann.tasks.planning import Z_TOLERANCE

    params = params or BlockWorldParams()
    rows = np.asarray(rows, dtype=np.float64)
    centre, size = rows[:, :3], rows[:, _COL["Size"]]
    ids = rows[:, _COL["Target"]]
    lo, hi = centre - size[:, None] / 2, centre + size[:, None] / 2
    covered = (rows[:, _COL["Up"]] != 0) | np.isin(ids, rows[:, _COL["Down"]])
    z_in = (hi[None, :, 2] > lo[:, None, 2] + Z_TOLERANCE) & (
        lo[None, :, 2] < hi[:, None, 2] - Z_TOLERANCE)
    free = np.zeros(len(rows), dtype=bool)
    for axis in (0, 1):
        other = 1 - axis
        span = ((lo[None, :, axis] < hi[:, None, axis] + params.gripper_finger_width)
                & (hi[None, :, axis] > lo[:, None, axis] - params.gripper_finger_width))
        pad = ((hi[None, :, other] > lo[:, None, other] + params.finger_margin)
               & (lo[None, :, other] < hi[:, None, other] - params.finger_margin))
        hit = span & pad & z_in
        np.fill_diagonal(hit, False)
        free |= ~hit.any(axis=1)
    return (~covered & free).astype(np.float32)


def free_now_column(kind: str, x: np.ndarray, params: BlockWorldParams | None = None
                    ) -> np.ndarray:
    """The control column of a D1 or D2 feature array (one value per sample)."""
    n = len(FEATURE_NAMES)
    if kind == "D1":
        out = np.zeros(len(x), dtype=np.float32)
        image = x[:, n]
        for value in np.unique(image):
            where = np.flatnonzero(image == value)
            out[where] = free_now(x[where, :n], params)
        return out
    out = np.zeros(len(x), dtype=np.float32)
    for k, sample in enumerate(x):
        rows = sample[:MAX_BLOCKS * n].reshape(MAX_BLOCKS, n)
        present = rows[rows[:, _COL["Size"]] > 0]
        target = np.flatnonzero(present[:, _COL["Target"]] == sample[-1])[0]
        out[k] = free_now(present, params)[target]
    return out


def net_inputs(data, kind: str) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """(train, test) inputs of the three nets."""
    control = (free_now_column(kind, data.X_train), free_now_column(kind, data.X_test))
    return {
        "ann": (data.X_train, data.X_test),
        "sann": (with_logical(data.X_train, data.logical_train),
                 with_logical(data.X_test, data.logical_test)),
        "control": (with_logical(data.X_train, control[0]),
                    with_logical(data.X_test, control[1])),
    }


def epochs_for(n_samples: int, config: BlocksExperiment) -> int:
    """The configured epochs, or more so that training takes at least ``min_steps`` steps."""
    batches = math.ceil(n_samples / config.train.batch_size)
    return max(config.train.epochs, math.ceil(config.min_steps / batches))


def train_nets(inputs: list[tuple[np.ndarray, np.ndarray]], y_train: np.ndarray,
               y_test: np.ndarray, config: BlocksExperiment) -> list[list[TrainResult]]:
    """The shallow net trained with every initialisation seed on each (train, test) input of
    the same samples, all at once (`train_groups`); one list of runs per input."""
    train = TrainConfig(epochs=epochs_for(len(y_train), config),
                        batch_size=config.train.batch_size, lr=config.train.lr,
                        weight_decay=config.train.weight_decay)
    return train_groups(lambda n: ShallowNet(n, hidden=config.hidden), inputs, y_train, y_test,
                        list(range(config.seeds)), train)


def train_pair(data, config: BlocksExperiment, seed: int) -> dict[str, TrainResult]:
    """Train the standard ANN and SANN on one dataset with one seed (the t-SNE figures)."""
    inputs = net_inputs(data, data.kind)
    runs = train_groups(lambda n: ShallowNet(n, hidden=config.hidden),
                        [inputs[net] for net in CURVE_NETS], data.y_train, data.y_test, [seed],
                        config.train)
    return {net: group[0] for net, group in zip(CURVE_NETS, runs, strict=True)}


# --------------------------------------------------------------------------- evaluation


def code_sha256() -> str:
    """The sha256 over the code that computes an evaluation (part of its cache key)."""
    digest = hashlib.sha256()
    for path in _CODE:
        digest.update(path.read_bytes())
    return digest.hexdigest()


def _description(kind: str, mode: str, data_seed: int, config: BlocksExperiment) -> dict:
    from sann import cache
    from sann.tasks.planning import DEFAULT_RULES

    settings = asdict(config)
    for key in ("data_seeds", "resamples", "tsne_points", "workers"):
        settings.pop(key)
    return {"kind": kind, "mode": mode, "data_seed": int(data_seed), "settings": settings,
            "params": asdict(BlockWorldParams()),
            "rules_code_sha256": cache.soar_code_sha256(DEFAULT_RULES),
            "dataset_version": DATASET_VERSION, "code_sha256": code_sha256()}


def evaluate(kind: str, mode: str, data_seed: int, config: BlocksExperiment,
             progress: bool = False) -> dict[str, np.ndarray]:
    """Every predictor's per-sample correctness on one dataset (cached): arrays
    ``<method>`` (runs, n_test) bool, ``curve_<net>`` (sizes, seeds, n_test) bool,
    ``error_<net>`` (seeds, epochs), ``scene``, ``y_test``, ``control_test``, ``rules_test``."""
    from sann import cache

    def build() -> dict[str, np.ndarray]:
        return _evaluate(kind, mode, data_seed, config, progress)

    arrays, _ = cache.get_or_build(f"blocks-eval-{kind}-{mode}",
                                   _description(kind, mode, data_seed, config), build)
    return arrays


def _evaluate(kind: str, mode: str, data_seed: int, config: BlocksExperiment,
              progress: bool) -> dict[str, np.ndarray]:
    data = make_dataset(kind, mode, n_train=config.n_train, n_test=config.n_test,
                        seed=data_seed, progress=progress, workers=config.workers)
    y_train, y_test = data.y_train, data.y_test
    majority = int(y_train.mean() >= 0.5)
    rules = rules_verdict(data.plans_test)
    inputs = net_inputs(data, kind)
    out: dict[str, np.ndarray] = {
        "majority": (np.full_like(y_test, majority) == y_test)[None, :],
        "rules": (rules == y_test)[None, :],
        "scene": data.image_test, "y_test": y_test, "y_train_mean": np.array(y_train.mean()),
        "rules_test": rules, "control_test": inputs["control"][1][:, -1],
        "logical_test": data.logical_test,
    }
    full = train_nets([inputs[net] for net in NETS], y_train, y_test, config)
    for net, runs in zip(NETS, full, strict=True):
        out[net] = np.stack([r.predict(inputs[net][1]) == y_test for r in runs])
        out[f"error_{net}"] = np.array([r.test_error for r in runs])
    curves: dict[str, list[np.ndarray]] = {net: [] for net in CURVE_NETS}
    for k in config.sizes[:-1]:
        grouped = train_nets([(inputs[net][0][:k], inputs[net][1]) for net in CURVE_NETS],
                             y_train[:k], y_test, config)
        for net, runs in zip(CURVE_NETS, grouped, strict=True):
            curves[net].append(np.stack([r.predict(inputs[net][1]) == y_test for r in runs]))
    for net in CURVE_NETS:
        out[f"curve_{net}"] = np.stack([*curves[net], out[net]])
    return out


def bootstrap(correct: dict[str, list[np.ndarray]], scenes: list[np.ndarray],
              resamples: int, seed: int = 0) -> dict[str, np.ndarray]:
    """Bootstrap replicates of each method's accuracy. ``correct[m][d]`` is a (runs, n) bool
    array of data seed ``d``'s test samples, ``scenes[d]`` their scene ids. Each replicate
    draws the data seeds, each drawn seed's test scenes and each method's runs (initialisation
    seeds) with replacement; all methods share the seeds and scenes drawn, so replicates of
    two methods can be subtracted. Returns (resamples,) accuracies per method."""
    rng = np.random.default_rng(seed)
    n_data = len(scenes)
    seed_counts = rng.multinomial(n_data, [1 / n_data] * n_data, size=resamples)
    hits = {m: np.zeros(resamples) for m in correct}
    total = {m: np.zeros(resamples) for m in correct}
    for d, scene in enumerate(scenes):
        ids, index = np.unique(scene, return_inverse=True)
        per_scene = np.bincount(index, minlength=len(ids))
        weights = rng.multinomial(len(ids), [1 / len(ids)] * len(ids), size=resamples)
        weights = weights * seed_counts[:, d:d + 1]
        for m, arrays in correct.items():
            runs = arrays[d]
            by_scene = np.stack([np.bincount(index, weights=r, minlength=len(ids))
                                 for r in runs.astype(float)])
            drawn = rng.integers(0, len(runs), size=(resamples, len(runs)))
            hits[m] += (by_scene[drawn].sum(axis=1) * weights).sum(axis=1)
            total[m] += len(runs) * (weights * per_scene).sum(axis=1)
    return {m: hits[m] / total[m] for m in correct}


def summary(point: float, replicates: np.ndarray) -> dict:
    """Point estimate and 95% percentile interval."""
    low, high = np.percentile(replicates, [2.5, 97.5])
    return {"mean": float(point), "ci95": [float(low), float(high)]}


def _point(arrays: list[np.ndarray]) -> float:
    """Accuracy over every sample, run and data seed (data seeds weigh by their samples)."""
    return float(np.mean(np.concatenate([a.mean(axis=0) for a in arrays])))


def summarise_dataset(evals: list[dict[str, np.ndarray]], config: BlocksExperiment,
                      seed: int = 0) -> dict:
    """Baselines, SANN - ANN, learning curves and agreements of one dataset's evaluations
    (one per data seed)."""
    scenes = [e["scene"] for e in evals]
    correct = {m: [e[m] for e in evals] for m in METHODS}
    reps = bootstrap(correct, scenes, config.resamples, seed)
    baselines = {m: summary(_point(correct[m]), reps[m]) for m in METHODS}
    for m in NETS:
        baselines[m]["per_seed"] = [[float(v) for v in e[m].mean(axis=1)] for e in evals]
    diff = summary(baselines["sann"]["mean"] - baselines["ann"]["mean"],
                   reps["sann"] - reps["ann"])
    curves: dict = {"sizes": config.sizes, "rules": baselines["rules"]}
    for net in CURVE_NETS:
        points = []
        for s in range(len(config.sizes)):
            one = [e[f"curve_{net}"][s] for e in evals]
            points.append(summary(_point(one), bootstrap({net: one}, scenes, config.resamples,
                                                         seed + 1 + s)[net]))
        curves[net] = points
    curves["sann_better"] = [k for k, a, s in zip(config.sizes, curves["ann"], curves["sann"],
                                                  strict=True) if s["ci95"][0] > a["ci95"][1]]
    y = np.concatenate([e["y_test"] for e in evals])
    rules = np.concatenate([e["rules_test"] for e in evals])
    control = np.concatenate([e["control_test"] for e in evals])
    return {
        "baselines": baselines, "sann_minus_ann": diff, "learning_curve": curves,
        "test_positive": float(y.mean()),
        "train_positive": [float(e["y_train_mean"]) for e in evals],
        "test_scenes": [len(np.unique(s)) for s in scenes],
        "control_equals_rules": float(np.mean(control == rules)),
        "rules_equals_label": float(np.mean(rules == y)),
        "test_error": {net: [c.tolist() for e in evals for c in e[f"error_{net}"]]
                       for net in CURVE_NETS},
    }


def results_for(evals: dict[tuple[str, str], list[dict]], config: BlocksExperiment) -> dict:
    """The results.json document of a set of evaluations."""
    results: dict = {"config": _jsonable(asdict(config)), "code_sha256": code_sha256(),
                     "sizes": config.sizes, "datasets": {}, "accuracy": {}, "test_error": {}}
    for k, (kind, mode) in enumerate(sorted(evals)):
        cell = summarise_dataset(evals[(kind, mode)], config, seed=100 * k)
        results["datasets"].setdefault(kind, {})[mode] = cell
        results["accuracy"].setdefault(kind, {})[mode] = {
            net: cell["baselines"][net] for net in CURVE_NETS}
        results["test_error"].setdefault(kind, {})[mode] = cell.pop("test_error")
    return results


def cached_results(config: BlocksExperiment = BlocksExperiment()) -> dict | None:
    """The results of ``config`` if every evaluation is in the cache, else None (nothing is
    computed: the book uses it to show a finished full-size run)."""
    from sann import cache

    evals = {}
    for kind in KINDS:
        for mode in MODES:
            found = []
            for seed in config.data_seeds:
                key = cache.make_key(_description(kind, mode, seed, config))
                arrays = cache.load(f"blocks-eval-{kind}-{mode}", key)
                if arrays is None:
                    return None
                found.append(arrays)
            evals[(kind, mode)] = found
    return results_for(evals, config)


# --------------------------------------------------------------------------- the run


def embed(values: np.ndarray, seed: int) -> np.ndarray:
    """2-D t-SNE map of ``values`` on one OpenMP thread: the gradient's parallel sums make
    the map depend on the thread count, and on a busy machine (the test suite runs two
    workers) spinning OpenMP threads made each map take 25-30 s instead of 4."""
    tsne = TSNE(n_components=2, init="pca", random_state=seed,
                perplexity=min(30.0, (len(values) - 1) / 3))
    with threadpool_limits(limits=1, user_api="openmp"):
        return tsne.fit_transform(values)


def tsne_layers(data, runs: dict[str, TrainResult], points: int, seed: int) -> dict:
    """t-SNE maps of the input layer and of the hidden layer of ANN and SANN (Figs. 13-14),
    on the same subsample of test samples."""
    import torch

    rng = np.random.default_rng(seed)
    chosen = rng.choice(len(data.y_test), size=min(points, len(data.y_test)), replace=False)
    inputs = {"ann": data.X_test[chosen],
              "sann": with_logical(data.X_test[chosen], data.logical_test[chosen])}
    maps: dict[str, dict[str, np.ndarray]] = {"input": {}, "hidden": {}}
    for name, run in runs.items():
        x = run.standardiser(inputs[name])
        with torch.no_grad():
            hidden = run.model.hidden(torch.from_numpy(x)).numpy()
        for layer, values in (("input", x), ("hidden", hidden)):
            maps[layer][name.upper()] = embed(values, seed)
    return {"maps": maps, "labels": data.y_test[chosen]}


#: The datasets by how long planning and training them took in a book build, longest first
#: (D2 plans one scene per sample; C3's scenes are the hardest to plan, C2's the easiest).
LONGEST_FIRST = (("D2", "C3"), ("D2", "C1"), ("D2", "C2"), ("D1", "C3"), ("D1", "C2"),
                 ("D1", "C1"))


def _evaluate_task(task: tuple) -> tuple[tuple[str, str, int], dict[str, np.ndarray]]:
    kind, mode, seed, config, progress = task
    return (kind, mode, seed), evaluate(kind, mode, seed, config, progress)


def evaluate_all(config: BlocksExperiment, progress: bool = False
                 ) -> dict[tuple[str, str], list[dict[str, np.ndarray]]]:
    """Every (dataset, data seed) evaluation, from the cache where possible. The missing ones
    are computed ``config.workers`` at a time (None: one per core), each in one forked
    process that plans its scenes and trains its nets, the longest first: planning alone
    was parallel before, and training kept one core busy. Every scene and every net has its
    own seed, so the numbers do not depend on which process computed them."""
    from sann import cache
    from sann.tasks.blocks.dataset import _check_workers

    found: dict[tuple[str, str, int], dict[str, np.ndarray]] = {}
    missing = []
    for kind, mode in LONGEST_FIRST:
        for seed in config.data_seeds:
            key = cache.make_key(_description(kind, mode, seed, config))
            arrays = cache.load(f"blocks-eval-{kind}-{mode}", key)
            if arrays is None:
                missing.append((kind, mode, seed))
            else:
                found[(kind, mode, seed)] = arrays
    workers = min(_check_workers(config.workers), len(missing))
    if workers <= 1:
        for kind, mode, seed in missing:
            found[(kind, mode, seed)] = evaluate(kind, mode, seed, config, progress)
    else:
        import multiprocessing as mp

        alone = replace(config, workers=1)  # no pool inside a pool
        tasks = [(kind, mode, seed, alone, progress) for kind, mode, seed in missing]
        with mp.get_context("fork").Pool(workers) as pool:
            for task, arrays in pool.imap_unordered(_evaluate_task, tasks):
                found[task] = arrays
    return {(kind, mode): [found[(kind, mode, seed)] for seed in config.data_seeds]
            for kind in KINDS for mode in MODES}


def run(out: str | Path, config: BlocksExperiment = BlocksExperiment(),
        progress: bool = False) -> dict:
    """Evaluate the six datasets over the data seeds (from the cache where possible), write
    results.json and the figures into ``out``; returns the results."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    evals = evaluate_all(config, progress)
    results = results_for(evals, config)
    _figures(out, results, config)
    (out / "results.json").write_text(json.dumps(results, indent=1))
    return results


def _figures(out: Path, results: dict, config: BlocksExperiment) -> None:
    plots.error_curves(results["test_error"]["D1"]["C3"], "Fig. 8: test error, D1-C3",
                       out / "fig8_test_error_D1_C3.png")
    plots.accuracy_bars(results["accuracy"]["D1"], "Fig. 9a: test accuracy, D1",
                        out / "fig9a_accuracy_D1.png")
    plots.accuracy_bars(results["accuracy"]["D2"], "Fig. 9b: test accuracy, D2",
                        out / "fig9b_accuracy_D2.png")
    plots.learning_curves({f"{k}-{m}": results["datasets"][k][m]["learning_curve"]
                           for k in KINDS for m in MODES},
                          "Test accuracy against training size", out / "learning_curves.png")
    if config.tsne_points <= 0:
        return
    data = make_dataset("D1", "C3", n_train=config.n_train, n_test=config.n_test,
                        seed=config.data_seed, workers=config.workers)
    tsne = tsne_layers(data, train_pair(data, config, 0), config.tsne_points, config.data_seed)
    plots.tsne_pair(tsne["maps"]["input"], tsne["labels"], "Fig. 13: t-SNE of the input layer",
                    out / "fig13_tsne_input.png")
    plots.tsne_pair(tsne["maps"]["hidden"], tsne["labels"],
                    "Fig. 14: t-SNE of the hidden layer", out / "fig14_tsne_hidden.png")


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value
