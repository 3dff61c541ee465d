"""Training and evaluation of the graspability nets, with fixed seeds and seed statistics.

Inputs are standardised with statistics of the training set only (the test set must not leak
into the model). Every reported figure is a mean over several seeds with a 95% Student-t
interval, because a single run of a 5-unit net says little.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import torch
from scipy import stats
from torch import nn


@dataclass(frozen=True)
class Standardiser:
    """Per-column (x - mean) / std with the training set's statistics; constant columns are
    left centred (std 1) instead of dividing by zero."""

    mean: np.ndarray
    std: np.ndarray

    @classmethod
    def fit(cls, x: np.ndarray) -> Standardiser:
        mean = x.mean(axis=0)
        std = x.std(axis=0)
        return cls(mean.astype(np.float32), np.where(std > 1e-8, std, 1.0).astype(np.float32))

    def __call__(self, x: np.ndarray) -> np.ndarray:
        return ((x - self.mean) / self.std).astype(np.float32)


@dataclass(frozen=True)
class TrainConfig:
    """Optimiser settings. Adam with mini-batches; the defaults reach the block task's
    accuracy in a few seconds on two cores."""

    epochs: int = 60
    batch_size: int = 64
    lr: float = 0.01
    weight_decay: float = 0.0


@dataclass
class TrainResult:
    """What one training run produced: per-epoch curves (eq. 4 test error) and the model."""

    seed: int
    test_error: list[float]
    train_loss: list[float]
    accuracy: float
    model: nn.Module = field(repr=False)
    standardiser: Standardiser = field(repr=False)

    def predict(self, x: np.ndarray) -> np.ndarray:
        with torch.no_grad():
            logits = self.model(torch.from_numpy(self.standardiser(x)))
        return logits.argmax(dim=1).numpy()


def train(
    make_net: Callable[[int], nn.Module],
    x_train: np.ndarray,
    y_train: np.ndarray,
    x_test: np.ndarray,
    y_test: np.ndarray,
    seed: int,
    config: TrainConfig = TrainConfig(),
    progress: bool = False,
) -> TrainResult:
    """Train ``make_net(n_inputs)`` from scratch with ``seed`` and report the test error after
    every epoch. Same seed and data give the same numbers (single-threaded torch)."""
    return train_seeds(make_net, x_train, y_train, x_test, y_test, [seed], config, progress)[0]


def train_seeds(
    make_net: Callable[[int], nn.Module],
    x_train: np.ndarray,
    y_train: np.ndarray,
    x_test: np.ndarray,
    y_test: np.ndarray,
    seeds: Sequence[int],
    config: TrainConfig = TrainConfig(),
    progress: bool = False,
) -> list[TrainResult]:
    """One net per seed on the same data, all trained at once.

    Each seed's net starts from the weights ``make_net`` gives after ``torch.manual_seed(seed)``
    and sees its own order of mini-batches (a generator seeded with ``seed``), as if trained
    alone. The nets' parameters are stacked and run under ``torch.vmap`` (torch.func's model
    ensembling), so a step costs the Python and dispatch overhead once for all seeds: for the
    paper's 5-unit net that overhead is most of the time. The loss is the sum of the nets' mean
    losses, so each net's gradient is its own, and Adam updates each element on its own: the
    numbers equal separate runs up to float rounding (tests/test_train.py)."""
    seeds = [int(s) for s in seeds]
    if not seeds:
        raise ValueError("train_seeds needs at least one seed")
    if len(x_train) == 0 or len(x_test) == 0:
        raise ValueError("training and test sets must not be empty")
    if config.epochs < 1 or config.batch_size < 1:
        raise ValueError(f"epochs and batch_size must be >= 1, got {config}")
    torch.set_num_threads(1)
    scaler = Standardiser.fit(x_train)
    xt, yt = torch.from_numpy(scaler(x_train)), torch.from_numpy(y_train.astype(np.int64))
    xv, yv = torch.from_numpy(scaler(x_test)), torch.from_numpy(y_test.astype(np.int64))
    models = []
    for seed in seeds:
        torch.manual_seed(seed)
        models.append(make_net(xt.shape[1]))
    params, buffers = torch.func.stack_module_state(models)
    skeleton = copy.deepcopy(models[0]).to("meta")

    def call(p: dict, b: dict, x: torch.Tensor) -> torch.Tensor:
        return torch.func.functional_call(skeleton, (p, b), (x,))

    batched, on_test = torch.vmap(call), torch.vmap(call, in_dims=(0, 0, None))
    optimiser = torch.optim.Adam(params.values(), lr=config.lr, weight_decay=config.weight_decay)
    orders = [torch.Generator().manual_seed(seed) for seed in seeds]
    errors, losses = [], []
    epochs = range(config.epochs)
    if progress:
        from tqdm.auto import tqdm

        epochs = tqdm(epochs, desc=f"train seeds {seeds}", leave=False)
    for _ in epochs:
        order = torch.stack([torch.randperm(len(xt), generator=g) for g in orders])
        total = torch.zeros(len(seeds))
        for batch in order.split(config.batch_size, dim=1):
            optimiser.zero_grad()
            logits = batched(params, buffers, xt[batch])
            each = nn.functional.cross_entropy(logits.flatten(0, 1), yt[batch].flatten(),
                                               reduction="none").view(len(seeds), -1).mean(1)
            each.sum().backward()
            optimiser.step()
            total += each.detach() * batch.shape[1]
        losses.append((total / len(xt)).tolist())
        with torch.no_grad():
            wrong = (on_test(params, buffers, xv).argmax(-1) != yv).sum(1)
        errors.append([w / len(yv) for w in wrong.tolist()])
    results = []
    for k, (seed, model) in enumerate(zip(seeds, models, strict=True)):
        model.load_state_dict({name: value[k].detach().clone() for name, value in params.items()})
        model.eval()
        curve = [epoch[k] for epoch in errors]
        results.append(TrainResult(seed, curve, [epoch[k] for epoch in losses],
                                   1.0 - curve[-1], model, scaler))
    return results


def summarise(values: Sequence[float]) -> dict:
    """Mean and 95% Student-t interval over seeds, plus the per-seed values."""
    data = np.asarray(values, dtype=float)
    mean = float(data.mean())
    if len(data) < 2 or float(data.std()) == 0.0:
        low = high = mean
    else:
        half = stats.t.ppf(0.975, len(data) - 1) * data.std(ddof=1) / np.sqrt(len(data))
        low, high = mean - half, mean + half
    return {"mean": mean, "ci95": [float(low), float(high)], "seeds": [float(v) for v in data]}


def intervals_overlap(a: dict, b: dict) -> bool:
    """Do two summaries' 95% intervals overlap?"""
    return not (a["ci95"][1] < b["ci95"][0] or b["ci95"][1] < a["ci95"][0])
