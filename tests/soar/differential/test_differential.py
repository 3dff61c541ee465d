"""Every agent runs in the real Soar kernel (the oracle) and in our engine; they must agree.

Deterministic agents must agree on halting, decisions, production firings, elaboration
cycles, WM changes, the operator-name sequence, written output and the final working memory
(modulo identifier renaming). Agents marked ``# differential: random`` must agree on
halting and written output only. The kernel-only tests run even before the engine exists:
they prove that every agent is a valid Soar 9.6 agent that halts on its own, and that the
oracle's own measurements are stable.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from .kernel import (
    RunResult,
    canonical_wm,
    parse_internal,
    read_spec,
    run_kernel,
    run_ours,
    split_trace,
)

# What the kernel (and our engine) prints when (halt) stops a run, at every watch level.
HALTED = "\nSystem halted.\nInterrupt received.This Agent halted."

HERE = Path(__file__).parent
ROOT = HERE.parents[2]
AGENTS = sorted((HERE / "agents").glob("*.soar")) + [
    ROOT / "rules" / "water-jug.soar",
    ROOT / "rules" / "hanoi.soar",
]
# Hanoi's own default is 11 disks (2,060 decisions); 6 disks keep the suite fast.
INPUT_OVERRIDES = {"hanoi.soar": (("disks", 6),)}


def _inputs(path: Path):
    return INPUT_OVERRIDES.get(path.name)


def _id(path: Path) -> str:
    return path.stem


@pytest.fixture(scope="module")
def kernel_results() -> dict[Path, RunResult]:
    """Each agent run once in the kernel, shared by the tests of this module."""
    return {path: run_kernel(path, inputs=_inputs(path)) for path in AGENTS}


def test_the_corpus_has_at_least_12_agents() -> None:
    assert len(list((HERE / "agents").glob("*.soar"))) >= 12


@pytest.mark.parametrize("path", AGENTS, ids=_id)
def test_kernel_runs_agent_to_halt(path: Path, kernel_results: dict[Path, RunResult]) -> None:
    result = kernel_results[path]
    spec = read_spec(path)
    assert result.halted, f"{path.name} did not halt in the kernel:\n{result.trace[-2000:]}"
    assert result.decisions < spec.decisions
    alarms = ("Error", "error", "Goal stack depth exceeded")
    for bad in alarms if spec.warnings else ("Warning", *alarms):
        assert bad not in result.trace, f"{path.name}: kernel said {bad!r}:\n{result.trace}"
    assert result.operators, "no operator was ever selected"
    assert result.wm and any(t[0] == "S1" for t in result.wm)


@pytest.mark.parametrize("path", [p for p in AGENTS if not read_spec(p).random], ids=_id)
def test_kernel_is_reproducible(path: Path, kernel_results: dict[Path, RunResult]) -> None:
    """The oracle itself: a second run in a fresh agent measures exactly the same."""
    again = run_kernel(path, inputs=_inputs(path))
    first = kernel_results[path]
    assert _comparable(again) == _comparable(first)


def test_known_figures_of_the_rule_files(kernel_results: dict[Path, RunResult]) -> None:
    jug = kernel_results[ROOT / "rules" / "water-jug.soar"]
    assert jug.decisions == 9
    assert jug.output.endswith("The problem has been solved.\n" + HALTED)
    hanoi = kernel_results[ROOT / "rules" / "hanoi.soar"]
    assert hanoi.decisions == 1 + 6 + 63 + 1
    assert hanoi.operators.count("move-disk") == 63
    assert hanoi.output == (
        "Moved 6 disks from peg a to peg c in 63 moves.\n" + HALTED
    )
    full = run_kernel(ROOT / "rules" / "hanoi.soar")
    assert full.decisions == 2060
    assert full.output == "Moved 11 disks from peg a to peg c in 2047 moves.\n" + HALTED


@pytest.mark.parametrize("path", AGENTS, ids=_id)
def test_our_engine_agrees_with_kernel(path: Path, kernel_results: dict[Path, RunResult]) -> None:
    pytest.importorskip("sann.soar.agent", reason="our engine (sann/soar/agent.py) has not landed")
    theirs = kernel_results[path]
    random = read_spec(path).random
    # A deterministic agent needs no more decisions than the kernel took: a small margin
    # shows a difference without letting a runaway run to the file's decision limit.
    limit = None if random else theirs.decisions + 50
    ours = run_ours(path, decisions=limit, inputs=_inputs(path))
    if random:
        assert (ours.halted, ours.output) == (theirs.halted, theirs.output)
        return
    assert ours.halted == theirs.halted
    assert ours.operators == theirs.operators
    assert ours.output == theirs.output
    assert _counts(ours) == _counts(theirs)
    assert _wm_diff(ours, theirs) == ([], [])


def _counts(result: RunResult) -> dict[str, int]:
    keys = ("decisions", "production_firings", "elaboration_cycles", "wme_changes", "wm_size")
    return {key: getattr(result, key) for key in keys}


def _comparable(result: RunResult) -> tuple:
    return (result.halted, result.operators, result.output, _counts(result), result.wm)


def _wm_diff(ours: RunResult, theirs: RunResult) -> tuple[list, list]:
    """WMEs only in ours, and only in the kernel's (canonical names)."""
    a, b = set(ours.wm), set(theirs.wm)
    return sorted(a - b), sorted(b - a)


