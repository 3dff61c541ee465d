"""The Soar agent: working memory, the decision cycle, trace, stats and print.

The cycle follows the Soar 9.6 kernel phase by phase (input, propose, decide, apply,
output), including the details that change what users observe:

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
import sys
import weakref
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import TextIO, cast

from . import decide as dec
from .chunking import Chunker, Explanation
from .errors import SoarError, SoarRuntimeError
from .goals import Goal
from .instantiation import (
    COMPILE_AFTER,
    MIXED,
    Instantiation,
    ProductionInfo,
    compile_actions,
    interpret_actions,
    is_o_supported,
    match_goal,
    tested_operators,
)
from .io import InputHandle, OutputHandle, WMEHandle
from .memory import WME, Identifier, IdentifierFactory, Symbol
from .preferences import ACCEPTABLE, PROHIBIT, REJECT, REQUIRE, Preference, Slot
from .production import (
    Command,
    Condition,
    ConjunctiveNegation,
    Const,
    Production,
    Var,
    duplicate_key,
    same_production,
)
from .results import find_results
from .rete import KernelOrder, _wme_fits, equality_vars, negation_matches, prefix_token
from .rhs import FUNCTIONS, format_value, kernel_random
from .trace import print_identifier, symbol_text, trace_preference, trace_wme

PHASES = ("input", "propose", "decide", "apply", "output")

_new = object.__new__

#: Where a new kernel agent's printer believes its output line to be, and again after
#: init-soar (measured: its first print wraps as if 17 characters were on the line).
START_COLUMN = 17
#: A state's links to its memories: the kernel removes them (and their children) last
_LINK_ATTRS = ("reward-link", "epmem", "smem")


#: Python's young-generation collection threshold that creating an agent sets for the
#: process when it is lower (the default is 700; it is never lowered). A run's tokens, WMEs
#: and preferences live for some decisions, and an input-link scene until init-soar, so a
#: collection every 700 allocations keeps traversing live objects: measured with callgrind,
#: 3.3% of the block planner's instructions (2,000 takes nearly all of it; hanoi 0.3%).
#: Reference counting still frees nearly everything at once. Raised per run and restored
#: after, it saved nothing: the scene's objects were then traversed after the run.
GC_YOUNG_THRESHOLD = 10_000


def _raise_gc_threshold() -> None:
    threshold = gc.get_threshold()
    if threshold[0] < GC_YOUNG_THRESHOLD:
        gc.set_threshold(GC_YOUNG_THRESHOLD, *threshold[1:])


def _default_matcher() -> type:
    from .rete import Rete

    return Rete


def _vkey(value: Symbol | None) -> object:
    """Dictionary key of a value: ``1`` and ``1.0`` are different Soar symbols."""
    return value if type(value) is not float else (float, value)


class Agent:
    """A Soar agent. See the module docstring for the cycle; the README for the API."""

    # declared here: assigned first outside ``__init__`` (mypyc takes the first type)
    _input_handle: InputHandle | None
    _traced_adds: list[WME]

    def __init__(
        self,
        name: str = "soar",
        *,
        matcher: type | None = None,
        seed: int | None = None,
        out: TextIO | None = None,
    ) -> None:
        _raise_gc_threshold()
        self.name = name
        self._matcher_class = matcher or _default_matcher()
        self.out = out
        self.trace_level = 0
        self.max_elaborations = 100
        self.max_goal_depth = 100
        #: ``waitsnc --on``: a state with nothing to do waits instead of a state no-change
        self.wait_snc = False
        #: RHS errors met while running (each also printed), newest last.
        self.errors: list[str] = []
        self.exploration = dec.Exploration()
        self.srand(seed)
        self._productions: dict[str, ProductionInfo] = {}
        # duplicate_key -> names of the loaded productions with it (duplicates are refused)
        self._by_shape: dict[tuple, list[str]] = {}
        self._load_count = 0
        self._dir_stack: list[Path] = []
        self._pushd: list[Path] = []  # directories pushd put on top of the sourcing file's
        self._aliases: dict[str, tuple[str, ...]] = {}  # alias -> the command words
        self.max_gp = 20000  # most productions one gp may make (the kernel's default)
        self.multi_attributes: dict[str, int] = {}
        self.warnings = True
        #: when the kernel would learn chunks (``chunk always|never|only|except``)
        self.learning = "never"
        self.chunker = Chunker()
        self._gensym_counter = 0
        self.matcher = self._matcher_class()
        # the kernel Rete's node tree, for the order it makes matches in (_kernel_key)
        self._kernel_order = KernelOrder()
        self._kernel_places: dict[str, dict[int, tuple]] = {}
        self._build()

    # ------------------------------------------------------------------ public API

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
        from . import commands
        from .syntax import parse

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
                    self._collect_changes(in_match_order=True)
                    commands.execute(self, item, base)
        finally:
            # One collection for a run of productions: the matcher builds them together,
            # knowing which attributes the whole file's rules remove (it joins those last),
            # and the matches are queued in the same load order as one by one.
            self._collect_changes(in_match_order=True)
        if error is not None:
            raise error

    @staticmethod
    def _items_before(text: str, file: str, error: SoarError) -> list:
        """The items that parse before the line of ``error`` (empty if none can be found)."""
        from .syntax import parse

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
        self._collect_changes(in_match_order=True)

    def _add_production(self, production: Production) -> None:
        """Add a production, leaving its load-time matches in the matcher for the caller."""
        if production.name in self._productions:
            self._collect_changes(in_match_order=True)
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
        self._collect_changes()

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
            self._build()
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
        self._trace_wm_changes()
        self._emit(line)
        self._traced_adds = [w for w in wmes if io in (w.id, w.value)]
        self._trace_wm_changes()

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
            self._run_phase()
            if target is not None and self._decisions >= target and self._phase == "apply":
                break
        if self.trace_level >= 4:
            self._trace_wm_changes()
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

    def _emit_uncounted(self, text: str) -> None:
        """Text the kernel prints without counting it in its output column."""
        column = self._column
        self._emit(text)
        self._column = column

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

    # -------------------------------------------------------------- RHS context

    def write_output(self, text: str) -> None:
        self._emit(text)

    def request_halt(self) -> None:
        if not self._halted:
            self._halt_note = "This Agent halted."  # printed when the run stops
        self._halted = True
        self._stop = True

    def request_interrupt(self) -> None:
        self._stop = True

    def decision_count(self) -> int:
        return self._decisions

    def mark_learning(self, function: str, state: Identifier) -> None:
        """``force-learn`` / ``dont-learn`` on a state (see `Chunker.allowed`)."""
        self.chunker.mark(function, state)

    def gensym(self, prefix: str) -> str:
        existing = {w.value for w in self._wm.values() if isinstance(w.value, str)}
        while True:
            self._gensym_counter += 1
            name = f"{prefix}{self._gensym_counter}"
            if name not in existing:
                return name

    # ------------------------------------------------------------ construction

    def _build(self) -> None:
        """Fresh working memory and counters, then the top state as the kernel makes it."""
        self._ids = IdentifierFactory()
        self._epoch = getattr(self, "_epoch", 0) + 1
        self._input_handle = None
        self._timetag = 0
        self._wm: dict[int, WME] = {}
        self._slots: dict[Identifier, dict[object, Slot]] = {}
        self._arch: dict[Identifier, list[WME]] = {}
        self._level: dict[Identifier, int] = {}
        self._goals: dict[Identifier, Goal] = {}
        self._inst_of: dict[object, Instantiation] = {}
        # The instantiation being fired, for deep-copy (which puts its waiting copies here).
        self.firing: object = None
        # Characters on the output's current line: the kernel's print wraps by them.
        self._column = START_COLUMN
        self._pending_goal: dict[object, Goal] = {}
        self._nil_retractions: list[Instantiation] = []
        self._changed: list[Slot] = []
        self._changed_context: list[Slot] = []
        # (instantiation, the justification of its results) made in this wave
        self._new_justifications: list[tuple[Instantiation, Instantiation]] = []
        #: A new justification's preference -> the result it copies, while not asserted.
        self._copied_from: dict[Preference, Preference] = {}
        self._refs: dict[Identifier, int] = {}
        self._in_wm_phase = False
        self._phase_timetag = 0
        # the newest timetag when the matcher's changes were last taken (_collect_changes)
        self._batch_start = 0
        # (goal, instantiation) whose o-supported local preferences extend the goal's GDS
        # once the wave's preferences are asserted (_grow_gds)
        self._gds_requests: list[tuple[Goal, Instantiation]] = []
        # every earlier _batch_start that began a batch of new WMEs (see _entry_rank)
        self._batch_starts: list[int] = []
        # _batch_of of the joins' birth timetags: it changes no more once asked for (a
        # later batch starts after every WME already made)
        self._born_batches: dict[int, int] = {}
        # per kernel join (serial): when it was last linked (_join_link), a token of its
        # parent memory (WMEs), the production and place it was looked up for, the
        # _collects count of the look, and the tokens of the memory seen since
        self._join_links: dict[int, tuple] = {}
        self._collects = 0  # the takes of matcher changes so far (_collect_changes)
        # the links of the joins whose memory _check_links found emptied, before
        self._links_before: dict[int, tuple] = {}
        # working memory by identifier, then attribute (_vkey), kept once _candidates
        # needs it
        self._by_id: dict[Symbol, dict[object, dict[WME, None]]] | None = None
        # working memory by attribute (_vkey), kept once _wmes_of needs it
        self._by_attr: dict[object, dict[WME, None]] | None = None
        # removed WMEs by identifier, then attribute (_vkey), with when the kernel's Rete
        # took each out (_removal_rank): the unblocking of the negations they matched
        self._removed: dict[Symbol, dict[object, dict[WME, tuple[int, int]]]] = {}
        self._removed_size = 0
        self._removed_limit = 4096
        self._removed_now: list[WME] = []  # removed since the matcher's changes were taken
        self._last_removed: list[WME] = []  # removed in the batch taken last
        self._removals = 0  # WMEs removed so far (their order in a batch)
        # WMEs added and removed since the last trace of working-memory changes (watch 4+)
        self._traced_adds = []
        self._traced_removes: list[WME] = []
        # removed goals' link WMEs and their children: traced after the batch's others
        self._traced_late: list[WME] = []
        # slots whose o-supported preferences a working-memory phase collected (tracing)
        self._collected_slots: set[tuple[Identifier, object]] = set()
        self._context_changed: Goal | None = None
        self._neg_watch: dict[tuple, list[tuple]] = {}
        # (justification, conjunctive negation, bindings) whose watched WME came this phase
        self._ncc_checks: list[tuple] = []
        self._justification_index: dict[tuple, Instantiation] = {}
        self._neg_keys: dict[Instantiation, list[tuple]] = {}
        self._dead_ids: list[Identifier] = []
        self._sources: weakref.WeakKeyDictionary[WME, Instantiation] = weakref.WeakKeyDictionary()
        self._unlinked: list[Identifier] = []
        self._dependents: dict[WME, list[Instantiation]] = {}
        #: WME -> the goals whose GDS holds it (a dict: removal order is insertion order).
        self._gds_index: dict[WME, dict[Goal, None]] = {}
        #: Input handles whose WME is to be added or removed at the next input phase.
        self._input_ops: list[WMEHandle] = []
        self._input_wmes: dict[Identifier, list[WME]] = {}
        self._operator_names: list[str] = []
        self._decisions = self._e_cycles = self._pe_cycles = self._firings = 0
        # Every addition takes the next timetag and every removal leaves ``_wm``, so the
        # kernel's addition and removal counts are ``_timetag`` and ``_timetag - len(_wm)``.
        self._wm_max = 0
        self._halted = False
        self._stop = False
        self._halt_note = ""
        self._phase = "input"
        self._active: Goal | None = None
        self._active_type = ""
        self._phase_cycles = 0
        self._inner_goal: Goal | None = None  # the goal the last cycle went down to
        self._justifications = 0
        top = self._ids.new("S", level=1)
        self._top = self._new_goal(top, None)
        self._io_id = self._ids_new_after_top(top)
        self._collect_changes()

    def _ids_new_after_top(self, top: Identifier) -> Identifier:
        io = self._ids.new("I", level=None)
        self._level[io] = 1
        self._add_arch(top, "io", io)
        self._input_link_id = self._new_id("I", 1)
        self._output_link_id = self._new_id("I", 1)
        self._add_arch(io, "input-link", self._input_link_id)
        self._add_arch(io, "output-link", self._output_link_id)
        return io

    def _new_id(self, hint: str, level: int) -> Identifier:
        ident = self._ids.new(hint)
        self._level[ident] = level
        return ident

    def _new_goal(self, ident: Identifier, superstate: Goal | None) -> Goal:
        """Create a state's standard augmentations (type, superstate, reward-link, epmem, smem)."""
        goal = Goal(ident, superstate, Slot(ident, "operator", True))
        self._goals[ident] = goal
        self._slots.setdefault(ident, {})[_vkey("operator")] = goal.op_slot
        level = goal.level
        goal.arch_wmes.append(self._add_arch(ident, "type", "state"))
        goal.arch_wmes.append(
            self._add_arch(ident, "superstate", superstate.id if superstate else "nil")
        )
        reward = self._new_id("R", level)
        goal.arch_wmes.append(self._add_arch(ident, "reward-link", reward))
        epmem = self._new_id("E", level)
        command, result = self._new_id("C", level), self._new_id("R", level)
        goal.arch_wmes.append(self._add_arch(ident, "epmem", epmem))
        goal.arch_wmes.append(self._add_arch(epmem, "command", command))
        goal.arch_wmes.append(self._add_arch(epmem, "result", result))
        goal.arch_wmes.append(self._add_arch(epmem, "present-id", 1))
        smem = self._new_id("L", level)
        command, result = self._new_id("C", level), self._new_id("R", level)
        goal.arch_wmes.append(self._add_arch(ident, "smem", smem))
        goal.arch_wmes.append(self._add_arch(smem, "command", command))
        goal.arch_wmes.append(self._add_arch(smem, "result", result))
        return goal

    # ------------------------------------------------------------- WM primitives

    def _add_wme(self, ident: Identifier, attr: Symbol, value: Symbol, acceptable=False) -> WME:
        timetag = self._timetag = self._timetag + 1
        # WME.__init__, inline: CPython 3.11 runs a class's Python __init__ through a C
        # call into a new interpreter frame, and every WME of a run is made here
        wme = _new(WME)
        wme.id = ident
        wme.attr = attr
        wme.value = value
        wme.timetag = timetag
        wme.acceptable = acceptable
        wm = self._wm
        wm[timetag] = wme
        if type(value) is Identifier and value.level is None:
            refs = self._refs
            refs[value] = refs.get(value, 0) + 1
        if self._neg_watch:
            self._check_negations(wme)
        self.matcher.add_wme(wme)
        by_id = self._by_id
        if by_id is not None:  # _file_wme, inline: every WME of a run is made here
            slots = by_id.get(ident)
            if slots is None:
                by_id[ident] = {_vkey(attr): {wme: None}}
            else:
                key = _vkey(attr)
                bucket = slots.get(key)
                if bucket is None:
                    slots[key] = {wme: None}
                else:
                    bucket[wme] = None
        by_attr = self._by_attr
        if by_attr is not None:
            key = _vkey(attr)
            bucket = by_attr.get(key)
            if bucket is None:
                by_attr[key] = {wme: None}
            else:
                bucket[wme] = None
        if self.trace_level >= 4:
            self._traced_adds.append(wme)
        return wme

    def _remove_wme(self, wme: WME) -> None:
        wm = self._wm
        if len(wm) > self._wm_max:
            # Working memory only shrinks here, so its high-water mark is reached just
            # before a removal (or now: see stats).
            self._wm_max = len(wm)
        timetag: int = wme.timetag
        if timetag not in wm:  # (not ``wm.pop(timetag, None)``: mypyc calls that generically)
            return
        del wm[timetag]
        self.matcher.remove_wme(wme)
        self._removed_now.append(wme)
        by_id = self._by_id
        if by_id is not None:
            slots = by_id[wme.id]
            key = _vkey(wme.attr)
            bucket = slots[key]
            del bucket[wme]
            if not bucket:
                del slots[key]
                if not slots:
                    del by_id[wme.id]
        by_attr = self._by_attr
        if by_attr is not None:
            key = _vkey(wme.attr)
            bucket = by_attr[key]
            del bucket[wme]
            if not bucket:
                del by_attr[key]
        value = wme.value
        if type(value) is Identifier and value.level is None:
            count = self._refs[value] - 1
            if count:
                self._refs[value] = count
            else:
                del self._refs[value]
                self._unlinked.append(value)
        if self.trace_level >= 4:
            self._traced_removes.append(wme)
        if self._dependents or self._gds_index:  # justifications and substates only
            self._substate_wme_gone(wme)

    def _trace_wm_changes(self) -> None:
        """Print the WME changes buffered since the last call, as the kernel's
        ``do_buffered_wm_changes`` does at the end of each working-memory phase (measured:
        additions newest first, then removals, the last requested first; each line ends
        with a newline)."""
        adds, removes = self._traced_adds, self._traced_removes
        if not adds and not removes and not self._traced_late:
            return
        removes += self._traced_late
        self._traced_adds, self._traced_removes, self._traced_late = [], [], []
        lines = [f"=>WM: {trace_wme(wme)}\n" for wme in reversed(adds)]
        lines += [f"<=WM: {trace_wme(wme)}\n" for wme in reversed(removes)]
        self._emit("".join(lines))

    def _substate_wme_gone(self, wme: WME) -> None:
        """A WME left: retract the justifications that rest on it and remove the substates
        whose goal dependency set holds it."""
        dependents = self._dependents.pop(wme, None)
        if dependents:
            for inst in dependents:
                source = inst.source
                if source is not None and not source.alive and all(
                    p.o_supported for p in inst.prefs
                ):
                    # Its retraction, which changes nothing, went with its substate
                    # (measured: no elaboration cycle for it when the decision that
                    # removed its ground removed the substate too).
                    continue
                self._schedule_retraction(inst)
        goals = self._gds_index.pop(wme, None)
        if goals:
            for goal in goals:
                if goal.alive:
                    if self.trace_level >= 2:
                        self._trace_gds_removal(goal, wme)
                    self._remove_goal(goal)

    def _trace_gds_removal(self, goal: Goal, wme: WME) -> None:
        """The kernel's watch-2 text for a goal-dependency-set violation (measured in
        soar_sml; one text wherever the WME goes): on a fresh line, two messages naming
        the WME, each line ended."""
        where = trace_wme(wme)
        self._emit_line(
            f"Removing state {goal.id} because element in GDS changed. WME: {where}\n"
            f"\n    REMOVING GOAL [{goal.id}] due to change in GDS WME {where}\n"
        )

    def _add_arch(self, ident: Identifier, attr: Symbol, value: Symbol) -> WME:
        wme = self._add_wme(ident, attr, value)
        self._arch.setdefault(ident, []).append(wme)
        return wme

    def _remove_arch(self, wme: WME) -> None:
        bucket = self._arch.get(wme.id)
        if bucket is not None:
            try:
                bucket.remove(wme)
            except ValueError:
                pass
            if not bucket:
                del self._arch[wme.id]
        self._remove_wme(wme)

    def _level_of(self, ident: Identifier) -> int:
        level = ident.level
        return level if level is not None else self._level.get(ident, 1)

    def _augmentations(self, ident: Identifier) -> list[WME]:
        """Every WME whose identifier is ``ident`` (for print)."""
        out = list(self._arch.get(ident, ()))
        for slot in self._slots.get(ident, {}).values():
            out.extend(slot.wmes.values())
            out.extend(slot.acceptable_wmes.values())
        return out

    # ------------------------------------------------------------- the cycle

    def _run_phase(self) -> None:
        phase = self._phase
        if phase == "input":
            self._input_phase()
        elif phase == "propose":
            self._elaboration_phase(apply=False)
        elif phase == "decide":
            self._decision_phase()
        elif phase == "apply":
            self._elaboration_phase(apply=True)
        else:
            self._output_phase()

    def _input_phase(self) -> None:
        if self.trace_level >= 2:
            self._emit("\n--- Input Phase --- \n")
        self._apply_input_ops()
        if self.trace_level >= 4:
            self._trace_wm_changes()
        self._collect_changes()
        if self.trace_level >= 2:
            self._emit("\n--- END Input Phase --- \n")
        self._phase = "propose"
        self._active = None
        self._active_type = ""
        self._phase_cycles = 0
        if self.trace_level >= 2:
            self._emit("\n--- Propose Phase ---\n")

    def _output_phase(self) -> None:
        if self.trace_level >= 2:
            self._emit("\n--- Output Phase ---\n\n--- END Output Phase ---\n")
        self._phase = "input"

    def _elaboration_phase(self, apply: bool) -> None:
        """Run elaboration cycles until quiescence ends the phase, or a halt stops the run
        (after the cycle it happened in). An interrupt stops the run when the phase is over,
        as in the kernel (measured)."""
        end = "output" if apply else "decide"
        if self._phase_cycles == 0:
            self._inner_goal = None
        if self._phase_cycles == 0 and apply and self.trace_level >= 2 and self._active is None:
            self._emit("\n--- Application Phase ---\n")
        while True:
            goal, firing = self._next_active(apply)
            if firing == "":
                # The kernel checks the stack at the end of an application phase only
                # after an IE cycle (measured: a tie that a PE cycle's result resolved
                # stands until the propose phase).
                if not apply or self._active_type != "PE":
                    self._consistent_through(None)
                self._end_phase(apply, end)
                return
            self._elaboration_cycle(goal, firing)
            self._e_cycles += 1
            self._phase_cycles += 1
            if firing == "PE":
                self._pe_cycles += 1
            if self._phase_cycles >= self.max_elaborations and not self._halted:
                self._emit(f"\nWarning: reached max-elaborations; proceeding to {end} phase.")
                self._end_phase(apply, end)
                return
            if self._halted:  # an interrupt (_stop) lets the phase finish, as in the kernel
                # The phase's END line only when the halt came in its last cycle (measured:
                # 'Change Working Memory (PE) ---\n\nSystem halted.' when IE firings follow).
                if self._quiescent(apply):
                    self._trace_phase_end(apply)
                return

    def _quiescent(self, apply: bool) -> bool:
        """Whether no goal has firings or retractions waiting (without the consistency
        checks of ``_next_active``)."""
        if self._nil_retractions:
            return False
        goal: Goal | None = self._top
        while goal is not None:
            if goal.pending_i or goal.retractions or (apply and goal.pending_o):
                return False
            goal = goal.sub
        return True

    def _trace_phase_end(self, apply: bool) -> None:
        if self.trace_level >= 2:
            self._emit(
                "\n--- END Application Phase ---\n" if apply else "\n--- END Propose Phase ---\n"
            )

    def _end_phase(self, apply: bool, end: str) -> None:
        self._trace_phase_end(apply)
        self._phase = end
        self._active = None
        self._active_type = ""
        self._phase_cycles = 0

    def _next_active(self, apply: bool) -> tuple[Goal | None, str]:
        """The goal and firing type of the next elaboration cycle, '' at quiescence.

        Checks the goal stack's consistency like the kernel when the active level moves or
        a goal switches from i- to o-firing; an inconsistent decision ends the phase.
        """
        if not apply and self._nil_retractions:
            # The propose phase does the retractions of removed goals first, on their own
            # (measured); the apply phase lets them ride along with the next cycle.
            return None, "NIL"
        goal: Goal | None = self._top
        chosen: Goal | None = None
        firing = ""
        while goal is not None:
            if goal.pending_i or goal.retractions:
                chosen, firing = goal, "IE"
                break
            if apply and goal.pending_o:
                chosen, firing = goal, "PE"
                break
            goal = goal.sub
        if chosen is None:
            # Retractions of instantiations whose goal is gone are done in any cycle; on
            # their own they make a cycle at "level 0", like the kernel's.
            return (None, "NIL") if self._nil_retractions else (None, "")
        previous, previous_type = self._active, self._active_type
        check: Goal | None = None
        if previous is not None and previous.alive:
            if chosen.level > previous.level:
                check = previous  # moving down the stack: re-check the goals above
            elif firing == "PE" and previous_type != "PE":
                check = chosen
        elif previous is not None and not previous.alive and firing == "PE":
            check = chosen
        if check is not None and not self._consistent_through(check):
            return None, ""
        self._active, self._active_type = chosen, firing
        return chosen, firing

    def _elaboration_cycle(self, goal: Goal | None, firing: str) -> None:
        """One elaboration cycle, as the kernel's "new waterfall" preference phase: the
        pending assertions of the firing type fire level by level from the active goal down
        (each level's preferences asserted before the next level fires), then the active
        goal's retractions and those of removed goals, then the working-memory phase."""
        # A cycle of removed goals' retractions alone is an IE cycle, traced at the goal the
        # last cycle went down to, or at level 0 when that goal is gone (measured)
        shown = "IE" if goal is None else firing
        last = self._inner_goal
        traced = goal if goal is not None else last if last is not None and last.alive else None
        if self.trace_level >= 2 and self._phase == "apply":
            depth = 0 if traced is None else traced.level
            self._emit_line(
                f"\t--- Firing Productions ({shown}) For State At Depth {depth} ---\n"
            )
        if goal is None and self.trace_level >= 3:
            where = "0 goal #" if traced is None else f"{traced.level} goal {traced.id}"
            self._emit(f"\n--- Inner Elaboration Phase, active level {where} ---\n")
        level_goal = goal
        change_level = goal.level if goal is not None else 0
        while level_goal is not None:
            if level_goal is not goal and not self._pending_from(level_goal, firing):
                break  # the kernel goes down the stack only while assertions wait below
            if self.trace_level >= 3:
                self._emit(
                    f"\n--- Inner Elaboration Phase, active level {level_goal.level}"
                    f" goal {level_goal.id} ---\n"
                )
            self._inner_goal = level_goal
            limit = change_level if level_goal is not goal else 0
            if self._fire_level(level_goal, firing, limit) and level_goal.level > change_level:
                change_level = level_goal.level
            level_goal = level_goal.sub
        retractions, self._nil_retractions = self._nil_retractions, []
        if goal is not None:
            # Newest first, like the kernel's match-set lists.
            retractions = goal.retractions[::-1] + retractions
            goal.retractions = []
        for inst in retractions:
            self._retract(inst)
        if self.trace_level >= 2 and self._phase == "apply":
            # Not on a fresh line: after a write that did not end its line, the kernel
            # goes on on the same line (measured: "applied\t--- Change Working Memory").
            self._emit(f"\t--- Change Working Memory ({shown}) ---\n")
        self._working_memory_phase()
        if self.trace_level >= 4:
            self._trace_wm_changes()
        self._collect_changes()

    def _pending_from(self, goal: Goal, firing: str) -> bool:
        """Whether ``goal`` or a goal below it has retractions or assertions of the
        ``firing`` type waiting (measured: the kernel prints a lower level's 'Inner
        Elaboration Phase' header only then)."""
        level_goal: Goal | None = goal
        while level_goal is not None:
            if level_goal.retractions:
                return True
            queue = level_goal.pending_i if firing == "IE" else level_goal.pending_o
            if any(type(match) is not _JustificationMatch for match in queue):
                return True
            level_goal = level_goal.sub
        return False

    def _fire_level(self, goal: Goal, firing: str, change_level: int) -> bool:
        """Fire one level's pending assertions; return whether any were pending.

        Below the active level, the kernel's waterfall postpones an instantiation that
        would change an identifier at or above ``change_level`` (a level already changed in
        this cycle): it stays pending for a later cycle."""
        queue = goal.pending_i if firing == "IE" else goal.pending_o
        if not queue:
            return False
        matches = list(queue.items())
        queue.clear()
        fired: list[Instantiation] = []
        o_support = firing == "PE"
        pending_goal = self._pending_goal
        postponed: list[tuple[object, ProductionInfo]] = []
        for match, info in reversed(matches):
            if type(match) is _JustificationMatch:
                if change_level and match.level <= change_level:
                    postponed.append((match, info))
                continue
            if change_level and self._touches_level(match, info, change_level):
                postponed.append((match, info))
                continue
            if match in pending_goal:
                del pending_goal[match]
            fired.append(self._fire(match, info, goal, o_support))
        if postponed:
            # They keep their places in the queue (measured in soar_sml: two snc matches
            # the waterfall put off, of (S1 ^count 2) and the newer-entered (S1 ^count 0),
            # fire count 0 first, as they would have; we had reversed them).
            queue.update(reversed(postponed))
        self._assert_preferences(fired, o_support)
        if self._gds_requests:
            self._grow_gds()
        return True

    def _touches_level(self, match: object, info: ProductionInfo, change_level: int) -> bool:
        bindings = match.bindings  # type: ignore[attr-defined]
        for name in info.make_ids:
            ident = bindings.get(name)
            if isinstance(ident, Identifier) and self._level_of(ident) <= change_level:
                if self.trace_level >= 5:
                    self._emit(
                        f"\n*** Waterfall: aborting firing because ({ident} * *) level"
                        f" {self._level_of(ident)} is on or higher (lower int) than change"
                        f" level {change_level}"
                    )
                return True
        return False

    def _decision_phase(self) -> None:
        if self.trace_level >= 2:
            self._emit("\n--- Decision Phase ---\n")
        self._collect_changes()
        self._decide_context_slots()
        self._decisions += 1
        self._collect_changes()
        if self.trace_level >= 4:
            self._trace_wm_changes()
        if self.trace_level >= 2:
            self._emit("\n--- END Decision Phase ---\n")
        self._phase = "apply"
        self._active = None
        self._active_type = ""
        self._phase_cycles = 0

    # ------------------------------------------------------------- matches

    def _collect_changes(self, in_match_order: bool = False) -> None:
        """Move the matcher's new and retracted matches into the goals' queues.

        New matches are queued in the order the kernel's Rete would have made them: by
        the newest WME they match, and for one WME the later-loaded production first (its
        node is activated first); firing then takes them newest first, like the kernel's
        match-set lists."""
        new, gone = self.matcher.take_changes()
        self._collects += 1
        start, self._batch_start = self._batch_start, self._timetag
        if start != self._timetag:
            self._batch_starts.append(start)
        if self._removed_now:
            self._file_removals()
        elif self._last_removed:
            self._last_removed = []
        if self._join_links and (new or gone):
            self._check_links()
        elif self._links_before:
            self._links_before = {}
        if gone:
            self._retract_matches(gone, self.matcher.blocked_retractions)
        if new:
            if len(new) > 1 and not in_match_order:
                new = self._batch_sorted(new, start)
            self._queue_matches(new)

    def _file_removals(self) -> None:
        """File the WMEs removed in the batch just taken with when the kernel's Rete took
        them out, as an ``_entry_rank``: after the batch's additions (``_batch_sorted``),
        the last requested first (as watch 4 lists them); the batch is the latest that
        added a WME (this one, if it added any). Records of identifiers no
        longer in working memory are dropped when their number has doubled: no token can
        bind such an identifier again."""
        batch = len(self._batch_starts)
        removed = self._removed
        for wme in reversed(self._removed_now):
            self._removals += 1
            slots = removed.get(wme.id)
            if slots is None:
                slots = removed[wme.id] = {}
            key = _vkey(wme.attr)
            bucket = slots.get(key)
            if bucket is None:
                bucket = slots[key] = {}
            bucket[wme] = (-batch, -self._removals)
            self._removed_size += 1
        self._last_removed, self._removed_now = self._removed_now, []
        if self._removed_size >= self._removed_limit:
            for ident in [i for i in removed if i not in self._refs and i not in self._goals]:
                del removed[ident]
            self._removed_size = sum(len(bucket) for slots in removed.values()
                                     for bucket in slots.values())
            self._removed_limit = max(4096, 2 * self._removed_size)

    def _unblock_rank(self, cond: Condition, bindings: dict[str, Symbol]) -> tuple | None:
        """When the kernel's negative node of ``cond`` (a negated condition) last passed
        on a token of ``bindings``: the removal of the latest removed WME that matched it
        (the negation holds now, so that removal was of its last blocker), as an
        ``_entry_rank``; None when no such WME was removed (or its identifier is not
        bound: the token was then made by its positive WMEs)."""
        ident: Symbol | None = None
        for name in equality_vars(cond.id_test):
            ident = bindings.get(name)
            if ident is not None:
                break
        if ident is None:
            return None
        slots = self._removed.get(ident)
        if slots is None:
            return None
        attr = cond.attr_test
        if type(attr) is Const:
            bucket = slots.get(_vkey(attr.value))  # type: ignore[union-attr]
            buckets = [bucket] if bucket is not None else []
        else:
            buckets = list(slots.values())
        positive = Condition(cond.id_test, cond.attr_test, cond.value_test,
                             acceptable=cond.acceptable, goal=cond.goal)
        latest: tuple | None = None
        for bucket in buckets:
            for wme, rank in bucket.items():
                if (latest is None or rank < latest) and _wme_fits(positive, wme, bindings):
                    latest = rank
        return latest

    def _prefix_ranks(self, name: str, place: tuple, wmes: tuple) -> list[tuple | None]:
        """Per condition above the join of ``place`` in the kernel's order (its positive
        conditions ``place[1]`` and the negated conditions among them): when the kernel's
        Rete took the WME in (``_entry_rank``), or, for a negation, last passed its token
        on (``_unblock_rank``; None: never, or a conjunctive negation)."""
        starts = self._batch_starts
        ordered = self._kernel_order.ordered(name)
        if ordered is None or not any(kcond.negated for kcond in ordered[:place[5]]):
            return [_entry_rank(wmes[j], starts) for j in place[1]]
        ranks: list[tuple | None] = []
        bindings: dict[str, Symbol] = {}
        seen: set[int] = set()
        for kcond in ordered[:place[5]]:
            if kcond.is_ncc:
                ranks.append(None)
            elif kcond.negated:
                ranks.append(self._unblock_rank(kcond.element, bindings))
            elif kcond.index not in seen:
                seen.add(kcond.index)
                wme = wmes[kcond.index]
                ranks.append(_entry_rank(wme, starts))
                bindings = _wme_fits(kcond.element, wme, bindings) or bindings
        return ranks

    def _batch_sorted(self, new: list, start: int) -> list:
        """New matches in the order the kernel's Rete made them from one batch of WME
        changes (the WMEs newer than ``start``). The kernel adds a batch to its Rete newest
        first (measured: three ``(S1 ^x v)`` made by one firing each match one rule, whose
        firings come oldest WME first), so a match is made when its oldest WME of the batch
        enters, and the matches of older WMEs are made later; matches made by no new WME
        (a removal unblocked them) come last: the kernel removes a batch's WMEs after it
        has added them all (measured in soar_sml, the collapsed hanoi: the ^upper-disk
        that a move's removed ^above uncovers fires before the rejections that its new
        ^last-moved makes). See ``_kernel_key``."""
        creators = [_creator(match, start) for match in new]
        firsts: list[tuple] = []
        removed = self._last_removed
        for k, creator in enumerate(creators):
            made: int = creator[0]
            if made <= start or (removed and self._unblocked_now(new[k], removed)):
                firsts.append((2, made))
            else:
                firsts.append((1, -made))
        if len(new) == 2:  # the usual case, without sorting
            one: tuple
            two: tuple
            one, two = firsts
            if one == two:
                one, two = self._tied_keys(firsts, new, creators, None)
            return [new[1], new[0]] if two < one else new
        keys: list[tuple] = list(firsts)
        shared = _shared(firsts)
        if shared:
            keys = self._tied_keys(firsts, new, creators, shared)
        order = sorted(range(len(new)), key=keys.__getitem__)
        return [new[k] for k in order]

    @staticmethod
    def _unblocked_now(match: object, removed: list[WME]) -> bool:
        """Whether a WME the batch removed matched a negated condition of ``match``: its
        token was blocked when its new WMEs entered, and the match was made when the
        removal unblocked it, after the batch's additions (measured in soar_sml, the
        farmer: never-undo, whose new operator enters while the ^failure it negates is
        still there, fires before the result*farmer matches of the same batch)."""
        production = match.production  # type: ignore[attr-defined]
        bindings = match.bindings  # type: ignore[attr-defined]
        for cond in production.conditions:
            if type(cond) is Condition and cond.negated:
                positive = Condition(cond.id_test, cond.attr_test, cond.value_test,
                                     acceptable=cond.acceptable, goal=cond.goal)
                for wme in removed:
                    if _wme_fits(positive, wme, bindings) is not None:
                        return True
        return False

    def _tied_keys(self, firsts: list[tuple], new: list, creators: list[tuple],
                   shared: set[tuple] | None) -> list[tuple]:
        """``(first, *_kernel_key[1:])`` for each new match whose ``first`` another shares
        (in ``shared``; ``None``: all do), the others' ``first`` alone (it settles their
        order); the matches made at one join (same creating WME, alpha memory and path)
        also get the order of their tokens (``_token_order``) and one relinking time, the
        earliest: the kernel relinks a join once, when its parent memory gets its first
        token. Tokens are ordered only there: elsewhere the key is settled before
        (measured by callgrind: most ties are not)."""
        keys: list[tuple] = []
        joined: list[int] = []  # the keys that name a join
        for k in range(len(new)):
            first = firsts[k]
            if shared is not None and first not in shared:
                keys.append(first)
                continue
            key = first + self._kernel_key(new[k], creators[k])[1:]
            if len(key) > 4:
                joined.append(k)
            keys.append(key)
        if len(joined) < 2:
            return keys
        if len(joined) == 2:  # the usual tie: two joins, settled without the token order
            one, two = keys[joined[0]], keys[joined[1]]
            if (one[0] != two[0] or one[1] != two[1] or one[2] != two[2]
                    or one[4][0] != two[4][0]):
                return keys
        joins: dict[tuple, list[int]] = {}
        for k in joined:
            key = keys[k]
            joins.setdefault((key[0], key[1], key[2], key[4][0]), []).append(k)
        for members in joins.values():
            if len(members) > 1:
                linked = min(keys[k][3] for k in members)
                for k in members:
                    full = self._kernel_key(new[k], creators[k], True)
                    keys[k] = (*keys[k][:3], linked, *full[3:])
        return keys

    def _retract_matches(self, gone: list, blocked: int = -1) -> None:
        """Schedule the retraction of fired matches that stopped matching, in creation
        order (it decides the order of retraction); unfired ones just leave their queue."""
        inst_of = self._inst_of
        pending_goal = self._pending_goal
        fired: list[Instantiation] = []
        first_removed = 0  # fired[:first_removed]: blocked by new WMEs (when known)
        for k, match in enumerate(gone):
            inst = inst_of.get(match)
            if inst is not None:
                del inst_of[match]
                fired.append(inst)
                if k < blocked:
                    first_removed += 1
                continue
            goal = pending_goal.get(match)
            if goal is not None:
                del pending_goal[match]
                goal.pending_i.pop(match, None)
                goal.pending_o.pop(match, None)
        if len(fired) > 1:
            # The kernel's order of queueing them, which it undoes when retracting: first
            # those a new WME blocked (WMEs are added to the Rete before any is removed),
            # then those of removed WMEs, the newest match first.
            if blocked >= 0:
                made, removed = fired[:first_removed], fired[first_removed:]
            else:  # those that lost no WME
                wm = self._wm
                made, removed = [], []
                for inst in fired:
                    for wme in inst.wmes:
                        if wme is not None and wm.get(wme.timetag) is not wme:
                            removed.append(inst)
                            break
                    else:
                        made.append(inst)
            if len(made) > 1:
                made = self._kernel_sorted(made, [inst.match for inst in made], True)
            if len(removed) > 1:
                removed = self._found_order(removed)
            fired = made + removed
        for inst in fired:
            self._schedule_retraction(inst)

    def _found_order(self, removed: list[Instantiation]) -> list[Instantiation]:
        """Fired matches that lost a WME, in the order the kernel's Rete finds them (to be
        retracted last found first): a removed WME's tokens are walked newest first (its
        ``w->tokens`` list), each with its subtree, so they retract in the order their
        tokens were made. Measured in soar_sml: when ``(S1 ^count 0)`` leaves, pop1 of
        ``(S1 ^thing T4)`` retracts before pop1 of the older ``(S1 ^thing T1)``: the count
        join made its tokens visiting the parent's newest first. A match was made when the
        last of its WMEs entered the Rete (``_creation_keys``), not by its newest WME."""
        keys = self._creation_keys([inst.match for inst in removed])
        return [removed[k] for k in _latest_first(keys)]

    def _creation_keys(self, matches: list) -> list:
        """Sort keys of the order the kernel's Rete made ``matches`` in: the batch of the
        newest WME, then the WME of that batch that entered last (a batch enters newest
        first: its oldest), then, only for ties, ``_kernel_key`` with the token order."""
        starts = self._batch_starts
        creators: list[tuple] = []
        firsts: list[tuple] = []
        for match in matches:
            newest: int = match.newest[0]
            batch = _batch_of(starts, newest)
            made = _creator(match, starts[batch - 1] if batch else 0)
            creators.append(made)
            timetag: int = made[0]
            firsts.append((batch, -timetag))
        shared = _shared(firsts)
        if not shared:
            return firsts
        return self._tied_keys(firsts, matches, creators, shared)

    def _queue_matches(self, new: list) -> None:
        """Queue new matches at their goals as i- or o-assertions."""
        top = self._top
        only_top = top.sub is None
        productions = self._productions
        pending_goal = self._pending_goal
        for match in new:
            info = productions.get(match.production.name)
            if info is None:
                continue
            if only_top:
                goal = top  # every state-linked match belongs to the only state
                if not info.operator_conditions and info.declared is None:
                    top.pending_i[match] = info
                    pending_goal[match] = top
                    continue
                wmes = match.wmes
            else:
                wmes = match.wmes
                ident = match_goal(wmes)
                maybe = self._goals.get(ident) if ident is not None else None
                if maybe is None or not maybe.alive:
                    continue
                goal = maybe  # (mypyc checks the declared Goal: no None here)
            support = is_o_supported(info, wmes, goal.id, match)
            if support is MIXED:
                self._warn_mixed_support(info.production.name)
                support = False
            if support:
                goal.pending_o[match] = info
            else:
                goal.pending_i[match] = info
            pending_goal[match] = goal

    def _warn_mixed_support(self, name: str, justification: bool = False) -> None:
        """The kernel's warning for a rule (or justification) that both elaborates and
        applies its operator: all its preferences get i-support. (Measured: a
        justification's warning starts on a new line, a rule's does not.)"""
        if self.warnings:
            self._emit(("\n" if justification else "")
                       + "WARNING:  Operator elaborations mixed with operator applications"
                       f"\nAssigning i_support to prod {name}")

    def _creation_key(self, match: object) -> tuple[int, int, int]:
        """Kernel order of match creation: by the newest matched WME; for one WME, by the
        alpha memory that passed it (the kernel visits ``(* ^attr *)`` before
        ``(* ^attr value)``), then the later-loaded production first."""
        newest, index = match.newest  # type: ignore[attr-defined]
        info = self._productions.get(match.production.name)  # type: ignore[attr-defined]
        if info is None:
            return (newest, 0, 0)
        return (newest, info.cond_masks[index] if index >= 0 else 0, -info.load_index)

    def _kernel_sorted(self, items: list, matches: list, newest_first: bool = False) -> list:
        """``items`` (stable) sorted by the ``_kernel_key`` of their ``matches``.  The key's
        first part, the newest WME, is all there is to compare when the matches' newest
        WMEs differ (the usual pair): the rest of the key is made only when needed."""
        if len(items) == 2:
            first, second = matches
            one, two = first.newest[0], second.newest[0]
            if one == two:
                one, two = self._kernel_key(first), self._kernel_key(second)
            if (one < two) if newest_first else (two < one):
                return [items[1], items[0]]
            return items
        keys = [match.newest[0] for match in matches]
        if len(set(keys)) < len(keys):
            keys = [self._kernel_key(match) for match in matches]
        order = sorted(range(len(items)), key=keys.__getitem__, reverse=newest_first)
        return [items[k] for k in order]

    def _kernel_key(self, match: object, creator: tuple | None = None,
                    tokens: bool = False) -> tuple:
        """The order the kernel's Rete makes new matches in: by the newest matched WME, then
        by the alpha memory it entered (``(* ^attr *)`` before ``(* ^attr value)``) and the
        path from the join it activated down to the production (``KernelOrder``).  A WME
        matched by several conditions makes the match in the last alpha memory it enters,
        at the first of them in the kernel's order. ``creator``: the WME that made the
        match and its index, when not the newest (see ``_batch_sorted``); ``tokens``: order
        the matches one WME makes at one join too (``_token_order``)."""
        newest, index = creator or match.newest  # type: ignore[attr-defined]
        places = self._kernel_places.get(match.production.name)  # type: ignore[attr-defined]
        if places is None:
            return (newest,)
        place = places.get(index)
        if place is None:
            return (newest,)
        if newest <= place[6]:
            # Made when the production was loaded, in the order of loading (measured: of
            # two such rules with the same conditions, a new WME that blocks both retracts
            # the first loaded first, as it does the match made first at run time).
            return (newest, -1, -place[3][-1])
        wmes = match.wmes  # type: ignore[attr-defined]
        if place[4]:  # the WME may be in other conditions too
            wme = wmes[index]
            for j in place[4]:
                if wmes[j] is wme:
                    other = places[j]
                    if other[0] > place[0] or (other[0] == place[0] and other[5] < place[5]):
                        place = other
        # When its join was made, or relinked (see KernelOrder): the entry of the latest
        # WME before it, in the order the kernel's Rete took the WMEs in (the negated
        # _entry_rank). Joins relinked by one WME's entry go in the order it activated
        # them: its (* ^attr *) memory before (* ^attr value), each's joins by path.
        born: int = place[2]
        starts = self._batch_starts
        link_batch = self._born_batches.get(born)
        if link_batch is None:
            link_batch = self._born_batches[born] = _batch_of(starts, born)
        own = tuple([wmes[j] for j in place[1]])
        linked = _token_link(place[1], own, places, born, link_batch, starts)
        if linked[1] != _LATEST:  # else linked since it was made (its memory never emptied)
            linked = self._join_link(match.production.name,  # type: ignore[attr-defined]
                                     place, places, born, link_batch, own, linked)
        if not tokens:
            return (newest, place[0], linked, place[3])
        return (newest, place[0], linked, (place[3][0],),
                *_token_order(wmes, place, self._batch_starts,
                              self._prefix_ranks(match.production.name,  # type: ignore[attr-defined]
                                                 place, wmes)))

    def _join_link(self, name: str, place: tuple, places: dict[int, tuple], born: int,
                   born_batch: int, own: tuple, own_link: tuple) -> tuple:
        """When the kernel's Rete last linked the join of ``place`` to its alpha memory
        (right unlinking: a join whose parent memory is empty is unlinked, and relinked
        when the memory gets a token), as a sort key (``_token_link`` of that token);
        ``own``: the match's token of that memory (its WMEs there), ``own_link`` its key.

        The memory's tokens are its prefix's partial matches in working memory; a record
        keeps the earliest of those seen while the memory is not emptied (``_check_links``):
        a token seen there now was there since it was made. Only the matches' own tokens
        are seen: looking all of the memory's tokens up when a record is made cost the
        blocks planner a third more time, for one more watch-3 trace of 150 random
        matching agents as the kernel's. Measured
        in soar_sml, matching agent 8: op1x's ^stage join, linked by the first (X1 ^p 1)
        token, keeps its place before op0x's while the ^p WMEs are replaced one by one. A
        match whose token is gone (a retraction) was made in the link on record before
        this batch."""
        serial: int = place[3][0]
        record = self._join_links.get(serial)
        if not _all_there(own, self._wm):  # the token is gone now
            before = self._links_before.get(serial)
            if before is not None:
                return before  # type: ignore[no-any-return]
            if record is not None and record[4] != self._collects:
                return record[0]  # type: ignore[no-any-return]
            return own_link
        if record is not None:
            seen: set[tuple] = record[5]
            if own not in seen:
                seen.add(own)
                _live_tokens(seen, self._wm)
                if own_link < record[0]:  # there now, so the memory was not empty since
                    self._join_links[serial] = (own_link, *record[1:])
                    return own_link
            return record[0]  # type: ignore[no-any-return]
        starts = self._batch_starts
        if own_link[0] == len(starts) and starts:  # made now, and no link on record
            older = self._older_token(name, place, starts[-1])
            if older is not None:
                own, own_link = older, _token_link(place[1], older, places, born,
                                                   born_batch, starts)
        self._join_links[serial] = (own_link, own, name, place, self._collects, {own})
        return own_link

    def _older_token(self, name: str, place: tuple, start: int) -> tuple | None:
        """A token of the kernel's memory above the join of ``place`` made before this
        batch (of WMEs no newer than ``start``, those the batch removed included: the
        kernel takes them out after the batch's additions), or None. A join whose link
        was never asked for has no record (``_join_link``): its memory did not empty when
        a new token came in if such a token was there (measured in soar_sml, the farmer
        crossing with the wolf: the new (F1 ^on R4) replaces (F1 ^on L2) in the tokens of
        the passenger's ^on join, which keeps its place before result*stays's join)."""
        ordered = self._kernel_order.ordered(name)
        if ordered is None:
            return None
        removed = self._last_removed

        def candidates(cond: Condition, bindings: dict[str, Symbol]) -> list[WME]:
            found = [wme for wme in self._candidates(cond, bindings) if wme.timetag <= start]
            return found + removed if removed else found

        return prefix_token(ordered, place[5], candidates, place[1])

    def _memory_token(self, name: str, place: tuple) -> tuple | None:
        """A token of the kernel's memory above the join of ``place`` (see
        ``_join_link``), as the WMEs of the conditions ``place[1]``; None if it is empty."""
        ordered = self._kernel_order.ordered(name)
        if ordered is None:
            return None
        return prefix_token(ordered, place[5], self._candidates, place[1])

    def _check_links(self) -> None:
        """After a batch of WME changes: a recorded join (``_join_link``) whose token on
        record lost a WME stays linked, with another token on record (one seen before, or
        else one looked up in working memory), if its memory still has one (the kernel
        adds a batch's WMEs before it removes any, so a token that replaces another keeps
        the memory from emptying), and is forgotten if not. The links of the batch before
        are kept for ordering retractions."""
        wm = self._wm
        if self._links_before:
            self._links_before = {}
        gone = [serial for serial, record in self._join_links.items()
                if not _all_there(record[1], wm)]
        for serial in gone:
            record = self._join_links[serial]
            self._links_before[serial] = record[0]
            seen = {token for token in record[5] if _all_there(token, wm)}
            if seen:
                witness = next(iter(seen))
            else:
                found = self._memory_token(record[2], record[3])
                if found is None:
                    del self._join_links[serial]
                    continue
                witness = found
                seen.add(witness)
            self._join_links[serial] = (record[0], witness, *record[2:5], seen)

    def _candidates(self, cond: Condition, bindings: dict[str, Symbol]) -> Iterable[WME]:
        """The WMEs that may match ``cond`` given ``bindings`` (for ``prefix_token``):
        those of its bound identifier with its attribute (all of the identifier's, when
        the attribute is not a constant); of every state, for a state test on an unbound
        identifier. The index of working memory by identifier is kept from the first call
        on."""
        index = self._by_id
        if index is None:
            index = self._by_id = {}
            for wme in self._wm.values():
                _file_wme(index, wme)
        ident: Symbol | None = None
        for name in equality_vars(cond.id_test):
            ident = bindings.get(name)
            if ident is not None:
                break
        if ident is not None:
            idents: Iterable[Symbol] = (ident,)
        elif cond.goal is not None:
            idents = list(self._goals)
        else:
            return list(self._wm.values())
        attr = cond.attr_test
        key = _vkey(attr.value) if type(attr) is Const else None  # type: ignore[union-attr]
        found: list[WME] = []
        for one in idents:
            slots = index.get(one)
            if slots is None:
                continue
            if key is not None:
                found.extend(slots.get(key, ()))
            else:
                for bucket in slots.values():
                    found.extend(bucket)
        return found

    def _wmes_of(self, cond: Condition) -> list[WME]:
        """The WMEs with the condition's attribute (all, when it is not a constant), from an
        index of working memory by attribute kept from the first call on."""
        index = self._by_attr
        if index is None:
            index = self._by_attr = {}
            for wme in self._wm.values():
                key = _vkey(wme.attr)
                bucket = index.get(key)
                if bucket is None:
                    index[key] = {wme: None}
                else:
                    bucket[wme] = None
        attr = cond.attr_test
        if type(attr) is Const:
            found = index.get(_vkey(attr.value))  # type: ignore[union-attr]
            return list(found) if found is not None else []
        return list(self._wm.values())

    def _schedule_retraction(self, inst: Instantiation) -> None:
        if inst.retracted:
            return
        inst.retracted = True
        if inst.goal.alive:
            inst.goal.retractions.append(inst)
        else:
            self._nil_retractions.append(inst)

    # ------------------------------------------------------------- firing

    def _fire(
        self, match: object, info: ProductionInfo, goal: Goal, o_support: bool
    ) -> Instantiation:
        """Fire a match (``o_support``: it was queued as an o-assertion)."""
        name = info.production.name
        inst = Instantiation(name, match, goal, match.wmes, o_support)  # type: ignore[attr-defined]
        self._firings += 1
        info.firings += 1
        if self.trace_level >= 3:
            self._emit(f"\nFiring {symbol_text(name)}\n")  # |s*p| (measured)
        self._inst_of[match] = inst
        operators = (
            tested_operators(info, inst.wmes, goal.id)
            if o_support and info.declared != "o-support"
            else ()
        )
        bindings = match.bindings  # type: ignore[attr-defined]
        program = info.program
        # for deep-copy, which may replace it by its waiting copies (cast: not narrowed to
        # Instantiation, which mypyc would check when reading it back)
        self.firing = cast(object, inst)
        if program is not None:
            program(self, bindings, inst, o_support, operators)
        else:
            info.runs += 1
            if info.runs >= COMPILE_AFTER:
                info.program = compile_actions(name, info.actions, frozenset(bindings))
            interpret_actions(info.actions, self, bindings, inst, o_support, operators)
        if self.firing is not inst:
            self.firing.settle()  # type: ignore[attr-defined]
        if goal.level > 1:
            goal.insts[inst] = None
            self._handle_substate_preferences(inst)
        return inst

    def _report_rhs_error(self, inst: Instantiation, error: SoarError) -> None:
        """Like the kernel: print ``Error: <text>`` and a newline where the output stands
        (on a fresh line first for the errors that say so, `rhs.FreshLineError`), naming
        no production; the firing goes on without the action. ``errors`` keeps the name."""
        self.errors.append(f"Error: production {inst.name}: {error}")
        if getattr(error, "fresh_line", False):
            self._emit_line(f"Error: {error}\n")
        else:
            self._emit(f"Error: {error}\n")

    def _retract(self, inst: Instantiation) -> None:
        """Remove an instantiation's i-supported preferences (o-supported ones stay)."""
        trace = self.trace_level
        if trace >= 3:
            self._trace_retraction(inst)
        # In the order the kernel made them (inst.prefs is newest first): the slots they
        # leave are decided in that order's reverse, which the trace shows (measured:
        # <=WM: (37: O4 ^name buy), then (38: O4 ^item I5) for a rule that made both).
        for pref in reversed(inst.prefs):
            if pref.live and not pref.o_supported:
                self._remove_preference(pref)
        if inst.goal.level > 1 and not any(p.live for p in inst.prefs):
            inst.goal.insts.pop(inst, None)
        if inst.is_justification:
            if inst.source is not None and not any(p.live for p in inst.prefs):
                inst.source.justified.pop(inst, None)
            if self._justification_index.get(inst.match) is inst:  # type: ignore[arg-type]
                del self._justification_index[inst.match]  # type: ignore[arg-type]
            for key in self._neg_keys.pop(inst, ()):
                bucket = self._neg_watch.get(key)
                if bucket is not None:
                    bucket[:] = [entry for entry in bucket if entry[0] is not inst]
                    if not bucket:
                        del self._neg_watch[key]
            for wme in inst.grounds:
                bucket = self._dependents.get(wme)
                if bucket is not None and inst in bucket:
                    bucket.remove(inst)

    def _trace_retraction(self, inst: Instantiation) -> None:
        """``Retracting name`` when the instantiation loses a preference; at watch 5 the
        preferences it loses, in the order they were asserted (measured)."""
        gone = [pref for pref in reversed(inst.prefs) if pref.live and not pref.o_supported]
        if gone:
            self._emit(f"\nRetracting {symbol_text(inst.name)}\n")
            if self.trace_level >= 5:
                self._emit_line("".join(trace_preference("-", pref) for pref in gone))

    def _assert_preferences(self, fired: list[Instantiation], o_support: bool) -> None:
        """Let o-supported rejects remove the older preferences for their values, then add
        the new preferences to their slots, both in the kernel's order (a rule may remove
        and re-add the same value in one firing: the new preference survives).  The rejects
        go first, as in the kernel: their slots are then decided last in the working-memory
        phase, after the slots that gained preferences (it matters when the removal takes
        a substate away: what was decided before stays for the phase, measured).
        ``o_support``: the wave fired o-assertions (an i-assertion wave makes no o-supported
        preference; a justification may)."""
        justifications, self._new_justifications = self._new_justifications, []
        insts = _with_justifications(fired, justifications) if justifications else fired[::-1]
        tracing = self.trace_level >= 5
        # The kernel takes the o-rejects in the reverse of the order it asserts the rest
        # (measured: '- (S1 ^last-moved other ...)' of the last rule to assert, before the
        # first rule's '- (D1 ^on a ...)' and '- (S1 ^moves 0 ...)').
        o_rejects = [pref for inst in reversed(insts) for pref in inst.prefs
                     if pref.o_supported and pref.type == REJECT
                     ] if o_support or justifications else ()
        for pref in o_rejects:  # not traced itself (measured): what it removes is
            self._o_reject(pref)
            pref.inst = None  # type: ignore[assignment]  # never in a slot: done with
        for inst in insts:
            for pref in reversed(inst.prefs):
                if pref.inst is None:  # an o-reject, done with above
                    continue
                if pref.o_supported and inst.goal.level == 1 and self._already_supported(pref):
                    if tracing:
                        self._emit_line(trace_preference("+", pref)[:-1]
                                        + " ALREADY SUPPORTED ON TOP LEVEL.  IGNORING.\n")
                    self._drop_copied(pref)
                    continue
                if tracing:
                    self._emit_line(trace_preference("+", pref))
                self._add_preference(pref)
        self._copied_from.clear()

    def _drop_copied(self, pref: Preference) -> None:
        """An ignored justification preference takes the results it copies with it: the
        kernel's clones go together (measured in soar_sml: when '+ (S1 ^y 1 +  :O )
        (justify1) ALREADY SUPPORTED ON TOP LEVEL.  IGNORING.', the substate rule's own
        (S1 ^y 1) is neither asserted nor removed with the substate)."""
        original = self._copied_from.get(pref)
        while original is not None:
            original.inst = None  # type: ignore[assignment]  # never asserted
            original = self._copied_from.get(original)

    def _already_supported(self, pref: Preference) -> bool:
        """Whether the slot already holds the same o-supported preference: the kernel then
        ignores a new one made on the top level (measured in soar_sml: '+ (S1 ^note x +
        :O ) (a) ALREADY SUPPORTED ON TOP LEVEL.  IGNORING.', and a later o-reject of x
        removes only the older preference). Only a top-level instantiation's preference
        counts: a substate's own stays beside its justification's copy, which outlives it
        (measured: ``(S1 ^x 1 :O) [level 2]`` does not make ``justify1``'s ignored, a
        top-level rule's or an older justification's does)."""
        slots = self._slots.get(pref.id)
        attr = pref.attr
        slot = slots.get(attr if type(attr) is not float else (float, attr)) if slots else None
        bucket = slot.prefs.get(pref.type) if slot is not None else None
        if not bucket:
            return False
        value, referent = pref.value, pref.referent
        for old in bucket:  # 1 and 1.0 are different symbols: the types must agree too
            if (old.o_supported and old.value == value and type(old.value) is type(value)
                    and old.referent == referent and type(old.referent) is type(referent)
                    and old.inst is not None and old.inst.goal.level == 1):
                return True
        return False

    def _slot(self, ident: Identifier, attr: Symbol, create: bool = True) -> Slot | None:
        slots = self._slots.get(ident)
        if slots is None:
            if not create:
                return None
            slots = self._slots[ident] = {}
        key = _vkey(attr)
        slot = slots.get(key)
        if slot is None and create:
            slot = slots[key] = Slot(ident, attr, False)
        return slot

    def _add_preference(self, pref: Preference) -> None:
        ident = pref.id
        slots = self._slots.get(ident)
        if slots is None:
            slots = self._slots[ident] = {}
        attr = pref.attr
        key = attr if type(attr) is not float else (float, attr)
        slot = slots.get(key)
        if slot is None:
            slot = slots[key] = Slot(ident, attr, False)
        # Slot.add, inlined: the kernel puts a new preference at the head of its list.
        bucket = slot.prefs.get(pref.type)
        if bucket is None:
            slot.prefs[pref.type] = [pref]
        else:
            bucket.insert(0, pref)
        pref.slot = slot
        pref.live = True
        if slot.is_context:
            self._context_changed_at(ident)
            slot.touched = True
            if not slot.changed:
                slot.changed = True
                self._changed_context.append(slot)
        elif not slot.changed:
            slot.changed = True
            self._changed.append(slot)

    def _remove_preference(self, pref: Preference) -> None:
        slot = pref.slot
        if slot is None or not pref.live:
            return
        # Slot.remove, inlined (Preference compares by identity: list.remove is a C search).
        prefs = slot.prefs
        bucket = prefs.get(pref.type)
        if bucket is not None:
            try:
                bucket.remove(pref)
            except ValueError:
                pass
            if not bucket:
                del prefs[pref.type]
        pref.live = False
        # A removed preference no longer needs its instantiation; dropping the link breaks
        # the inst.prefs <-> pref.inst cycle, so reference counting frees both at once and
        # the cyclic garbage collector (a quarter of the run time when it had to) stays idle.
        pref.inst = None  # type: ignore[assignment]
        if slot.is_context:
            self._context_changed_at(slot.id)
            slot.touched = True
        if not slot.changed:
            slot.changed = True
            (self._changed_context if slot.is_context else self._changed).append(slot)

    def _o_reject(self, reject: Preference) -> None:
        """An o-supported reject removes every preference for that value from the slot."""
        slots = self._slots.get(reject.id)
        if slots is None:
            return
        attr = reject.attr
        slot = slots.get(attr if type(attr) is not float else (float, attr))
        if slot is None:
            return
        target = reject.value
        buckets = slot.prefs.values()
        if type(target) is Identifier:  # identifiers are equal only to themselves
            doomed = [
                pref
                for bucket in buckets
                for pref in bucket
                if pref.value is target
            ]
        elif type(target) is float:  # 1.0 is not the symbol 1
            doomed = [
                pref
                for bucket in buckets
                for pref in bucket
                if type(pref.value) is float
                and (pref.value is target or pref.value == target)
            ]
        else:
            doomed = [
                pref
                for bucket in buckets
                for pref in bucket
                if pref.value == target
                and type(pref.value) is not float
            ]
        for pref in doomed:
            if self.trace_level >= 5:
                self._emit_line(trace_preference("-", pref))
            self._remove_preference(pref)

    # ------------------------------------------------------------- WM phase

    def _working_memory_phase(self, diffs_last: bool = False) -> None:
        """Turn changed slots into WME changes, in the kernel's timetag order."""
        if self._in_wm_phase:
            return
        self._in_wm_phase = True
        try:
            self._working_memory_changes(diffs_last)
        finally:
            self._in_wm_phase = False
        while self._dead_ids:
            self._slots.pop(self._dead_ids.pop(), None)
        if self._ncc_checks:
            self._check_conjunctive_negations()

    def _check_conjunctive_negations(self) -> None:
        """Retract the justifications whose watched conjunctive negation now matches (a
        brute-force match over the WMEs with its attributes: this is rare)."""
        checks, self._ncc_checks = self._ncc_checks, []
        for just, element, bindings in checks:
            if just.retracted:
                continue
            attrs = {cond.attr_test.value for cond in element.conditions
                     if isinstance(cond, Condition) and isinstance(cond.attr_test, Const)}
            wmes = [w for w in self._wm.values() if w.attr in attrs]
            if len(attrs) < len(element.conditions):  # a variable attribute somewhere
                wmes = list(self._wm.values())
            if negation_matches(element, wmes, bindings):
                self._schedule_retraction(just)

    def _working_memory_changes(self, diffs_last: bool = False) -> None:
        """Decide the changed slots until none is left. The trace shows the removals in
        the kernel's order (measured in soar_sml; see ``_order_traced_removals``)."""
        self._phase_timetag = self._timetag
        tracing = self.trace_level >= 4
        buffer = self._traced_removes
        phase_start = len(buffer)
        if tracing and self._collected_slots:
            self._collected_slots = set()
        context_removals: list[WME] = []
        collected: list[WME] = []
        while self._changed or self._changed_context:
            changed, self._changed = self._changed, []
            adds: list[tuple[Slot, object, Symbol]] = []
            removes: list[WME] = []
            gds_index = self._gds_index
            for slot in reversed(changed):
                slot.changed = False
                if not gds_index:
                    self._diff_slot(slot, adds, removes)
                    continue
                before = len(removes)
                self._diff_slot(slot, adds, removes)
                if len(removes) > before:
                    # Like the kernel, while deciding the slot: a substate whose GDS holds
                    # a WME about to go is removed now; WMEs already decided still come
                    # and go in this phase, later slots see the substate gone.
                    self._gds_violations(removes[before:])
            if adds:
                self._add_slot_wmes(adds)
            context, self._changed_context = self._changed_context, []
            traced = len(buffer)
            for slot in reversed(context):
                slot.changed = False
                self._update_acceptable_wmes(slot)
            if tracing:
                context_removals += buffer[traced:]
                del buffer[traced:]
            if removes:
                self.matcher.mark_removals()
            for wme in removes:
                self._remove_wme(wme)
            if self._unlinked:
                traced = len(buffer)
                self._collect_unlinked()
                if tracing:
                    collected += buffer[traced:]
                    del buffer[traced:]
            for slot in changed:
                if not slot.prefs and not slot.wmes:
                    self._drop_slot(slot)
            for slot in context:
                if not slot.prefs and not slot.wmes and not slot.acceptable_wmes:
                    self._collect_garbage(slot)
        if tracing:
            self._order_traced_removals(phase_start, context_removals, collected, diffs_last)

    def _order_traced_removals(self, start: int, context: list[WME], collected: list[WME],
                               diffs_last: bool) -> None:
        """Lay the phase's traced removals (from ``start``) out in the kernel's order of
        requests: the slot diffs' (its ``decide_non_context_slots``), those of the operator
        slots' acceptable-preference WMEs (measured: '(15: S1 ^operator O1 +)', '(16: S1
        ^operator O1)', then '(14: O1 ^name init)' in the trace, which reverses them), then
        those of identifiers no longer linked. After a goal removed outside a
        working-memory phase (``diffs_last``), the kernel collects the goal's structures
        as unlinked: the diffs come after the acceptable-preference WMEs (measured)."""
        buffer = self._traced_removes
        if self._collected_slots:  # WMEs the diffs removed from collected slots
            keys = self._collected_slots
            region = buffer[start:]
            collected = collected + [w for w in region if (w.id, _vkey(w.attr)) in keys]
            buffer[start:] = [w for w in region if (w.id, _vkey(w.attr)) not in keys]
        if diffs_last:
            buffer[start:] = context + buffer[start:] + collected
        else:
            buffer += context + collected

    def _add_slot_wmes(self, adds: list[tuple[Slot, object, Symbol]]) -> None:
        """Make the WMEs the slot diffs decided on: ``(slot, value key, value)``; the diff
        already entered the key in ``slot.wmes``, without its WME."""
        if self._top.sub is None:  # no substate: no WME to remember the source of
            for slot, key, value in adds:
                slot.wmes[key] = self._add_wme(slot.id, slot.attr, value)
            return
        levels = self._level
        for slot, key, value in adds:
            ident = slot.id
            wme = slot.wmes[key] = self._add_wme(ident, slot.attr, value)
            level = ident.level
            if (level if level is not None else levels.get(ident, 1)) > 1:
                self._remember_source(wme, slot, (ACCEPTABLE,))

    def _gds_violations(self, removes: list[WME]) -> bool:
        """Remove the substates whose goal dependency set holds a WME about to go, before
        any WME is added (the kernel does it while deciding the slot)."""
        removed = False
        for wme in removes:
            goals = self._gds_index.pop(wme, None)
            for goal in goals or ():
                if goal.alive:
                    if self.trace_level >= 2:
                        self._trace_gds_removal(goal, wme)
                    self._remove_goal(goal)
                    removed = True
        return removed

    def _collect_unlinked(self) -> None:
        """Soar 9.6 drops the o-supported preferences (and input WMEs) of identifiers that
        no WME links to any more; their i-supported WMEs wait for their instantiations to
        retract, as in the kernel. The slots are decided again in this same phase."""
        unlinked, refs = self._unlinked, self._refs
        while unlinked:
            ident = unlinked.pop()
            if ident in refs:
                continue
            arch = self._arch.get(ident)
            if arch:
                for wme in list(arch):
                    self._remove_arch(wme)
            slots = self._slots.get(ident)
            if slots:
                for slot in list(slots.values()):
                    self._drop_unlinked_slot(slot)

    def _drop_unlinked_slot(self, slot: Slot) -> None:
        """Remove an unlinked slot's o-supported preferences and the WMEs it gained in this
        phase (measured on the kernel); older i-supported WMEs wait for their
        instantiations to retract."""
        doomed = [pref for bucket in slot.prefs.values() for pref in bucket if pref.o_supported]
        if doomed and self.trace_level >= 4:
            self._collected_slots.add((slot.id, _vkey(slot.attr)))
        for pref in doomed:
            self._remove_preference(pref)
        wmes = slot.wmes
        if wmes:
            since = self._phase_timetag
            fresh = [key for key, wme in wmes.items() if wme is not None and wme.timetag > since]
            for key in fresh:
                self._remove_wme(wmes.pop(key))

    def _diff_slot(self, slot: Slot, adds: list, removes: list[WME]) -> None:
        """A non-operator slot holds every acceptable value that is not rejected. Its WMEs
        that go are removed newest first, as the kernel's slot lists them (measured in
        soar_sml, n-queens: two ^tried WMEs of S1 leave the Rete oldest first, as watch 4
        prints them)."""
        prefs = slot.prefs
        wmes = slot.wmes
        if not prefs:  # the slot's last preference went: so do all its WMEs
            _move_values(wmes, removes)
            return
        if len(prefs) == 1:
            acceptable = prefs.get(ACCEPTABLE)
            if acceptable is not None:
                if len(acceptable) > 1:
                    self._diff_acceptable(slot, acceptable, adds, removes)
                    return
                # Fast path: one acceptable preference and nothing else.
                value = acceptable[0].value
                key: object = value if type(value) is not float else (float, value)
                if key in wmes:
                    if len(wmes) > 1:
                        for other in [k for k in reversed(wmes)
                                      if k != key or type(k) is not type(key)]:
                            removes.append(wmes.pop(other))
                    return
                if wmes:
                    _move_values(wmes, removes)
                wmes[key] = None  # type: ignore[assignment]
                adds.append((slot, key, value))
                return
        acceptable = prefs.get(ACCEPTABLE)
        wanted: dict[object, Symbol] = {}
        if acceptable:
            for pref in acceptable:
                value = pref.value
                key = value if type(value) is not float else (float, value)
                if key not in wanted:
                    wanted[key] = value
            if len(wanted) > 1:  # the kernel's candidate list is built front-first
                wanted = dict(reversed(wanted.items()))
            for ptype in (REJECT, PROHIBIT):
                for pref in prefs.get(ptype, ()):
                    wanted.pop(_vkey(pref.value), None)
        for key in [k for k in reversed(wmes) if k not in wanted]:
            removes.append(wmes.pop(key))
        for key, value in wanted.items():
            if key not in wmes:
                wmes[key] = None  # type: ignore[assignment]
                adds.append((slot, key, value))

    @staticmethod
    def _diff_acceptable(
        slot: Slot, acceptable: list[Preference], adds: list, removes: list[WME]
    ) -> None:
        """A slot with only acceptable preferences (the usual multi-valued slot) holds
        their distinct values. Sets find what changed without rebuilding the kernel's
        candidate order, which only the new values need (see the general case)."""
        wmes = slot.wmes
        present = {
            p.value if type(p.value) is not float else (float, p.value) for p in acceptable
        }
        gone = [key for key in reversed(wmes) if key not in present]
        key: object
        for key in gone:
            removes.append(wmes.pop(key))
        missing = len(present) - len(wmes)
        if missing == 0:
            return
        if missing == 1:  # one new value (the usual case): no order to keep, usually the head
            for pref in acceptable:
                value = pref.value
                key = value if type(value) is not float else (float, value)
                if key not in wmes:
                    wmes[key] = None  # type: ignore[assignment]
                    adds.append((slot, key, value))
                    return
        new: dict[object, Symbol] = {}
        for pref in acceptable:  # head first: a value's first occurrence is its newest
            value = pref.value
            key = value if type(value) is not float else (float, value)
            if key not in wmes and key not in new:
                new[key] = value
        for key, value in reversed(new.items()):  # the kernel's candidate list, front-first
            wmes[key] = None  # type: ignore[assignment]
            adds.append((slot, key, value))

    def _update_acceptable_wmes(self, slot: Slot) -> None:
        """An operator slot shows each required or acceptable value as ``(S ^operator O +)``."""
        wanted: dict[object, Symbol] = {}
        prefs = slot.prefs
        for ptype in (REQUIRE, ACCEPTABLE):
            for pref in prefs.get(ptype, ()):
                value = pref.value
                key: object = value if type(value) is not float else (float, value)
                if key not in wanted:
                    wanted[key] = value
        current = slot.acceptable_wmes
        # Newest first, as the kernel's list of them (measured: the trace shows the oldest
        # removed first, the selected operator's WME just after its acceptable one).
        gone = [key for key in reversed(current) if key not in wanted]
        for key in gone:
            wme = current.pop(key)
            self._operator_proposal_gone(slot, wme)
            self._remove_wme(wme)
        for key, value in wanted.items():
            if key not in current:
                current[key] = self._add_wme(slot.id, "operator", value, True)

    def _operator_proposal_gone(self, slot: Slot, wme: WME) -> None:
        """Soar 9.6: a selected operator whose proposal no longer matches is removed."""
        selected = slot.wmes.get(_vkey(wme.value))
        if selected is None:
            return
        if self.trace_level >= 2:
            self._emit(
                "\n        REMOVING: Operator from context slot (proposal no longer matches): "
                + trace_wme(wme) + "\n"
            )
        goal = self._goals[slot.id]
        traced = len(self._traced_removes)
        sub = goal.sub
        if sub is not None:
            if self.trace_level >= 2:
                self._emit_line(f"Removing state {sub.id} because of an operator removal.\n")
            self._remove_goal(sub)
        del slot.wmes[_vkey(wme.value)]
        self._context_changed_at(slot.id)
        self._remove_wme(selected)
        if sub is not None and self.trace_level >= 4:
            # the kernel removes the operator before the substate (measured)
            self._traced_removes.insert(traced, self._traced_removes.pop())

    def _collect_garbage(self, slot: Slot) -> None:
        if slot.is_empty() and not slot.is_context:
            self._drop_slot(slot)

    def _drop_slot(self, slot: Slot) -> None:
        """Forget an empty non-context slot (the caller checked that it is empty)."""
        slots = self._slots.get(slot.id)
        if slots is not None:
            attr = slot.attr
            key = attr if type(attr) is not float else (float, attr)
            if slots.get(key) is slot:
                del slots[key]
                if not slots:
                    del self._slots[slot.id]

    # ------------------------------------------------------------- decisions

    def _context_changed_at(self, ident: Identifier) -> None:
        """Remember the highest goal whose operator slot changed since the last decision
        (the kernel's ``highest_goal_whose_context_changed``)."""
        goal = self._goals.get(ident)
        if goal is not None and (
            self._context_changed is None
            or not self._context_changed.alive
            or goal.level < self._context_changed.level
        ):
            self._context_changed = goal

    def _decide_context_slots(self) -> None:
        """Decide from the highest goal whose context changed, else only the bottom goal."""
        goal: Goal | None = self._context_changed
        self._context_changed = None
        if goal is None or not goal.alive:
            goal = self._top
            while goal.sub is not None:
                goal = goal.sub
        while goal is not None:
            slot = goal.op_slot
            decidable = not slot.wmes and bool(slot.prefs)
            if decidable or goal.sub is None:
                if self._decide_slot(goal, decidable):
                    return
            goal = goal.sub

    def _decide_slot(self, goal: Goal, decidable: bool) -> bool:
        slot = goal.op_slot
        slot.touched = False
        if not decidable:
            impasse, candidates = dec.NO_CHANGE, []
        else:
            impasse, candidates = dec.run_preference_semantics(slot, self.exploration)
            if impasse == dec.NONE:
                if candidates:
                    self._select(goal, candidates[0])
                    return True
                impasse = dec.NO_CHANGE
        attribute = "operator" if slot.wmes or impasse != dec.NO_CHANGE else "state"
        if attribute == "state" and self.wait_snc and goal.sub is None:
            if self.trace_level >= 1:  # the kernel shows the waiting state again (measured)
                indent = " " + "   " * (goal.level - 1)
                kind = ""
                if goal.impasse:
                    no_change = goal.impasse == dec.NO_CHANGE
                    kind = f"({goal.attribute} {'no-change' if no_change else goal.impasse})"
                self._emit(f"\n{self._decisions + 1:>6}:{indent}==>S: {goal.id} {kind}")
            return True
        sub = goal.sub
        if sub is not None and sub.impasse == impasse and sub.attribute == attribute:
            self._update_items(sub, candidates, slot)
            return False
        if sub is not None:
            self._remove_goal(sub)
        self._create_substate(goal, impasse, attribute, candidates, slot)
        return True

    def _select(self, goal: Goal, value: Symbol) -> None:
        if goal.sub is not None:
            self._remove_goal(goal.sub)
        slot = goal.op_slot
        wme = slot.wmes[_vkey(value)] = self._add_wme(goal.id, "operator", value)
        if goal.level > 1:
            self._remember_source(wme, slot, (REQUIRE, ACCEPTABLE))
            if self.learning != "never":
                self.chunker.selected(self, wme, slot)
        name = self._operator_name(value)
        self._operator_names.append(name if name is not None else "?")
        self._collect_changes()  # before the WME trace: it may warn (measured)
        if self.trace_level >= 4:
            self._trace_wm_changes()  # the kernel traces the decision after its WM changes
        if self.trace_level >= 1:
            indent = " " + "   " * goal.level
            label = f" ({symbol_text(name)})" if name is not None else ""
            self._emit(f"\n{self._decisions + 1:>6}:{indent}O: {format_value(value)}{label}")

    def _operator_name(self, value: Symbol) -> Symbol | None:
        if not isinstance(value, Identifier):
            return None
        slot = self._slot(value, "name", create=False)
        if slot is not None:
            for wme in slot.wmes.values():
                return wme.value
        for wme in self._arch.get(value, ()):
            if wme.attr == "name":
                return wme.value
        return None

    def _create_substate(
        self, goal: Goal, impasse: str, attribute: str, candidates: list[Symbol], slot: Slot
    ) -> None:
        if goal.level >= self.max_goal_depth:
            # The kernel's guard against runaway subgoaling: say so, make the state, stop.
            # It prints "System halted." (when the run stops) but only interrupts: a later
            # run goes on (measured).
            self._emit(
                f"\nGoal stack depth exceeded {self.max_goal_depth} on a {impasse} impasse."
                "\nSoar appears to be in an infinite loop.  \nContinuing to subgoal may cause"
                " Soar to \nexceed the program stack of your system.\n"
            )
            self._halt_note = self._halt_note or "Interrupt received."
            self.request_interrupt()
        ident = self._ids.new("S", level=goal.level + 1)
        sub = self._new_goal(ident, goal)
        sub.impasse, sub.attribute = impasse, attribute
        goal.sub = sub
        # a constraint failure has ^choices none too (measured)
        choices = "none" if impasse in (dec.NO_CHANGE, dec.CONSTRAINT_FAILURE) else "multiple"
        sub.arch_wmes.append(self._add_arch(ident, "attribute", attribute))
        sub.arch_wmes.append(self._add_arch(ident, "impasse", impasse))
        sub.arch_wmes.append(self._add_arch(ident, "choices", choices))
        sub.arch_wmes.append(self._add_arch(ident, "quiescence", "t"))
        self._update_items(sub, candidates, slot)
        self._collect_changes()  # before the WME trace: it may warn (measured)
        if self.trace_level >= 4:
            self._trace_wm_changes()  # the kernel traces the decision after its WM changes
        if self.trace_level >= 1:
            indent = " " + "   " * goal.level
            kind = (
                f"{attribute} {impasse}" if impasse != dec.NO_CHANGE else f"{attribute} no-change"
            )
            self._emit(f"\n{self._decisions + 1:>6}:{indent}==>S: {ident} ({kind})")

    def _update_items(self, sub: Goal, candidates: list[Symbol], slot: Slot) -> None:
        """Make the substate's ``^item``/``^non-numeric`` WMEs and counts match the candidates."""
        if sub.impasse == dec.NO_CHANGE:
            return
        numeric = {dec._key(p.value) for p in slot.of_type("n=")}
        self._sync_items(sub, "item", candidates)
        self._sync_items(sub, "non-numeric", [c for c in candidates if dec._key(c) not in numeric])

    def _sync_items(self, sub: Goal, attr: str, values: list[Symbol]) -> None:
        wanted = {(attr, dec._key(v)): v for v in values}
        for key, wme in list(sub.items.items()):
            if key[0] == attr and key not in wanted:
                del sub.items[key]
                self._remove_arch(wme)
        for key, value in wanted.items():
            if key not in sub.items:
                sub.items[key] = self._add_arch(sub.id, attr, value)
        count_attr = f"{attr}-count"
        old = sub.counts.pop(count_attr, None)
        if old is not None:
            self._remove_arch(old)  # the kernel renews the count at every update
        if values:  # no ^non-numeric-count when every candidate has a numeric value
            sub.counts[count_attr] = self._add_arch(sub.id, count_attr, len(values))

    def _remove_goal(self, goal: Goal) -> None:
        """Remove a substate and everything below it (``remove_existing_context...``)."""
        if not goal.alive:
            return
        if goal.sub is not None:
            self._remove_goal(goal.sub)
        goal.alive = False
        selected = goal.selected()
        if selected is not None:
            goal.op_slot.wmes.clear()
            self._remove_wme(selected)
        for inst in list(goal.insts):
            for pref in reversed(inst.prefs):  # as made (measured: the watch-5 trace)
                if pref.live:
                    if self.trace_level >= 5:
                        self._emit_line(trace_preference("-", pref))
                    self._remove_preference(pref)
        goal.insts.clear()
        self._drop_local_results(goal)
        traced = len(self._traced_removes)
        for wme in list(goal.items.values()) + list(goal.counts.values()) + goal.arch_wmes:
            self._remove_arch(wme)
        if self.trace_level >= 4:
            self._trace_goal_removal(goal, traced)
        goal.items.clear()
        goal.counts.clear()
        for match in list(goal.pending_i) + list(goal.pending_o):
            self._pending_goal.pop(match, None)
        goal.pending_i.clear()
        goal.pending_o.clear()
        self._nil_retractions.extend(goal.retractions)
        goal.retractions = []
        for wme in goal.gds:
            bucket = self._gds_index.get(wme)
            if bucket is not None:
                bucket.pop(goal, None)
                if not bucket:
                    del self._gds_index[wme]
        goal.gds.clear()
        if goal.superstate is not None and goal.superstate.sub is goal:
            goal.superstate.sub = None
        del self._goals[goal.id]
        self._dead_ids.append(goal.id)
        if not self._in_wm_phase:
            self._working_memory_phase(diffs_last=True)

    def _drop_local_results(self, goal: Goal) -> None:
        """A result may link the substate's own identifiers (the state, its operators):
        the justification's preferences on them go with the substate, the rest stay
        (measured in soar_sml: ``(A1 ^local-copy S2)`` made a result of ``(S2 ^operator
        O2 +)`` and ``(O2 ^name answer)``; removing S2 traces '- (S2 ^operator O2 +  :O )
        (justify1)' and '- (O2 ^name answer +  :O ) (justify1)' after its own
        instantiations' preferences)."""
        level = goal.level
        for just in goal.justified:
            for pref in reversed(just.prefs):
                if pref.live and self._level_of(pref.id) >= level:
                    if self.trace_level >= 5:
                        self._emit_line(trace_preference("-", pref))
                    self._remove_preference(pref)
        goal.justified.clear()

    def _trace_goal_removal(self, goal: Goal, start: int) -> None:
        """Put the removed goal's architecture WMEs (traced from ``start`` on) in the
        kernel's order of removal (measured in soar_sml; the trace shows it reversed): its
        ^item WMEs with their count, its ^non-numeric ones with theirs, its impasse WMEs
        (type, superstate, attribute, impasse, choices, quiescence), each group newest
        first; then, after the
        batch's other removals, its ^reward-link, ^epmem and ^smem WMEs newest first, and
        the epmem and smem links' children, each link's newest first."""
        group = self._newest_first
        items = group([*goal.items.values(), *goal.counts.values()])
        items = ([w for w in items if w.attr in ("item", "item-count")]
                 + [w for w in items if w.attr not in ("item", "item-count")])
        own = [w for w in goal.arch_wmes if w.id is goal.id]
        links = group(w for w in own if w.attr in _LINK_ATTRS)
        early = items + group(w for w in own if w.attr not in _LINK_ATTRS)
        late = links + [child for link in reversed(links) for child in
                        group(w for w in goal.arch_wmes if w.id is link.value)]
        placed = {id(wme) for wme in early + late}
        kept = [wme for wme in self._traced_removes[start:] if id(wme) not in placed]
        self._traced_removes[start:] = early + kept
        self._traced_late += late

    @staticmethod
    def _newest_first(wmes: Iterable[WME]) -> list[WME]:
        return sorted(wmes, key=lambda wme: -wme.timetag)

    def _consistent_through(self, limit: Goal | None) -> bool:
        """Check decisions from the top down to ``limit`` (the bottom if None); remove the
        first inconsistent one with everything below it."""
        goal: Goal | None = self._top
        while goal is not None:
            if not self._decision_consistent(goal):
                if self.trace_level >= 2 and (goal.sub is not None or goal.selected()):
                    self._trace_inconsistent(goal)
                self._remove_current_decision(goal)
                return False
            if goal is limit:
                break
            goal = goal.sub
        return True

    def _trace_inconsistent(self, goal: Goal) -> None:
        """What the kernel prints at watch 2 and more when it removes an inconsistent
        decision (measured in soar_sml): the 'REMOVING CONTEXT SLOT' line only when no
        operator was selected (an impasse stood there)."""
        text = (f"Removing substates of {goal.id} because the operator last selected"
                f" in {goal.id} is not\nconsistent with the current preferences.\n")
        if goal.selected() is None:
            text += (f"\n       REMOVING CONTEXT SLOT: Slot Identifier [{goal.id}] and"
                     " attribute [operator]\n")
        text += (f"\n          Decision for goal [{goal.id}] is inconsistent.  Replacing it"
                 " with....\n")
        self._emit_line(text)

    def _decision_consistent(self, goal: Goal) -> bool:
        slot = goal.op_slot
        prefs = slot.prefs
        selected_wme = goal.selected()
        if selected_wme is not None:
            if len(prefs) == 1:
                # Fast path: only acceptable preferences, all for the selected operator.
                only = prefs.get(ACCEPTABLE)
                value = selected_wme.value
                if only and all(p.value is value for p in only):
                    return True
        elif goal.sub is None:
            # No operator and no impasse: nothing to be inconsistent with. The next decision
            # settles what was proposed meanwhile (measured: pending o-assertions still fire).
            return True
        impasse, candidates = dec.run_preference_semantics(slot, None, consistency=True)
        selected = goal.selected()
        if selected is not None:
            key = dec._key(selected.value)
            return impasse == dec.NONE and any(dec._key(c) == key for c in candidates)
        sub = goal.sub
        if sub is not None and sub.impasse != dec.NO_CHANGE:
            return impasse == sub.impasse
        if sub is not None:
            # A state no-change stands while no preference came or went since the slot was
            # decided (measured in soar_sml: one made while the slot held a rejected
            # proposal stays; any later preference, even a lone reject, prohibit or better,
            # or a second reject of the same operator, takes it away).
            return not slot.touched
        return impasse == dec.NONE and not candidates

    def _remove_current_decision(self, goal: Goal) -> None:
        if goal.sub is None and goal.selected() is None:
            return
        traced = len(self._traced_removes)
        if goal.sub is not None:
            self._remove_goal(goal.sub)
        selected = goal.selected()
        if selected is not None:
            goal.op_slot.wmes.clear()
            self._remove_wme(selected)
            if self.trace_level >= 4:  # the kernel removes it before the substates
                self._traced_removes.remove(selected)
                self._traced_removes.insert(traced, selected)
        self._context_changed_at(goal.id)
        self._collect_changes()
        if self.trace_level >= 4:
            self._trace_wm_changes()

    # ------------------------------------------------------------- results, GDS

    def _handle_substate_preferences(self, inst: Instantiation) -> None:
        """Results (preferences on superstate structure) get a justification; o-supported
        local preferences extend the goal dependency set."""
        goal = inst.goal
        level = goal.level
        results = self._find_results(inst, level)
        if results:
            self._justify(inst, results)
        if any(p.o_supported and p not in results for p in inst.prefs):
            self._gds_requests.append((goal, inst))

    def _grow_gds(self) -> None:
        """Make the goal dependency set of a substate whose first o-supported local
        preferences this wave made, from the instantiation that made them; once made, the
        kernel does not extend it (measured in soar_sml: with the set made by an earlier
        operator, or by another rule of the same wave, a superstate WME that only a later
        o-supported instantiation tested leaves without removing the substate; tested by
        the rule that made the set, it removes it, whoever made the WME). The set goes
        through the local i-supported WMEs' current acceptable preferences, so a WME that
        an o-reject of the wave took away leads nowhere (measured: a counter made by an
        elaboration on a superstate flag and modified by ``^steps <n> - (+ <n> 1)`` does
        not make the flag part of the GDS)."""
        requests, self._gds_requests = self._gds_requests, []
        for goal, inst in requests:
            if not goal.alive or goal.gds_made:
                continue
            goal.gds_made = True
            for wme in self._backtrace(inst, goal.level, through_o_support=False):
                goal.gds.add(wme)
                self._gds_index.setdefault(wme, {})[goal] = None

    def _find_results(self, inst: Instantiation, level: int) -> list[Preference]:
        return find_results(inst, level, self._level_of, self._slots)

    def _promote(self, results: list[Preference]) -> None:
        """Identifiers a result links to move up to the result's level (parents first:
        ``results`` is the last found first), once the results have been backtraced: the
        kernel backtraces a result made from local structure through that structure."""
        for pref in reversed(results):
            level = self._level_of(pref.id)
            for sym in (pref.value, pref.referent):
                if (isinstance(sym, Identifier) and sym.level is None
                        and self._level_of(sym) > level):
                    self._level[sym] = level

    def _justify(self, inst: Instantiation, results: list[Preference]) -> None:
        """Stand in for the substate's reasoning with justifications whose conditions are
        the superstate WMEs the results depend on. As in the kernel, the first lives one
        level up and holds every result; when results go higher, that justification is an
        instantiation with results of its own, justified one level further up, and so on
        (measured in soar_sml: a result two levels up is asserted by '[level 2] (justify1)'
        and by 'justify3', which stays when the middle state goes)."""
        visited: list[Instantiation] = []
        grounds = tuple(self._backtrace(
            inst, inst.goal.level, through_o_support=True, visited=visited,
            also=[pref.inst for pref in results if pref.inst is not inst],
        ))
        # explained before the results' identifiers are promoted (they are local to it)
        explained = self.chunker.explain(self, inst, results)
        self._promote(results)
        if not grounds:
            self._ignore_unconditional_justification(inst)
            return
        home = inst.goal.superstate
        assert home is not None  # results come from substates
        just, learned = self._justify_or_learn(inst, results, grounds, home, inst, explained)
        if self._watch_negations(just, visited, inst.goal.level):
            self._justification_matches(inst.goal, min(self._level_of(p.id) for p in results))
        while home.superstate is not None:
            higher = [p for p in just.prefs if self._level_of(p.id) < home.level]
            if not higher:
                break
            more: list[Instantiation] = []
            grounds = tuple(
                self._backtrace(just, home.level, through_o_support=True, visited=more)
            )
            if not grounds:
                break
            # the negated conditions of every rule behind it (the first is the previous
            # justification itself)
            visited += more[1:]
            # a chunk's instantiation with results higher up is explained in turn (the
            # kernel's chunkx2*...)
            explained = self.chunker.explain(self, just, higher) if learned else None
            source, home = home, home.superstate
            just, learned = self._justify_or_learn(just, higher, grounds, home, inst,
                                                   explained)
            self._watch_negations(just, visited, source.level)

    def _justify_or_learn(
        self, made_by: Instantiation, results: list[Preference], grounds: tuple[WME, ...],
        home: Goal, fired: Instantiation, explained: Explanation | None,
    ) -> tuple[Instantiation, bool]:
        """The justification at ``home`` for ``made_by``'s results, which is the
        instantiation of the chunk learned from ``explained`` when there is one (see
        `Chunker`); whether a chunk was learned."""
        chunk = self.chunker.build(self, explained) if explained is not None else None
        just = self._make_justification(made_by, results, grounds, home, fired,
                                        None if chunk is None else chunk.name)
        if chunk is None or explained is None:
            return just, False
        return just, self.chunker.learn(self, just, explained, chunk)

    def _make_justification(
        self, inst: Instantiation, results: list[Preference], grounds: tuple[WME, ...],
        home: Goal, fired: Instantiation, chunk: str | None = None,
    ) -> Instantiation:
        """A justification at ``home`` for ``inst``'s results; its support is computed like
        a rule's: o-support when its conditions include the selected operator of its goal.
        ``fired``: the rule instantiation whose firing made it (its preferences are
        asserted next to that one's, see ``_with_justifications``); ``chunk``: the name
        of the chunk learned from it, which its instantiation is (see `Chunker`)."""
        self._justifications += 1
        match_goal_id = self._goal_of_grounds(grounds).id
        operators = [
            w.value
            for w in grounds
            if w.id is match_goal_id and w.attr == "operator" and not w.acceptable
        ]
        just = Instantiation(
            # the kernel spends two numbers on each justification (measured: justify1,
            # justify3, justify5, ...)
            chunk or f"justify{2 * self._justifications - 1}", None, home, grounds,
            bool(operators), True
        )
        just.grounds = grounds
        just.source = inst.goal
        inst.goal.justified[just] = None
        if operators and _proposes_on_a_state(results, match_goal_id):
            operators = []  # a proposal is i-supported, as a rule's (see is_o_supported)
        on_operator = [any(pref.id is op for op in operators) for pref in results]
        mixed = bool(operators) and any(on_operator) and not all(on_operator)
        if mixed and chunk is None:  # a chunk's own instantiation is not warned of (measured)
            self._warn_mixed_support(just.name, justification=True)
        for pref, elaborates in zip(results, on_operator, strict=True):
            copy = Preference(pref.type, pref.id, pref.attr, pref.value, pref.referent, just)
            copy.o_supported = bool(operators) and not elaborates and not mixed
            just.prefs.append(copy)
            if not pref.live:
                self._copied_from[copy] = pref
            if copy.o_supported and pref.type == REJECT and not pref.live:
                # The copy is an o-reject, which takes the rule's own reject with it
                # (measured in soar_sml: '+ (S1 ^x 5 -) [level 2]' is not asserted then).
                pref.inst = None  # type: ignore[assignment]
        self._new_justifications.append((fired, just))
        self._replace_duplicate_justification(just)
        if home.level > 1:
            home.insts[just] = None
            level = home.level
            if any(p.o_supported and self._level_of(p.id) == level for p in just.prefs):
                self._gds_requests.append((home, just))
        return just

    def _ignore_unconditional_justification(self, inst: Instantiation) -> None:
        """Results that test nothing in the superstate get no justification: the kernel
        warns at watch 2 and up and the results keep only the substate rule's support, so
        they go with the substate (measured in soar_sml: a result made from a negated
        superstate test leaves when its substate does)."""
        if self.trace_level >= 2:
            self._emit(
                "\nWarning: Soar has created a chunk or justification with no conditions."
                "  Ignoring.\n\n         Any results created will lose support when the"
                " sub-state disappears.\n         To avoid this issue, the problem-solving"
                " in the sub-state must\n         positively test at least one item in the"
                f" super-state.\n\nRule firing that led to invalid chunk: {inst.name}\n"
            )

    def _replace_duplicate_justification(self, just: Instantiation) -> None:
        """A justification identical to a live one (same conditions, same results)
        replaces it: the kernel retracts the old one in the next cycle (measured). One
        made in the same wave is not retracted: no cycle goes to its level for it
        (measured in soar_sml: justify5 and justify7 of two elaborations firing together
        for the same (S1 ^seen O4) leave level 1 quiet)."""
        signature = (
            frozenset(w.timetag for w in just.grounds),
            frozenset(
                (p.type, id(p.id), _vkey(p.attr), _vkey(p.value), _vkey(p.referent))
                for p in just.prefs
            ),
        )
        old = self._justification_index.get(signature)
        if old is not None and not old.retracted and all(
                made is not old for _, made in self._new_justifications):
            self._schedule_retraction(old)
        self._justification_index[signature] = just
        just.match = signature

    def _justification_matches(self, source: Goal, result_level: int) -> None:
        """The kernel adds a justification to its Rete for each level a result passes
        (from the substate up to the result's level). When a result goes up two levels or
        more, each new one matches at once, which is activity at its level (a cycle there
        fires nothing; measured with soar_sml). Count it the same way."""
        if source.level - result_level < 2:
            return  # one level up: the kernel refracts the match, no new activity
        goal: Goal | None = source.superstate
        while goal is not None and goal.level >= result_level:
            goal.pending_i[_JustificationMatch(result_level)] = None  # type: ignore[assignment]
            goal = goal.superstate

    def _watch_negations(
        self, just: Instantiation, visited: list[Instantiation], level: int
    ) -> bool:
        """Watch what the new justification matches: a WME it tested leaving, or one that
        a negated condition of its instantiations tested in superstates appearing,
        retracts it even when its results are all o-supported: no preference changes,
        but it is activity at its level, like the kernel's (an elaboration cycle that
        fires nothing; measured).

        A justification whose conditions do not hold when it is made (backtracing
        through local o-supported WMEs reaches tests of the past: a negation of a WME
        that has since come, a WME since gone) never matches, so nothing retracts it:
        watch nothing then and return False (measured in soar_sml: justify3 with
        ``(state S1 -^problem <p*1>)`` when (S1 ^problem P1) stands and
        ``(C5 -^digit1 <d*1>)`` for its own result (C5 ^digit1 5) makes no cycle at S1's
        level, while justify1 with only the first makes one when (S1 ^problem P1) comes).
        """
        entries = list(self._negations_of(visited, level))
        wm = self._wm
        if any(wm.get(wme.timetag) is not wme for wme in just.grounds) or any(
            self._negation_holds_not(element, bindings) for _, element, _, bindings in entries
        ):
            return False
        for wme in just.grounds:
            self._dependents.setdefault(wme, []).append(just)
        keys = []
        for key, _, test, bindings in entries:
            self._neg_watch.setdefault(key, []).append((just, test, bindings))
            keys.append(key)
        self._neg_keys[just] = keys
        return True

    def _negation_holds_not(self, element: object, bindings: dict[str, Symbol]) -> bool:
        """Whether a WME now matches a negated condition or conjunctive negation."""
        if isinstance(element, ConjunctiveNegation):
            wmes: dict[WME, None] = {}
            for cond in element.conditions:
                if isinstance(cond, Condition):
                    wmes.update(dict.fromkeys(self._candidates(cond, bindings)))
                else:
                    wmes.update(dict.fromkeys(self._wm.values()))
            return negation_matches(element, list(wmes), bindings)
        assert isinstance(element, Condition)
        return negation_matches(element, self._candidates(element, bindings), bindings)

    def _negations_of(
        self, visited: list[Instantiation], level: int
    ) -> Iterator[tuple[tuple, object, object, dict[str, Symbol]]]:
        """``(watch key, element, watched test, bindings)`` of every negated condition
        on a superstate identifier in the instantiations behind a justification."""
        for source in visited:
            match = source.match
            if match is None:
                continue
            bindings = match.bindings  # type: ignore[attr-defined]
            for element in match.production.conditions:  # type: ignore[attr-defined]
                if isinstance(element, ConjunctiveNegation):
                    # Watched on each inner condition of a superstate identifier bound
                    # outside; whether the whole negation now matches is checked at the end
                    # of the phase (its other WMEs may come later in it).
                    for cond in element.conditions:
                        key = self._watch_key(cond, bindings, level)
                        if key is not None:
                            yield key, element, element, bindings
                    continue
                if not isinstance(element, Condition) or not element.negated:
                    continue
                key = self._watch_key(element, bindings, level)
                if key is not None:
                    yield key, element, element.value_test, bindings

    def _watch_key(self, cond: object, bindings: dict[str, Symbol],
                   level: int) -> tuple | None:
        """``(identifier, attribute)`` of a negated condition on a superstate identifier
        that the match bound, or None."""
        if not isinstance(cond, Condition) or not isinstance(cond.id_test, Var):
            return None
        if not isinstance(cond.attr_test, Const):
            return None
        ident = bindings.get(cond.id_test.name)
        if not isinstance(ident, Identifier) or self._level_of(ident) >= level:
            return None
        return (ident, _vkey(cond.attr_test.value))

    def _check_negations(self, wme: WME) -> None:
        watchers = self._neg_watch.get((wme.id, _vkey(wme.attr)))
        if not watchers:
            return
        for just, test, bindings in list(watchers):
            if just.retracted:
                continue
            if isinstance(test, ConjunctiveNegation):
                self._ncc_checks.append((just, test, bindings))
                continue
            if isinstance(test, Const) and _vkey(test.value) != _vkey(wme.value):
                continue
            if isinstance(test, Var):
                bound = bindings.get(test.name)
                if bound is not None and _vkey(bound) != _vkey(wme.value):
                    continue
            self._schedule_retraction(just)

    def _goal_of_grounds(self, grounds: tuple[WME, ...]) -> Goal:
        """The justification's match goal: the deepest state among its conditions."""
        best = self._top
        for wme in grounds:
            goal = self._goals.get(wme.id)
            if goal is not None and goal.level > best.level:
                best = goal
        return best

    def _backtrace(
        self,
        inst: Instantiation,
        level: int,
        through_o_support: bool,
        visited: list[Instantiation] | None = None,
        also: Iterable[Instantiation | None] = (),
    ) -> list[WME]:
        """Superstate WMEs (identifier above ``level``) that ``inst`` depends on, found by
        walking back through the instantiations that made its local WMEs. ``also``: the
        instantiations of its other results (made earlier, linked to the superstate by
        ``inst``), which the justification depends on too."""
        grounds: dict[int, WME] = {}
        starts = [inst]
        for other in also:
            if other is not None and all(other is not start for start in starts):
                starts.append(other)
        if visited is not None:
            visited.extend(starts)
        seen: set[int] = {id(start) for start in starts}
        stack = starts[::-1]
        while stack:
            current = stack.pop()
            for wme in current.wmes:
                if wme is None:
                    continue
                if wme.attr in _ITEM_ATTRS:
                    wme = self._item_proposal(wme)
                if self._level_of(wme.id) < level:
                    grounds.setdefault(wme.timetag, wme)
                    continue
                supports = (self._supporting_instantiations(wme) if through_o_support
                            else self._current_supports(wme))
                for source in supports:
                    if id(source) in seen:
                        continue
                    if not through_o_support and any(
                        p.o_supported and p.live for p in source.prefs
                    ):
                        continue
                    seen.add(id(source))
                    stack.append(source)
                    if visited is not None:
                        visited.append(source)
        return list(grounds.values())

    def _item_proposal(self, wme: WME) -> WME:
        """An impasse's ``^item`` or ``^non-numeric`` WME stands for the superstate's
        acceptable-preference WME of that operator (measured in soar_sml: a result made
        from ``(S2 ^item O2)`` alone is justified by ``(state S1 ^operator O2 +)``); any
        other WME stands for itself."""
        goal = self._goals.get(wme.id)
        if goal is None or goal.superstate is None:
            return wme
        if goal.items.get((wme.attr, dec._key(wme.value))) is not wme:
            return wme
        proposal = goal.superstate.op_slot.acceptable_wmes.get(_vkey(wme.value))
        return wme if proposal is None else proposal

    def _remember_source(self, wme: WME, slot: Slot, types: tuple[str, ...]) -> None:
        """Note which instantiation made a substate WME, for backtracing after that
        instantiation has retracted (the kernel keeps it through ``wme->preference``)."""
        key = _vkey(wme.value)
        for ptype in types:
            for pref in slot.of_type(ptype):
                if _vkey(pref.value) == key:
                    self._sources[wme] = pref.inst
                    return

    def _current_supports(self, wme: WME) -> list[Instantiation]:
        """The rule instantiations whose acceptable (or require) preferences hold ``wme``'s
        value in its slot now: what the kernel's GDS elaboration follows."""
        slot = self._slot(wme.id, wme.attr, create=False)
        if slot is None:
            return []
        key = _vkey(wme.value)
        return [pref.inst for ptype in (ACCEPTABLE, REQUIRE) for pref in slot.of_type(ptype)
                if _vkey(pref.value) == key and not pref.inst.is_justification]

    def _supporting_instantiations(self, wme: WME) -> list[Instantiation]:
        """The instantiation a justification backtraces ``wme`` through: the one that
        made it (kept after it retracted), else the first that supports it now."""
        source = self._sources.get(wme)
        if source is not None:
            return [] if source.is_justification else [source]
        return self._current_supports(wme)[:1]

    # ------------------------------------------------------------- input

    def _apply_input_ops(self) -> None:
        """Apply the queued input changes in order. A handle is queued when made and again
        when removed: unremoved without a WME it is added; removed with a WME it goes
        (removed before it was ever added, both entries are no-ops)."""
        ops, self._input_ops = self._input_ops, []
        arch = self._arch
        for handle in ops:
            if handle.removed:
                if handle.wme is not None:
                    self._remove_arch(handle.wme)
                    handle.wme = None
                continue
            if handle.wme is not None:
                continue  # defensive: a live handle is added once
            ident = handle.id
            wme = handle.wme = self._add_wme(ident, handle.attr, handle.value)
            bucket = arch.get(ident)
            if bucket is None:
                arch[ident] = [wme]
            else:
                bucket.append(wme)

    # ------------------------------------------------------------- output text

    def _emit(self, text: str) -> None:
        if text:
            stream = self.out if self.out is not None else sys.stdout
            stream.write(text)
            newline = text.rfind("\n")
            self._column = len(text) - newline - 1 if newline >= 0 else self._column + len(text)

    def _emit_line(self, text: str) -> None:
        """Trace text that starts on a fresh line, like the kernel's phase headers."""
        self._emit(text if self._column == 0 else "\n" + text)

    def __repr__(self) -> str:
        return f"<Agent {self.name}: {len(self._productions)} productions, {len(self._wm)} wmes>"


