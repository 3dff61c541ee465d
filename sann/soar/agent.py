"""The Soar agent: loading rules, running, stats, print and the io links.

``Agent`` is the public face of the decision cycle, whose phases are the modules of
``sann.soar.decision`` (its ``__init__`` lists them). The cycle follows the Soar 9.6
kernel phase by phase (input, propose, decide, apply, output), including the details that
change what users observe:

- elaboration cycles run level by level (the kernel's "waterfall"): each cycle fires the
  pending i-assertions and retractions of the highest goal that has any, and in the apply
  phase, when a goal has no i-activity left, its o-assertions (``PE`` cycles);
- a selected operator whose proposal stops matching is removed at once, and the goal stack
  is re-checked for consistency with the current preferences whenever the active level
  changes or a goal moves from i- to o-firing; an inconsistent decision ends the phase;
- ``run N`` stops before the apply phase of the Nth decision, like the kernel's default
  stop phase, so that ``run 1`` twice equals ``run 2``.
"""

from __future__ import annotations

import gc
import os
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import TextIO

from . import commands
from .chunking import Chunker
from .decision.agent_state import AgentState
from .decision.cycle import run_phase
from .decision.firing_order import creation_key
from .decision.matches import collect_changes
from .decision.substates import ids_new_after_top, new_goal, remove_goal
from .decision.working_memory import trace_wm_changes
from .errors import SoarError, SoarRuntimeError
from .goals import Goal
from .instantiation import ProductionInfo
from .io import InputHandle, OutputHandle
from .matching.rete import Rete
from .memory import WME, Identifier
from .parsing.parser import parse
from .production import Command, Production, duplicate_key, same_production
from .rhs import FUNCTIONS
from .rhs.rand import kernel_random
from .trace import print_identifier

PHASES = ("input", "propose", "decide", "apply", "output")


#: Python's young-generation collection threshold that creating an agent sets for the
#: process when it is lower (the default is 700; it is never lowered). A run's tokens, WMEs
#: and preferences live for some decisions, and an input-link scene until init-soar, so a
#: collection every 700 allocations keeps traversing live objects; reference counting still
#: frees nearly everything at once. (Raising it for a run only, and restoring it after,
#: leaves the scene's objects to be traversed after the run.)
GC_YOUNG_THRESHOLD = 10_000


def _raise_gc_threshold() -> None:
    threshold = gc.get_threshold()
    if threshold[0] < GC_YOUNG_THRESHOLD:
        gc.set_threshold(GC_YOUNG_THRESHOLD, *threshold[1:])


