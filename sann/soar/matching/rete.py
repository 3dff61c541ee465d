"""The Rete (Doorenbos 1995): the matcher the agent runs.

:class:`Rete` has the interface of :class:`~sann.soar.matching.oracle.BruteForceMatcher`:
productions and WMEs go in, new and retracted matches come out (``take_changes``).  An
alpha network hashed on constant attribute and value tests (alpha.py) feeds hashed beta
joins, negative and conjunctive-negation nodes (nodes.py, query_ncc.py, runs.py) with
shared prefixes, built by build.py in the join order of join_order.py; removal is
tree-based.  Adding or removing a WME costs in proportion to the alpha memories and tokens
it touches, not to the size of working memory.  ``Match.wmes`` stays in written order.
"""

from __future__ import annotations

from sann.soar.errors import SoarSemanticError
from sann.soar.matching.alpha import AlphaMemory, AlphaNetwork
from sann.soar.matching.build import Builder
from sann.soar.matching.join_order import const_attributes, singletons
from sann.soar.matching.matches import Changes, Match
from sann.soar.matching.nodes import NCCNode, NegativeNode, Node, PartnerNode, delete_tokens
from sann.soar.matching.production_node import Layout, ProductionNode
from sann.soar.matching.query_ncc import QueryNCCNode
from sann.soar.matching.tokens import (
    AMEMS,
    BLOCKED,
    BUILT,
    IDENT,
    UNTESTED,
    WITNESSED,
    new_token,
    unlink_tokens,
)
from sann.soar.matching.variables import bound_by
from sann.soar.memory import WME, Identifier
from sann.soar.parsing.checks import check_production
from sann.soar.production import Condition, Const, MakeAction, Production

__all__ = ["Rete"]


