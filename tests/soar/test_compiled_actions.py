"""Compiled right-hand sides behave exactly like interpreted ones.

Hot productions get their actions compiled to Python (`compile_actions`); the others are
interpreted. Every differential agent is run twice, everything compiled at the first firing
and nothing ever compiled, at trace level 5 (firings, retractions, WM changes and every
preference): the text, the counters, the errors and the final working memory must be equal.
"""

from __future__ import annotations

import io
from pathlib import Path

import pytest
from differential.kernel import _add_our_inputs, read_spec

import sann.soar.decision.firing as firing_module
from sann.soar.agent import Agent
from sann.soar.instantiation import compile_actions
from sann.soar.production import CallAction, Const, FuncCall, MakeAction, Var

HERE = Path(__file__).parent
AGENTS = sorted((HERE / "differential" / "agents").glob("*.soar")) + [
    HERE.parents[1] / "rules" / "water-jug.soar",
    HERE.parents[1] / "rules" / "hanoi.soar",
]
INPUT_OVERRIDES = {"hanoi.soar": (("disks", 6),)}


def _run(path: Path, compile_after: int, monkeypatch: pytest.MonkeyPatch) -> tuple:
    monkeypatch.setattr(firing_module, "COMPILE_AFTER", compile_after)
    spec = read_spec(path)
    out = io.StringIO()
    agent = Agent(out=out, seed=7)
    agent.source(str(path))
    agent.trace(5)
    _add_our_inputs(agent, INPUT_OVERRIDES.get(path.name, spec.inputs))
    agent.run(decisions=spec.decisions)
    wm = [(w.timetag, str(w.id), str(w.attr), str(w.value), w.acceptable) for w in agent.wmes()]
    return out.getvalue(), agent.stats, list(agent.errors), wm, agent.operator_sequence


@pytest.mark.parametrize("path", AGENTS, ids=lambda p: p.stem)
def test_compiled_and_interpreted_actions_agree(
    path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    compiled = _run(path, 1, monkeypatch)
    interpreted = _run(path, 10**9, monkeypatch)
    assert compiled == interpreted


class _Recorder:
    """The part of the agent a compiled program touches."""

    def __init__(self) -> None:
        self.ids = 0
        self.errors: list[str] = []
        self.text: list[str] = []

    def _new_id(self, hint: str, level: int) -> str:
        self.ids += 1
        return f"{hint}{self.ids}"

    def _report_rhs_error(self, inst: object, error: Exception) -> None:
        self.errors.append(str(error))

    def _emit(self, text: str) -> None:
        self.text.append(text)

    def write_output(self, text: str) -> None:
        self.text.append(text)


def test_errors_drop_only_their_action(monkeypatch: pytest.MonkeyPatch) -> None:
    """A failing function call, an unknown function and a non-identifier each drop one
    action, in order, and the other actions still make their preferences."""
    from sann.soar.goals import Goal
    from sann.soar.instantiation import Instantiation
    from sann.soar.memory import Identifier
    from sann.soar.preferences import Slot

    state = Identifier("S", 1, 1)
    actions = (
        MakeAction(Var("s"), Const("a"), FuncCall("+", (Const("x"), Const(1)))),
        CallAction(FuncCall("no-such-function", ())),
        MakeAction(Var("c"), Const("b"), Const(1)),
        CallAction(FuncCall("write", (Const("hi"), Var("n")))),
        MakeAction(Var("s"), Const("c"), Var("n")),
    )
    goal = Goal(state, None, Slot(state, "operator", True))
    inst = Instantiation("p", None, goal, (), False)
    host = _Recorder()
    program = compile_actions("p", actions, frozenset({"s", "c"}))
    program(host, {"s": state, "c": "constant"}, inst, False, ())
    assert host.errors == [
        "non-number (x) passed to + function",
        "unknown RHS function (no-such-function)",
        "RHS of action           ([RETE-loc] ^b 1 +) makes a preference for constant"
        " (not an identifier)",
    ]
    assert host.text == ["hin1"]
    assert [(p.attr, p.value) for p in inst.prefs] == [("c", "n1")]


@pytest.mark.parametrize("name", ["+", "-"])
@pytest.mark.parametrize("x, y", [
    (3, 1), (-5, 7), (2**63 - 1, 1), (-(2**63), 1), (2**63 - 1, -1), (1, 2.5), (1.5, 1),
    ("a", 1), (1, "b"),
])
def test_integer_arithmetic_agrees_with_the_functions(name: str, x: object, y: object) -> None:
    """The compiled fast path of ``(+ a b)`` and ``(- a b)`` (two integers whose result
    fits in 64 bits) gives what the RHS functions give: the sum, or their wrap-around,
    float or error otherwise; with a variable and an integer constant as in ``(+ <k> 1)``
    too."""
    from sann.soar.goals import Goal
    from sann.soar.instantiation import Instantiation
    from sann.soar.memory import Identifier
    from sann.soar.preferences import Slot
    from sann.soar.rhs import FUNCTIONS

    state = Identifier("S", 1, 1)
    goal = Goal(state, None, Slot(state, "operator", True))
    for args in ((Var("x"), Var("y")), (Var("x"), Const(y))):
        action = MakeAction(Var("s"), Const("a"), FuncCall(name, args))
        inst = Instantiation("p", None, goal, (), False)
        host = _Recorder()
        program = compile_actions("p", (action,), frozenset({"s", "x", "y"}))
        program(host, {"s": state, "x": x, "y": y}, inst, False, ())
        try:
            expected = [FUNCTIONS[name](host, [x, y])]
        except Exception as error:  # noqa: BLE001 -- the function's own error, compared
            assert host.errors == [str(error)]
            assert inst.prefs == []
            continue
        values = [p.value for p in inst.prefs]
        assert values == expected
        assert [type(v) for v in values] == [type(v) for v in expected]