class Agent(AgentState):
    """A Soar agent. See the module docstring for the cycle; the README for the API."""

    def __init__(
        self,
        name: str = "soar",
        *,
        matcher: type | None = None,
        seed: int | None = None,
        out: TextIO | None = None,
    ) -> None:
        _raise_gc_threshold()
        super().__init__(name, matcher or Rete, out)
        self.srand(seed)
        # duplicate_key -> names of the loaded productions with it (duplicates are refused)
        self._by_shape: dict[tuple, list[str]] = {}
        self._load_count = 0
        self._dir_stack: list[Path] = []
        self._pushd: list[Path] = []  # directories pushd put on top of the sourcing file's
        self._aliases: dict[str, tuple[str, ...]] = {}  # alias -> the command words
        self.max_gp = 20000  # most productions one gp may make (the kernel's default)
        self.learning = "never"
        self.chunker = Chunker()
        self._gensym_counter = 0
        self._make_top_state()

    @property
    def productions(self) -> list[str]:
        """Names of the loaded productions, in load order."""
        return list(self._productions)

    @property
    def halted(self) -> bool:
        return self._halted

    @property
    def stats(self) -> dict[str, int]:
        """Counters named after the kernel's ``stats`` lines."""
        return {
            "decisions": self._decisions,
            "elaboration_cycles": self._e_cycles,
            "pe_cycles": self._pe_cycles,
            "production_firings": self._firings,
            "wme_changes": 2 * self._timetag - len(self._wm),
            "wme_additions": self._timetag,
            "wme_removals": self._timetag - len(self._wm),
            "wm_size": len(self._wm),
            "wm_max": max(self._wm_max, len(self._wm)),
        }

    @property
    def top_state(self) -> Identifier:
        return self._top.id

    @property
    def phase(self) -> str:
        """The phase the next step starts with."""
        return self._phase

    def srand(self, seed: int | None) -> None:
        """Seed the generator of indifferent choices and of ``rand-int``/``rand-float``
        (``srand``); ``None`` means seed 0.  The state is the kernel's after the same
        ``srand``, so the random functions draw its very numbers."""
        self.exploration.rng = kernel_random(0 if seed is None else seed)

    def trace(self, level: int) -> None:
        """0 none, 1 decisions, 2 phases, 3 firings, 4 WM changes, 5 preferences."""
        if not 0 <= int(level) <= 5:
            raise SoarRuntimeError(f"trace level must be 0..5, got {level}")
        self.trace_level = int(level)

    def load(self, text: str, file: str = "<string>") -> None:
        """Load productions and run commands from rule-file text.

        As in the kernel, the first error stops the rest of the text: what precedes the
        item in error is loaded, then the error is raised."""
        base = Path(file).resolve().parent if not file.startswith("<") else Path.cwd()
        try:
            items = parse(text, file, FUNCTIONS.keys())
            error: SoarError | None = None
        except SoarError as exc:
            items, error = self._items_before(text, file, exc), exc
        try:
            for item in items:
                if isinstance(item, Production):
                    self._add_production(item)
                elif isinstance(item, Command):
                    collect_changes(self, in_match_order=True)
                    commands.execute(self, item, base)
        finally:
            # One collection for a run of productions: the matcher builds them together,
            # knowing which attributes the whole file's rules remove (it joins those last),
            # and the matches are queued in the same load order as one by one.
            collect_changes(self, in_match_order=True)
        if error is not None:
            raise error

    @staticmethod
    def _items_before(text: str, file: str, error: SoarError) -> list:
        """The items that parse before the line of ``error`` (empty if none can be found)."""
        line = getattr(error, "line", None)
        location = getattr(error, "location", None)
        if location is not None:
            line = location.line
        if not isinstance(line, int):
            return []
        lines = text.splitlines(keepends=True)
        starts = [
            i
            for i, row in enumerate(lines[: line - 1])
            if row[:1] not in (" ", "\t", "#", "\n", "}", "(", "-", "") and row.strip()
        ]
        cut = line - 1
        while True:
            try:
                return parse("".join(lines[:cut]), file, FUNCTIONS.keys())
            except SoarError:
                earlier = [i for i in starts if i < cut]
                if not earlier:
                    return []
                cut = earlier[-1]

    def source(self, path: str | os.PathLike[str]) -> None:
        """Load a rule file; relative paths resolve against the current source directory."""
        resolved = self._resolve(path)
        if not resolved.is_file():
            raise SoarRuntimeError(f"source: cannot open {path}")
        self._dir_stack.append(resolved.parent)
        try:
            self.load(resolved.read_text(encoding="utf-8"), str(resolved))
        finally:
            self._dir_stack.pop()

    def _resolve(self, path: str | os.PathLike[str]) -> Path:
        candidate = Path(path)
        if not candidate.is_absolute() and self._dir_stack:
            candidate = self._dir_stack[-1] / candidate
        return candidate.resolve()

    def add_production(self, production: Production) -> None:
        """Add a parsed production; one with the same name replaces the old one."""
        self._add_production(production)
        # Matches that exist at load time are queued now, in load order, as the kernel
        # makes them when it adds the production to its Rete.
        collect_changes(self, in_match_order=True)

    def _add_production(self, production: Production) -> None:
        """Add a production, leaving its load-time matches in the matcher for the caller."""
        if production.name in self._productions:
            collect_changes(self, in_match_order=True)
            self.excise(production.name)
        key = duplicate_key(production)
        for name in self._by_shape.get(key, ()):
            if same_production(self._productions[name].production, production):
                # The kernel refuses it with this line and keeps the first (measured).
                self._emit_line(f"Ignoring {production.name} because it is a duplicate of"
                                f" {name} \n")
                return
        self._by_shape.setdefault(key, []).append(production.name)
        self._kernel_places[production.name] = self._kernel_order.add(
            production, self._timetag, self.multi_attributes)
        self.matcher.add_production(self._kernel_order.with_kernel_relations(production))
        info = ProductionInfo.of(production)
        self._load_count += 1
        info.load_index = self._load_count
        self._productions[production.name] = info

    def excise(self, name: str) -> None:
        """Remove a production; its i-supported preferences retract in the next cycle."""
        if name not in self._productions:
            raise SoarRuntimeError(f"excise: no production named {name}")
        self.matcher.excise(name)
        self._kernel_order.remove(name)
        del self._kernel_places[name]
        info = self._productions.pop(name)
        same_shape = self._by_shape[duplicate_key(info.production)]
        same_shape.remove(name)
        if not same_shape:
            del self._by_shape[duplicate_key(info.production)]
        collect_changes(self)

    def excise_all(self) -> None:
        for name in list(self._productions):
            self.excise(name)

    def init(self) -> None:
        """``init-soar``: clear working memory and counters, keep the rules, rebuild S1.

        The matcher is kept (only its working memory is emptied), as the kernel keeps its
        Rete, so re-initialising between problems costs the WMEs, not the rules."""
        self.matcher.clear_wmes()
        self.matcher.take_changes()
        self._kernel_order.restart()
        for info in self._productions.values():
            info.firings = 0
        self._release_slots()
        column, level = self._column, self.trace_level
        self.trace_level = 0  # the new top state is traced below, laid out as the kernel does
        try:
            self._reset()
            self._make_top_state()
        finally:
            self.trace_level = level
        self._column = column
        self._trace_new_top()

    def _trace_new_top(self) -> None:
        """What the kernel's init-soar traces (measured in soar_sml): at watch 1-3 the new
        top state's decision line, which leaves the output column after it; at watch 4-5
        its WMEs newest first, the line, then the io WMEs newest first; at watch 0 nothing
        (the column stays where it was)."""
        if self.trace_level <= 0:
            return
        line = f"\n     0: ==>S: {self._top.id} "
        if self.trace_level < 4:
            self._emit(line)
            return
        io = self._io_id
        wmes = sorted(self._wm.values(), key=lambda w: w.timetag)
        self._traced_adds = [w for w in wmes if io not in (w.id, w.value)]
        trace_wm_changes(self)
        self._emit(line)
        self._traced_adds = [w for w in wmes if io in (w.id, w.value)]
        trace_wm_changes(self)

    def _release_slots(self) -> None:
        """Break the cycles of the preferences about to be dropped (a live preference, its
        slot and its instantiation point at one another), so reference counting frees the
        old working memory at once rather than the cyclic garbage collector later."""
        for slots in self._slots.values():
            for slot in slots.values():
                for bucket in slot.prefs.values():
                    for pref in bucket:
                        pref.inst = None  # type: ignore[assignment]
                slot.prefs.clear()

    def run(self, decisions: int | None = None) -> dict[str, int]:
        """Run until halt or interrupt, or until ``decisions`` more decisions were made."""
        if decisions is not None and decisions < 0:
            raise SoarRuntimeError(f"run: decision count must be >= 0, got {decisions}")
        self._stop = False
        self._halt_note = ""
        target = None if decisions is None else self._decisions + self._owed(decisions)
        if decisions == 0:
            return self.stats
        while not self._halted and not self._stop:
            run_phase(self)
            if target is not None and self._decisions >= target and self._phase == "apply":
                break
        if self.trace_level >= 4:
            trace_wm_changes(self)
        self._stopped_message(target)
        return self.stats

    def _owed(self, decisions: int) -> int:
        """The decision phases ``run N`` makes.  A run stopped by an interrupt at the end of
        an apply phase resumes mid-cycle; the kernel counts the rest of that cycle as one
        of the N (measured in soar_sml: after it, run 1 and run 2 both stop before the next
        apply phase, run 3 one decision later; after an interrupt in a propose phase, the
        cycle's decision is still to come and run N makes N)."""
        return decisions - 1 if decisions > 1 and self._phase == "output" else decisions

    def _stopped_message(self, target: int | None) -> None:
        """What the kernel prints, at every watch level, when a run stops at the end of the
        phase a halt or an interrupt happened in (measured in soar_sml): after a halt
        '\nSystem halted.\nInterrupt received.This Agent halted.' (once: a later run
        prints nothing); after the goal stack grew too deep '\nSystem halted.\nInterrupt
        received.Interrupt received.'; after an interrupt 'Interrupt received.', preceded
        by '\n\n' when the run has no decision limit or the interrupt came in the decision
        that was to be the run's last. 'Interrupt received.' and 'This Agent halted.' do not
        move the kernel's output column (measured by where a later print wraps)."""
        if self._halt_note:
            self._emit("\nSystem halted.\n")
            self._emit_uncounted("Interrupt received." + self._halt_note)
            self._halt_note = ""
        elif self._stop and not self._halted:
            current = self._decisions + (1 if self._phase in ("propose", "decide") else 0)
            if target is None or current == target:
                self._emit("\n\n")
            self._emit_uncounted("Interrupt received.")

    def step(self) -> dict[str, int]:
        """One decision cycle (stopping before the next apply phase, like ``run 1``)."""
        return self.run(1)

    def wmes(self) -> Iterator[WME]:
        """Every WME in working memory, oldest first."""
        return iter(sorted(self._wm.values(), key=lambda w: w.timetag))

    def print(self, identifier: str | Identifier, depth: int = 1) -> str:
        """The kernel's ``print --depth N <id>`` text."""
        ident = self.find_identifier(identifier)
        text = print_identifier(ident, depth, self._augmentations, self._column)
        self._column = 0  # the kernel's print ends its text with a newline
        return text

    def find_identifier(self, identifier: str | Identifier) -> Identifier:
        if isinstance(identifier, Identifier):
            return identifier
        name = str(identifier).upper()
        for wme in self._wm.values():
            for sym in (wme.id, wme.value):
                if isinstance(sym, Identifier) and sym.name == name:
                    return sym
        raise SoarRuntimeError(f"There is no identifier {identifier}.")

    @property
    def operator_sequence(self) -> list[str]:
        """Names of the operators selected so far (``?`` for an operator without a name)."""
        return list(self._operator_names)

    @property
    def input_link(self) -> InputHandle:
        handle = self._input_handle
        if handle is None:
            handle = self._input_handle = InputHandle(self, self._input_link_id, None)
        return handle

    @property
    def output_link(self) -> OutputHandle:
        return OutputHandle(self, self._output_link_id)

    def write_output(self, text: str) -> None:
        self._emit(text)

    def decision_count(self) -> int:
        return self._decisions

    def mark_learning(self, function: str, state: Identifier) -> None:
        """``force-learn`` / ``dont-learn`` on a state (see `Chunker.mark`)."""
        self.chunker.mark(function, state)

    def gensym(self, prefix: str) -> str:
        existing = {w.value for w in self._wm.values() if isinstance(w.value, str)}
        while True:
            self._gensym_counter += 1
            name = f"{prefix}{self._gensym_counter}"
            if name not in existing:
                return name

    def _make_top_state(self) -> None:
        """The top state and its io links, as the kernel makes them."""
        top = self._ids.new("S", level=1)
        self._top = new_goal(self, top, None)
        self._io_id = ids_new_after_top(self, top)
        collect_changes(self)

    # ------------------------------------------------------- for the phases

    def _remove_goal(self, goal: Goal) -> None:
        remove_goal(self, goal)

    def _run_phase(self) -> None:
        """Run the phase the agent is in (one step of a decision cycle)."""
        run_phase(self)

    def _creation_key(self, match: object) -> tuple[int, int, int]:
        """The order the kernel made ``match`` in among one WME's matches (``matches``)."""
        return creation_key(self, match)

    def __repr__(self) -> str:
        return f"<Agent {self.name}: {len(self._productions)} productions, {len(self._wm)} wmes>"

def load_agent(paths: Iterable[str], **kwargs: object) -> Agent:
    """An agent with the given rule files sourced, in order."""
    agent = Agent(**kwargs)  # type: ignore[arg-type]
    for path in paths:
        agent.source(path)
    return agent
