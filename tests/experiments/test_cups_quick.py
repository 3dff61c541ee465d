"""`python -m sann reproduce cups --quick` end to end: results.json and every figure."""

import json

import pytest

from sann.__main__ import main
from sann.experiments.cups import CupsExperiment, run

pytestmark = pytest.mark.xdist_group("cups-datasets")


def test_reproduce_cups_quick_writes_results_and_figures(tmp_path, capsys):
    assert main(["reproduce", "cups", "--out", str(tmp_path), "--quick"]) == 0
    results = json.loads((tmp_path / "results.json").read_text())
    config = results["config"]
    assert config["seeds"] >= 5
    for net in ("dnn", "sann"):
        summary = results["accuracy"][net]
        assert len(summary["seeds"]) == config["seeds"]
        assert summary["ci95"][0] <= summary["mean"] <= summary["ci95"][1]
        assert 0.0 <= summary["mean"] <= 1.0
        curves = results["test_error"][net]
        assert len(curves) == config["seeds"]
        assert all(len(c) == config["train"]["epochs"] for c in curves)
    data = results["dataset"]
    assert data["train_piles"] == config["n_train_piles"]
    assert data["test_piles"] == config["n_test_piles"]
    assert data["train_samples"] > 0 and data["test_samples"] > 0
    assert data["inputs_dnn"] == 131 and data["inputs_sann"] == 132
    assert data["rules_sha256"]
    for method in ("patch", "linemod"):
        det = results["detection"][method]
        assert det["frames"] == config["n_test_piles"]
        assert 0.0 <= det["precision"] <= 1.0 and 0.0 <= det["recall"] <= 1.0
    assert 0.0 <= results["logical_only_accuracy"] <= 1.0
    assert isinstance(results["intervals_overlap"], bool)
    for name in results["figures"].values():
        assert (tmp_path / name).stat().st_size > 10_000
    assert sorted(results["figures"]) == ["fig10", "fig11", "fig12"]
    assert "test accuracy" in capsys.readouterr().out


def test_bad_config_is_refused(tmp_path):
    with pytest.raises(ValueError, match="seeds"):
        CupsExperiment(seeds=0)
    with pytest.raises(ValueError, match="CupsExperiment"):
        run(tmp_path, config="quick")
