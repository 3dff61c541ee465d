"""The multi-block experiment (paper Figs. 8, 9, 13, 14): ANN vs SANN on D1/D2 x C1/C2/C3.

For every dataset the standard ANN sees the features, SANN the features plus the logical item
that fusion computed from the Soar plans; both are the paper's shallow net (inputs -> 5 tanh
units -> 2), trained from the same seeds. Accuracies are means over seeds with a 95% interval.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np
from sklearn.manifold import TSNE
from threadpoolctl import threadpool_limits

from sann.nets import ShallowNet
from sann.tasks.blocks import make_dataset
from sann.train import TrainConfig, TrainResult, summarise, train_baseline_and_sann
from sann.viz import plots

KINDS = ("D1", "D2")
MODES = ("C1", "C2", "C3")


@dataclass(frozen=True)
class BlocksExperiment:
    """Sizes and settings of one reproduction; `quick()` is the small version for tests.
    ``tsne_points=0`` leaves out the t-SNE figures (13-14), e.g. where another part of the
    book draws them."""

    n_train: int = 10_000
    n_test: int = 2_000
    seeds: int = 5
    data_seed: int = 0
    hidden: int = 5
    train: TrainConfig = TrainConfig(epochs=60, batch_size=64, lr=0.01)
    tsne_points: int = 1_000

    @classmethod
    def quick(cls, seeds: int = 2) -> BlocksExperiment:
        return cls(n_train=800, n_test=300, seeds=seeds,
                   train=TrainConfig(epochs=15, batch_size=64, lr=0.02), tsne_points=300)


def with_logical(x: np.ndarray, logical: np.ndarray) -> np.ndarray:
    """The fused M x (N+1) array: features plus the logical item column."""
    return np.hstack([x, logical.reshape(-1, 1)]).astype(np.float32)


def train_pair(data, config: BlocksExperiment, seed: int) -> dict[str, TrainResult]:
    """Train the standard ANN and SANN on one dataset with one seed."""
    return train_pairs(data, config, [seed])[0]


def train_pairs(data, config: BlocksExperiment, seeds: list[int]) -> list[dict[str, TrainResult]]:
    """Train the standard ANN and SANN on one dataset with every seed (each net kind's seeds
    are trained together, see `train_seeds`); one {"ann", "sann"} pair per seed."""
    fused = (with_logical(data.X_train, data.logical_train),
             with_logical(data.X_test, data.logical_test))
    return train_baseline_and_sann(lambda n: ShallowNet(n, hidden=config.hidden), data, fused,
                                   seeds, config.train, "ann")


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


def embed(values: np.ndarray, seed: int) -> np.ndarray:
    """2-D t-SNE map of ``values`` on one OpenMP thread: the gradient's parallel sums make
    the map depend on the thread count, and on a busy machine (the test suite runs two
    workers) spinning OpenMP threads made each map take 25-30 s instead of 4."""
    tsne = TSNE(n_components=2, init="pca", random_state=seed,
                perplexity=min(30.0, (len(values) - 1) / 3))
    with threadpool_limits(limits=1, user_api="openmp"):
        return tsne.fit_transform(values)


def run(out: str | Path, config: BlocksExperiment = BlocksExperiment(),
        progress: bool = False) -> dict:
    """Build the six datasets, train ANN and SANN over the seeds, write results.json and the
    figures into ``out``; returns the results."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    results: dict = {"config": _config_dict(config), "accuracy": {}, "test_error": {},
                     "datasets": {}}
    tsne_input = None
    for kind in KINDS:
        for mode in MODES:
            data = make_dataset(kind, mode, n_train=config.n_train, n_test=config.n_test,
                                seed=config.data_seed, progress=progress,
                                workers=None)
            runs = train_pairs(data, config, list(range(config.seeds)))
            results["datasets"].setdefault(kind, {})[mode] = _jsonable(data.meta)
            results["accuracy"].setdefault(kind, {})[mode] = {
                net: summarise([r[net].accuracy for r in runs]) for net in ("ann", "sann")}
            results["test_error"].setdefault(kind, {})[mode] = {
                net: [r[net].test_error for r in runs] for net in ("ann", "sann")}
            if (kind, mode) == ("D1", "C3"):
                tsne_input = (data, runs[0])
    _figures(out, results, tsne_input, config)
    (out / "results.json").write_text(json.dumps(results, indent=1))
    return results


def _figures(out: Path, results: dict, tsne_input, config: BlocksExperiment) -> None:
    plots.error_curves(results["test_error"]["D1"]["C3"], "Fig. 8: test error, D1-C3",
                       out / "fig8_test_error_D1_C3.png")
    plots.accuracy_bars(results["accuracy"]["D1"], "Fig. 9a: test accuracy, D1",
                        out / "fig9a_accuracy_D1.png")
    plots.accuracy_bars(results["accuracy"]["D2"], "Fig. 9b: test accuracy, D2",
                        out / "fig9b_accuracy_D2.png")
    if config.tsne_points <= 0:
        return
    data, runs = tsne_input
    tsne = tsne_layers(data, runs, config.tsne_points, config.data_seed)
    plots.tsne_pair(tsne["maps"]["input"], tsne["labels"], "Fig. 13: t-SNE of the input layer",
                    out / "fig13_tsne_input.png")
    plots.tsne_pair(tsne["maps"]["hidden"], tsne["labels"],
                    "Fig. 14: t-SNE of the hidden layer", out / "fig14_tsne_hidden.png")


def _config_dict(config: BlocksExperiment) -> dict:
    return asdict(replace(config))


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, str | int | float | bool) or value is None:
        return value
    if hasattr(value, "__dataclass_fields__"):
        return _jsonable(asdict(value))
    return str(value)
