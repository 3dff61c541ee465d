"""Programs on which our engine is known to differ from the Soar 9.6 kernel, kept out of the
classic corpus (whose every program must agree) so that the corpus says what holds.

Each case is a strict xfail with the measured difference as its reason: the day it agrees,
the test fails and the program goes back to ``rules/classic``.

farmer-wolf-goat-cabbage: with ``srand 2, 3, 5`` the kernel fires ``cross*alone`` before
``goat-eaten`` after the third crossing, so the two monitor writes of one wave come in the
other order. The 7-rule reproducer is test_firing_order's
``test_a_relinked_join_goes_before_its_linked_ancestor``: a join relinked while an ancestor
join on the same alpha memory is linked seems to go just before that ancestor in the memory's
list. Modelling that made this program agree but broke water-jug-lookahead (199 vs 200
decisions with --first), so the model is not yet the kernel's.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from test_classic_corpus import first_difference, kernel_run, our_run

FARMER = Path(__file__).resolve().parent / "known_differences" / "farmer-wolf-goat-cabbage.soar"


@pytest.mark.parametrize("seed", [1, 4])
def test_farmer_agrees_where_the_order_does_not_matter(seed: int) -> None:
    theirs, ours = kernel_run(FARMER, f"seed{seed}"), our_run(FARMER, f"seed{seed}")
    assert ours.output == theirs.output, first_difference(ours.output, theirs.output)


def test_farmer_first_selection_agrees() -> None:
    theirs, ours = kernel_run(FARMER, "first"), our_run(FARMER, "first")
    assert (ours.output, ours.operators, ours.decisions) == (
        theirs.output, theirs.operators, theirs.decisions)


@pytest.mark.xfail(strict=True, reason="a relinked join's place in its alpha memory (see module)")
@pytest.mark.parametrize("seed", [2, 3, 5])
def test_farmer_write_order_differs(seed: int) -> None:
    theirs, ours = kernel_run(FARMER, f"seed{seed}"), our_run(FARMER, f"seed{seed}")
    assert ours.output == theirs.output, first_difference(ours.output, theirs.output)
