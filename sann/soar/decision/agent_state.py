"""What an agent holds while it runs, and the small operations every phase shares.

``AgentState`` is the data of the decision cycle: working memory and its indexes, the slots
of preferences, the goal stack, the queues of matches and retractions, the trace buffers
and the counters. The phases are functions of the modules beside this one
(``cycle``, ``matches``, ``firing``, ``wm_phase``, ``decide``, ``substates``, ``results``),
each taking the agent first; ``sann.soar.agent.Agent`` adds the public API on top.

The modules depend on each other in one direction (``working_memory`` below ``matches``
below ``firing`` ... below ``cycle``). The one operation needed from above is removing a
substate, which a WME leaving its goal dependency set asks for from working memory:
``_remove_goal`` is declared here and supplied by the ``Agent`` (``substates.remove_goal``).
"""

from __future__ import annotations

import sys
import weakref
from collections.abc import Iterable
from typing import TextIO

from ..errors import SoarError
from ..goals import Goal
from ..instantiation import Instantiation, ProductionInfo
from ..io import InputHandle, WMEHandle
from ..memory import WME, Identifier, IdentifierFactory, Symbol
from ..preferences import Preference, Slot
from ..production import Condition, Const
from ..rete import KernelOrder, equality_vars
from . import preference_semantics as semantics

#: Where a new kernel agent's printer believes its output line to be, and again after
#: init-soar (its first print wraps as if 17 characters were on the line).
START_COLUMN = 17


def vkey(value: Symbol | None) -> object:
    """Dictionary key of a value: ``1`` and ``1.0`` are different Soar symbols."""
    return value if type(value) is not float else (float, value)


class JoinLink:
    """What the agent knows of when the kernel's Rete last linked one join to its alpha
    memory (``firing_order._join_link``): the kernel unlinks a join whose parent memory
    is empty and relinks it when a token comes, so the join's place in the memory's list
    is that of the token that relinked it."""

    __slots__ = ("link", "witness", "production", "place", "looked", "seen")

    def __init__(self, link: tuple, witness: tuple, production: str, place: tuple,
                 looked: int, seen: set[tuple]) -> None:
        #: the relinking sort key: ``_token_link`` of the earliest token seen
        self.link = link
        #: a token of the parent memory (its WMEs) that is still in working memory
        self.witness = witness
        #: the production and its join's place (``rete.KernelOrder``) looked up for
        self.production = production
        self.place = place
        #: the agent's ``_collects`` when the record was made
        self.looked = looked
        #: the tokens of the memory seen since (the memory did not empty meanwhile)
        self.seen = seen


