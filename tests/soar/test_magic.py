"""The ``%%soar`` cell magic."""

from __future__ import annotations

import pytest

from sann.soar import Agent, SoarError
from sann.soar.magic import KERNEL_STATUS, load_ipython_extension, parse_line, soar_cell

RULES = """
sp {p (state <s> ^superstate nil -^done) --> (<s> ^operator <o> +) (<o> ^name hello)}
sp {a (state <s> ^operator.name hello) --> (<s> ^done yes) (write |Hello| (crlf))}
sp {h (state <s> ^done yes) --> (halt)}
"""


def test_cell_creates_named_agent_and_runs(capsys) -> None:
    namespace: dict = {}
    agent = soar_cell("greeter", RULES, namespace)
    assert namespace["greeter"] is agent and agent.halted
    out = capsys.readouterr().out
    assert "O: O1 (hello)Hello" in out and "greeter: halted after 1 decisions." in out


def test_cells_share_the_agent_and_replace_rules(capsys) -> None:
    namespace: dict = {}
    soar_cell("--no-run", RULES, namespace)
    agent = namespace["soar"]
    assert isinstance(agent, Agent) and agent.stats["decisions"] == 0
    soar_cell(
        "--init -t 0",
        "sp {a (state <s> ^operator.name hello) --> (<s> ^done yes) (write |Bye| (crlf))}",
        namespace,
    )
    assert namespace["soar"] is agent
    assert capsys.readouterr().out.startswith("Bye")
    soar_cell("--reset --no-run", "", namespace)
    assert namespace["soar"] is not agent


def test_decision_limit_and_bad_options() -> None:
    namespace: dict = {}
    agent = soar_cell("x -d 0", RULES, namespace)
    assert agent.stats["decisions"] == 0
    with pytest.raises(SoarError):
        parse_line("x --bogus")
    with pytest.raises(SoarError):
        parse_line("not-an-identifier")
    with pytest.raises(SoarError):
        parse_line("x --trace 9")


def test_ipython_registration() -> None:
    ipython_app = pytest.importorskip("IPython.testing.globalipapp")
    shell = ipython_app.get_ipython()
    load_ipython_extension(shell)
    shell.run_cell_magic("soar", "magicagent -t 0", RULES)
    assert shell.user_ns["magicagent"].halted


def test_cell_output_leaves_out_the_kernels_halt_messages(capsys) -> None:
    """The kernel's 'System halted.' / 'Interrupt received.' would repeat after every run of
    a page; the cell's own line says how the run ended."""
    soar_cell("stopper --trace 0", "sp {stop (state <s> ^superstate nil) --> (write |bye|) (halt)}",
              {})
    out = capsys.readouterr().out
    assert "bye" in out and "stopper: halted after 0 decisions." in out
    assert not any(status in out for status in KERNEL_STATUS)
