"""Soar 9.6 preference semantics for a slot, and the exploration policies of indifferent choice.

`run_preference_semantics` follows the kernel's ``run_preference_semantics`` step by step
(require/prohibit, acceptable minus reject/prohibit, better/worse with conflict detection,
best, worst, indifference) so that impasses and candidate orders agree with it.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass

from ..memory import Identifier, Symbol
from ..preferences import (
    ACCEPTABLE,
    BEST,
    BETTER,
    BINARY_INDIFFERENT,
    NUMERIC_INDIFFERENT,
    PROHIBIT,
    REJECT,
    REQUIRE,
    UNARY_INDIFFERENT,
    WORSE,
    WORST,
    Slot,
)
from ..rhs.rand import kernel_rand_int

NONE = "none"
TIE = "tie"
CONFLICT = "conflict"
CONSTRAINT_FAILURE = "constraint-failure"
NO_CHANGE = "no-change"

POLICIES = ("first", "last", "softmax", "epsilon-greedy", "boltzmann", "random")


@dataclass
class Exploration:
    """The ``indifferent-selection`` settings (kernel defaults) and the seeded generator."""

    policy: str = "softmax"
    epsilon: float = 0.1
    temperature: float = 25.0
    numeric_mode: str = "sum"
    rng: random.Random | None = None

    def __post_init__(self) -> None:
        if self.rng is None:
            self.rng = random.Random(0)


def run_preference_semantics(
    slot: Slot, exploration: Exploration | None, consistency: bool = False
) -> tuple[str, list[Symbol]]:
    """Return ``(impasse type, candidates)``; with a winner the list holds just the winner.

    With ``consistency`` (the mid-phase check of the selected operator) indifferent
    candidates are all returned instead of choosing one at random.
    """
    prefs = slot.prefs
    if len(prefs) == 1:  # the usual slot: one acceptable preference and nothing else
        only = prefs.get(ACCEPTABLE)
        if only is not None and len(only) == 1:
            return NONE, [only[0].value]
    if slot.of_type(REQUIRE):
        return _require_semantics(slot)
    candidates = _acceptable_candidates(slot)
    if not slot.is_context or len(candidates) <= 1:
        return NONE, candidates
    if slot.of_type(BETTER) or slot.of_type(WORSE):
        conflicted, candidates = _better_worse(slot, candidates)
        if conflicted:
            return CONFLICT, conflicted
    candidates = _best_worst(slot, candidates)
    if len(candidates) <= 1:
        return NONE, candidates
    if not _all_indifferent(slot, candidates):
        return TIE, candidates
    if consistency or exploration is None:
        return NONE, candidates
    return NONE, [choose(slot, candidates, exploration)]


def _push_front_unique(values: list[Symbol]) -> list[Symbol]:
    """The kernel builds candidate lists by pushing each new value on the front."""
    seen: set[object] = set()
    out: list[Symbol] = []
    for value in values:
        key = _key(value)
        if key not in seen:
            seen.add(key)
            out.append(value)
    out.reverse()
    return out


def _key(value: Symbol | None) -> object:
    """Symbols compare by type and value (``1`` and ``1.0`` are different symbols);
    identifiers by identity."""
    return id(value) if type(value) is Identifier else (type(value), value)


def _require_semantics(slot: Slot) -> tuple[str, list[Symbol]]:
    required = _push_front_unique([p.value for p in slot.of_type(REQUIRE)])
    if len(required) > 1:
        return CONSTRAINT_FAILURE, required
    value = required[0]
    if any(_key(p.value) == _key(value) for p in slot.of_type(PROHIBIT)):
        return CONSTRAINT_FAILURE, required
    return NONE, required


def _acceptable_candidates(slot: Slot) -> list[Symbol]:
    excluded = {_key(p.value) for p in slot.of_type(PROHIBIT)}
    excluded.update(_key(p.value) for p in slot.of_type(REJECT))
    values = [p.value for p in slot.of_type(ACCEPTABLE) if _key(p.value) not in excluded]
    return _push_front_unique(values)


def _better_worse(slot: Slot, candidates: list[Symbol]) -> tuple[list[Symbol], list[Symbol]]:
    """Remove dominated and conflicted candidates; return (the conflict impasse's items,
    remaining): no items while a candidate remains.

    As in the 9.6 kernel, a conflict impasse arises only when no candidate is left that is
    neither dominated nor in conflict: ``a > b, b > a`` with a third candidate ``c`` selects
    ``c``."""
    flags: dict[object, str] = {}
    better = slot.of_type(BETTER)
    worse = slot.of_type(WORSE)
    for cand in candidates:
        flags[_key(cand)] = "candidate"
    better_pairs = {(_key(p.value), _key(p.referent)) for p in better}
    worse_pairs = {(_key(p.value), _key(p.referent)) for p in worse}
    for pref in better:
        j, k = _key(pref.value), _key(pref.referent)
        if j == k or j not in flags or k not in flags:
            continue
        if flags[k] != "conflicted":
            flags[k] = "former"
        if (k, j) in better_pairs or (j, k) in worse_pairs:
            flags[j] = flags[k] = "conflicted"
    for pref in worse:
        j, k = _key(pref.value), _key(pref.referent)
        if j == k or j not in flags or k not in flags:
            continue
        if flags[j] != "conflicted":
            flags[j] = "former"
        if (k, j) in worse_pairs:
            flags[j] = flags[k] = "conflicted"
    remaining = [c for c in candidates if flags[_key(c)] == "candidate"]
    if remaining:
        return [], remaining
    # The conflict impasse's items are all the candidates, dominated ones too (measured in
    # soar_sml: a > b, b > a, a > c makes items a, b and c).
    return list(candidates), candidates


def _best_worst(slot: Slot, candidates: list[Symbol]) -> list[Symbol]:
    if slot.of_type(BEST):
        best = {_key(p.value) for p in slot.of_type(BEST)}
        kept = [c for c in candidates if _key(c) in best]
        if kept:
            candidates = kept
    if slot.of_type(WORST):
        worst = {_key(p.value) for p in slot.of_type(WORST)}
        kept = [c for c in candidates if _key(c) not in worst]
        if kept:
            candidates = kept
    return candidates


def _all_indifferent(slot: Slot, candidates: list[Symbol]) -> bool:
    unary = {_key(p.value) for p in slot.of_type(UNARY_INDIFFERENT)}
    unary.update(_key(p.value) for p in slot.of_type(NUMERIC_INDIFFERENT))
    pairs = set()
    for pref in slot.of_type(BINARY_INDIFFERENT):
        pairs.add((_key(pref.value), _key(pref.referent)))
        pairs.add((_key(pref.referent), _key(pref.value)))
    for cand in candidates:
        ck = _key(cand)
        if ck in unary:
            continue
        for other in candidates:
            ok = _key(other)
            if ok != ck and (ck, ok) not in pairs:
                return False
    return True


def numeric_values(slot: Slot, candidates: list[Symbol], mode: str = "sum") -> list[float]:
    """Each candidate's numeric-indifferent value (sum, or average with ``--avg``)."""
    totals: dict[object, float] = {}
    counts: dict[object, int] = {}
    for pref in slot.of_type(NUMERIC_INDIFFERENT):
        key = _key(pref.value)
        totals[key] = totals.get(key, 0.0) + float(pref.referent)  # type: ignore[arg-type]
        counts[key] = counts.get(key, 0) + 1
    values = []
    for cand in candidates:
        key = _key(cand)
        total = totals.get(key, 0.0)
        if mode == "avg" and counts.get(key):
            total /= counts[key]
        values.append(total)
    return values