class Rete:
    """Doorenbos's Rete with hashed alpha and beta memories, negative and NCC nodes and
    shared prefixes.  Same interface as :class:`BruteForceMatcher`.

    Conditions not linked to a state load, as in the kernel (which warns about them); they
    are joined on any bound variable, or as a cross product.  ``check_links=True`` refuses
    them instead (see :func:`check_production`).
    """

    def __init__(self, check_links: bool = False) -> None:
        self.check_links = check_links
        # per WME: [alpha memories, tokens built on it, negative tokens it blocks,
        # query NCC tokens it is a witness of]
        self._wme_info: dict[WME, list] = {}
        self._root = Node(self._wme_info, None)
        self._root_token = new_token(None, None, (), self._root)
        self._root.tokens[self._root_token] = None
        self._pnodes: dict[str, ProductionNode] = {}
        self._productions: dict[str, Production] = {}  # in the order added
        self._pending: list[Production] = []  # added, network not built yet (see _flush)
        self._removed_attrs: set[object] = {"operator"}  # attributes rules remove
        self._stale: set[str] = set()  # built before an attribute they check became volatile
        self._alpha = AlphaNetwork(self._wme_info)
        # the alpha network's dicts, read by add_wme on every WME (never replaced)
        self._amems = self._alpha.memories
        self._tested_values = self._alpha.tested_values
        self._alpha_cache = self._alpha.cache
        self._builder = Builder(self._wme_info, self._alpha, self._removed_attrs, self._root)
        self._changes = Changes()

    def add_production(self, production: Production) -> None:
        if production.name in self._productions:
            raise SoarSemanticError(production.name, "a production with this name exists",
                                    production.location)
        check_production(production, links=self.check_links)
        self._productions[production.name] = production
        self._pending.append(production)
        for action in production.actions:
            if (isinstance(action, MakeAction) and action.preference == "-"
                    and isinstance(action.attr, Const)
                    and action.attr.value not in self._removed_attrs):
                attr = action.attr.value
                self._removed_attrs.add(attr)
                self._stale.update(name for name, pnode in self._pnodes.items()
                                   if attr in const_attributes(pnode.production.conditions))

    def _flush(self) -> None:
        """Build the productions added since the last change of working memory or query.

        Deferring the build lets the join order see the rules added together: which
        attributes the rules remove (volatile) is known only then.  A production built
        before one of its checked attributes turned out volatile is rebuilt, keeping its
        Match objects.  Matches still appear in the next take_changes(), as promised."""
        stale, self._stale = self._stale, set()
        for name in stale:
            if name in self._pnodes:
                self._rebuild(self._pnodes[name])
        pending, self._pending = self._pending, []
        for production in pending:
            self._build(production)

    def _rebuild(self, old: ProductionNode) -> None:
        """Rebuild a production with the current join order; its live matches keep their
        identity (same WMEs, same Match object), so no change is reported for them."""
        live = {tuple(map(id, tok.extra.wmes)): tok for tok in old.tokens}
        added = self._changes.added
        new = self._build(old.production)
        for tok in new.tokens:
            match = tok.extra
            previous = live.pop(tuple(map(id, match.wmes)), None)
            if previous is None:
                continue
            kept = previous.extra
            previous.extra = None  # its old token leaves without retracting it
            added.pop(match, None)
            tok.extra = kept
        self._builder.remove_node(old)

    def _build(self, production: Production) -> ProductionNode:
        conditions = production.conditions
        scope = bound_by(conditions)
        var_pos: dict[str, int] = {}
        bottom, levels = self._builder.build_scope(conditions, self._root, var_pos, 0, scope,
                                           singletons(production), set(), runs=True)
        positive = {i for i, element in enumerate(conditions)
                    if isinstance(element, Condition) and not element.negated}
        bindings = sorted((n, p) for n, p in var_pos.items() if n in scope)
        layout = Layout(production, levels, bindings, positive)
        pnode = ProductionNode(self._wme_info, bottom, production, layout, self._changes)
        bottom.children.append(pnode)
        self._pnodes[production.name] = pnode
        for tok in list(bottom.tokens):
            pnode.left_activate(tok)
        return pnode

    def excise(self, name: str) -> None:
        if self._pending:
            self._flush()
        pnode = self._pnodes.pop(name, None)
        if pnode is None:
            raise KeyError(f"no production named {name!r}")
        del self._productions[name]
        self._builder.remove_node(pnode)

    def add_wme(self, wme: WME) -> None:
        if self._pending:
            self._flush()
        attr, value = wme.attr, wme.value
        key = (IDENT if type(attr) is Identifier else attr,
               value if value in self._tested_values else UNTESTED,  # an identifier never is
               wme.acceptable)
        entry = self._alpha_cache.get(key)
        found, plain = entry if entry is not None else self._alpha.entry(key)
        if plain:
            # No memory here filters further: the WME enters them all, and the cache's list
            # (never mutated, see AlphaNetwork.memory) is its record of them.
            record = [found, {}, None, None]
            if self._wme_info.setdefault(wme, record) is not record:
                raise ValueError(f"{wme!r} is already in working memory")
            for amem in found:
                amem.on_add(wme)
            return
        amems: list[AlphaMemory] = []
        record = [amems, {}, None, None]
        if self._wme_info.setdefault(wme, record) is not record:
            raise ValueError(f"{wme!r} is already in working memory")
        for amem in found:
            accept = amem.accept
            if accept is None or accept(wme):
                amems.append(amem)
                amem.on_add(wme)

    def remove_wme(self, wme: WME) -> None:
        if self._pending:
            self._flush()
        info = self._wme_info.pop(wme, None)
        if info is None:
            raise ValueError(f"{wme!r} is not in working memory")
        for amem in info[AMEMS]:
            amem.on_remove(wme)
        built = info[BUILT]
        if built:
            # Detached from their parents first, then deleted in one walk (a token built on
            # this WME below another one is detached from its still-live parent: each is
            # deleted once).
            doomed = []
            for tok in built:
                if tok.node is not None:
                    del tok.parent.children[tok]
                    doomed.append(tok)
            doomed.reverse()  # the walk pops from the end: the first built goes first
            delete_tokens(self._wme_info, doomed)
        blocked = info[BLOCKED]
        if blocked:
            for tok in blocked:
                node = tok.node
                if node is not None:
                    blockers = tok.extra
                    del blockers[wme]
                    if not blockers:
                        node.unblock(tok)
        witnessed = info[WITNESSED]
        if witnessed:
            for tok in list(witnessed):
                node = tok.node
                if node is not None and tok.extra is not None:
                    node.recheck(tok)
        for amem in info[AMEMS]:
            if amem.listeners:
                for node, k in amem.listeners:
                    if node.owners and node.levels[k].negated:
                        node.inner_removed(k, wme)

    def clear_wmes(self) -> None:
        """Remove every WME at once: the same changes as ``remove_wme`` on each (every live
        match is retracted), but the memories are emptied in place instead of deleting the
        tokens one by one, so ``init-soar`` costs the size of the network, not the joins."""
        if self._pending:
            self._flush()
        for pnode in self._pnodes.values():
            for tok in pnode.tokens:
                if tok.extra is not None:
                    self._changes.retract(tok.extra)
        self._wme_info.clear()
        for amem in self._amems.values():
            amem.wmes.clear()
            for index in amem.indexes.values():
                index.clear()  # cleared in place: the join nodes hold these very dicts
        self._clear_memories(self._root)
        unlink_tokens(self._root_token)
        for child in self._root.children:  # a node needing no WME gets its token back
            child.left_activate(self._root_token)

    def _clear_memories(self, top: Node) -> None:
        """Empty the token memories of every node below ``top`` (in place).  A node passes
        on only its active tokens, so the children of a node without any hold none either:
        the walk costs the live part of the network."""
        stack = list(top.children)
        while stack:
            node = stack.pop()
            if node.tokens:
                stack.extend(node.children)
                node.tokens.clear()
            for index in node.indexes.values():
                index.clear()
            if isinstance(node, NegativeNode):
                node.every.clear()
                node.every_index.clear()
            elif isinstance(node, NCCNode):
                node.owners.clear()
            elif isinstance(node, PartnerNode):
                node.buffer.clear()
            elif isinstance(node, QueryNCCNode):
                node.owners.clear()
                for index in node.owner_index.values():
                    index.clear()

    def take_changes(self) -> tuple[list[Match], list[Match]]:
        if self._pending:
            self._flush()
        return self._changes.take()

    def mark_removals(self) -> None:
        """The WMEs removed from here on: the retractions reported before were made by
        added WMEs (``blocked_retractions`` counts them at the next take_changes)."""
        self._changes.mark_removals()

    @property
    def blocked_retractions(self) -> int:
        return self._changes.blocked

    def matches(self, name: str) -> list[Match]:
        if self._pending:
            self._flush()
        pnode = self._pnodes.get(name)
        if pnode is None:
            raise KeyError(f"no production named {name!r}")
        return [tok.extra for tok in pnode.tokens]

    def productions(self) -> list[Production]:
        return list(self._productions.values())

    def network(self) -> tuple[Node, list[AlphaMemory]]:
        """The beta network's root and the alpha memories (oldest first), built up to date:
        what a reader of the network's structure walks (``sann.viz.rete_graph`` draws it)."""
        if self._pending:
            self._flush()
        return self._root, list(self._amems.values())
