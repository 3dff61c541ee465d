"""`python -m sann reproduce blocks --quick` end to end: results.json and every figure."""

import json

import pytest

from sann.__main__ import main

pytestmark = pytest.mark.xdist_group("blocks-datasets")


def test_reproduce_blocks_quick_writes_results_and_figures(tmp_path, capsys):
    assert main(["reproduce", "blocks", "--out", str(tmp_path), "--quick", "--seeds", "2"]) == 0
    results = json.loads((tmp_path / "results.json").read_text())
    for kind in ("D1", "D2"):
        for mode in ("C1", "C2", "C3"):
            cell = results["accuracy"][kind][mode]
            for net in ("ann", "sann"):
                summary = cell[net]
                assert len(summary["seeds"]) == 2
                assert summary["ci95"][0] <= summary["mean"] <= summary["ci95"][1]
                assert 0.0 <= summary["mean"] <= 1.0
                curves = results["test_error"][kind][mode][net]
                assert len(curves) == 2 and len(curves[0]) == results["config"]["train"]["epochs"]
            assert results["datasets"][kind][mode]["rules_sha256"]
            assert cell["sann"]["mean"] > 0.75, (kind, mode, cell)
    for name in ("fig8_test_error_D1_C3", "fig9a_accuracy_D1", "fig9b_accuracy_D2",
                 "fig13_tsne_input", "fig14_tsne_hidden"):
        assert (tmp_path / f"{name}.png").stat().st_size > 10_000
    assert "test accuracy" in capsys.readouterr().out


def test_reproduce_rejects_bad_arguments():
    with pytest.raises(SystemExit):
        main(["reproduce", "blocks", "--out", "x", "--seeds", "0"])
    with pytest.raises(SystemExit):
        main(["reproduce", "marbles", "--out", "x"])
