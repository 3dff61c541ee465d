"""Top-level commands of agent files."""

from __future__ import annotations

import io

import pytest

from sann.soar import Agent, SoarRuntimeError


def agent_with(text: str) -> tuple[Agent, io.StringIO]:
    out = io.StringIO()
    agent = Agent(out=out)
    agent.load(text)
    return agent, out


def test_watch_trace_levels() -> None:
    agent, _ = agent_with("watch 3")
    assert agent.trace_level == 3
    agent.load("trace --level 1")
    assert agent.trace_level == 1
    agent.load("watch 0")
    assert agent.trace_level == 0
    with pytest.raises(SoarRuntimeError, match="trace level"):
        agent.load("watch 7")


def test_settings_commands() -> None:
    agent, out = agent_with(
        "srand 42\nmax-elaborations 7\nmulti-attributes foo 3\n"
        "indifferent-selection --epsilon-greedy\nindifferent-selection --epsilon 0.2\n"
        "decide indifferent-selection --first\nnumeric-indifferent-mode --avg\n"
        "learn --off\nchunk never\noutput console on\necho hello world\n"
    )
    assert agent.max_elaborations == 7
    assert agent.multi_attributes == {"foo": 3}
    assert agent.exploration.policy == "first"
    assert agent.exploration.epsilon == 0.2
    assert agent.exploration.numeric_mode == "avg"
    assert out.getvalue() == "hello world\n"


def test_srand_makes_random_choices_reproducible() -> None:
    rules = (
        "indifferent-selection --random\n"
        "sp {p (state <s> ^superstate nil) --> (<s> ^operator <a> + = ^operator <b> + ="
        " ^operator <c> + =) (<a> ^name a) (<b> ^name b) (<c> ^name c)}\n"
        "sp {q (state <s> ^operator <o>) --> (<s> ^operator <o> -)}\n"
    )
    runs = []
    for _ in range(2):
        agent, _ = agent_with("srand 5\n" + rules)
        agent.run(6)
        runs.append(agent.operator_sequence)
    assert runs[0] == runs[1]


@pytest.mark.parametrize("text", ["learn --on", "chunk always", "learn -e"])
def test_learning_on_is_refused(text: str) -> None:
    with pytest.raises(SoarRuntimeError, match="learning"):
        agent_with(text)


@pytest.mark.parametrize("text", ["excise-everything now", "rl --set learning on", "gp {}"])
def test_unknown_commands_name_themselves(text: str) -> None:
    with pytest.raises(SoarRuntimeError) as info:
        agent_with(text)
    assert text.split()[0] in str(info.value)


def test_bad_arguments() -> None:
    for text in (
        "max-elaborations 0",
        "max-elaborations x",
        "srand a",
        "popd",
        "indifferent-selection --epsilon 3",
        "pushd /no/such/dir",
    ):
        with pytest.raises(SoarRuntimeError):
            agent_with(text)


def test_pushd_popd_and_source(tmp_path) -> None:
    (tmp_path / "lib").mkdir()
    (tmp_path / "lib" / "r.soar").write_text("sp {r (state <s> ^superstate nil) --> (<s> ^r 1)}\n")
    (tmp_path / "main.soar").write_text("pushd lib\nsource r.soar\npopd\n")
    agent = Agent(out=io.StringIO())
    agent.source(tmp_path / "main.soar")
    assert agent.productions == ["r"]


def test_excise_and_init_soar_commands() -> None:
    agent, _ = agent_with("sp {r (state <s> ^superstate nil) --> (<s> ^r 1)}\nexcise r\n")
    assert agent.productions == []
    agent.load("init-soar")
    assert agent.stats["wm_size"] == 13
