"""``%%soar`` — an IPython cell magic that loads Soar rules into an agent and runs it.

In a notebook::

    %load_ext sann.soar.magic

    %%soar blocks --decisions 20 --trace 1
    sp {propose*hello (state <s> ^superstate nil -^done) --> (<s> ^operator <o> +)}
    ...

The agent is kept in the user namespace under its name (``soar`` by default), so later
cells and Python code reach the same agent: productions with an existing name replace the
old ones, as in the kernel. Options: ``--decisions N`` (default: run until halt, at most
``DEFAULT_LIMIT`` decisions), ``--trace LEVEL`` (default 1), ``--seed N``, ``--init``
(``init-soar`` before loading), ``--reset`` (a brand-new agent), ``--no-run`` (load only).
"""

from __future__ import annotations

import argparse
import shlex
import sys
from typing import Any, TextIO

from .agent import Agent
from .errors import SoarError

#: Decisions a cell runs at most when no --decisions is given, so a rule set that never
#: halts cannot hang the notebook.
DEFAULT_LIMIT = 10_000


#: What the kernel prints when a run halts or is interrupted. A cell says in its own words how
#: the run ended (``halted after N decisions``), so these are left out of what a reader sees.
KERNEL_STATUS = ("System halted.", "Interrupt received.", "This Agent halted.")


class ReaderStream:
    """A text stream for readers: passes the agent's output on without the kernel's status
    messages (``System halted.``, ``Interrupt received.``), which a page of runs would repeat
    after every halt. The trace and the ``write`` output go through unchanged."""

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream

    def write(self, text: str) -> int:
        kept = text
        for status in KERNEL_STATUS:
            kept = kept.replace(status + "\n", "").replace(status, "")
        if kept:
            self.stream.write(kept)
        return len(text)

    def flush(self) -> None:
        self.stream.flush()


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="%%soar", add_help=False, exit_on_error=False)
    parser.add_argument("agent", nargs="?", default="soar")
    parser.add_argument("--decisions", "-d", type=int, default=None)
    parser.add_argument("--trace", "-t", type=int, default=1)
    parser.add_argument("--seed", "-s", type=int, default=None)
    parser.add_argument("--init", action="store_true")
    parser.add_argument("--reset", action="store_true")
    parser.add_argument("--no-run", dest="run", action="store_false")
    return parser


def parse_line(line: str) -> argparse.Namespace:
    """Options of a ``%%soar`` line; a clear SoarError for bad ones."""
    try:
        options, extra = _parser().parse_known_args(shlex.split(line))
    except (argparse.ArgumentError, ValueError) as error:
        raise SoarError(f"%%soar: bad options {line!r}: {error}") from None
    if extra:
        raise SoarError(f"%%soar: unknown options {' '.join(extra)}")
    if not options.agent.isidentifier():
        raise SoarError(f"%%soar: agent name must be a Python identifier, got {options.agent!r}")
    if not 0 <= options.trace <= 5:
        raise SoarError("%%soar: --trace must be 0..5")
    return options


def soar_cell(line: str, cell: str, namespace: dict[str, Any]) -> Agent:
    """Do what the magic does, with an explicit namespace (testable without IPython)."""
    options = parse_line(line)
    agent = namespace.get(options.agent)
    if options.reset or not isinstance(agent, Agent):
        agent = Agent(options.agent, seed=options.seed)
        namespace[options.agent] = agent
    elif options.seed is not None:
        agent.srand(options.seed)
    previous = agent.out
    agent.out = ReaderStream(sys.stdout)  # type: ignore[assignment]  # Agent.out only writes
    try:
        if options.run:  # before init-soar, which traces the new top state
            agent.trace(options.trace)
        if options.init:
            agent.init()
        agent.load(cell, file=f"<%%soar {options.agent}>")
        if options.run:
            limit = options.decisions if options.decisions is not None else DEFAULT_LIMIT
            before = agent.stats["decisions"]
            agent.run(limit)
            done = agent.stats["decisions"] - before
            print()
            if agent.halted:
                print(f"{options.agent}: halted after {done} decisions.")
            elif options.decisions is None and done >= limit:
                print(f"{options.agent}: stopped at the {limit}-decision limit (no halt).")
    finally:
        agent.out = previous
    return agent


def load_ipython_extension(ipython: Any) -> None:
    """Register ``%%soar``; called by ``%load_ext sann.soar.magic``."""

    def soar(line: str, cell: str) -> None:
        try:
            soar_cell(line, cell, ipython.user_ns)
        except SoarError as error:
            print(f"Soar error: {error}", file=sys.stderr)

    ipython.register_magic_function(soar, magic_kind="cell", magic_name="soar")
