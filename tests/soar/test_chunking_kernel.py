"""Chunking agrees with the Soar 9.6 kernel: the same chunks, decisions and firings.

Each agent runs with ``chunk always`` in the real kernel (``soar_sml``) and in our engine,
from a fresh agent, with ``indifferent-selection --first`` and ``srand 1`` given first (the
arithmetic agent draws its problems with ``rand-int``). Compared: decisions, production
firings, halting, the written output, and the chunks: as many, with the same names, each
the same rule up to variable names (`same_chunk`: conditions and actions in any order, as
the kernel prints them grouped its own way). A second run after ``init-soar`` keeps the
chunks and is compared the same way: it makes no substate where a chunk answers.
"""

from __future__ import annotations

import io
import re
from dataclasses import dataclass
from pathlib import Path

import pytest
from differential.kernel import KernelAgent

from sann.soar.agent import Agent
from sann.soar.chunking.compare import same_chunk
from sann.soar.parsing.parser import parse_production
from sann.soar.production import Production
from sann.soar.rhs import FUNCTIONS

ROOT = Path(__file__).resolve().parents[2]
#: the classic programs whose chunks agree with the kernel's (the others: see the report
#: in tests/soar/known_differences)
CLASSIC = ("arithmetic", "count-test", "water-jug-lookahead", "eight-puzzle-lookahead",
           "blocks-world-operator-subgoaling", "hierarchical-task", "graph-search",
           "problem-builder")
AGENTS = sorted((Path(__file__).parent / "chunking" / "agents").glob("*.soar")) + [
    ROOT / "rules" / "classic" / f"{name}.soar" for name in CLASSIC]
BEFORE = ("indifferent-selection --first", "srand 1", "chunk always")
DECISIONS = 2000


@dataclass
class Run:
    decisions: int
    firings: int
    output: str
    chunks: dict[str, Production]
    substates: int


def _kernel_stats(text: str) -> tuple[int, int]:
    decisions = re.search(r"(\d+) decisions", text)
    firings = re.search(r"(\d+) production firings", text)
    assert decisions is not None and firings is not None, text
    return int(decisions.group(1)), int(firings.group(1))


def kernel_runs(path: Path) -> list[Run]:
    """The kernel's first run and its run after init-soar."""
    runs = []
    with KernelAgent() as ka:
        for line in BEFORE:
            ka.cmd(line)
        ka.cmd(f"source {{{path}}}")
        for again in (False, True):
            if again:
                ka.cmd("init-soar")
            ka.take_log()
            ka.cmd("watch 1")
            ka.cmd(f"run {DECISIONS}")
            trace = ka.take_log()
            ka.cmd("watch 0")
            decisions, firings = _kernel_stats(ka.cmd("stats"))
            names = ka.cmd("print --chunks").split()
            chunks = {name: parse_production(ka.cmd(f"print {name}"), name, FUNCTIONS.keys())
                      for name in names}
            output = re.sub(r"\n\s*\d+:\s+(O:|==>S:).*", "", trace)
            runs.append(Run(decisions, firings, _written(output), chunks,
                            trace.count("==>S:")))
    return runs


def our_runs(path: Path) -> list[Run]:
    out = io.StringIO()
    agent = Agent(out=out)
    for line in BEFORE:
        agent.load(line)
    agent.source(path)
    runs = []
    for again in (False, True):
        if again:
            agent.load("init-soar")
        out.seek(0)
        out.truncate()
        agent.trace(1)
        agent.run(DECISIONS)
        agent.trace(0)
        trace = out.getvalue()
        chunks = {name: info.production for name, info in agent._productions.items()
                  if "chunk" in info.production.flags}
        output = re.sub(r"\n\s*\d+:\s+(O:|==>S:).*", "", trace)
        runs.append(Run(agent.stats["decisions"], agent.stats["production_firings"],
                        _written(output), chunks, trace.count("==>S:")))
    return runs


