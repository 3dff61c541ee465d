"""Training is deterministic per seed, learns a separable problem and summarises honestly."""

import numpy as np
import pytest
import torch
from torch import nn

from sann.nets import DeepNet, ShallowNet
from sann.train import (
    StackedNets,
    Standardiser,
    TrainConfig,
    intervals_overlap,
    summarise,
    train,
    train_groups,
    train_seeds,
)


def _xor_like(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    x = rng.uniform(-1, 1, size=(n, 3)).astype(np.float32) * [1, 1, 100]
    y = ((x[:, 0] > 0) ^ (x[:, 1] > 0)).astype(np.int64)
    return x, y


def test_standardiser_uses_training_statistics_and_survives_constant_columns():
    x = np.array([[1.0, 5.0], [3.0, 5.0]], dtype=np.float32)
    scale = Standardiser.fit(x)
    np.testing.assert_allclose(scale(x), [[-1, 0], [1, 0]])
    np.testing.assert_allclose(scale(np.array([[5.0, 6.0]], dtype=np.float32)), [[3, 1]])


def test_training_learns_and_is_deterministic():
    x, y = _xor_like(1200, 0)
    xv, yv = _xor_like(400, 1)
    config = TrainConfig(epochs=25, batch_size=32, lr=0.02)
    a = train(lambda n: ShallowNet(n, hidden=8), x, y, xv, yv, seed=3, config=config)
    b = train(lambda n: ShallowNet(n, hidden=8), x, y, xv, yv, seed=3, config=config)
    assert a.test_error == b.test_error and len(a.test_error) == 25
    assert a.accuracy > 0.9 > 1 - a.test_error[0] - 0.3
    assert (a.predict(xv) == yv).mean() == pytest.approx(a.accuracy)


def test_summary_interval_contains_the_mean_and_detects_separation():
    high = summarise([0.99, 0.995, 0.992, 0.993, 0.991])
    low = summarise([0.95, 0.96, 0.955, 0.962, 0.958])
    assert high["ci95"][0] < high["mean"] < high["ci95"][1]
    assert not intervals_overlap(high, low)
    assert intervals_overlap(high, summarise([0.98, 0.999, 0.99]))
    assert summarise([0.5])["ci95"] == [0.5, 0.5]


def _one_net_alone(make, x, y, xv, yv, seed: int, config: TrainConfig) -> tuple[list, list]:
    """The textbook loop for one net (what `train_seeds` must equal per seed)."""
    torch.manual_seed(seed)
    scale = Standardiser.fit(x)
    xt, yt = torch.from_numpy(scale(x)), torch.from_numpy(y)
    xe, ye = torch.from_numpy(scale(xv)), torch.from_numpy(yv)
    model = make(xt.shape[1])
    optimiser = torch.optim.Adam(model.parameters(), lr=config.lr)
    order = torch.Generator().manual_seed(seed)
    losses, errors = [], []
    for _ in range(config.epochs):
        total = 0.0
        for batch in torch.randperm(len(xt), generator=order).split(config.batch_size):
            optimiser.zero_grad()
            loss = nn.functional.cross_entropy(model(xt[batch]), yt[batch])
            loss.backward()
            optimiser.step()
            total += loss.item() * len(batch)
        losses.append(total / len(xt))
        with torch.no_grad():
            errors.append((model(xe).argmax(1) != ye).sum().item() / len(ye))
    return losses, errors


@pytest.mark.parametrize("make", [lambda n: ShallowNet(n, hidden=5),
                                  lambda n: DeepNet(n, hidden=(6, 4))], ids=["shallow", "deep"])
def test_seeds_trained_together_equal_each_seed_trained_alone(make):
    x, y = _xor_like(300, 0)
    xv, yv = _xor_like(100, 1)
    config = TrainConfig(epochs=6, batch_size=32, lr=0.02)
    together = train_seeds(make, x, y, xv, yv, [4, 0, 9], config)
    assert [r.seed for r in together] == [4, 0, 9]
    for run in together:
        losses, errors = _one_net_alone(make, x, y, xv, yv, run.seed, config)
        np.testing.assert_allclose(run.train_loss, losses, rtol=1e-5)
        assert np.abs(np.array(run.test_error) - errors).max() <= 1 / len(yv)
        assert run.accuracy == 1 - run.test_error[-1]
    alone = train(make, x, y, xv, yv, seed=9, config=config)
    np.testing.assert_allclose(alone.train_loss, together[2].train_loss, rtol=1e-5)
    with torch.no_grad():
        probe = torch.from_numpy(together[2].standardiser(xv))
        np.testing.assert_allclose(together[2].model(probe), alone.model(probe), atol=1e-4)


@pytest.mark.parametrize("make", [lambda n: ShallowNet(n, hidden=5),
                                  lambda n: DeepNet(n, hidden=(6, 4))], ids=["shallow", "deep"])
def test_inputs_of_different_widths_trained_together_equal_each_alone(make):
    """The features alone and with one more column (the ANN and SANN of a dataset): the
    narrower input is padded with a zero column inside the stack, which changes nothing."""
    x, y = _xor_like(300, 0)
    xv, yv = _xor_like(100, 1)
    extra = np.column_stack([x, x[:, 0] * x[:, 1]]).astype(np.float32)
    extra_v = np.column_stack([xv, xv[:, 0] * xv[:, 1]]).astype(np.float32)
    config = TrainConfig(epochs=5, batch_size=32, lr=0.02)
    plain, fused = train_groups(make, [(x, xv), (extra, extra_v)], y, yv, [4, 0], config)
    for runs, (xt, xe) in ((plain, (x, xv)), (fused, (extra, extra_v))):
        assert [r.seed for r in runs] == [4, 0]
        for run in runs:
            assert run.model(torch.zeros(1, xt.shape[1])).shape == (1, 2)
            losses, errors = _one_net_alone(make, xt, y, xe, yv, run.seed, config)
            np.testing.assert_allclose(run.train_loss, losses, rtol=1e-5)
            assert np.abs(np.array(run.test_error) - errors).max() <= 1 / len(yv)
    with pytest.raises(ValueError, match="one row per label"):
        train_groups(make, [(x, xv), (extra[:-1], extra_v)], y, yv, [1], config)


def test_train_seeds_refuses_empty_input():
    x, y = _xor_like(20, 0)
    make = lambda n: ShallowNet(n)  # noqa: E731
    with pytest.raises(ValueError, match="at least one seed"):
        train_seeds(make, x, y, x, y, [])
    with pytest.raises(ValueError, match="must not be empty"):
        train_seeds(make, x[:0], y[:0], x, y, [1])
    with pytest.raises(ValueError, match="epochs"):
        train_seeds(make, x, y, x, y, [1], TrainConfig(epochs=0))


class _Residual(nn.Module):
    """A net whose forward is not its layers in order: stacking must refuse it."""

    def __init__(self, n: int) -> None:
        super().__init__()
        self.a, self.b = nn.Linear(n, n), nn.Linear(n, 2)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.b(x + self.a(x))


def test_stacking_refuses_nets_it_cannot_compute():
    probe = torch.randn(4, 3)
    with pytest.raises(ValueError, match="cannot be stacked"):
        StackedNets([_Residual(3), _Residual(3)], probe)
    with pytest.raises(ValueError, match="cannot stack a Dropout"):
        StackedNets([nn.Sequential(nn.Linear(3, 2), nn.Dropout())], probe)
