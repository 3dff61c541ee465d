"""A list of commands run in both engines after the same rules: what each prints for each
command, and the check that the texts agree. The action-order and trace-of-phases tests
compare whole outputs this way."""

from __future__ import annotations

import io

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