def _written(text: str) -> str:
    """What the agent wrote, without the run's summary lines and blank lines."""
    lines = [line.strip() for line in text.splitlines()]
    return "\n".join(line for line in lines if line and not line.startswith(
        ("-->", "System halted", "Interrupt received", "This Agent halted", "Agent reinit")))


@pytest.fixture(scope="module", params=AGENTS, ids=[p.stem for p in AGENTS])
def runs(request: pytest.FixtureRequest) -> tuple[list[Run], list[Run]]:
    return kernel_runs(request.param), our_runs(request.param)


def test_decisions_and_firings(runs: tuple[list[Run], list[Run]]) -> None:
    kernel, ours = runs
    for k, o in zip(kernel, ours, strict=True):
        assert (o.decisions, o.firings) == (k.decisions, k.firings)
        assert o.substates == k.substates
        assert o.output == k.output


def test_same_chunks(runs: tuple[list[Run], list[Run]]) -> None:
    """The same chunks; in the first run with the kernel's names too (after init-soar the
    kernel's decision count in a name restarts and it adds a suffix we do not reproduce)."""
    kernel, ours = runs
    assert sorted(ours[0].chunks) == sorted(kernel[0].chunks)
    for k, o in zip(kernel, ours, strict=True):
        left = dict(o.chunks)
        for name, production in k.chunks.items():
            twin = next((n for n, p in left.items() if same_chunk(production, p)), None)
            assert twin is not None, f"no chunk of ours is the kernel's {name}"
            del left[twin]
        assert not left, f"chunks the kernel did not learn: {sorted(left)}"


def test_agents_learn_and_use_their_chunks(runs: tuple[list[Run], list[Run]]) -> None:
    """Not a vacuous comparison: every agent learns, and the second run goes through fewer
    substates than the first (the chunks answer instead)."""
    _, ours = runs
    first, second = ours
    assert first.chunks
    assert second.substates < first.substates


def test_water_jug_second_run_has_no_impasse() -> None:
    """The tutorial's point: after one look-ahead run, the chunks choose every operator."""
    first, second = our_runs(ROOT / "rules" / "classic" / "water-jug-lookahead.soar")
    assert first.substates > 0 and second.substates == 0
    assert second.decisions < first.decisions


#: classic programs whose chunks still differ from the kernel's, with what differs
#: (strict xfails: the day one agrees, it joins CLASSIC)
DIFFERING = {
    "blocks-world-lookahead": "the kernel learns 2 chunks from the first success (substates "
    "analyzed 2) where we learn one at every level the success passes (7)",
    "tower-of-hanoi-recursive": "our chunkx2 keeps two spare-peg constraints (<> from, <> to) "
    "the kernel's drops, and the kernel learns three chunkx3 where we learn none",
}


@pytest.mark.xfail(strict=True, reason="see DIFFERING")
@pytest.mark.parametrize("name", sorted(DIFFERING))
def test_known_chunking_differences(name: str) -> None:
    path = ROOT / "rules" / "classic" / f"{name}.soar"
    kernel, ours = kernel_runs(path)[0], our_runs(path)[0]
    assert (ours.decisions, ours.firings) == (kernel.decisions, kernel.firings)
    assert sorted(ours.chunks) == sorted(kernel.chunks)
    for name_, production in kernel.chunks.items():
        assert same_chunk(production, ours.chunks[name_])


def _learning_lines(text: str) -> list[str]:
    return [line for line in text.splitlines()
            if line.startswith(("Learning new rule", "Ignoring "))]


def test_learning_trace_as_the_kernel_prints_it() -> None:
    """``trace --learning print``: each rule learned, and each duplicate refused, by name."""
    path = ROOT / "rules" / "classic" / "arithmetic.soar"
    with KernelAgent() as ka:
        for line in BEFORE:
            ka.cmd(line)
        ka.cmd(f"source {{{path}}}")
        ka.cmd("trace --learning print")
        ka.take_log()
        ka.cmd(f"run {DECISIONS}")
        theirs = _learning_lines(ka.take_log())
    out = io.StringIO()
    agent = Agent(out=out)
    for line in BEFORE:
        agent.load(line)
    agent.source(path)
    agent.load("trace --learning print")
    agent.run(DECISIONS)
    ours = _learning_lines(out.getvalue())
    assert any(line.startswith("Ignoring ") for line in theirs)
    assert ours == theirs


