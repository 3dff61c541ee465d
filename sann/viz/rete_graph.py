"""A Rete as a graph a reader can look at: read from a live ``sann.soar`` matcher, then drawn.

``read_rete`` walks the real network (``Rete.network()``: the beta network's root and the
alpha memories), so the picture is the matcher's own structure, sharing included: a node
that two productions pass through is one node with two productions below it. Each beta
node is labelled with the condition it joins, found from the productions' layouts (which
token level holds which condition). ``ReteGraph.tokens_since`` tells which tokens appeared
between two readings, such as the tokens one added WME makes.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import matplotlib.pyplot as plt
from matplotlib.figure import Figure
from matplotlib.patches import FancyArrowPatch, FancyBboxPatch

from sann.soar.matching.alpha import AlphaMemory
from sann.soar.matching.nodes import JoinNode, NCCNode, NegativeNode, Node, PartnerNode
from sann.soar.matching.production_node import ProductionNode
from sann.soar.matching.query_ncc import QueryNCCNode
from sann.soar.matching.rete import Rete
from sann.soar.matching.runs import RunNode
from sann.soar.matching.tokens import ANY, Token
from sann.soar.memory import WME, format_symbol
from sann.soar.printer import format_condition

#: What each beta node class is called in the graph (the root is a plain ``Node``).
KINDS: dict[type, str] = {
    Node: "root", JoinNode: "join", NegativeNode: "negative", NCCNode: "ncc",
    PartnerNode: "ncc-partner", QueryNCCNode: "query-ncc", RunNode: "run",
    ProductionNode: "production",
}
COLOURS = {"alpha": "#fbe3c2", "root": "#eeeeee", "join": "#dbe9f6", "negative": "#f6d5d5",
           "ncc": "#f6d5d5", "ncc-partner": "#f6d5d5", "query-ncc": "#f6d5d5",
           "run": "#dbe9f6", "production": "#e3f1de"}
NEW_COLOUR = "#d9480f"


@dataclass(frozen=True)
class AlphaView:
    """An alpha memory: its constant tests as a pattern, and the WMEs in it."""

    name: str
    pattern: str
    wmes: tuple[WME, ...]


@dataclass(frozen=True)
class TokenView:
    """A token (partial match) of a beta node: the WMEs it holds, from the root down."""

    node: str
    wmes: tuple[WME, ...]


@dataclass(frozen=True)
class NodeView:
    """A beta node: its kind, the condition it joins (or the production it ends), where it
    sits in the tree, the alpha memories that feed it, its tokens (those it passes on) and
    how many more it keeps blocked (a negative or NCC node's tokens that a match stops)."""

    name: str
    kind: str
    label: str
    parent: str | None
    children: tuple[str, ...]
    alphas: tuple[str, ...]
    productions: tuple[str, ...]
    tokens: tuple[TokenView, ...]
    blocked: int


class ReteGraph:
    """One reading of a Rete: alpha memories ``A1``... (oldest first) and beta nodes ``N0``
    (the root), ``N1``... in depth-first order, children in the network's own order."""

    def __init__(self, alphas: list[AlphaView], nodes: list[NodeView],
                 raw_tokens: dict[str, list[Token]]) -> None:
        self.alphas = {alpha.name: alpha for alpha in alphas}
        self.nodes = {node.name: node for node in nodes}
        # the token objects themselves, to tell by identity which ones a later reading adds
        self._raw = raw_tokens

    def of_kind(self, kind: str) -> list[NodeView]:
        return [node for node in self.nodes.values() if node.kind == kind]

    def tokens_since(self, earlier: ReteGraph) -> list[TokenView]:
        """The tokens in this reading that were not in ``earlier``, node by node in
        depth-first order. Both readings must be of the same network."""
        if self._shape() != earlier._shape():
            raise ValueError("the two readings are of different networks")
        made = []
        for name, tokens in self._raw.items():
            before = {id(tok) for tok in earlier._raw[name]}
            views = self.nodes[name].tokens
            made += [view for tok, view in zip(tokens, views, strict=True)
                     if id(tok) not in before]
        return made

    def _shape(self) -> list[tuple[str, str, str | None]]:
        return [(node.name, node.label, node.parent) for node in self.nodes.values()]


def read_rete(rete: Rete) -> ReteGraph:
    """The network of ``rete`` as it is now (pending productions are built first)."""
    root, memories = rete.network()
    amem_names = {id(amem): f"A{k}" for k, amem in enumerate(memories, start=1)}
    alphas = [AlphaView(amem_names[id(amem)], alpha_pattern(amem), tuple(amem.wmes))
              for amem in memories]
    order = list(_depth_first(root))
    names = {id(node): f"N{k}" for k, node in enumerate(order)}
    labels, below = _labels(order)
    nodes, raw = [], {}
    for node in order:
        name = names[id(node)]
        raw[name] = list(node.tokens)
        nodes.append(NodeView(
            name=name, kind=kind_of(node), label=labels.get(id(node), ""),
            parent=None if node.parent is None else names[id(node.parent)],
            children=tuple(names[id(child)] for child in node.children),
            alphas=tuple(amem_names[id(amem)] for amem in _alpha_memories(node)),
            productions=tuple(below.get(id(node), ())),
            tokens=tuple(TokenView(name, token_wmes(tok)) for tok in raw[name]),
            blocked=len(node.all_tokens()) - len(raw[name])))
    return ReteGraph(alphas, nodes, raw)


def kind_of(node: Node) -> str:
    kind = KINDS.get(type(node))
    if kind is None:
        raise ValueError(f"a beta node of an unknown class: {type(node).__name__}")
    return kind


def _depth_first(root: Node) -> Iterator[Node]:
    stack = [root]
    while stack:
        node = stack.pop()
        yield node
        stack.extend(reversed(node.children))


def _labels(order: list[Node]) -> tuple[dict[int, str], dict[int, list[str]]]:
    """The condition each node joins and the productions below it, from each production
    node's layout: token level k above the production node holds the written conditions
    ``layout.levels[k]``. Nodes no production walks through (inside an NCC subnetwork)
    get no condition."""
    labels: dict[int, str] = {}
    below: dict[int, list[str]] = {}
    for pnode in order:
        if not isinstance(pnode, ProductionNode):
            continue
        production = pnode.production
        labels[id(pnode)] = production.name
        below.setdefault(id(pnode), []).append(production.name)
        node: Node | None = pnode.parent
        for level in pnode.layout.levels:
            if node is None:
                raise AssertionError(f"{production.name}: more levels than nodes above it")
            text = "  ".join(format_condition(production.conditions[i]) for i in level)
            labels.setdefault(id(node), text)
            below.setdefault(id(node), []).append(production.name)
            node = node.parent
        if node is None or node.parent is not None:
            raise AssertionError(f"{production.name}: its levels do not reach the root")
        below.setdefault(id(node), []).append(production.name)
    return labels, below


def _alpha_memories(node: Node) -> list[AlphaMemory]:
    if isinstance(node, (JoinNode, NegativeNode)):
        return [node.amem]
    if isinstance(node, (RunNode, QueryNCCNode)):
        return list(dict.fromkeys(node.amems))
    return []


def alpha_pattern(amem: AlphaMemory) -> str:
    """An alpha memory's constant tests as a WME pattern, ``*`` for a field it does not test:
    ``(state * ^block *)``, ``(* ^clear yes)``, ``(* ^operator * +)``."""
    attr, value, acceptable = amem.lookup
    tests = amem.key[3]
    ident = "state *" if ("state",) in tests else "*"
    text = (f"({ident} ^{'*' if attr is ANY else format_symbol(attr)} "
            f"{'*' if value is ANY else format_symbol(value)}{' +' if acceptable else ''})")
    extra = [_alpha_test(test) for test in tests if test[0] not in ("state", "type")]
    return text + (f" [{', '.join(extra)}]" if extra else "")


def _alpha_test(test: tuple) -> str:
    """One further constant test of an alpha memory (see ``plan.plan_condition``)."""
    if test[0] == "eq":
        return f"{test[1]} = {format_symbol(test[2][1])}"
    if test[0] == "rel":
        return f"{test[1]} {test[2]} {format_symbol(test[3][1])}"
    if test[0] == "disj":
        return f"{test[1]} in << {' '.join(format_symbol(v) for _, v in test[2])} >>"
    return "never"


def token_wmes(tok: Token) -> tuple[WME, ...]:
    """The WMEs a token holds, from the root down (a run node's token holds several; the
    tokens of negative nodes and production nodes hold none of their own)."""
    found: list[WME] = []
    while tok.parent is not None:
        wme = tok.wme
        if isinstance(wme, tuple):
            found.extend(reversed(wme))
        elif wme is not None:
            found.append(wme)
        tok = tok.parent
    return tuple(reversed(found))


def format_token(token: TokenView) -> str:
    return "⟨" + ", ".join(str(wme) for wme in token.wmes) + "⟩"


# --- drawing ------------------------------------------------------------------------------

_DX, _DY, _BOX_W, _BOX_H = 3.0, 1.0, 2.7, 0.75


def draw_rete(graph: ReteGraph, new: list[TokenView] | None = None, added: WME | None = None,
              title: str = "") -> Figure:
    """The network as boxes: alpha memories in a column on the left (dashed arrows to the
    nodes they right-activate), the beta tree on the right, root at the top. Each box shows
    its token count (WME count for an alpha memory); the tokens ``new`` and the alpha
    memories holding the WME ``added`` are in orange."""
    new_at: dict[str, int] = {}
    for token in new or []:
        new_at[token.node] = new_at.get(token.node, 0) + 1
    places = _tree_places(graph)
    alpha_places = _alpha_places(graph, places)
    left = -1.25 * _DX - _BOX_W / 2 - 0.2
    right = max(x for x, _ in places.values()) + _BOX_W / 2 + 0.2
    depth = -min(y for _, y in [*places.values(), *alpha_places.values()]) + _DY
    figure, ax = plt.subplots(figsize=(1.5 * (right - left), 1.5 * depth + 0.6))
    for name, node in graph.nodes.items():
        x, y = places[name]
        for child in node.children:
            _arrow(ax, (x, y - _BOX_H / 2), (places[child][0], places[child][1] + _BOX_H / 2),
                   dashed=False)
        for feeder in node.alphas:
            fx, fy = alpha_places[feeder]
            _arrow(ax, (fx + _BOX_W / 2, fy), (x - _BOX_W / 2, y), dashed=True)
        count = f"{len(node.tokens)} token{'s' if len(node.tokens) != 1 else ''}" + (
            f", {node.blocked} blocked" if node.blocked else "")
        _box(ax, x, y, COLOURS[node.kind], f"{name}  {node.kind}", node.label, count,
             new_at.get(name, 0))
    for name, alpha in graph.alphas.items():
        x, y = alpha_places[name]
        entered = sum(1 for wme in alpha.wmes if wme is added)
        count = f"{len(alpha.wmes)} WME{'s' if len(alpha.wmes) != 1 else ''}"
        _box(ax, x, y, COLOURS["alpha"], f"{name}  alpha memory", alpha.pattern, count,
             entered)
    ax.set_xlim(left, right)
    ax.set_ylim(-depth, _BOX_H)
    ax.set_aspect("equal")
    ax.axis("off")
    if title:
        ax.set_title(title, fontsize=11)
    figure.tight_layout()
    return figure


def _tree_places(graph: ReteGraph) -> dict[str, tuple[float, float]]:
    """Leaves side by side in order, each parent centred over its children."""
    places: dict[str, tuple[float, float]] = {}
    leaves = [0]

    def place(name: str, depth: int) -> float:
        children = graph.nodes[name].children
        if children:
            xs = [place(child, depth + 1) for child in children]
            x = sum(xs) / len(xs)
        else:
            x = leaves[0] * _DX
            leaves[0] += 1
        places[name] = (x, -depth * _DY)
        return x

    place("N0", 0)
    return places


def _alpha_places(graph: ReteGraph, places: dict[str, tuple[float, float]]
                  ) -> dict[str, tuple[float, float]]:
    """Each alpha memory left of the tree, level with the first node it feeds, moved down
    where it would overlap the one above."""
    wanted = []
    for name in graph.alphas:
        fed = [places[node.name][1] for node in graph.nodes.values() if name in node.alphas]
        wanted.append((max(fed) if fed else 0.0, name))
    result: dict[str, tuple[float, float]] = {}
    lowest = _BOX_H
    for y, name in sorted(wanted, key=lambda item: -item[0]):
        y = min(y, lowest - _DY)
        result[name] = (-1.25 * _DX, y)
        lowest = y
    return result


def _box(ax, x: float, y: float, colour: str, title: str, body: str, count: str,
         new: int) -> None:
    edge, width = (NEW_COLOUR, 2.4) if new else ("#555555", 1.0)
    ax.add_patch(FancyBboxPatch((x - _BOX_W / 2, y - _BOX_H / 2), _BOX_W, _BOX_H,
                                boxstyle="round,pad=0.02,rounding_size=0.1", fc=colour,
                                ec=edge, lw=width))
    ax.text(x, y + 0.22, title, ha="center", va="center", fontsize=7.5, weight="bold")
    ax.text(x, y + 0.02, body, ha="center", va="center", fontsize=6.5, family="monospace",
            )
    ax.text(x, y - 0.22, count + (f"  (+{new} new)" if new else ""), ha="center",
            va="center", fontsize=7, color=NEW_COLOUR if new else "#333333")


def _arrow(ax, start: tuple[float, float], end: tuple[float, float], dashed: bool) -> None:
    ax.add_patch(FancyArrowPatch(start, end, arrowstyle="-|>", mutation_scale=10, lw=0.9,
                                 color="#777777" if dashed else "#333333",
                                 linestyle="--" if dashed else "-"))
