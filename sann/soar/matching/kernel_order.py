"""The kernel Rete's order of making matches: a model of its node tree.

Which of several matches made by one WME the kernel fires first is its Rete's order of
making them (its match-set lists take the newest first).  As soar_sml 9.6 behaves: a WME
enters its alpha memories (* ^attr *) before (* ^attr value); an alpha memory right-activates
its join nodes oldest first (a new join goes to the tail of the list); a join passes a token
to its children newest first (a new child goes to the head), and all its positive
continuations hang below one beta memory, which takes its place among the join's children
when the second of them comes (the kernel merges a memory with its only join and splits
them then, the new memory going to the head).  The kernel's join
nodes are its own: the conditions in the kernel's order (reorder.py), shared by equal
prefixes.  This model builds that tree of nodes (no memories, no tokens): a production's
nodes are numbered when made, and a match's place (:class:`Place`) is the path from the
join that the WME activated down to the production.
"""

from __future__ import annotations

import re
from typing import NamedTuple

from sann.soar.matching.reorder import (
    PREDEFINED,
    KCond,
    constants,
    format_kcond,
    kernel_conditions,
    with_kernel_relations,
)
from sann.soar.matching.symbols import same_symbol
from sann.soar.production import (
    Condition,
    Const,
    Production,
)


class KernelNode:
    __slots__ = ("serial", "born", "children", "users")

    def __init__(self, serial: int, born: int) -> None:
        self.serial = serial
        self.born = born  # the timetag counter when it was made
        self.children: dict[object, KernelNode] = {}
        self.users = 0


_KERNEL_VAR = re.compile(r"<[^<>\s]+>")


def _same_alpha(one: Condition, other: Condition) -> bool:
    """Whether one WME may match both conditions (in one alpha memory or two)."""
    if one.acceptable != other.acceptable:
        return False
    a, b = one.attr_test, other.attr_test
    return not (type(a) is Const and type(b) is Const and not same_symbol(a.value, b.value))


def _node_keys(ordered: list[KCond]) -> list[object]:
    """The keys of the kernel's nodes for conditions in the kernel's order: their text with
    the variables numbered in order of appearance, so that equal prefixes share nodes.
    Worked out once per order (``reorder.kernel_conditions`` shares its lists)."""
    hit = _NODE_KEYS.get(id(ordered))
    if hit is not None and hit[0] is ordered:  # (the order the keys are of, the keys)
        return hit[1]
    names: dict[str, str] = {}

    def canonical(text: str) -> str:
        return _KERNEL_VAR.sub(
            lambda m: names.setdefault(m.group(0), f"<{len(names)}>"), text)

    def key(kcond: KCond) -> object:
        # A -{...} may hold another -{...}: its key is made of its own conditions' keys.
        if kcond.is_ncc:
            return ("ncc", tuple(key(c) for c in kcond.inner))
        return canonical(format_kcond(kcond))

    keys: list[object] = [key(kcond) for kcond in ordered]
    if len(_NODE_KEYS) >= 4096:
        _NODE_KEYS.clear()
    _NODE_KEYS[id(ordered)] = (ordered, keys)
    return keys


_NODE_KEYS: dict[int, tuple[list, list[object]]] = {}


class Place(NamedTuple):
    """Where the matches a WME makes through one positive condition of a production come in
    the kernel's order of making them (see :class:`KernelOrder`)."""

    #: which of the condition's attribute (2) and value (4) are constants: the alpha memory
    #: a WME enters first is the one testing fewer constants
    constants: int
    #: the written indexes of the positive conditions joined before this one
    before: tuple[int, ...]
    #: the timetag counter when the condition's join node was made (0: before any WME)
    born: int
    #: the path key: the join's serial number, then the negated serials of the nodes below
    #: it down to the production (newer children come first)
    path: tuple[int, ...]
    #: the other positive conditions a WME may match too (the same alpha memory or two
    #: that overlap)
    twins: tuple[int, ...]
    #: the condition's position in the kernel's order
    position: int
    #: the timetag counter when the production was loaded (its matches of older WMEs
    #: were made then, in loading order)
    loaded: int
    #: the path below the join cut at each positive join after it, with the written index
    #: of that join's condition in between: the order of the matches one activation makes
    #: is depth first
    steps: tuple[object, ...]