def _operators_after_init(run: list[str], steps: int, kernel: bool) -> list[str]:
    """The look-ahead water jug run ``steps`` decisions, then ``init-soar`` and run on: the
    second run's decision lines and operator proposals (``+ (O9 ^name pour +)``), in order."""
    path = ROOT / "rules" / "classic" / "water-jug-lookahead.soar"
    commands = [*run, f"source {{{path}}}", f"run {steps}", "init-soar"]
    if kernel:
        with KernelAgent() as ka:
            for line in commands:
                ka.cmd(line)
            ka.take_log()
            ka.cmd("watch 5")
            ka.cmd(f"run {DECISIONS}")
            trace = ka.take_log()
    else:
        out = io.StringIO()
        agent = Agent(out=out)
        for line in commands:
            agent.load(line)
        out.seek(0)
        out.truncate()
        agent.load("watch 5")
        agent.run(DECISIONS)
        trace = out.getvalue()
    return re.findall(r"^(?:\+ \(O\d+ \^name \S+|\s+\d+: .*)", trace, re.M)


@pytest.mark.xfail(strict=True, reason="our firing order after init-soar is the fresh one")
def test_firing_order_after_init_soar() -> None:
    """The kernel's order of new matches changes after ``init-soar``; ours does not.

    Found with the book's learning exercise (chunks kept, a new goal, ``init-soar``: the
    kernel 27 decisions, ours 26) and reduced: no chunk and no new rule is needed, only
    ``init-soar`` after two decisions (the first substate made). In the second run, when
    ``fill`` is applied in the first look-ahead substate, the kernel creates
    ``water-jug*propose*empty``'s operator after ``*propose*pour``'s (O9 empty, O8 pour in
    a fresh run and in ours; O9 pour, O8 empty after init-soar); the numbering of the tied
    operators then differs, ``indifferent-selection --first`` evaluates other copies, and
    the decisions differ from decision 30 on (after one decision, ``init-soar`` changes
    none: ``test_same_decisions_after_an_early_init_soar``).

    Both propose rules join the new ``^contents`` WME from the (* ^contents *) alpha
    memory, so the kernel's order of those joins changed. Our best reading (not measured
    node by node) is the Rete's unlinking: init-soar empties every memory, and a join is
    unlinked from its alpha memory if its beta memory empties first (relinked at the
    tail of the alpha memory's list when a token comes back), from its parent if its
    alpha memory empties first (keeping its place in the alpha memory's list), never both;
    so the order init-soar removes the WMEs in, which depends on what the first run built,
    decides which joins move to the tail in the second run. ``KernelOrder.restart`` counts
    every join as made before the new working memory instead, keeping the first run's
    order of joins (``firing_order.kernel_key``).
    """
    ours = _operators_after_init(_FIRST, 2, kernel=False)
    theirs = _operators_after_init(_FIRST, 2, kernel=True)
    assert ours[:20] == theirs[:20]  # to decision 6: the proposals of pour and empty
    assert _decisions(ours) == _decisions(theirs)


def test_same_decisions_after_an_early_init_soar() -> None:
    """The control of ``test_firing_order_after_init_soar``: ``init-soar`` after one
    decision leaves the second run as the kernel's."""
    ours = _operators_after_init(_FIRST, 1, kernel=False)
    theirs = _operators_after_init(_FIRST, 1, kernel=True)
    assert _decisions(ours) == _decisions(theirs) and len(_decisions(ours)) > 100


_FIRST = ["indifferent-selection --first", "srand 1"]


def _decisions(lines: list[str]) -> list[str]:
    return [line.strip() for line in lines if not line.startswith("+")]