# --------------------------------------------------------------------------- the harness itself


def test_canonical_wm_ignores_identifier_names() -> None:
    text_a = """
(1: S1 ^io I1)
(2: S1 ^thing T4)
(3: S1 ^thing T9)
(4: T4 ^size 1)
(5: T9 ^size 2)
(6: T9 ^next T4)
(7: S1 ^operator O3 +)
"""
    text_b = """
(1: S1 ^io I7)
(2: S1 ^thing T1)
(3: S1 ^thing T2)
(4: T2 ^size 1)
(5: T1 ^size 2)
(6: T1 ^next T2)
(7: S1 ^operator O1 +)
"""
    assert _canon(text_a) == _canon(text_b)
    changed = text_b.replace("(6: T1 ^next T2)", "(6: T2 ^next T1)")
    assert _canon(text_a) != _canon(changed)


def test_canonical_wm_keeps_types_and_support_marks() -> None:
    base = _canon("(1: S1 ^a 12)\n(2: S1 ^operator O1 +)\n")
    assert base != _canon("(1: S1 ^a |12|)\n(2: S1 ^operator O1 +)\n")
    assert base != _canon("(1: S1 ^a 12.0)\n(2: S1 ^operator O1 +)\n")
    assert base != _canon("(1: S1 ^a 12)\n(2: S1 ^operator O1)\n")
    assert _canon("(1: S1 ^x 1.5)\n") == _canon("(1: S1 ^x 1.500000)\n")


def test_split_trace_separates_written_output() -> None:
    trace = (
        "\n     1:    O: O2 (hello)Hi hello\n\n     2:    ==>S: S2 (operator tie)"
        "\n     3:       O: O5 (evaluate)x\nSystem halted.\nInterrupt received.This Agent halted."
    )
    operators, output = split_trace(trace)
    assert operators == ["hello", "evaluate"]
    assert output == "Hi hello\nx" + HALTED


def _canon(text: str):
    graph: dict = {}
    for ident, attr, value, acc in parse_internal(text):
        graph.setdefault(ident, []).append((attr, value, acc))
        if value[0] == "id":
            graph.setdefault(value[1], [])
    return canonical_wm(graph, ["S1"])


# --------------------------------------------------------------------------- the I/O links


def _benchmark_module():
    """benchmarks/engine.py, sharing this process's kernel module (one kernel, not two)."""
    import importlib.util
    import sys

    from . import kernel as oracle

    sys.modules.setdefault("kernel", oracle)
    path = ROOT / "benchmarks" / "engine.py"
    spec = importlib.util.spec_from_file_location("sann_engine_benchmark", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up while executing it
    spec.loader.exec_module(module)
    return module


def test_kernel_plans_blocks_through_io_links() -> None:
    bench = _benchmark_module()
    scenes = bench.make_scenes(40, 26, seed=3)
    planner = bench.KernelPlanner()
    try:
        plans = [planner.solve(scene) for scene in scenes]
    finally:
        planner.close()
    assert plans == [scene.plan() for scene in scenes]
    assert any(len(plan) > 3 for plan in plans)


def test_our_engine_plans_blocks_through_io_links() -> None:
    pytest.importorskip("sann.soar.agent", reason="our engine (sann/soar/agent.py) has not landed")
    bench = _benchmark_module()
    scenes = bench.make_scenes(40, 26, seed=3)
    planner = bench.OurPlanner()
    assert [planner.solve(scene) for scene in scenes] == [scene.plan() for scene in scenes]


def test_agent_headers_are_read(tmp_path: Path) -> None:
    agent = tmp_path / "a.soar"
    agent.write_text(
        "# differential: random\n# differential: decisions 40\n"
        "# input: item name=apple price=3 weight=0.5\n# input: disks=4\n"
    )
    spec = read_spec(agent)
    assert spec.random and spec.decisions == 40
    assert spec.inputs == (
        ("item", (("name", "apple"), ("price", 3), ("weight", 0.5))),
        ("disks", 4),
    )


@pytest.mark.parametrize(
    "header", ["# differential: sometimes", "# input: =3", "# input: item price"]
)
def test_bad_agent_headers_are_refused(tmp_path: Path, header: str) -> None:
    agent = tmp_path / "bad.soar"
    agent.write_text(header + "\n")
    with pytest.raises(ValueError, match="bad.soar"):
        read_spec(agent)


def test_source_time_output_is_dropped_on_both_sides(tmp_path: Path) -> None:
    """``echo``/``print`` while sourcing go to the kernel's ``source`` result, which the
    harness drops; our half must drop them too, or any agent that echoes would differ."""
    pytest.importorskip("sann.soar.agent", reason="our engine (sann/soar/agent.py) has not landed")
    agent = tmp_path / "echo.soar"
    agent.write_text(
        "echo loading the agent\nsp {go\n   (state <s> ^superstate nil)\n-->\n"
        "   (<s> ^operator <o> +)\n   (<o> ^name go)}\nprint go\n"
        "sp {stop\n   (state <s> ^operator.name go)\n-->\n   (write |ran|)\n   (halt)}\n"
    )
    theirs, ours = run_kernel(agent), run_ours(agent)
    assert theirs.output == ours.output == "ran" + HALTED
