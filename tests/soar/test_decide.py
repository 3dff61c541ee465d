"""Soar 9.6 preference semantics on one operator slot, and the exploration policies."""

from __future__ import annotations

import random

import pytest

from sann.soar.decision import preference_semantics as dec
from sann.soar.goals import Goal
from sann.soar.instantiation import Instantiation
from sann.soar.memory import Identifier
from sann.soar.preferences import Preference, Slot, preference_type

S1 = Identifier("S", 1, level=1)


def slot_with(*prefs: tuple) -> tuple[Slot, dict[str, Identifier]]:
    """``("a", "+")``, ``("a", ">", "b")``, ``("a", "=", 0.5)`` ... on S1's operator slot."""
    slot = Slot(S1, "operator", True)
    ops: dict[str, Identifier] = {}
    inst = Instantiation("test", None, Goal(S1, None, slot), (), False)
    for spec in prefs:
        value = ops.setdefault(spec[0], Identifier("O", len(ops) + 1))
        referent = None
        if len(spec) == 3:
            ref = spec[2]
            referent = (
                ops.setdefault(ref, Identifier("O", len(ops) + 1)) if isinstance(ref, str) else ref
            )
        ptype = preference_type(spec[1], referent)
        slot.add(Preference(ptype, S1, "operator", value, referent, inst))
    return slot, ops


def decide(slot: Slot, policy: str = "first", seed: int = 0) -> tuple[str, list]:
    exploration = dec.Exploration(policy=policy, rng=random.Random(seed))
    return dec.run_preference_semantics(slot, exploration)


def test_single_acceptable_wins() -> None:
    slot, ops = slot_with(("a", "+"))
    assert decide(slot) == (dec.NONE, [ops["a"]])


def test_two_acceptables_tie_in_kernel_candidate_order() -> None:
    slot, ops = slot_with(("a", "+"), ("b", "+"))
    # Preferences go to the head of the list; candidates are pushed on the front again,
    # so candidates come out in the order the preferences were added.
    assert decide(slot) == (dec.TIE, [ops["a"], ops["b"]])


def test_reject_and_prohibit_remove_candidates() -> None:
    slot, ops = slot_with(("a", "+"), ("b", "+"), ("c", "+"), ("a", "-"), ("b", "~"))
    assert decide(slot) == (dec.NONE, [ops["c"]])


def test_all_rejected_means_no_candidates() -> None:
    slot, _ = slot_with(("a", "+"), ("a", "-"))
    assert decide(slot) == (dec.NONE, [])


def test_require_wins_even_without_acceptable() -> None:
    slot, ops = slot_with(("a", "+"), ("b", "!"))
    assert decide(slot) == (dec.NONE, [ops["b"]])


def test_two_requires_or_require_and_prohibit_fail() -> None:
    slot, _ = slot_with(("a", "!"), ("b", "!"))
    assert decide(slot)[0] == dec.CONSTRAINT_FAILURE
    slot, ops = slot_with(("a", "!"), ("a", "~"))
    assert decide(slot) == (dec.CONSTRAINT_FAILURE, [ops["a"]])


def test_better_and_worse_leave_the_one_nothing_beats() -> None:
    slot, ops = slot_with(("a", "+"), ("b", "+"), ("c", "+"), ("a", ">", "b"), ("c", "<", "a"))
    assert decide(slot) == (dec.NONE, [ops["a"]])


def test_conflict_only_when_nothing_else_is_left() -> None:
    slot, ops = slot_with(("a", "+"), ("b", "+"), ("a", ">", "b"), ("b", ">", "a"))
    assert decide(slot)[0] == dec.CONFLICT
    slot, ops = slot_with(("a", "+"), ("b", "+"), ("c", "+"), ("a", ">", "b"), ("b", ">", "a"))
    assert decide(slot) == (dec.NONE, [ops["c"]])  # the kernel selects c


def test_best_wins_worst_loses_and_all_worst_tie() -> None:
    slot, ops = slot_with(("a", "+"), ("b", "+"), ("c", "+"), ("b", ">"))
    assert decide(slot) == (dec.NONE, [ops["b"]])
    slot, ops = slot_with(("a", "+"), ("b", "+"), ("a", "<"))
    assert decide(slot) == (dec.NONE, [ops["b"]])
    slot, ops = slot_with(("a", "+"), ("b", "+"), ("a", "<"), ("b", "<"))
    assert decide(slot)[0] == dec.TIE  # all worst: none is dropped


def test_indifference_unary_binary_numeric() -> None:
    slot, ops = slot_with(("a", "+"), ("b", "+"), ("a", "="), ("b", "="))
    assert decide(slot, "first") == (dec.NONE, [ops["a"]])
    assert decide(slot, "last") == (dec.NONE, [ops["b"]])
    slot, ops = slot_with(("a", "+"), ("b", "+"), ("a", "=", "b"))
    assert decide(slot)[0] == dec.NONE
    slot, ops = slot_with(("a", "+"), ("b", "+"), ("a", "=", 0.5))
    assert decide(slot)[0] == dec.TIE  # b is not indifferent to anything
    slot, ops = slot_with(("a", "+"), ("b", "+"), ("a", "=", 0.5), ("b", "=", 0.2))
    assert decide(slot)[0] == dec.NONE


def test_consistency_mode_returns_all_indifferent_candidates() -> None:
    slot, ops = slot_with(("a", "+"), ("b", "+"), ("a", "="), ("b", "="))
    assert dec.run_preference_semantics(slot, None, consistency=True) == (
        dec.NONE,
        [ops["a"], ops["b"]],
    )


@pytest.mark.parametrize("policy", ["softmax", "boltzmann", "epsilon-greedy", "random"])
def test_random_policies_are_seeded_and_follow_weights(policy: str) -> None:
    slot, ops = slot_with(("a", "+"), ("b", "+"), ("a", "=", 0.9), ("b", "=", 0.1))
    picks = [decide(slot, policy, seed)[1][0] for seed in range(300)]
    again = [decide(slot, policy, seed)[1][0] for seed in range(300)]
    assert picks == again
    share = picks.count(ops["a"]) / len(picks)
    if policy in ("softmax", "epsilon-greedy"):
        assert share > 0.8
    else:
        assert 0.3 < share < 0.7  # boltzmann at temperature 25 and random: near uniform


def test_numeric_values_sum_or_average() -> None:
    slot, ops = slot_with(("a", "+"), ("a", "=", 0.5), ("a", "=", 0.25), ("b", "+"))
    assert dec.numeric_values(slot, [ops["a"], ops["b"]]) == [0.75, 0.0]
    assert dec.numeric_values(slot, [ops["a"]], "avg") == [0.375]


def test_non_operator_slot_keeps_all_unrejected_values() -> None:
    slot = Slot(S1, "color", False)
    inst = Instantiation("t", None, Goal(S1, None, Slot(S1, "operator", True)), (), False)
    for value, kind in (("red", "+"), ("blue", "+"), ("red", "-")):
        slot.add(Preference(kind, S1, "color", value, None, inst))
    assert dec.run_preference_semantics(slot, None) == (dec.NONE, ["blue"])