_ITEM_ATTRS = frozenset(("item", "non-numeric"))
_LATEST = float("inf")  # a join made between two batches: after every WME of the first


def _with_justifications(fired: list[Instantiation],
                         justifications: list[tuple[Instantiation, Instantiation]]
                         ) -> list[Instantiation]:
    """The order the kernel asserts a wave's preferences in: the instantiations the wave
    fired, the last first, each right after the justification of its results (measured
    in soar_sml: sx then sy fire in a substate, the kernel traces '+ ... (justify3)',
    '+ ... [level 2] (sy)', '+ ... (justify1)', '+ ... [level 2] (sx)'; with snc fired
    for counts 0 then 2, justify7 and snc of count 2 come first, so (S1 ^count 3) gets the
    older timetag). We asserted all the justifications first."""
    made: dict[int, list[Instantiation]] = {}
    for source, just in justifications:
        made.setdefault(id(source), []).append(just)
    insts: list[Instantiation] = []
    for inst in reversed(fired):
        justs = made.pop(id(inst), None)
        if justs:
            insts += reversed(justs)
        insts.append(inst)
    if made:  # not of this wave's firings (none known): first, as before
        others = [just for justs in made.values() for just in justs]
        insts[:0] = reversed(others)
    return insts


def _latest_first(keys: list) -> list[int]:
    """``sorted(range(len(keys)), key=keys.__getitem__, reverse=True)``; the few keys of
    the usual retraction (three in hanoi) by insertion, without sorted's calls."""
    if len(keys) > 8:
        return sorted(range(len(keys)), key=keys.__getitem__, reverse=True)
    order: list[int] = []
    for k in range(len(keys)):
        key = keys[k]
        place = len(order)
        while place > 0 and keys[order[place - 1]] < key:  # after the equal ones: stable
            place -= 1
        order.insert(place, k)
    return order


