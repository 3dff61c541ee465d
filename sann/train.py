"""Training and evaluation of the graspability nets, with fixed seeds and seed statistics.

Inputs are standardised with statistics of the training set only (the test set must not leak
into the model). Every reported figure is a mean over several seeds with a 95% Student-t
interval, because a single run of a 5-unit net says little.
"""

from __future__ import annotations

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


def error_rate(model: nn.Module, x: torch.Tensor, y: torch.Tensor) -> float:
    """Eq. 4: wrongly predicted test samples over all test samples."""
    with torch.no_grad():
        wrong = (model(x).argmax(dim=1) != y).sum().item()
    return wrong / max(1, len(y))


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
    if len(x_train) == 0 or len(x_test) == 0:
        raise ValueError("training and test sets must not be empty")
    torch.set_num_threads(1)
    torch.manual_seed(seed)
    scaler = Standardiser.fit(x_train)
    xt, yt = torch.from_numpy(scaler(x_train)), torch.from_numpy(y_train.astype(np.int64))
    xv, yv = torch.from_numpy(scaler(x_test)), torch.from_numpy(y_test.astype(np.int64))
    model = make_net(xt.shape[1])
    optimiser = torch.optim.Adam(model.parameters(), lr=config.lr, weight_decay=config.weight_decay)
    loss_fn = nn.CrossEntropyLoss()
    order = torch.Generator().manual_seed(seed)
    errors, losses = [], []
    epochs = range(config.epochs)
    if progress:
        from tqdm.auto import tqdm

        epochs = tqdm(epochs, desc=f"train seed {seed}", leave=False)
    for _ in epochs:
        model.train()
        total = 0.0
        for batch in torch.randperm(len(xt), generator=order).split(config.batch_size):
            optimiser.zero_grad()
            loss = loss_fn(model(xt[batch]), yt[batch])
            loss.backward()
            optimiser.step()
            total += loss.item() * len(batch)
        model.eval()
        losses.append(total / len(xt))
        errors.append(error_rate(model, xv, yv))
    return TrainResult(seed, errors, losses, 1.0 - errors[-1], model, scaler)


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