def choose(slot: Slot, candidates: list[Symbol], exploration: Exploration) -> Symbol:
    """Pick one of several mutually indifferent candidates by the exploration policy."""
    policy = exploration.policy
    rng = exploration.rng
    assert rng is not None
    if policy == "first":
        return candidates[0]
    if policy == "last":
        return candidates[-1]
    if policy == "random":
        return candidates[kernel_rand_int(rng, len(candidates) - 1)]
    values = numeric_values(slot, candidates, exploration.numeric_mode)
    if policy == "softmax":
        return _softmax(candidates, values, rng)
    if policy == "boltzmann":
        return _boltzmann(candidates, values, exploration.temperature, rng)
    return _epsilon_greedy(candidates, values, exploration.epsilon, rng)


def _kernel_real(rng: random.Random) -> float:
    """The kernel's ``SoarRand()`` (MTRand's ``rand``): one 32-bit draw over 2**32 - 1."""
    return rng.getrandbits(32) * (1.0 / 4294967295.0)


def _softmax(candidates: list[Symbol], values: list[float], rng: random.Random) -> Symbol:
    """The kernel's 'softmax': proportional to the positive numeric values, else uniform."""
    total = sum(v for v in values if v > 0)
    if total <= 0:
        return candidates[kernel_rand_int(rng, len(candidates) - 1)]
    target = _kernel_real(rng) * total
    running = 0.0
    for cand, value in zip(candidates, values, strict=True):
        if value > 0:
            running += value
            if target <= running:
                return cand
    return candidates[-1]


def _boltzmann(
    candidates: list[Symbol], values: list[float], temperature: float, rng: random.Random
) -> Symbol:
    top = max(values)
    weights = [math.exp((v - top) / temperature) for v in values]
    target = _kernel_real(rng) * sum(weights)
    running = 0.0
    for cand, weight in zip(candidates, weights, strict=True):
        running += weight
        if target <= running:
            return cand
    return candidates[-1]


def _epsilon_greedy(
    candidates: list[Symbol], values: list[float], epsilon: float, rng: random.Random
) -> Symbol:
    if _kernel_real(rng) < epsilon:
        return candidates[kernel_rand_int(rng, len(candidates) - 1)]
    top = max(values)
    best = [c for c, v in zip(candidates, values, strict=True) if v == top]
    return best[kernel_rand_int(rng, len(best) - 1)] if len(best) > 1 else best[0]
