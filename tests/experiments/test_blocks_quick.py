"""`python -m sann reproduce blocks --quick` end to end, and the baselines it reports."""

import json
from dataclasses import replace

import numpy as np
import pytest

from sann.__main__ import main
from sann.experiments import blocks
from sann.tasks.blocks import FEATURE_NAMES, features, graspable, make_dataset, scene_from_blocks
from sann.tasks.planning import Planner, PlannerConfig
from sann.train import TrainConfig

pytestmark = pytest.mark.xdist_group("blocks-datasets")

QUICK = blocks.BlocksExperiment.quick()
TINY = blocks.BlocksExperiment(n_train=60, n_test=40, seeds=2, data_seeds=(0, 1),
                               train=TrainConfig(epochs=3, batch_size=32, lr=0.02),
                               curve_sizes=(30,), min_steps=10, resamples=50, tsne_points=0)


@pytest.fixture(scope="module")
def quick_results(tmp_path_factory):
    out = tmp_path_factory.mktemp("blocks-quick")
    assert main(["reproduce", "blocks", "--out", str(out), "--quick"]) == 0
    return out, json.loads((out / "results.json").read_text())


def test_quick_results_hold_the_five_baselines_and_the_learning_curves(quick_results):
    out, results = quick_results
    assert results["sizes"] == [30, 100, QUICK.n_train]
    for kind in blocks.KINDS:
        for mode in blocks.MODES:
            cell = results["datasets"][kind][mode]
            assert set(cell["baselines"]) == set(blocks.METHODS)
            for method, summary in cell["baselines"].items():
                low, high = summary["ci95"]
                assert 0.0 <= low <= summary["mean"] <= high <= 1.0, (kind, mode, method)
            for net in blocks.NETS:
                per_seed = cell["baselines"][net]["per_seed"]
                assert len(per_seed) == 2 and all(len(s) == QUICK.seeds for s in per_seed)
            curve = cell["learning_curve"]
            assert curve["sizes"] == results["sizes"]
            assert len(curve["ann"]) == len(curve["sann"]) == len(curve["sizes"])
            for net in blocks.CURVE_NETS:  # the last size is the full training set
                assert curve[net][-1]["mean"] == pytest.approx(cell["baselines"][net]["mean"])
            assert curve["rules"] == cell["baselines"]["rules"]
            diff = cell["sann_minus_ann"]
            assert diff["ci95"][0] <= diff["mean"] <= diff["ci95"][1]
            assert len(cell["test_scenes"]) == 2
    for name in ("fig8_test_error_D1_C3", "fig9a_accuracy_D1", "fig9b_accuracy_D2",
                 "learning_curves", "fig13_tsne_input", "fig14_tsne_hidden"):
        assert (out / f"{name}.png").stat().st_size > 10_000


def test_majority_is_the_frequency_of_the_training_majority_in_the_test_labels(quick_results):
    _, results = quick_results
    for kind in blocks.KINDS:
        for mode in blocks.MODES:
            hits = total = 0
            for seed in QUICK.data_seeds:
                data = make_dataset(kind, mode, n_train=QUICK.n_train, n_test=QUICK.n_test,
                                    seed=seed)
                majority = int(data.y_train.mean() >= 0.5)
                hits += int((data.y_test == majority).sum())
                total += len(data.y_test)
            got = results["datasets"][kind][mode]["baselines"]["majority"]["mean"]
            assert got == pytest.approx(hits / total), (kind, mode)


def test_rules_alone_is_the_planners_verdict_replanned_here(quick_results):
    """Plan every test scene of D1-C3 (data seed 1) again from its feature rows and read the
    verdict off the sequences: it must give the accuracy the experiment reports."""
    data = make_dataset("D1", "C3", n_train=QUICK.n_train, n_test=QUICK.n_test, seed=1)
    n = len(FEATURE_NAMES)
    verdict = np.zeros(len(data.y_test), dtype=int)
    with Planner(PlannerConfig(clearance=4.0, margin=1.0)) as planner:
        for image in np.unique(data.image_test):
            rows = np.flatnonzero(data.image_test == image)
            plans = planner.plan(data.X_test[rows, :n].astype(np.float64))
            for r in rows:
                target = int(data.X_test[r, FEATURE_NAMES.index("Target")])
                verdict[r] = int(any(s.t_o == 1 for s in plans[target]))
    evaluation = blocks.evaluate("D1", "C3", 1, QUICK)
    assert np.array_equal(evaluation["rules"][0], verdict == data.y_test)
    assert np.array_equal(evaluation["rules_test"], verdict)


