"""Building the beta network for a production's conditions, and taking it down again.

Conditions are planned one by one in the join order (plan.py, join_order.py); equal nodes
below equal parents are shared (``child_map``, keyed on what the node tests); consecutive
independent conditions become one run node; a conjunctive negation becomes a query node
(query_ncc.py), or an NCC node over a subnetwork when it holds another negation.  A node
made below a parent that has tokens is left-activated with each of them at once.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from sann.soar.matching.alpha import AlphaMemory, AlphaNetwork
from sann.soar.matching.join_order import join_order
from sann.soar.matching.nodes import (
    JoinNode,
    NCCNode,
    NegativeNode,
    Node,
    PartnerNode,
    delete_tokens,
)
from sann.soar.matching.plan import Plan, plan_condition
from sann.soar.matching.query import InnerCondition
from sann.soar.matching.query_ncc import QueryNCCNode
from sann.soar.matching.runs import Member, RunNode, joins_within
from sann.soar.matching.templates import compile_check, extender
from sann.soar.matching.tokens import GET
from sann.soar.matching.variables import bound_by, equality_vars
from sann.soar.production import ConditionElement, ConjunctiveNegation


class Builder:
    """Makes and removes the beta nodes of one Rete: below ``root``, over the alpha memories
    of ``alpha``, recording tokens in ``registry`` (the Rete's WME records); ``volatile``
    is the set of attributes rules remove (the join order puts them last), which the Rete
    grows as productions arrive."""

    __slots__ = ("registry", "alpha", "volatile", "root")

    def __init__(self, registry: dict, alpha: AlphaNetwork, volatile: set[object],
                 root: Node) -> None:
        self.registry = registry
        self.alpha = alpha
        self.volatile = volatile
        self.root = root

    def build_scope(self, elements: tuple[ConditionElement, ...], parent: Node,
                     var_pos: dict[str, int], nvals: int, scope: set[str],
                     singletons: set[str], states: set[str], runs: bool = False
                     ) -> tuple[Node, list[tuple[int, ...]]]:
        """Build the nodes of ``elements`` below ``parent``; return the bottom node and the
        written indices matched at each token level.  ``runs``: join consecutive independent
        conditions as one node (not inside an NCC subnetwork, whose partner counts levels)."""
        order = join_order(elements, var_pos, scope, singletons, self.volatile)
        deferred: list[tuple[int, str, str]] = []
        node = parent
        levels: list[tuple[int, ...]] = []
        run: list[tuple[int, Plan, AlphaMemory]] = []  # independent conditions to join
        base = nvals  # the parent's number of values when the run started

        def close_run() -> None:
            nonlocal node, base
            if run:
                node = self.run_node(node, run)
                levels.append(tuple(index for index, _, _ in run))
                run.clear()
            base = nvals

        for index in order:
            element = elements[index]
            if isinstance(element, ConjunctiveNegation):
                close_run()
                node = self.build_ncc(element, node, dict(var_pos), nvals, scope, singletons,
                                       set(states))
                levels.append((index,))
                continue
            plan = plan_condition(element, var_pos, nvals, deferred, states)
            if element.goal is not None and not element.negated:
                states.update(equality_vars(element.id_test))
            amem = self.alpha.memory(plan)
            if runs and not element.negated:
                if run and not joins_within(plan, base, amem, run):
                    close_run()
                if joins_within(plan, nvals if not run else base, amem, run):
                    run.append((index, plan, amem))
                    nvals += len(plan.new_fields)
                    continue
            close_run()
            levels.append((index,))
            check = compile_check(plan.beta)
            if element.negated:
                key: tuple = ("neg", id(amem), plan.index, tuple(plan.beta))
                node = self.child(node, key, lambda p, k, a=amem, pl=plan, c=check:
                                   NegativeNode(self.registry, p, k, a, pl.index, c), amem)
            else:
                fields = tuple(plan.new_fields)
                key = ("join", id(amem), plan.index, tuple(plan.beta), fields)
                node = self.child(node, key, lambda p, k, a=amem, pl=plan, c=check, f=fields:
                                   JoinNode(self.registry, p, k, a, pl.index, c, extender(f)), amem)
                nvals += len(fields)
        close_run()
        if deferred:  # unreachable after check_production; kept as a loud guard
            raise AssertionError(f"relational tests never placed: {deferred}")
        return node, levels

    def run_node(self, parent: Node, run: list[tuple[int, Plan, AlphaMemory]]) -> Node:
        """A lone condition is an ordinary join node; two or more make a RunNode."""
        if len(run) == 1:
            _, plan, amem = run[0]
            fields = tuple(plan.new_fields)
            key: tuple = ("join", id(amem), plan.index, tuple(plan.beta), fields)
            return self.child(parent, key, lambda p, k: JoinNode(
                self.registry, p, k, amem, plan.index, compile_check(plan.beta), extender(fields)),
                amem)
        key = ("run", tuple((id(amem), plan.index, tuple(plan.beta), tuple(plan.new_fields))
                            for _, plan, amem in run))
        node = parent.child_map.get(key)
        if node is not None:
            return node
        members = [Member(amem, amem.index(plan.index[1]), plan.index[0], GET[plan.index[1]],
                          compile_check(plan.beta), tuple(plan.new_fields))
                   for _, plan, amem in run]  # type: ignore[index]
        node = RunNode(self.registry, parent, key, members)
        parent.children.append(node)
        parent.child_map[key] = node
        for _, _, amem in run:
            amem.link(node)
        for tok in list(parent.tokens):
            node.left_activate(tok)
        return node

    def child(self, parent: Node, key: tuple, make: Callable, amem: AlphaMemory) -> Node:
        node = parent.child_map.get(key)
        if node is not None:
            return node
        node = make(parent, key)
        parent.children.append(node)
        parent.child_map[key] = node
        amem.link(node)
        for tok in list(parent.tokens):
            node.left_activate(tok)
        return node

    def build_ncc(self, ncc: ConjunctiveNegation, parent: Node, var_pos: dict[str, int],
                   nvals: int, scope: set[str], singletons: set[str], states: set[str]
                   ) -> Node:
        inner_scope = scope | bound_by(ncc.conditions)
        if not any(isinstance(e, ConjunctiveNegation) for e in ncc.conditions):
            return self.build_query_ncc(ncc, parent, var_pos, nvals, inner_scope, singletons,
                                         states)
        bottom, _ = self.build_scope(ncc.conditions, parent, var_pos, nvals, inner_scope,
                                      singletons, states)
        key = ("ncc", id(bottom))
        node = parent.child_map.get(key)
        if node is not None:
            return node
        node = NCCNode(self.registry, parent, key)
        partner = PartnerNode(self.registry, bottom, node, len(ncc.conditions))
        node.partner = partner
        bottom.children.append(partner)
        for tok in list(bottom.tokens):
            partner.left_activate(tok)
        parent.children.append(node)  # after the subnetwork: it must see a token first
        parent.child_map[key] = node
        for tok in list(parent.tokens):
            node.left_activate(tok)
        return node

    def build_query_ncc(self, ncc: ConjunctiveNegation, parent: Node,
                         var_pos: dict[str, int], nvals: int, scope: set[str],
                         singletons: set[str], states: set[str]) -> Node:
        """Plan the inner conditions as for a subnetwork, but keep them as the levels of a
        query (see :class:`QueryNCCNode`)."""
        order = join_order(ncc.conditions, var_pos, scope, singletons, self.volatile)
        deferred: list[tuple[int, str, str]] = []
        levels: list[InnerCondition] = []
        shape: list[tuple] = []
        amems: list[AlphaMemory] = []
        owner_tests: list[list[tuple[Callable, int]]] = []
        width = nvals
        for index in order:
            element = ncc.conditions[index]
            plan = plan_condition(element, var_pos, nvals, deferred, states)  # type: ignore[arg-type]
            if element.goal is not None and not element.negated:  # type: ignore[union-attr]
                states.update(equality_vars(element.id_test))  # type: ignore[union-attr]
            amem = self.alpha.memory(plan)
            negated = bool(element.negated)  # type: ignore[union-attr]
            fields = () if negated else tuple(plan.new_fields)
            if plan.index is None:
                pos, getter, hashed = -1, None, None
            else:
                pos, field = plan.index
                getter, hashed = GET[field], amem.index(field)
            equalities: list[tuple[Any, Any]] = (
                [] if plan.index is None else [(plan.index[1], plan.index[0])])
            equalities += [(left[1], right[1]) for left, op, right in plan.beta
                           if op == "=" and left[0] == "w" and right[0] == "v"]
            levels.append(InnerCondition(amem.wmes, hashed, pos, getter,
                                         compile_check(plan.beta), fields, negated,
                                         tuple(equalities)))
            owner_tests.append([(GET[field], p) for field, p in equalities if p < width])
            shape.append((id(amem), plan.index, tuple(plan.beta), fields, negated))
            amems.append(amem)
            nvals += len(fields)
        if deferred:  # unreachable after check_production; kept as a loud guard
            raise AssertionError(f"relational tests never placed: {deferred}")
        key = ("query-ncc", tuple(shape))
        node = parent.child_map.get(key)
        if node is not None:
            return node
        node = QueryNCCNode(self.registry, parent, key, levels, width, amems, owner_tests)
        for k, amem in enumerate(amems):
            amem.listen(node, k)
        parent.children.append(node)
        parent.child_map[key] = node
        for tok in list(parent.tokens):
            node.left_activate(tok)
        return node

    def remove_node(self, node: Node) -> None:
        """Remove a childless node, then its ancestors that are left without children."""
        if node is self.root or node.parent is None or node.children:
            return
        parent = node.parent
        for tok in node.all_tokens():
            if tok.node is not None:
                tok.parent.children.pop(tok, None)
                delete_tokens(self.registry, [tok])
        parent.children.remove(node)
        if parent.child_map.get(node.key) is node:
            del parent.child_map[node.key]
        node.parent = None  # marks it removed
        amem = getattr(node, "amem", None)
        if amem is not None:
            amem.unlink(node)
            if not amem.successors and not amem.listeners:
                self.alpha.drop(amem)
        if isinstance(node, RunNode):
            for amem in node.amems:
                amem.unlink(node)
                if not amem.successors and not amem.listeners and amem.key in self.alpha.memories:
                    self.alpha.drop(amem)
        if isinstance(node, QueryNCCNode):
            for k, amem in enumerate(node.amems):
                amem.unlisten(node, k)
            for amem in dict.fromkeys(node.amems):
                if not amem.successors and not amem.listeners and amem.key in self.alpha.memories:
                    self.alpha.drop(amem)
        if isinstance(node, NCCNode):
            self.remove_node(node.partner)  # type: ignore[arg-type]
        self.remove_node(parent)