class KernelOrder:
    """The kernel's node tree for the loaded productions (see the module).  ``add`` gives a
    :class:`Place` per written condition index of a positive condition: the match a WME
    makes through that condition is made in the order of the path keys, except that a join
    whose parent memory was empty is unlinked from its alpha memory and relinked at the
    tail when the memory gets a token: its place is then the newest WME of the conditions
    before it, when that is newer than the join (``Agent._kernel_key``).  The kernel passes
    each token down to every child before it makes the next, so the matches one activation
    makes are ordered depth first (``Place.steps``, ``Agent._token_order``)."""

    def __init__(self) -> None:
        self._ages: dict[tuple[type, object], int] = {
            (str, s): i for i, s in enumerate(PREDEFINED)}
        self._serial = 0
        self._top = KernelNode(0, 0)
        self._paths: dict[str, list[tuple[KernelNode, object, KernelNode]]] = {}
        self._places: dict[str, dict[int, Place]] = {}
        self._ordered: dict[str, list] = {}
        self._joins: dict[str, tuple[list[tuple[int, int, int]], tuple]] = {}

    def ordered(self, name: str) -> list | None:
        """The production's conditions in the kernel's order (``reorder.KCond``)."""
        return self._ordered.get(name)

    def _node(self, parent: KernelNode, key: object,
              path: list[tuple[KernelNode, object, KernelNode]], now: int) -> KernelNode:
        node = parent.children.get(key)
        if node is None:
            self._serial += 1
            node = parent.children[key] = KernelNode(self._serial, now)
        node.users += 1
        path.append((parent, key, node))
        return node

    def add(self, production: Production, now: int, multi: dict[str, int] | None = None
            ) -> dict[int, Place]:
        """Place a new production's conditions in the node tree (see the class);
        ``multi``: the ``multi-attributes`` counts in force, which the kernel's reorderer
        weighs when the production is added."""
        for value in constants(production):
            self._ages.setdefault((type(value), value), len(self._ages))
        ordered = kernel_conditions(production, self._ages, dict(multi or {}))
        self._ordered[production.name] = ordered
        path: list[tuple[KernelNode, object, KernelNode]] = []
        node, is_join = self._top, False
        joins: list[tuple[int, int, int]] = []  # (written index, kernel position, path length)
        for position, (kcond, key) in enumerate(zip(ordered, _node_keys(ordered),
                                                    strict=True)):
            parent = node
            positive = not kcond.negated and not kcond.is_ncc
            if positive and is_join:
                parent = self._node(node, "memory", path, now)
                if key not in parent.children and len(parent.children) == 1:
                    self._split(parent)
            node = self._node(parent, key, path, now)
            if positive:
                joins.append((kcond.index, position, len(path)))
            is_join = positive
        self._serial += 1
        pnode = KernelNode(self._serial, now)
        node.children[("p", production.name)] = pnode
        pnode.users = 1
        path.append((node, ("p", production.name), pnode))
        self._paths[production.name] = path
        self._joins[production.name] = (joins, production.conditions)
        places = _places(path, joins, production.conditions)
        self._places[production.name] = places  # shared with the caller: see restart
        return places

    def _split(self, memory: KernelNode) -> None:
        """A second positive continuation comes below ``memory``: the kernel's Rete had it
        merged with its one join (an MP node) and splits it, and the new memory node goes
        to the head of its parent's children, newest. The places of the productions below
        it are made again from the new serial number."""
        self._serial += 1
        memory.serial = self._serial
        for name, path in self._paths.items():
            if any(node is memory for _, _, node in path):
                joins, conditions = self._joins[name]
                places = self._places[name]  # shared with the caller: updated in place
                places.clear()
                places.update(_places(path, joins, conditions))

    def with_kernel_relations(self, production: Production) -> Production:
        """``production`` with its relational tests where the kernel's Rete runs them
        (``reorder.with_kernel_relations``; call after ``add``, which ages its constants)."""
        return with_kernel_relations(production, self._ages)

    def restart(self) -> None:
        """Working memory was emptied (init-soar): every join counts as made before it."""
        stack = [self._top]
        while stack:
            node = stack.pop()
            node.born = 0
            stack.extend(node.children.values())
        for places in self._places.values():
            for index, place in list(places.items()):
                if place.born or place.loaded:  # after the first restart they are all 0
                    places[index] = place._replace(born=0, loaded=0)

    def remove(self, name: str) -> None:
        self._places.pop(name, None)
        self._ordered.pop(name, None)
        self._joins.pop(name, None)
        for parent, key, node in reversed(self._paths.pop(name, [])):
            node.users -= 1
            if node.users <= 0:
                del parent.children[key]


def _places(path: list[tuple[KernelNode, object, KernelNode]],
            joins: list[tuple[int, int, int]], conditions: tuple) -> dict[int, Place]:
    """The :class:`Place` of each written positive condition of a production whose nodes
    are ``path`` (its p-node last); ``joins``: (written index, kernel position, path
    length) per positive join, in the kernel's order."""
    pnode = path[-1][2]
    below = [-node.serial for _, _, node in path]
    places: dict[int, Place] = {}
    for k, (index, position, length) in enumerate(joins):
        if index not in places:
            _, _, join = path[length - 1]
            before = tuple(dict.fromkeys(written for written, _, _ in joins[:k]))
            cond = conditions[index]
            mask = ((2 if type(cond.attr_test) is Const else 0)
                    | (4 if type(cond.value_test) is Const else 0))
            twins = tuple(j for j, _, _ in joins if j != index
                          and _same_alpha(cond, conditions[j]))
            steps: list[object] = []
            start = length
            for later, _, later_length in joins[k + 1:]:
                steps.append(tuple(below[start:later_length]))
                steps.append(later)
                start = later_length
            steps.append(tuple(below[start:]))
            places[index] = Place(mask, before, join.born, (join.serial, *below[length:]),
                                  twins, position, pnode.born, tuple(steps))
    return places