def test_free_now_is_the_one_step_test_on_the_observed_boxes():
    scene = scene_from_blocks([
        ("A", 10, (30, 30, 15)),   # on B
        ("B", 10, (30, 30, 5)),    # carries A
        ("C", 10, (43, 30, 5)),    # 3 units right of B: x pair blocked by B, y pair free
        ("D", 10, (90, 90, 5)),    # alone
        ("E", 10, (43, 43, 5)),    # 3 units behind C: C's y pair blocked too
    ])
    feats = features(scene)
    got = blocks.free_now(feats)
    assert got.tolist() == [1.0, 0.0, 0.0, 1.0, 1.0]
    assert got.astype(bool).tolist() == graspable(scene).tolist()


def test_bootstrap_resamples_whole_scenes():
    correct = {"net": [np.array([[True] * 10 + [False] * 10])]}
    scenes = [np.array([0] * 10 + [1] * 10)]
    reps = blocks.bootstrap(correct, scenes, resamples=200, seed=3)["net"]
    assert set(np.round(reps, 6)) <= {0.0, 0.5, 1.0}
    assert len(set(np.round(reps, 6))) == 3
    again = blocks.bootstrap(correct, scenes, resamples=200, seed=3)["net"]
    assert np.array_equal(reps, again)


def test_an_evaluation_is_deterministic_and_read_back_from_the_cache(monkeypatch, tmp_path):
    monkeypatch.setenv("SANN_CACHE", str(tmp_path))
    first = blocks._evaluate("D1", "C1", 0, TINY, False)
    second = blocks._evaluate("D1", "C1", 0, TINY, False)
    assert first.keys() == second.keys()
    for key in first:
        assert np.array_equal(first[key], second[key]), key
    assert blocks.cached_results(TINY) is None
    for kind in blocks.KINDS:
        for mode in blocks.MODES:
            for seed in TINY.data_seeds:
                blocks.evaluate(kind, mode, seed, TINY)
    cached = blocks.cached_results(TINY)
    assert cached is not None
    again = blocks.evaluate("D1", "C1", 0, TINY)
    for key in first:
        assert np.array_equal(first[key], again[key]), key
    assert cached == blocks.cached_results(TINY)


def test_evaluations_do_not_depend_on_the_processes_that_computed_them(monkeypatch, tmp_path):
    mini = replace(TINY, n_train=16, n_test=10, curve_sizes=(8,))
    monkeypatch.setenv("SANN_CACHE", str(tmp_path / "alone"))
    alone = blocks.evaluate_all(replace(mini, workers=1))
    monkeypatch.setenv("SANN_CACHE", str(tmp_path / "pooled"))
    pooled = blocks.evaluate_all(replace(mini, workers=2))
    assert alone.keys() == pooled.keys() == {(k, m) for k in blocks.KINDS for m in blocks.MODES}
    for dataset, evals in alone.items():
        assert len(evals) == len(mini.data_seeds)
        for mine, theirs in zip(evals, pooled[dataset], strict=True):
            assert mine.keys() == theirs.keys()
            for key in mine:
                assert np.array_equal(mine[key], theirs[key]), (dataset, key)
    assert blocks.cached_results(mini) is not None  # the pool's evaluations were cached


def test_reproduce_rejects_bad_arguments():
    with pytest.raises(SystemExit):
        main(["reproduce", "blocks", "--out", "x", "--seeds", "0"])
    with pytest.raises(SystemExit):
        main(["reproduce", "marbles", "--out", "x"])
    with pytest.raises(ValueError):
        blocks.BlocksExperiment(data_seeds=(1, 1))
