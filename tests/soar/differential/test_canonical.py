"""canonical_wm: equal working memories compare equal whatever the identifiers' names and
the order the engines list them in."""

from __future__ import annotations

from .kernel import Graph, canonical_wm


def _things(order: list[str], names: dict[str, str]) -> Graph:
    """S1 with three things; ``linked`` refers to ``first``, which looks like ``other``."""
    t = names
    edges = {
        "first": [(("str", "kind"), ("str", "b"), False)],
        "linked": [(("str", "kind"), ("str", "c"), False),
                   (("str", "link"), ("id", t["first"]), False)],
        "other": [(("str", "kind"), ("str", "b"), False)],
    }
    graph: Graph = {"S1": [(("str", "thing"), ("id", t[k]), False) for k in order]}
    for k in order:
        graph[t[k]] = edges[k]
    return graph


def test_names_and_listing_order_do_not_matter() -> None:
    one = _things(["first", "linked", "other"],
                  {"first": "T1", "linked": "T2", "other": "T3"})
    two = _things(["other", "linked", "first"],
                  {"first": "T9", "linked": "T4", "other": "T2"})
    assert canonical_wm(one, ["S1"]) == canonical_wm(two, ["S1"])


def test_a_different_referent_is_a_difference() -> None:
    one = _things(["first", "linked", "other"],
                  {"first": "T1", "linked": "T2", "other": "T3"})
    two = _things(["first", "linked", "other"],
                  {"first": "T1", "linked": "T2", "other": "T3"})
    two["T2"] = [(("str", "kind"), ("str", "c"), False)]  # links nothing
    assert canonical_wm(one, ["S1"]) != canonical_wm(two, ["S1"])