def _move_values(wmes: dict[object, WME], removes: list[WME]) -> None:
    """Empty a slot's WMEs into ``removes``, newest first (a loop: mypyc's ``list.extend``
    of a dict's values goes through the generic iterator protocol, several times slower
    for the usual one WME)."""
    if len(wmes) == 1:
        for wme in wmes.values():
            removes.append(wme)
    else:
        for wme in reversed(wmes.values()):
            removes.append(wme)
    wmes.clear()


def _entry_rank(wme: WME, starts: list[int]) -> tuple[int, int]:
    """When the kernel's Rete took ``wme`` in, as a sort key, latest first: batch after
    batch (``starts``: the timetag before each), a batch's WMEs newest first."""
    timetag: int = wme.timetag
    return (-_batch_of(starts, timetag), timetag)


def _batch_of(starts: list[int], timetag: int) -> int:
    """``bisect_left(starts, timetag)``: the batch of a WME (see ``_entry_rank``), in
    native integers (the bisect module compares Python objects, ten times slower), and
    searched from both ends at once, doubling the steps, where the batches of the WMEs
    asked about mostly are: the newest, and the structure made when the run began, whose
    search from the end alone grew with the run (four batches a decision)."""
    high = len(starts) - 1
    if high < 0 or starts[high] < timetag:
        return high + 1
    if starts[0] >= timetag:
        return 0
    low = 0  # from here on starts[low] < timetag <= starts[high]
    step = 1
    while high - low > 1:
        probe = high - step
        if probe <= low:
            break
        if starts[probe] < timetag:
            low = probe
            break
        high = probe
        probe = low + step
        if probe >= high:
            break
        if starts[probe] >= timetag:
            high = probe
            break
        low = probe
        step <<= 1
    while high - low > 1:
        middle = (low + high) >> 1
        if starts[middle] < timetag:
            low = middle
        else:
            high = middle
    return high


