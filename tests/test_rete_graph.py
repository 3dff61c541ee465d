"""The Rete graph (sann.viz.rete_graph) is read from a real Rete: its nodes, their sharing
between productions, and the tokens one added WME makes."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import pytest  # noqa: E402

from sann.soar import parse  # noqa: E402
from sann.soar.matching.rete import Rete  # noqa: E402
from sann.soar.memory import WME, Identifier  # noqa: E402
from sann.viz.rete_graph import draw_rete, format_token, read_rete  # noqa: E402

TWO_RULES = """
sp {grasp*propose (state <s> ^block <b>) (<b> ^clear yes)
   --> (<s> ^operator <o> +) (<o> ^name grasp ^block <b>)}
sp {block*free (state <s> ^block <b>) (<b> ^clear yes) -(<b> ^on <other>)
   --> (<s> ^free <b>)}
"""
S1, B1 = Identifier("S", 1, level=1), Identifier("B", 1)


def rete_with_block(rules: str = TWO_RULES) -> Rete:
    rete = Rete()
    for production in parse(rules):
        rete.add_production(production)
    for timetag, (ident, attr, value) in enumerate(
            [(S1, "superstate", "nil"), (S1, "type", "state"), (S1, "block", B1)], start=1):
        rete.add_wme(WME(ident, attr, value, timetag))
    return rete


def test_the_graph_has_the_networks_nodes_and_memories() -> None:
    graph = read_rete(rete_with_block())
    kinds = sorted(node.kind for node in graph.nodes.values())
    assert kinds == ["join", "join", "join", "negative", "production", "production", "root"]
    assert {alpha.pattern for alpha in graph.alphas.values()} == {
        "(state * ^block *)", "(* ^clear yes)", "(* ^on *)"}
    for node in graph.nodes.values():
        for child in node.children:
            assert graph.nodes[child].parent == node.name


def test_a_condition_two_productions_share_is_one_node() -> None:
    graph = read_rete(rete_with_block())
    shared = [node for node in graph.nodes.values()
              if node.kind != "root" and len(node.productions) == 2]
    assert [(node.kind, node.label) for node in shared] == [("join", "(state <s> ^block <b>)")]
    assert len(shared[0].children) == 2
    clear = next(name for name, alpha in graph.alphas.items() if alpha.pattern == "(* ^clear yes)")
    assert len([node for node in graph.nodes.values() if clear in node.alphas]) == 2


def test_the_tokens_one_wme_makes() -> None:
    rete = rete_with_block()
    before = read_rete(rete)
    rete.add_wme(WME(B1, "clear", "yes", 4))
    after = read_rete(rete)
    made = after.tokens_since(before)
    assert sorted(after.nodes[t.node].kind for t in made) == [
        "join", "join", "production", "production"]
    assert {format_token(t) for t in made} == {"⟨(3: S1 ^block B1), (4: B1 ^clear yes)⟩"}
    assert {p for t in made for p in after.nodes[t.node].productions} == {
        "grasp*propose", "block*free"}
    assert len(rete.take_changes()[0]) == 2


def test_a_blocked_negation_makes_no_match() -> None:
    rete = rete_with_block()
    rete.add_wme(WME(B1, "on", "table", 4))
    before = read_rete(rete)
    rete.add_wme(WME(B1, "clear", "yes", 5))
    after = read_rete(rete)
    negative = after.of_kind("negative")[0]
    # blocked: (B1 ^on table) matches -(<b> ^on <other>)
    assert (len(negative.tokens), negative.blocked) == (0, 1)
    ends = [after.nodes[t.node].label for t in after.tokens_since(before)
            if after.nodes[t.node].kind == "production"]
    assert ends == ["grasp*propose"]


def test_readings_of_different_networks_are_not_compared() -> None:
    rete = rete_with_block()
    before = read_rete(rete)
    rete.add_production(parse("sp {more (state <s> ^colour red) --> (<s> ^red yes)}")[0])
    with pytest.raises(ValueError, match="different networks"):
        read_rete(rete).tokens_since(before)


def test_the_drawing_has_a_box_per_node_and_memory() -> None:
    rete = rete_with_block()
    graph = read_rete(rete)
    figure = draw_rete(graph)
    try:
        boxes = figure.axes[0].patches
        titles = [t.get_text() for t in figure.axes[0].texts]
        assert sum(1 for t in titles if t.startswith(("N", "A"))) == len(graph.nodes) + len(
            graph.alphas)
        assert len(boxes) > len(graph.nodes) + len(graph.alphas)  # boxes and arrows
    finally:
        plt.close(figure)
