"""The plain Python twins of the Rete's generated activations (``codegen.use_plain``,
``SANN_PLAIN=1``) do what the generated code does: the same matches, reported in the same
order after every change, and agents that run alike; and generated code shows its source to
tracebacks and ``inspect``.
"""

from __future__ import annotations

import contextlib
import inspect
import os
import re
import subprocess
import sys
import traceback
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from differential.kernel import RunResult, run_ours
from hypothesis import HealthCheck, given, settings
from test_rete_properties import negation_scripts, scripts

from sann.soar import codegen
from sann.soar.errors import SoarSemanticError
from sann.soar.matching.matches import Match
from sann.soar.matching.nodes import JoinNode
from sann.soar.matching.rete import Rete
from sann.soar.memory import WME, Identifier
from sann.soar.production import Condition, Const, MakeAction, Production, Var

ROOT = Path(__file__).resolve().parents[2]


@contextlib.contextmanager
def plain_python(flag: bool = True) -> Iterator[None]:
    previous = codegen.use_plain(flag)
    try:
        yield
    finally:
        codegen.use_plain(previous)


class _Twin:
    """Calls on a Rete whose nodes run their plain twins: nodes generate (or not) their
    code on first use, so every call runs with the switch on."""

    def __init__(self, rete: Rete) -> None:
        self.rete = rete

    def __getattr__(self, name: str) -> Callable[..., Any]:
        method = getattr(self.rete, name)

        def call(*args: object) -> object:
            with plain_python():
                return method(*args)

        return call


def _key(match: Match) -> tuple:
    bindings = tuple(sorted((name, type(v).__name__, id(v) if isinstance(v, Identifier) else v)
                            for name, v in match.bindings.items()))
    return match.production.name, tuple(id(w) for w in match.wmes), match.newest, bindings


def _same_state(generated: Rete, plain: _Twin) -> None:
    """The same changes in the same order, and the same matches in the same order."""
    added, removed = generated.take_changes()
    plain_added, plain_removed = plain.take_changes()
    assert [_key(m) for m in added] == [_key(m) for m in plain_added]
    assert [_key(m) for m in removed] == [_key(m) for m in plain_removed]
    for production in generated.productions():
        assert ([_key(m) for m in generated.matches(production.name)]
                == [_key(m) for m in plain.matches(production.name)])


def _replay(script: list[tuple]) -> None:
    generated, plain = Rete(True), _Twin(Rete(True))
    memory: list[WME] = []
    names: list[str] = []
    for timetag, step in enumerate(script, start=1):
        kind = step[0]
        if kind == "add":
            wme = WME(*step[1][:3], timetag, step[1][3])  # type: ignore[arg-type]
            memory.append(wme)
            generated.add_wme(wme)
            plain.add_wme(wme)
        elif kind == "remove" and memory:
            wme = memory.pop(step[1] % len(memory))
            generated.remove_wme(wme)
            plain.remove_wme(wme)
        elif kind == "excise" and names:
            name = names.pop(step[1] % len(names))
            generated.excise(name)
            plain.excise(name)
        elif kind == "production":
            # every third rule removes an attribute: the rules it checks are rebuilt
            actions = () if timetag % 3 else (
                MakeAction(Var("s"), Const("abc"[timetag % 9 // 3]), Const("x"), "-"),)
            production = Production(f"{step[1].name}-{timetag}", step[1].conditions, actions)
            try:
                generated.add_production(production)
            except SoarSemanticError:
                with pytest.raises(SoarSemanticError):
                    plain.add_production(production)
                continue
            plain.add_production(production)
            names.append(production.name)
        _same_state(generated, plain)


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scripts())
def test_plain_twins_match_like_the_generated_code(script: list[tuple]) -> None:
    _replay(script)


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(negation_scripts())
def test_plain_twins_negate_like_the_generated_code(script: list[tuple]) -> None:
    _replay(script)


def _fields(result: RunResult) -> tuple:
    return (result.output, result.operators, result.halted, result.decisions,
            result.production_firings, result.wme_changes, result.wm)


@pytest.mark.parametrize("name", ["rules/hanoi.soar", "rules/water-jug.soar",
                                  "rules/classic/eight-puzzle.soar",
                                  "rules/classic/blocks-world-lookahead.soar"])
def test_agents_run_alike_on_the_plain_twins(name: str) -> None:
    inputs = (("disks", 5),) if name.endswith("hanoi.soar") else None
    before = ("srand 3",)
    generated = run_ours(ROOT / name, inputs=inputs, before=before)
    with plain_python():
        plain = run_ours(ROOT / name, inputs=inputs, before=before)
    assert generated.production_firings > 0
    assert _fields(plain) == _fields(generated)


def test_sann_plain_is_read_from_the_environment() -> None:
    code = "from sann.soar import codegen; print(codegen.plain())"
    env = {**os.environ, "SANN_PLAIN": "1"}
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, cwd=ROOT, timeout=120, check=True)
    assert run.stdout.split() == ["True"]


def _one_join(plain: bool) -> JoinNode:
    s, b = Identifier("S", 1, level=1), Identifier("B", 2)
    rete = Rete()
    rete.add_production(Production("p", (
        Condition(Var("s"), Const("block"), Var("b"), goal="state"),
        Condition(Var("b"), Const("size"), Var("z"))), ()))
    with plain_python(plain):
        for timetag, wme in enumerate([(s, "block", b), (b, "size", 2)], start=1):
            rete.add_wme(WME(*wme, timetag))  # type: ignore[arg-type]
        assert len(rete.matches("p")) == 1
    joins = [n for n in _nodes(rete) if isinstance(n, JoinNode)]
    return joins[-1]


def _nodes(rete: Rete) -> list:
    found, stack = [], [rete._root]
    while stack:
        node = stack.pop()
        found.append(node)
        stack.extend(node.children)
    return found


def test_generated_joins_show_their_source() -> None:
    join = _one_join(plain=False)
    code = join.left_activate.__code__  # type: ignore[attr-defined]
    assert re.fullmatch(r"<sann-rete:join:\d+>", code.co_filename)
    source = inspect.getsource(join.left_activate)
    assert source.startswith("def left_activate(parent):")
    assert "for wme in bucket:" in source


def test_plain_joins_are_methods() -> None:
    join = _one_join(plain=True)
    assert join.left_activate.__func__ is JoinNode.plain_left_activate  # type: ignore[attr-defined]
    assert join.right_activate.__func__ is JoinNode.plain_right_activate  # type: ignore[attr-defined]


def test_a_traceback_through_generated_code_shows_its_line() -> None:
    fail = codegen.define(["def fail(x):", "    return x / 0  # the failing line"], {}, "fail",
                          "rete:test")
    try:
        fail(1)
    except ZeroDivisionError:
        text = traceback.format_exc()
    assert re.search(r'File "<sann-rete:test:\d+>", line 2, in fail', text)
    assert "return x / 0  # the failing line" in text