def _creator(match: object, start: int) -> tuple:
    """The timetag and first index of the match's oldest WME newer than ``start`` (its
    newest WME when none is). (The kernel-order keys are plain tuples: mypyc would unpack
    a ``tuple[int, int]`` into a C struct and box it anew at every use.)"""
    found: tuple = match.newest  # type: ignore[attr-defined]
    newest: int = found[0]
    if newest <= start:
        return found
    oldest, index = newest, -1
    wmes: tuple[WME | None, ...] = match.wmes  # type: ignore[attr-defined]
    for i, wme in enumerate(wmes):
        if wme is not None:
            timetag: int = wme.timetag
            if start < timetag < oldest:
                oldest, index = timetag, i
    return found if index < 0 else (oldest, index)


def _token_link(order: tuple[int, ...], token: tuple, places: dict[int, tuple], born: int,
                born_batch: int, starts: list[int]) -> tuple:
    """The time a token (the WMEs of the written conditions ``order``) was made, as the
    relinking key of the join below its memory: the entry of its latest WME newer than
    the join, in the order the kernel's Rete took them (batch after batch, a batch newest
    first), with that WME's alpha memory and path (joins relinked by one WME go in the
    order it activated them); ``(born_batch, _LATEST)`` when none is newer than the join."""
    link_batch, link_time = born_batch, 0
    link_place: tuple | None = None
    for j, wme in zip(order, token, strict=True):
        if wme is None:
            continue
        timetag: int = wme.timetag
        if timetag > born:
            batch = _batch_of(starts, timetag)
            if batch > link_batch or (link_place is not None and batch == link_batch
                                      and -timetag > link_time):
                link_batch, link_time, link_place = batch, -timetag, places.get(j)
    if link_place is None:
        return (link_batch, _LATEST)
    return (link_batch, link_time, link_place[0], link_place[3])


