"""The alpha network: memories of the WMEs that pass one condition's constant tests.

A WME finds its alpha memories through a cache keyed on its attribute and value (and
acceptable flag); each memory keeps hash indices on the fields the beta nodes below it join
on, and hands the WME to those nodes (its successors) and to the query NCC nodes that
listen to it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

from sann.soar.codegen import define, plain
from sann.soar.matching.plan import Plan
from sann.soar.matching.templates import compile_alpha, filing_lines, unfiling_lines
from sann.soar.matching.tokens import (
    ALPHA_CACHE_LIMIT,
    AMEMS,
    ANY,
    FLOAT,
    GET,
    compile_first,
    index_add,
    index_remove,
)
from sann.soar.memory import WME, Identifier


class Successor(Protocol):
    """What an alpha memory needs of a beta node below it (nodes.py)."""

    parent: Any

    def activation(self, amem: AlphaMemory) -> Callable[[WME], None]: ...


class Listener(Protocol):
    """What an alpha memory needs of a query NCC node listening to it (query_ncc.py)."""

    owners: dict

    def inner_added(self, k: int, wme: WME) -> None: ...


class AlphaMemory:
    """The WMEs that pass one condition's constant tests, with hash indices on the fields
    the join nodes below test."""

    __slots__ = ("key", "lookup", "accept", "wmes", "indexes", "successors", "activations",
                 "listeners", "on_add", "on_remove")

    def __init__(self, key: tuple, lookup: tuple, accept: Callable[[WME], bool] | None) -> None:
        self.key = key
        self.lookup = lookup
        self.accept = accept
        self.wmes: dict[WME, None] = {}
        self.indexes: dict[str, dict] = {}  # field -> hash index on it
        self.successors: list[Successor] = []
        # (right_activate, parent memory) per successor: a node whose parent memory is empty
        # has nothing to join with, so add_wme skips the call (Doorenbos's right unlinking,
        # as a test instead of a relink).
        self.activations: list[tuple[Callable[[WME], None], dict]] = []
        # (query NCC node, inner condition number): told of every WME added and, for an
        # inner negated condition, removed
        self.listeners: list[tuple[Listener, int]] = []
        # What a WME entering (leaving) the memory does, generated from the above; compiled
        # on first use after any of them changes.
        self.on_add: Callable[[WME], None]
        self.on_remove: Callable[[WME], None]
        compile_first(self, "on_add", "on_remove")

    def link(self, node: Successor) -> None:
        """Add a successor in front: nodes are built top-down, and a descendant must be
        right-activated before its ancestor or a WME joining both makes a token twice."""
        self.successors.insert(0, node)
        self._relink()

    def unlink(self, node: Successor) -> None:
        self.successors.remove(node)
        self._relink()

    def listen(self, node: Listener, k: int) -> None:
        self.listeners.append((node, k))
        self._stale()

    def unlisten(self, node: Listener, k: int) -> None:
        self.listeners.remove((node, k))
        self._stale()

    def _relink(self) -> None:
        self.activations = [(node.activation(self), node.parent.tokens)  # type: ignore[union-attr]
                            for node in self.successors]
        self._stale()

    def _stale(self) -> None:
        compile_first(self, "on_add", "on_remove")

    def _compile(self) -> None:
        """Generate ``on_add`` and ``on_remove`` as straight-line code: store the WME in the
        memory and its indices, then right-activate each successor whose parent memory is
        not empty and tell the listening query nodes that have owners.  Every WME added to
        working memory passes here once per alpha memory it enters, so the loops over
        indices, successors and listeners are unrolled into the code once, not run for
        each WME.  ``plain_on_add`` and ``plain_on_remove`` are the loops."""
        if plain():
            self.on_add = self.plain_on_add  # type: ignore[method-assign]
            self.on_remove = self.plain_on_remove  # type: ignore[method-assign]
            return
        namespace: dict[str, object] = {"FLOAT": FLOAT, "wmes": self.wmes}
        add = ["def on_add(wme):", "    wmes[wme] = None"]
        remove = ["def on_remove(wme):", "    del wmes[wme]"]
        for field, index in self.indexes.items():
            namespace[f"index_{field}"] = index
            add += filing_lines(f"index_{field}", f"wme.{field}", "wme", "    ", field != "id")
            remove += unfiling_lines(f"index_{field}", f"wme.{field}", "wme", "    ",
                                     field != "id")
        for k, (activate, parent_tokens) in enumerate(self.activations):
            namespace[f"parent_tokens_{k}"] = parent_tokens
            namespace[f"right_activate_{k}"] = activate
            add.append(f"    if parent_tokens_{k}: right_activate_{k}(wme)")
        for k, (node, level) in enumerate(self.listeners):
            # the node's inner_added, read at each call: it is regenerated with the node
            namespace[f"owners_{k}"], namespace[f"listener_{k}"] = node.owners, node
            add.append(f"    if owners_{k}: listener_{k}.inner_added({level}, wme)")
        self.on_add = define(  # type: ignore[method-assign]
            add, namespace, "on_add", "rete:alpha-memory")
        self.on_remove = define(  # type: ignore[method-assign]
            remove, dict(namespace), "on_remove", "rete:alpha-memory")

    def plain_on_add(self, wme: WME) -> None:
        """Plain Python: what the generated ``on_add`` does."""
        self.wmes[wme] = None
        for field, index in self.indexes.items():
            index_add(index, GET[field](wme), wme)
        for activate, parent_tokens in self.activations:
            if parent_tokens:
                activate(wme)
        for node, level in self.listeners:
            if node.owners:
                node.inner_added(level, wme)

    def plain_on_remove(self, wme: WME) -> None:
        """Plain Python: what the generated ``on_remove`` does."""
        del self.wmes[wme]
        for field, index in self.indexes.items():
            index_remove(index, GET[field](wme), wme)

    def index(self, field: str) -> dict:
        index = self.indexes.get(field)
        if index is None:
            index = {}
            getter = GET[field]
            for wme in self.wmes:
                index_add(index, getter(wme), wme)
            self.indexes[field] = index
            self._stale()
        return index

    def add(self, wme: WME) -> None:
        """Store a WME without activating anything (a new memory taking in working memory)."""
        self.wmes[wme] = None
        for field, index in self.indexes.items():
            index_add(index, GET[field](wme), wme)


class AlphaNetwork:
    """Every alpha memory, by its sharing key and by its lookup key (constant attribute,
    constant value, acceptable flag), and the cache from a WME's key to its memories.

    ``registry`` is the Rete's record of each WME (its alpha memories first), updated when
    a memory is made or dropped while WMEs are in working memory."""

    __slots__ = ("memories", "index", "tested_values", "cache", "registry")

    def __init__(self, registry: dict[WME, list]) -> None:
        self.memories: dict[tuple, AlphaMemory] = {}
        self.index: dict[tuple, list[AlphaMemory]] = {}
        # constant values that alpha memories test for -> how many do: a WME whose value
        # is none of them is cached under UNTESTED, so a fresh number (a counter's next
        # value) does not miss the cache
        self.tested_values: dict[object, int] = {}
        self.cache: dict[tuple, tuple[list[AlphaMemory], bool]] = {}
        self.registry = registry

    def entry(self, key: tuple) -> tuple[list[AlphaMemory], bool]:
        """For an alpha cache key (see Rete.add_wme): the alpha memories whose lookup key fits,
        and whether none of them has a further test (then a WME enters them all); cached."""
        akey, vkey, acc = key
        found: list[AlphaMemory] = []
        for probe in (key, (akey, ANY, acc), (ANY, vkey, acc), (ANY, ANY, acc)):
            amems = self.index.get(probe)
            if amems:
                found.extend(amems)
        if len(self.cache) >= ALPHA_CACHE_LIMIT:
            self.cache.clear()
        entry = self.cache[key] = (found, all(a.accept is None for a in found))
        return entry

    def memory(self, plan: Plan) -> AlphaMemory:
        amem = self.memories.get(plan.alpha_key)
        if amem is not None:
            return amem
        amem = AlphaMemory(plan.alpha_key, plan.lookup,
                            compile_alpha(plan.alpha_tests))
        self.memories[plan.alpha_key] = amem
        self.index.setdefault(plan.lookup, []).append(amem)
        value_key = plan.lookup[1]
        if value_key is not ANY:
            self.tested_values[value_key] = self.tested_values.get(value_key, 0) + 1
        self.cache.clear()
        for wme, info in self.registry.items():
            if self.accepts(amem, wme):
                amem.add(wme)
                # a new list: it may be shared (see Rete.add_wme)
                info[AMEMS] = [*info[AMEMS], amem]
        return amem

    @staticmethod
    def accepts(amem: AlphaMemory, wme: WME) -> bool:
        attr_key, value_key, acc = amem.lookup
        if wme.acceptable != acc:
            return False
        if attr_key is not ANY and not (wme.attr.__class__ is not Identifier
                                         and wme.attr == attr_key):
            return False
        if value_key is not ANY and not (wme.value.__class__ is not Identifier
                                          and wme.value == value_key):
            return False
        return amem.accept is None or amem.accept(wme)

    def drop(self, amem: AlphaMemory) -> None:
        del self.memories[amem.key]
        value_key = amem.lookup[1]
        if value_key is not ANY:
            count = self.tested_values[value_key] - 1
            if count:
                self.tested_values[value_key] = count
            else:
                del self.tested_values[value_key]
        siblings = self.index[amem.lookup]
        siblings.remove(amem)
        if not siblings:
            del self.index[amem.lookup]
        self.cache.clear()
        for wme in amem.wmes:
            info = self.registry[wme]
            info[AMEMS] = [other for other in info[AMEMS] if other is not amem]  # may be shared

    # ----- building -----
