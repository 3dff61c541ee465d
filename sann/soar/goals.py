"""Goals (states) of the goal stack and the bookkeeping the decision cycle keeps per goal.

The kernel fires rules level by level ("waterfall"): each elaboration cycle processes the
pending assertions and retractions of the highest goal that has any. So each goal keeps its
own queues of matches waiting to fire: i-assertions (fire in any phase), o-assertions (fire
only in the apply phase), and retractions.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .memory import WME, Identifier
from .preferences import Slot

if TYPE_CHECKING:
    from .instantiation import Instantiation, ProductionInfo


class Goal:
    """One state of the goal stack: its operator slot, impasse and match queues."""

    __slots__ = (
        "id",
        "level",
        "superstate",
        "sub",
        "impasse",
        "attribute",
        "op_slot",
        "arch_wmes",
        "items",
        "counts",
        "pending_i",
        "pending_o",
        "retractions",
        "insts",
        "gds",
        "gds_made",
        "justified",
        "alive",
    )

    def __init__(self, ident: Identifier, superstate: Goal | None, op_slot: Slot) -> None:
        self.id = ident
        self.level: int = ident.level or 1
        self.superstate = superstate
        self.sub: Goal | None = None
        #: The impasse that created this state (``None`` for the top state).
        self.impasse: str | None = None
        self.attribute: str | None = None
        self.op_slot = op_slot
        self.arch_wmes: list[WME] = []
        #: ``^item``/``^non-numeric`` WMEs by (attribute, value key).
        self.items: dict[tuple[str, object], WME] = {}
        self.counts: dict[str, WME] = {}
        self.pending_i: dict[object, ProductionInfo | None] = {}  # None: a justification's match
        self.pending_o: dict[object, ProductionInfo | None] = {}
        self.retractions: list[Instantiation] = []
        #: Instantiations whose preferences die with this (sub)state, oldest first (a dict,
        #: not a set: removing the state walks them in an order that does not depend on
        #: where the objects happen to live in memory).
        self.insts: dict[Instantiation, None] = {}
        #: Goal dependency set: superstate WMEs its o-supported WMEs depend on.
        self.gds: set[WME] = set()
        #: Whether the GDS was made (it is made once: by the first o-supported firing).
        self.gds_made = False
        #: The justifications of this state's results, oldest first.
        self.justified: dict[Instantiation, None] = {}
        self.alive = True

    def has_i_activity(self) -> bool:
        return bool(self.pending_i or self.retractions)

    def selected(self) -> WME | None:
        for wme in self.op_slot.wmes.values():
            return wme
        return None

    def __repr__(self) -> str:
        return f"<Goal {self.id} level {self.level}>"
