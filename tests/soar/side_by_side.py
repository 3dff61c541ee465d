"""The same rules run in both engines, what each prints captured whole: per command of a list
(``ours`` / ``theirs``, and ``same`` that checks them against each other), or the trace of one
run at a watch level (``kernel_trace`` / ``our_trace``). The kernel side is a fresh agent in
the process's one kernel (``differential.kernel``)."""

from __future__ import annotations

import io
from pathlib import Path

from differential.kernel import Inputs, KernelAgent, _add_our_inputs

from sann.soar import Agent


def ours(rules: list[str], commands: list[str]) -> list[str]:
    """What our engine prints for each command (after loading the rules at watch 0)."""
    out = io.StringIO()
    agent = Agent(out=out)
    for rule in rules:
        agent.load(rule)
    printed = []
    for command in commands:
        out.seek(0)
        out.truncate()
        agent.load(command)
        printed.append(out.getvalue())
    return printed


def theirs(kernel, rules: list[str], commands: list[str]) -> list[str]:
    """What the kernel prints for each command: its print events, then its result unless
    the command is ``run`` (whose result is a summary our engine does not print)."""
    printed = []
    with kernel.KernelAgent() as ka:
        for rule in rules:
            ka.cmd(rule)
        ka.cmd("watch 0")
        ka.take_log()
        for command in commands:
            result = ka.cmd(command)
            printed.append(ka.take_log() + ("" if command.startswith("run") else result))
    return printed


def same(kernel, rules: list[str], commands: list[str]) -> list[str]:
    """Run the commands in both; the texts must agree (modulo blank lines after a print)."""
    expected = theirs(kernel, rules, commands)
    got = ours(rules, commands)
    for command, mine, their in zip(commands, got, expected, strict=True):
        if command.startswith("run"):
            assert mine == their, command
        elif not command.startswith("watch"):  # the kernel says what it watches now
            assert mine.rstrip("\n") == their.rstrip("\n"), command
    return expected


def kernel_trace(rules: list[str], path: Path | None, level: int, decisions: int,
                 inputs: Inputs = ()) -> str:
    """The kernel's print output of ``run decisions`` at ``watch level``."""
    with KernelAgent() as ka:
        if path is not None:
            ka.cmd(f"source {{{path}}}")
        for rule in rules:
            ka.cmd(rule)
        ka.cmd(f"watch {level}")
        ka.take_log()
        ka.add_inputs(inputs)
        ka.cmd(f"run {decisions}")
        return ka.take_log()


def our_trace(rules: list[str], path: Path | None, level: int, decisions: int,
              inputs: Inputs = ()) -> str:
    """Our engine's output of the same run (what loading printed left out)."""
    out = io.StringIO()
    agent = Agent(out=out)
    if path is not None:
        agent.source(str(path))
    for rule in rules:
        agent.load(rule)
    agent.trace(level)
    out.seek(0)
    out.truncate()
    _add_our_inputs(agent, inputs)
    agent.run(decisions=decisions)
    return out.getvalue()
