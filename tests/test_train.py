"""Training is deterministic per seed, learns a separable problem and summarises honestly."""

import numpy as np
import pytest

from sann.nets import ShallowNet
from sann.train import Standardiser, TrainConfig, intervals_overlap, summarise, train


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
