"""The call recorder (sann.viz.call_tree) sees the decision cycle's functions, in a process
that runs the engine from its sources."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from sann.viz import call_tree
from sann.viz.call_tree import Call, collapse, format_calls, module_of

ROOT = Path(__file__).resolve().parents[1]

RECORD = """
import json
from sann.soar import Agent
from sann.soar.decision.cycle import run_phase
from sann.viz.call_tree import record_calls
import io
agent = Agent(out=io.StringIO())
agent.load("sp {p (state <s> ^superstate nil) --> (<s> ^seen yes)}")
agent.load("sp {q (state <s> ^seen yes) --> (<s> ^done yes)}")
calls = record_calls(lambda: run_phase(agent))   # input
calls += record_calls(lambda: run_phase(agent))  # propose: p fires, then q
print(json.dumps([[c.depth, c.module, c.function] for c in calls]))
"""


def test_one_cycle_is_recorded_through_the_modules() -> None:
    env = {**os.environ, "SANN_INTERPRETED": "1", "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, "-c", RECORD], capture_output=True, text=True,
                          env=env, cwd=ROOT, timeout=120, check=True)
    calls = [Call(*row) for row in json.loads(done.stdout)]
    names = [f"{c.module}.{c.function}" for c in calls]
    assert [c for c in calls if c.depth == 0] == [Call(0, "decision.cycle", "run_phase")] * 2
    for name in ("decision.cycle._elaboration_phase", "decision.firing.fire",
                 "decision.wm_phase.working_memory_phase", "matching.rete.Rete.add_wme"):
        assert name in names
    assert any(c.module.startswith("<rete:") for c in calls)  # generated node code
    assert not any(c.module == "codegen" for c in calls)  # code making is left out
    fire = next(c for c in calls if c.function == "fire")
    assert fire.depth > next(c for c in calls if c.function == "_elaboration_phase").depth


def test_collapse_counts_repeats_and_cuts_depth() -> None:
    calls = [Call(0, "m", "a"), Call(1, "m", "b"), Call(2, "m", "deep"), Call(1, "m", "b"),
             Call(1, "m", "c")]
    shown = collapse(calls, 1)
    assert shown == [Call(0, "m", "a"), Call(1, "m", "b", 2), Call(1, "m", "c")]
    assert format_calls(shown).splitlines() == ["m.a", "    m.b  ×2", "    m.c"]


def test_module_names() -> None:
    assert module_of(str(call_tree.PACKAGE / "decision" / "cycle.py")) == "decision.cycle"
    assert module_of("<sann-rete:join:12>") == "<rete:join>"
    assert module_of("/usr/lib/python3.11/json/__init__.py") is None


def test_a_compiled_engine_is_refused(monkeypatch) -> None:
    monkeypatch.setattr(call_tree, "is_compiled", lambda: True)
    with pytest.raises(RuntimeError, match="SANN_INTERPRETED=1"):
        call_tree.record_calls(lambda: None)
