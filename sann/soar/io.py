"""Input-link and output-link handles.

Input changes are buffered and applied in the next input phase, as the kernel applies
SML changes; identifiers are named at once so that handles can be linked before a run.
"""

from __future__ import annotations

from typing import Protocol, Union, cast

from .errors import SoarRuntimeError
from .memory import WME, Identifier, Symbol


class Agent(Protocol):
    """What the handles use of the agent (``decision.agent_state.AgentState`` has it):
    its working memory, its queue of input changes and the count of its init-soars."""

    _wm: dict[int, WME]
    _input_ops: list[WMEHandle]
    _epoch: int

    def _new_id(self, hint: str, level: int) -> Identifier: ...

    def _augmentations(self, ident: Identifier) -> list[WME]: ...

_MISSING = object()
_new = object.__new__

InputValue = Union[str, int, float, "InputHandle"]


class WMEHandle:
    """One input WME ``(id ^attr value)``; ``remove()`` takes it out at the next input phase."""

    __slots__ = ("_agent", "id", "attr", "value", "wme", "removed")

    def __init__(self, agent: Agent, ident: Identifier, attr: str, value: Symbol) -> None:
        self._agent = agent
        self.id = ident
        self.attr = attr
        self.value = value
        self.wme: WME | None = None
        self.removed = False

    def remove(self) -> None:
        if self.removed:
            return
        self.removed = True
        agent = self._agent
        if self.wme is not None and self.wme.timetag not in agent._wm:
            return  # gone already (init() cleared working memory)
        agent._input_ops.append(self)

    def __repr__(self) -> str:
        return f"<input ({self.id} ^{self.attr} {self.value})>"


class InputHandle:
    """An identifier on the input side: the input-link itself or one made under it."""

    __slots__ = ("_agent", "identifier", "_link", "_children", "_sub", "_epoch")

    def __init__(self, agent: Agent, ident: Identifier, link: WMEHandle | None) -> None:
        self._agent = agent
        self.identifier = ident
        self._link = link
        self._children: list[WMEHandle] = []
        self._sub: dict[int, InputHandle] = {}
        self._epoch = agent._epoch

    @property
    def id(self) -> str:
        return self.identifier.name

    def add(self, attr: str, value: object = _MISSING) -> InputHandle | WMEHandle:
        """``add("block")`` makes a new identifier and returns its handle; ``add("id", 3)``
        a constant and ``add("on", handle)`` a link, returning the WME handle."""
        agent = self._agent
        link = self._link
        if self._epoch != agent._epoch or (link is not None and link.removed):
            self._check_live()  # raises the error that says which
        if not isinstance(attr, str) or not attr:
            raise SoarRuntimeError(f"input attribute must be a non-empty string, got {attr!r}")
        kind = type(value)
        if kind is str or kind is int or kind is float:  # the common case, checked first
            handle = _new(WMEHandle)  # WMEHandle.__init__, inline (a class call costs a C frame)
            handle._agent, handle.id, handle.attr = agent, self.identifier, attr
            handle.value, handle.wme, handle.removed = cast(Symbol, value), None, False
            self._children.append(handle)
            agent._input_ops.append(handle)
            return handle
        if value is _MISSING:
            ident = self._agent._new_id(attr, 1)
            link = self._queue(attr, ident)
            child = InputHandle(self._agent, ident, link)
            self._sub[id(link)] = child
            return child
        if isinstance(value, InputHandle):
            return self._queue(attr, value.identifier)
        if isinstance(value, bool) or not isinstance(value, str | int | float):
            raise SoarRuntimeError(
                f"input value must be a string, int, float or handle, got {value!r}"
            )
        return self._queue(attr, value)

    def update(self, attr: str, value: object) -> WMEHandle | InputHandle:
        """Replace every value of ``attr`` made through this handle by ``value``."""
        self._check_live()
        for child in list(self._children):
            if child.attr == attr and not child.removed:
                if (
                    not isinstance(value, InputHandle)
                    and child.value == value
                    and type(child.value) is type(value)
                ):
                    return child
                self._remove_child(child)
        return self.add(attr, value)

    def remove(self) -> None:
        """Remove this identifier's link and everything made under it."""
        if self._link is None:
            raise SoarRuntimeError("the input-link itself cannot be removed")
        if self._epoch != self._agent._epoch:
            return  # init() already cleared working memory
        self._link.remove()
        self._clear()

    def _clear(self) -> None:
        children, self._children = self._children, []
        for child in children:
            child.remove()
            sub = self._sub.pop(id(child), None)
            if sub is not None:
                sub._clear()

    def _remove_child(self, child: WMEHandle) -> None:
        child.remove()
        self._children.remove(child)
        sub = self._sub.pop(id(child), None)
        if sub is not None:
            sub._clear()

    def _queue(self, attr: str, value: Symbol) -> WMEHandle:
        agent = self._agent
        handle = WMEHandle(agent, self.identifier, attr, value)
        self._children.append(handle)
        agent._input_ops.append(handle)
        return handle

    def _check_live(self) -> None:
        if self._epoch != self._agent._epoch:
            raise SoarRuntimeError(
                f"input handle {self.id} dates from before init(); use agent.input_link again"
            )
        if self._link is not None and self._link.removed:
            raise SoarRuntimeError(f"input identifier {self.id} was removed")

    def __repr__(self) -> str:
        return f"<input {self.id}>"


class OutputHandle:
    """Read-only view of an identifier on the output side (the output-link and below)."""

    def __init__(self, agent: Agent, ident: Identifier) -> None:
        self._agent = agent
        self.identifier = ident

    @property
    def id(self) -> str:
        return self.identifier.name

    def _wrap(self, value: Symbol) -> Symbol | OutputHandle:
        return OutputHandle(self._agent, value) if isinstance(value, Identifier) else value

    def children(self) -> list[tuple[Symbol, Symbol | OutputHandle]]:
        """Every ``(attr, value)`` of this identifier, oldest WME first."""
        wmes = sorted(self._agent._augmentations(self.identifier), key=lambda w: w.timetag)
        return [(w.attr, self._wrap(w.value)) for w in wmes if not w.acceptable]

    def get(self, attr: str, default: object = None) -> Symbol | OutputHandle | object:
        """The (oldest) value of ``attr``, or ``default``."""
        oldest: WME | None = None
        for wme in self._agent._augmentations(self.identifier):
            if (
                wme.attr == attr
                and not wme.acceptable
                and (oldest is None or wme.timetag < oldest.timetag)
            ):
                oldest = wme
        return default if oldest is None else self._wrap(oldest.value)

    def all(self, attr: str) -> list[Symbol | OutputHandle]:
        return [value for key, value in self.children() if key == attr]

    def __eq__(self, other: object) -> bool:
        return isinstance(other, OutputHandle) and other.identifier is self.identifier

    def __hash__(self) -> int:
        return hash(id(self.identifier))

    def __repr__(self) -> str:
        return f"<output {self.id}>"
