"""When a result is returned, learn a chunk as Soar 9.6 does, or leave the justification.

`Chunker.learn` is called with the justification the agent just made for a substate's
results. With learning on for that state it explains the results (`backtrace`), builds the
chunk (`build`), and, unless the kernel would refuse it, adds it to the matcher with its
current match *refracted* (the kernel's chunk instantiation is the one that supports the
results, so that match does not fire again): the justification is renamed to the chunk and
keeps supporting the results, retracting when the chunk's match goes. Every other match of
the new chunk is queued, to fire in the next cycle. The kernel's names (measured):
``chunk*<rule>*t<decision>-<n>``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from ..decision.matches import _queue_matches
from ..decision.results import _make_justification
from ..errors import SoarError
from ..preferences import REQUIRE
from ..printer import format_production
from ..production import Production, duplicate_key, same_production
from .backtrace import SELECTION, Explanation, NotExplained, explain
from .build import build_chunk

if TYPE_CHECKING:
    from ..agent import Agent
    from ..goals import Goal
    from ..instantiation import Instantiation
    from ..memory import WME
    from ..preferences import Preference, Slot


_CHUNK_PREFIX = re.compile(r"chunk(?:x(\d+))?\*")
_CHUNK_SUFFIX = re.compile(r"(\*(Tie|OpNoChange|StateNoChange|Conflict|ConstraintFailure))?"
                           r"\*t\d+-\d+$")
#: the impasse of the state a chunk is learned for, as its name shows it
_IMPASSE_NAMES = {("tie", "operator"): "Tie", ("no-change", "operator"): "OpNoChange",
                  ("no-change", "state"): "StateNoChange", ("conflict", "operator"): "Conflict",
                  ("constraint-failure", "operator"): "ConstraintFailure"}


@dataclass
class ChunkRecord:
    """What ``explain`` shows of a chunk: where it came from."""

    name: str
    decision: int
    state: str
    firings: list[str]
    conditions: int
    actions: int


@dataclass
class ChunkStats:
    """The counters of ``chunk stats`` that this engine keeps."""

    learned: int = 0
    justifications: int = 0
    substates: int = 0
    firings_analyzed: int = 0
    duplicates: int = 0
    quiescence: int = 0
    no_grounds: int = 0
    local_negations: int = 0
    failed: int = 0


@dataclass
class Chunker:
    """Per-agent chunking state: records of the chunks learned, counters, name counts."""

    records: dict[str, ChunkRecord] = field(default_factory=dict)
    stats: ChunkStats = field(default_factory=ChunkStats)
    counts: dict[int, int] = field(default_factory=dict)
    messages: list[str] = field(default_factory=list)
    #: states where ``force-learn`` / ``dont-learn`` were called (for ``only`` / ``except``)
    forced: set[object] = field(default_factory=set)
    refused: set[object] = field(default_factory=set)
    #: the refracted match of each chunk's own instantiation (a justification here), for
    #: explaining it when its results go higher still
    matches: dict[Instantiation, object] = field(default_factory=dict)
    #: the instantiations of the preferences that chose each substate operator
    selection: dict[WME, list[Instantiation]] = field(default_factory=dict)
    selection_limit: int = 1024
    #: ``trace --learning noprint|print|fullprint``: the learned rules' names, or their text
    trace: str = "noprint"

    def selected(self, agent: Agent, wme: WME, slot: Slot) -> None:
        """A substate's operator was selected: note the preferences that chose it, what
        the kernel's ``add-osk`` backtraces the selection through (see `backtrace`)."""
        if len(self.selection) >= self.selection_limit:
            wm = agent._wm
            self.selection = {w: insts for w, insts in self.selection.items()
                              if wm.get(w.timetag) is w}
            self.selection_limit = max(1024, 2 * len(self.selection))
        # a required operator is chosen by its require alone (measured in soar_sml: the
        # look-ahead's ``+, !`` copy of the tied operator brings in no reject of the others)
        types = (REQUIRE,) if slot.of_type(REQUIRE) else SELECTION
        self.selection[wme] = [pref.inst for ptype in types
                               for pref in slot.of_type(ptype) if pref.inst is not None]

    def mark(self, function: str, state: object) -> None:
        """``(force-learn <s>)`` lets ``chunk only`` learn from results of ``<s>``;
        ``(dont-learn <s>)`` keeps ``chunk except`` from it (measured in soar_sml: both
        count when called before the result; ``chunk always`` ignores them)."""
        (self.forced if function == "force-learn" else self.refused).add(state)

    def allowed(self, agent: Agent, goal: Goal) -> bool:
        mode = agent.learning
        if mode == "always":
            return True
        if mode == "only":
            return goal.id in self.forced
        if mode == "except":
            return goal.id not in self.refused
        return False

    def explain(self, agent: Agent, inst: Instantiation,
                results: list[Preference]) -> Explanation | None:
        """The explanation of the ``results`` that ``inst``'s firing returned, when
        learning is on in its state (else None); made before the results' identifiers
        leave the substate."""
        goal = inst.goal
        if agent.learning == "never" or not self.allowed(agent, goal):
            return None
        self.stats.substates += 1
        try:
            return explain(agent, inst, results)
        except NotExplained as reason:
            self._fail(agent, str(reason))
            return None

    def build(self, agent: Agent, ex: Explanation) -> Production | None:
        """The chunk of an explanation, unless the kernel would not learn it (then a
        justification stands in)."""
        self.stats.firings_analyzed += len(ex.steps)
        self.stats.local_negations += bool(ex.local_negations)
        if ex.quiescence:
            self.stats.quiescence += 1
            return None
        if not ex.grounds:
            self.stats.no_grounds += 1
            return None
        name = self._name(agent, ex.fired, ex.goal.superstate)
        try:
            production = build_chunk(ex, name)
        except SoarError as error:
            self._fail(agent, f"{name}: {error}")
            return None
        if self.trace != "noprint":
            agent._emit_line(f"Learning new rule {name}\n")
            if self.trace == "fullprint":
                agent._emit(format_production(production) + "\n")
        other = self._duplicate(agent, production)
        if other is not None:
            self.stats.duplicates += 1
            if self.trace != "noprint":  # the kernel's line, trailing space included
                agent._emit_line(f"Ignoring {name} because it is a duplicate of {other} \n")
            return None
        return production

    def justify(self, agent: Agent, made_by: Instantiation, results: list[Preference],
                grounds: tuple[WME, ...], home: Goal, fired: Instantiation,
                ex: Explanation) -> tuple[Instantiation, bool]:
        """The justification at ``home`` for ``made_by``'s results, which is the
        instantiation of the chunk learned from ``ex`` when one is learned; whether one
        was."""
        chunk = self.build(agent, ex)
        just = _make_justification(agent, made_by, results, grounds, home, fired,
                                   None if chunk is None else chunk.name)
        if chunk is None:
            return just, False
        return just, self.learn(agent, just, ex, chunk)

    def learn(self, agent: Agent, just: Instantiation, ex: Explanation,
              production: Production) -> bool:
        """Add the chunk, whose instantiation ``just`` is; whether it could (when its match
        is not there, ``just`` is a plain justification)."""
        match = self._add(agent, production, {id(g.wme) for g in ex.grounds.values()})
        if match is None:
            just.name = f"justify{2 * agent._justifications - 1}"
            return self._fail(agent, f"{production.name} does not match the working memory "
                              "it was learned from; a justification stands in")
        self.matches[just] = match
        self.stats.learned += 1
        self.records[production.name] = ChunkRecord(
            production.name, agent._decisions, str(ex.goal.id),
            [step.inst.name for step in ex.steps.values()],
            len(production.conditions), len(production.actions))
        return True

    def _name(self, agent: Agent, fired: Instantiation, home: Goal | None) -> str:
        """``chunk*<rule>[*<impasse of the chunk's state>]*t<decision>-<n>`` (measured:
        ``chunk*sub*a*t2-1`` for a result on the top state,
        ``chunk*look-ahead*evaluate*symbolic*Tie*t50-1`` on a tie's state, ``-n`` counting
        the chunks of the decision); a chunk learned from a chunk's firing is
        ``chunkx2*...`` (and so on), named after the rule the first chunk came from."""
        base, times = fired.name, 0
        prefix = _CHUNK_PREFIX.match(base)
        if prefix is not None:
            times = int(prefix.group(1) or 1)
            base = _CHUNK_SUFFIX.sub("", base[prefix.end():])
        decision = agent._decisions
        count = self.counts.get(decision, 0) + 1
        self.counts = {decision: count}
        head = "chunk" if times == 0 else f"chunkx{times + 1}"
        impasse = _IMPASSE_NAMES.get((home.impasse, home.attribute)) if home else None
        middle = f"*{impasse}" if impasse else ""
        return f"{head}*{base}{middle}*t{decision}-{count}"

    def _fail(self, agent: Agent, message: str) -> bool:
        self.stats.failed += 1
        self.messages.append(message)
        if agent.trace_level >= 2 and agent.warnings:
            agent._emit_line(f"Warning: chunking: {message}\n")
        return False

    @staticmethod
    def _duplicate(agent: Agent, production: Production) -> str | None:
        """The rule the chunk would duplicate (the kernel keeps that one), if any."""
        for other in agent._by_shape.get(duplicate_key(production), ()):
            if same_production(agent._productions[other].production, production):
                return other
        return None

    @staticmethod
    def _add(agent: Agent, production: Production, grounds: set[int]) -> object | None:
        """Add the chunk; refract its match of ``grounds`` (the WMEs it was learned from),
        queue the others; return the refracted match. None (and the chunk excised) when
        that match is missing."""
        agent._add_production(production)
        new, gone = agent.matcher.take_changes()
        assert not gone, "a new production retracts nothing"
        rest = []
        refracted = None
        for match in new:
            wmes = {id(w) for w in match.wmes if w is not None}
            if refracted is None and match.production.name == production.name and (
                    wmes == grounds):
                refracted = match
                continue
            rest.append(match)
        if refracted is None:
            agent.excise(production.name)
            agent.matcher.take_changes()
            return None
        if rest:
            _queue_matches(agent, rest)
        return refracted