def _file_wme(index: dict[Symbol, dict[object, dict[WME, None]]], wme: WME) -> None:
    """Add ``wme`` to an index of working memory by identifier, then attribute."""
    slots = index.get(wme.id)
    if slots is None:
        index[wme.id] = {_vkey(wme.attr): {wme: None}}
        return
    key = _vkey(wme.attr)
    bucket = slots.get(key)
    if bucket is None:
        slots[key] = {wme: None}
    else:
        bucket[wme] = None


def _live_tokens(seen: set[tuple], wm: dict[int, WME]) -> None:
    """Drop from a link record's ``seen`` the tokens that lost a WME (they never come
    back: a WME that leaves is never added again), when their number has doubled since
    the last time: a record whose token on record stays keeps seeing new tokens, one or
    two a decision, and would otherwise keep every one of them for the rest of the run."""
    size = len(seen)
    if size >= 16 and not size & (size - 1):  # a power of two
        for token in [token for token in seen if not _all_there(token, wm)]:
            seen.discard(token)


def _all_there(wmes: tuple, wm: dict[int, WME]) -> bool:
    """Whether every WME of a token (``None``: a condition it has no WME for) is still in
    working memory (by timetag)."""
    for wme in wmes:
        if wme is not None and wm.get(wme.timetag) is not wme:
            return False
    return True


