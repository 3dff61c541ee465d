"""Working memory drawn as a graph (the paper's Fig. 7): identifiers as boxes, the attributes
that link identifiers as labelled edges, constant-valued attributes listed inside their box.

The graph is read from an agent's working memory, so the picture shows what the rules really
built: the scene on the input-link, the plans on the output-link. A tree is laid out from the
root (the top state) breadth first; an identifier reached a second time keeps its first place
and gets a dashed edge, so shared structure stays visible without crossing the page.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import matplotlib.pyplot as plt
from matplotlib.figure import Figure

#: Top-state links of the kernel's own memories, which planning never uses.
ARCHITECTURE_LINKS = ("epmem", "smem", "reward-link")
#: Constant augmentations listed in a box at most (the rest are counted).
MAX_SHOWN = 6


@dataclass
class Node:
    """One identifier: its constant augmentations and the identifiers it links to."""

    name: str
    constants: list[tuple[str, str]] = field(default_factory=list)
    children: list[tuple[str, str]] = field(default_factory=list)  # (attribute, identifier)


def wm_nodes(agent: object, root: str = "S1",
             skip: Sequence[str] = ARCHITECTURE_LINKS) -> dict[str, Node]:
    """The identifiers reachable from ``root`` in the agent's working memory, with their
    augmentations in timetag order; ``skip`` names root attributes left out."""
    from sann.soar.memory import Identifier, format_symbol

    nodes: dict[str, Node] = {}
    for wme in agent.wmes():  # type: ignore[attr-defined]
        node = nodes.setdefault(wme.id.name, Node(wme.id.name))
        attr = format_symbol(wme.attr)
        if isinstance(wme.value, Identifier):
            label = attr + (" +" if wme.acceptable else "")
            node.children.append((label, wme.value.name))
            nodes.setdefault(wme.value.name, Node(wme.value.name))
        else:
            node.constants.append((attr, format_symbol(wme.value)))
    if root not in nodes:
        raise KeyError(f"{root} is not in working memory")
    nodes[root].children = [(a, c) for a, c in nodes[root].children if a not in skip]
    return _reachable(nodes, root)


def _reachable(nodes: dict[str, Node], root: str) -> dict[str, Node]:
    seen = {root: nodes[root]}
    queue = [root]
    while queue:
        for _, child in nodes[queue.pop(0)].children:
            if child not in seen:
                seen[child] = nodes[child]
                queue.append(child)
    return seen


def tree_layout(nodes: dict[str, Node], root: str) -> tuple[dict[str, tuple[int, float]],
                                                           list[tuple[str, str, str, bool]]]:
    """Column (depth) and row of each node, and every edge ``(parent, attribute, child,
    in_tree)``. A node first claims all its unplaced children, then each child's branch is
    laid out in turn: the input-link keeps every block of the scene as its child (the links
    between blocks and from plans into the scene become dashed edges), and a branch is drawn
    whole before the next. A node's row is the mean
    of its tree children's rows and leaves take rows in that order, so siblings stay
    together."""
    depth = {root: 0}
    kids: dict[str, list[str]] = {root: []}
    edges: list[tuple[str, str, str, bool]] = []

    def visit(name: str) -> None:
        for attr, child in nodes[name].children:  # claim the children, then descend
            in_tree = child not in depth
            edges.append((name, attr, child, in_tree))
            if in_tree:
                depth[child] = depth[name] + 1
                kids[name].append(child)
                kids[child] = []
        for child in kids[name]:
            visit(child)

    visit(root)
    rows: dict[str, float] = {}
    next_row = [0.0]

    def place(name: str) -> float:
        if not kids[name]:
            rows[name] = next_row[0]
            next_row[0] += 1.0 + 0.5 * len(nodes[name].constants[:MAX_SHOWN])
        else:
            rows[name] = sum(place(k) for k in kids[name]) / len(kids[name])
        return rows[name]

    place(root)
    return {n: (depth[n], rows[n]) for n in depth}, edges


def draw_wm(nodes: dict[str, Node], root: str = "S1", title: str = "",
            highlight: Iterable[str] = ()) -> Figure:
    """The figure: one box per identifier (its name and up to ``MAX_SHOWN`` constant
    augmentations), tree edges solid and labelled with their attribute, the edges to an
    identifier drawn elsewhere dashed; identifiers in ``highlight`` in the accent colour."""
    places, edges = tree_layout(nodes, root)
    marked = set(highlight)
    columns = max(c for c, _ in places.values()) + 1
    height = max(r for _, r in places.values()) + 1
    fig, ax = plt.subplots(figsize=(2.3 * columns + 0.5, max(3.0, 0.26 * height + 1)))
    ax.set_axis_off()
    ax.set_xlim(-0.2, columns * 2.0)
    ax.set_ylim(height, -1.0)
    boxes = {}
    for name, (column, row) in places.items():
        node = nodes[name]
        shown = [f"^{a} {_short(v)}" for a, v in node.constants[:MAX_SHOWN]]
        if len(node.constants) > MAX_SHOWN:
            shown.append(f"… {len(node.constants) - MAX_SHOWN} more")
        colour = "#f4b183" if name in marked else ("#9dc3e6" if name == root else "#deebf7")
        boxes[name] = ax.text(column * 2.0, row, "\n".join([name, *shown]), fontsize=6.5,
                              family="monospace", va="center", ha="left",
                              bbox={"boxstyle": "round,pad=0.3", "fc": colour, "ec": "0.4",
                                    "lw": 0.6})
    for up, attr, child, in_tree in edges:
        ax.annotate("", xy=(0, 0.5), xycoords=boxes[child], xytext=(1, 0.5),
                    textcoords=boxes[up],
                    arrowprops={"arrowstyle": "-|>", "lw": 0.7, "shrinkA": 4, "shrinkB": 4,
                                "color": "0.3" if in_tree else "0.6",
                                "linestyle": "-" if in_tree else "--"})
        if in_tree:
            ax.annotate("^" + attr, xy=(0, 0.5), xycoords=boxes[child], xytext=(-6, 3),
                        textcoords="offset points", fontsize=6, ha="right", va="bottom",
                        color="0.15")
    if title:
        ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return fig


def _short(value: str) -> str:
    """A float as the kernel prints it (``45.000000``) loses its trailing zeros in a box."""
    head, dot, tail = value.partition(".")
    if dot and head.lstrip("-").isdigit() and tail.isdigit():
        return f"{head}.{tail.rstrip('0') or '0'}"
    return value