class AgentState:
    """The decision cycle's data (see the module docstring)."""

    # declared here: assigned first outside ``__init__`` (mypyc takes the first type), or
    # by the functions that make the top state (``substates.ids_new_after_top``)
    _input_handle: InputHandle | None
    _traced_adds: list[WME]
    _top: Goal
    _io_id: Identifier
    _input_link_id: Identifier
    _output_link_id: Identifier

    def __init__(self, name: str, matcher_class: type, out: TextIO | None) -> None:
        self.name = name
        self._matcher_class = matcher_class
        self.out = out
        self.trace_level = 0
        self.max_elaborations = 100
        self.max_goal_depth = 100
        #: ``waitsnc --on``: a state with nothing to do waits instead of a state no-change
        self.wait_snc = False
        #: RHS errors met while running (each also printed), newest last.
        self.errors: list[str] = []
        self.exploration = semantics.Exploration()
        self._productions: dict[str, ProductionInfo] = {}
        self.multi_attributes: dict[str, int] = {}
        self.warnings = True
        self.matcher = matcher_class()
        # the kernel Rete's node tree, for the order it makes matches in (kernel_key)
        self._kernel_order = KernelOrder()
        self._kernel_places: dict[str, dict[int, tuple]] = {}
        self._reset()

    def _reset(self) -> None:
        """Fresh working memory, queues and counters (the top state is made by the caller)."""
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
        # the newest timetag when the matcher's changes were last taken (collect_changes)
        self._batch_start = 0
        # (goal, instantiation) whose o-supported local preferences extend the goal's GDS
        # once the wave's preferences are asserted (grow_gds)
        self._gds_requests: list[tuple[Goal, Instantiation]] = []
        # every earlier _batch_start that began a batch of new WMEs (see _entry_rank)
        self._batch_starts: list[int] = []
        # _batch_of of the joins' birth timetags: it changes no more once asked for (a
        # later batch starts after every WME already made)
        self._born_batches: dict[int, int] = {}
        # per kernel join (serial): when it was last linked (firing_order._join_link)
        self._join_links: dict[int, JoinLink] = {}
        self._collects = 0  # the takes of matcher changes so far (collect_changes)
        # the links of the joins whose memory check_links found emptied, before
        self._links_before: dict[int, tuple] = {}
        # working memory by identifier, then attribute (vkey), kept once _candidates
        # needs it
        self._by_id: dict[Symbol, dict[object, dict[WME, None]]] | None = None
        # working memory by attribute (vkey), kept once _wmes_of needs it
        self._by_attr: dict[object, dict[WME, None]] | None = None
        # removed WMEs by identifier, then attribute (vkey), with when the kernel's Rete
        # took each out (_unblock_rank): the unblocking of the negations they matched
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
    def _emit_uncounted(self, text: str) -> None:
        """Text the kernel prints without counting it in its output column."""
        column = self._column
        self._emit(text)
        self._column = column

    def request_halt(self) -> None:
        if not self._halted:
            self._halt_note = "This Agent halted."  # printed when the run stops
        self._halted = True
        self._stop = True

    def request_interrupt(self) -> None:
        self._stop = True

    def _new_id(self, hint: str, level: int) -> Identifier:
        ident = self._ids.new(hint)
        self._level[ident] = level
        return ident

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

    def _warn_mixed_support(self, name: str, justification: bool = False) -> None:
        """The kernel's warning for a rule (or justification) that both elaborates and
        applies its operator: all its preferences get i-support. (Measured: a
        justification's warning starts on a new line, a rule's does not.)"""
        if self.warnings:
            self._emit(("\n" if justification else "")
                       + "WARNING:  Operator elaborations mixed with operator applications"
                       f"\nAssigning i_support to prod {name}")

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
        key = vkey(attr.value) if type(attr) is Const else None  # type: ignore[union-attr]
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
                key = vkey(wme.attr)
                bucket = index.get(key)
                if bucket is None:
                    index[key] = {wme: None}
                else:
                    bucket[wme] = None
        attr = cond.attr_test
        if type(attr) is Const:
            found = index.get(vkey(attr.value))  # type: ignore[union-attr]
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

    def _report_rhs_error(self, inst: Instantiation, error: SoarError) -> None:
        """Like the kernel: print ``Error: <text>`` and a newline where the output stands
        (on a fresh line first for the errors that say so, `rhs.FreshLineError`), naming
        no production; the firing goes on without the action. ``errors`` keeps the name."""
        self.errors.append(f"Error: production {inst.name}: {error}")
        if getattr(error, "fresh_line", False):
            self._emit_line(f"Error: {error}\n")
        else:
            self._emit(f"Error: {error}\n")

    def _slot(self, ident: Identifier, attr: Symbol, create: bool = True) -> Slot | None:
        slots = self._slots.get(ident)
        if slots is None:
            if not create:
                return None
            slots = self._slots[ident] = {}
        key = vkey(attr)
        slot = slots.get(key)
        if slot is None and create:
            slot = slots[key] = Slot(ident, attr, False)
        return slot

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

    def _emit(self, text: str) -> None:
        if text:
            stream = self.out if self.out is not None else sys.stdout
            stream.write(text)
            newline = text.rfind("\n")
            self._column = len(text) - newline - 1 if newline >= 0 else self._column + len(text)

    def _emit_line(self, text: str) -> None:
        """Trace text that starts on a fresh line, like the kernel's phase headers."""
        self._emit(text if self._column == 0 else "\n" + text)

    def _remove_goal(self, goal: Goal) -> None:
        """Remove a substate and everything below it: ``substates.remove_goal``, which the
        ``Agent`` supplies (working memory and its phase are below the goal stack)."""
        raise NotImplementedError


def _file_wme(index: dict[Symbol, dict[object, dict[WME, None]]], wme: WME) -> None:
    """Add ``wme`` to an index of working memory by identifier, then attribute."""
    slots = index.get(wme.id)
    if slots is None:
        index[wme.id] = {vkey(wme.attr): {wme: None}}
        return
    key = vkey(wme.attr)
    bucket = slots.get(key)
    if bucket is None:
        slots[key] = {wme: None}
    else:
        bucket[wme] = None
