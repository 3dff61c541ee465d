"""Training and evaluation of the graspability nets, with fixed seeds and seed statistics.

Inputs are standardised with statistics of the training set only (the test set must not leak
into the model). A single run of a 5-unit net says little, so every reported figure comes
from several seeds: :func:`summarise` gives a mean with a 95% Student-t interval over seeds
(the cup experiment); the block experiment resamples test scenes, data seeds and seeds
together (:func:`sann.experiments.blocks.bootstrap`), because the samples of one scene are
not independent.
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
    """One net per seed on the same data, all trained at once (see `train_groups`)."""
    return train_groups(make_net, [(x_train, x_test)], y_train, y_test, seeds, config,
                        progress)[0]


def train_groups(
    make_net: Callable[[int], nn.Module],
    inputs: Sequence[tuple[np.ndarray, np.ndarray]],
    y_train: np.ndarray,
    y_test: np.ndarray,
    seeds: Sequence[int],
    config: TrainConfig = TrainConfig(),
    progress: bool = False,
) -> list[list[TrainResult]]:
    """One net per seed for each of several inputs of the same samples, e.g. the features
    alone and with the logical item: all trained at once. ``inputs`` holds (train, test)
    arrays with one row per sample of ``y_train`` / ``y_test``; one list of results (one per
    seed) per input.

    Each net starts from the weights ``make_net(width)`` gives after ``torch.manual_seed(seed)``
    and sees its own order of mini-batches (a generator seeded with ``seed``), as if trained
    alone. The nets' layers are stacked into batched matrix products (`StackedNets`), so a
    step pays torch's per-operation overhead once for all of them: for the paper's 5-unit net
    that overhead is nearly all of the time (five seeds cost what one did; torch.vmap over
    torch.func's stacked state, tried first, cost twice as much per step). Narrower inputs
    are padded with zero columns, whose weights start at zero and get zero gradients, so they
    stay zero. The loss is the sum of the nets' mean losses, so each net's gradient is its
    own, and Adam updates each element on its own: the numbers equal separate runs up to float
    rounding (tests/test_train.py)."""
    seeds = [int(s) for s in seeds]
    if not seeds:
        raise ValueError("train_seeds needs at least one seed")
    if not inputs:
        raise ValueError("train_groups needs at least one input")
    if config.epochs < 1 or config.batch_size < 1:
        raise ValueError(f"epochs and batch_size must be >= 1, got {config}")
    for x_train, x_test in inputs:
        if len(x_train) == 0 or len(x_test) == 0:
            raise ValueError("training and test sets must not be empty")
        if len(x_train) != len(y_train) or len(x_test) != len(y_test):
            raise ValueError("every input needs one row per label")
    torch.set_num_threads(1)
    scalers = [Standardiser.fit(x_train) for x_train, _ in inputs]
    width = max(x_train.shape[1] for x_train, _ in inputs)
    pairs = list(zip(scalers, inputs, strict=True))
    xt = torch.stack([_padded(scaler(x), width) for scaler, (x, _) in pairs])
    xv = torch.stack([_padded(scaler(x), width) for scaler, (_, x) in pairs])
    yt = torch.from_numpy(y_train.astype(np.int64))
    yv = torch.from_numpy(y_test.astype(np.int64))
    models = []
    for x_train, _ in inputs:
        for seed in seeds:
            torch.manual_seed(seed)
            models.append(make_net(x_train.shape[1]))
    group = torch.arange(len(inputs)).repeat_interleave(len(seeds))  # the input of each net
    stack = StackedNets(models, probe=xt[group, :8])
    optimiser = torch.optim.Adam(stack.parameters(), lr=config.lr,
                                 weight_decay=config.weight_decay)
    orders = [torch.Generator().manual_seed(seed) for seed in seeds]
    test_inputs = xv[group]
    errors, losses = [], []
    epochs = range(config.epochs)
    if progress:
        from tqdm.auto import tqdm

        epochs = tqdm(epochs, desc=f"train seeds {seeds}", leave=False)
    n_nets, n = len(models), len(yt)
    for _ in epochs:
        order = torch.stack([torch.randperm(n, generator=g) for g in orders]).repeat(
            len(inputs), 1)
        total = torch.zeros(n_nets)
        for batch in order.split(config.batch_size, dim=1):
            optimiser.zero_grad()
            logits = stack(xt[group[:, None], batch])
            each = nn.functional.cross_entropy(logits.flatten(0, 1), yt[batch].flatten(),
                                               reduction="none").view(n_nets, -1).mean(1)
            each.sum().backward()
            optimiser.step()
            total += each.detach() * batch.shape[1]
        losses.append((total / n).tolist())
        with torch.no_grad():
            wrong = (stack(test_inputs).argmax(-1) != yv).sum(1)
        errors.append([w / len(yv) for w in wrong.tolist()])
    stack.write_back()
    results: list[list[TrainResult]] = [[] for _ in inputs]
    for k, model in enumerate(models):
        model.eval()
        g, seed = int(group[k]), seeds[k % len(seeds)]
        curve = [epoch[k] for epoch in errors]
        results[g].append(TrainResult(seed, curve, [epoch[k] for epoch in losses],
                                      1.0 - curve[-1], model, scalers[g]))
    return results


def _padded(x: np.ndarray, width: int) -> torch.Tensor:
    """``x`` with zero columns appended up to ``width``."""
    out = torch.zeros(len(x), width)
    out[:, :x.shape[1]] = torch.from_numpy(x)
    return out


def train_baseline_and_sann(
    make_net: Callable[[int], nn.Module],
    data,
    fused: tuple[np.ndarray, np.ndarray],
    seeds: Sequence[int],
    config: TrainConfig,
    baseline: str,
) -> list[dict[str, TrainResult]]:
    """The paper's comparison on one dataset: the net on ``data``'s features (named
    ``baseline``) and SANN, the same net on the ``fused`` (train, test) features with the
    logical item, all trained together; one pair per seed."""
    plain, sann = train_groups(make_net, [(data.X_train, data.X_test), fused], data.y_train,
                               data.y_test, seeds, config)
    return [{baseline: a, "sann": b} for a, b in zip(plain, sann, strict=True)]


#: Layers that act on each number alone: the same module serves every stacked net.
ELEMENTWISE = (nn.Tanh, nn.ReLU, nn.Sigmoid, nn.Identity)


class StackedNets:
    """Nets of one architecture, made of ``nn.Linear`` layers and elementwise activations
    applied in the order they are registered, run as one net on a batch per net: each
    Linear's weights become one (nets, in, out) tensor and its forward a batched matrix
    product; a Linear narrower than the widest of its position (the first layer of a net with
    fewer inputs) is padded with zero rows, for inputs padded with zero columns. ``probe``
    rows (shared, or one batch per net) check that the stack computes what each net computes
    (a net whose forward does something else is refused)."""

    def __init__(self, models: Sequence[nn.Module], probe: torch.Tensor) -> None:
        self.models = list(models)
        self.layers: list = []
        leaves = [[m for m in net.modules() if next(m.children(), None) is None]
                  for net in self.models]
        for position in zip(*leaves, strict=True):
            self.layers.append(self._stack(position))
        with torch.no_grad():
            mine = self(probe)
            for k, net in enumerate(self.models):
                mine_k = probe if probe.dim() == 2 else probe[k]
                first = next(m for m in net.modules() if isinstance(m, nn.Linear))
                if not torch.allclose(mine[k], net(mine_k[:, :first.in_features]), atol=1e-5):
                    raise ValueError(
                        f"{type(net).__name__} cannot be stacked: its forward is not its "
                        "Linear layers and activations in the order they are registered")

    @staticmethod
    def _stack(position: tuple[nn.Module, ...]):
        first = position[0]
        if isinstance(first, nn.Linear):
            width = max(m.in_features for m in position)
            weight = torch.zeros(len(position), width, first.out_features)
            for k, m in enumerate(position):
                weight[k, :m.in_features] = m.weight.detach().T
            bias = (None if first.bias is None
                    else torch.stack([m.bias.detach()[None] for m in position]))
            return (weight.requires_grad_(),
                    None if bias is None else bias.requires_grad_())
        if isinstance(first, ELEMENTWISE):
            return first
        raise ValueError(f"cannot stack a {type(first).__name__} layer (Linear and "
                         f"{', '.join(t.__name__ for t in ELEMENTWISE)} only)")

    def parameters(self) -> list[torch.Tensor]:
        return [t for layer in self.layers if type(layer) is tuple for t in layer
                if t is not None]

    def __call__(self, x: torch.Tensor) -> torch.Tensor:
        """(nets, batch, in) -> (nets, batch, out); a 2-D ``x`` is fed to every net."""
        for layer in self.layers:
            if type(layer) is tuple:
                weight, bias = layer
                if bias is None:
                    x = x @ weight
                elif x.dim() == 3:
                    x = torch.baddbmm(bias, x, weight)
                else:
                    x = x @ weight + bias
            else:
                x = layer(x)
        return x

    def write_back(self) -> None:
        """Put the trained weights into the nets themselves."""
        linear = [layer for layer in self.layers if type(layer) is tuple]
        with torch.no_grad():
            for k, net in enumerate(self.models):
                mine = [m for m in net.modules() if isinstance(m, nn.Linear)]
                for module, (weight, bias) in zip(mine, linear, strict=True):
                    module.weight.copy_(weight[k, :module.in_features].T)
                    if bias is not None:
                        module.bias.copy_(bias[k, 0])


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