def _shared(firsts: list[tuple]) -> set[tuple]:
    """The keys that occur more than once (none, usually)."""
    if len(firsts) == 2:
        return {firsts[0]} if firsts[0] == firsts[1] else set()
    seen: set[tuple] = set()
    shared: set[tuple] = set()
    for first in firsts:
        if first in seen:
            shared.add(first)
        seen.add(first)
    return shared


def _creation_key(ranks: list[tuple | None], sign: int) -> tuple:
    """The order the kernel's Rete made tokens in, from the ``_entry_rank``s of their
    WMEs in its condition order (``sign`` 1: made first first; -1: the reverse), and of
    the last unblocking of its negations (``Agent._prefix_ranks``; None: not known). A
    token was made when its latest WME entered or its latest negation unblocked it: by a
    right activation that visited the parent's tokens latest made first (or a negative
    node passing the one token on), then by left activations down to here, each visiting
    its alpha memory's WMEs latest entered first (a negative node, passed through, adds
    nothing to the order: measured in soar_sml, n-queens with indifferent-selection
    --first: the squares of a column unblocked at decisions 7, 10 and 11 are proposed
    again in that order, after the backtrack at decision 12)."""
    known = [k for k in range(len(ranks)) if ranks[k] is not None]
    if not known:
        return ()
    k = min(known, key=ranks.__getitem__)  # the latest entered
    latest: tuple = ranks[k]  # type: ignore[assignment]
    after = [r for r in ranks[k + 1:] if r is not None]
    return (
        (-sign * latest[0], -sign * latest[1]),
        *_creation_key(ranks[:k], -sign),
        *[(sign * r[0], sign * r[1]) for r in after],
    )


