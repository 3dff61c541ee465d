"""Working memory as a graph (Fig. 7): what is read from an agent, and how it is laid out."""

from __future__ import annotations

import pytest

from sann.soar import Agent
from sann.viz.wm_graph import MAX_SHOWN, _short, draw_wm, tree_layout, wm_nodes

RULES = """
sp {build (state <s> ^superstate nil) -->
   (<s> ^scene <sc> ^plan <p>)
   (<sc> ^block <a> <b>)
   (<a> ^name A ^x 1.5 ^on <b>)
   (<b> ^name B ^x 2.0)
   (<p> ^first <a> ^steps 2)}
"""


@pytest.fixture()
def agent() -> Agent:
    agent = Agent()
    agent.load(RULES)
    agent.run(1)
    return agent


def test_nodes_are_the_identifiers_reachable_from_the_state(agent: Agent) -> None:
    nodes = wm_nodes(agent)
    assert "S1" in nodes and len(nodes) >= 5
    names = {n.constants[0][1]: n for n in nodes.values() if n.constants[:1]
             and n.constants[0][0] == "name"}
    a, b = names["A"], names["B"]
    assert ("x", "1.500000") in a.constants and [c for _, c in a.children] == [b.name]
    assert not any(attr in ("epmem", "smem", "reward-link") for attr, _ in nodes["S1"].children)


def test_the_scene_branch_owns_the_blocks_and_other_links_are_dashed(agent: Agent) -> None:
    nodes = wm_nodes(agent)
    places, edges = tree_layout(nodes, "S1")
    assert set(places) == set(nodes)
    tree = [(up, attr, child) for up, attr, child, in_tree in edges if in_tree]
    assert len(tree) == len(nodes) - 1  # a spanning tree: every node but the root once
    by_attr = {attr: in_tree for _, attr, _, in_tree in edges}
    assert by_attr["block"] and not by_attr["first"] and not by_attr["on"]
    scene = next(child for up, attr, child, _ in edges if attr == "scene")
    assert all(places[c][0] == places[scene][0] + 1 for up, a, c, t in edges if a == "block")


def test_drawing_has_a_box_per_identifier(agent: Agent) -> None:
    nodes = wm_nodes(agent)
    fig = draw_wm(nodes, title="t", highlight=["S1"])
    texts = [t.get_text() for t in fig.axes[0].texts]
    assert sum(1 for t in texts if t.split("\n")[0] in nodes) == len(nodes)
    assert MAX_SHOWN >= 1


def test_float_values_are_shortened_and_others_kept() -> None:
    assert _short("45.000000") == "45.0" and _short("12.500000") == "12.5"
    assert _short("-3.250000") == "-3.25" and _short("x.y") == "x.y" and _short("7") == "7"


def test_unknown_root_is_an_error(agent: Agent) -> None:
    with pytest.raises(KeyError):
        wm_nodes(agent, root="Z9")