def _token_order(wmes: tuple, place: tuple, starts: list[int],
                 before: list[tuple | None]) -> tuple:
    """The order in which one WME's activation of a join makes several matches, as the
    kernel's Rete does (measured in soar_sml: two ``^thing`` WMEs of one firing, then a
    ``^count`` joined after them, fire the proposal of the older ``^thing`` first; items
    whose tokens one ``^box`` WME made fire in the order its ``^item`` WMEs entered). Its
    memories list items newest first: a right activation visits the parent's tokens latest
    made first, a left activation the alpha memory's WMEs latest entered first; and each
    token goes down to every child (newest first) before the next is made, so the key
    alternates the path to the next join and the rank of that join's WME (depth first:
    measured in soar_sml, (S1 ^go n) below the shared ^obj join makes pb of X2, pa of X2,
    then pb of X1)."""
    order: list[tuple] = [_creation_key(before, -1)]
    steps: tuple = place[7]
    for k in range(len(steps)):
        step = steps[k]
        if k & 1:  # a join below: its alpha memory's WMEs are visited latest entered first
            wme = wmes[step]
            order.append(_entry_rank(wme, starts) if wme is not None else (0, 0))
        else:  # the path to the next join (children newest first)
            order.append(step)
    return tuple(order)


def _proposes_on_a_state(prefs: list[Preference], goal: Identifier) -> bool:
    """Whether the preferences propose an operator on the justification's match goal:
    the kernel gives a justification that does i-support, as it does a rule's match
    (measured in soar_sml: a substate rule testing its selected operator that proposes an
    operator on the superstate makes '+ (S1 ^operator O3 +) (justify1)', without ':O';
    a result that links the substate itself, with its proposal, keeps
    '+ (S2 ^operator O2 +  :O ) (justify1)')."""
    return any(
        pref.type == ACCEPTABLE and pref.attr == "operator" and pref.id is goal
        for pref in prefs
    )


class _JustificationMatch:
    """A stand-in for the match of a new justification (see _justification_matches)."""

    __slots__ = ("level",)

    def __init__(self, level: int) -> None:
        self.level = level


def load_agent(paths: Iterable[str], **kwargs: object) -> Agent:
    """An agent with the given rule files sourced, in order."""
    agent = Agent(**kwargs)  # type: ignore[arg-type]
    for path in paths:
        agent.source(path)
    return agent


__all__ = ["Agent", "PHASES", "load_agent"]
