"""Fusion (paper eq. 2-3): logical sequences -> one probability-like column -> M x (N+1).

Eq. 3 gives each logical sequence the weight ``p = (1/N_dr)^(T_o - 1)``: ``T_o`` is the
target's 1-based position in the sequence and ``N_dr = 2`` the number of decision results
(graspable or not), so a sequence that grasps the target at once weighs 1, one that first
removes a blocker 1/2, and so on. Eq. 2 sums the weights over the ``R`` sequences the planner
found for the sample: ``P_target = sum_i p(i)``.

Eq. 2 is not a probability: with several sequences that grasp the target first it exceeds 1.
With rules/blocks.soar a target that is free on both side pairs gets two one-step sequences
(fingers along x, fingers along y), so ``P_target = 2``; a target that no plan reaches gets 0.
:func:`exceeds_one` flags those samples so the book can show them; :func:`logical_item` keeps
the paper's formula unchanged (the networks standardise their inputs anyway).
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

N_DR = 2


def sequence_probability(t_o: int, n_dr: int = N_DR) -> float:
    """Eq. 3: ``(1/n_dr) ** (t_o - 1)`` for a target at 1-based position ``t_o``."""
    if isinstance(t_o, bool) or not isinstance(t_o, int | np.integer) or t_o < 1:
        raise ValueError(f"T_o must be an integer >= 1 (a 1-based position), got {t_o!r}")
    if isinstance(n_dr, bool) or not isinstance(n_dr, int | np.integer) or n_dr < 1:
        raise ValueError(f"N_dr must be an integer >= 1, got {n_dr!r}")
    return float((1.0 / n_dr) ** (int(t_o) - 1))


def logical_item(sequences_t_o: Iterable[int], n_dr: int = N_DR) -> float:
    """Eq. 2: the sum of eq. 3 over the sequences' T_o values (0.0 for no sequence)."""
    return float(sum(sequence_probability(t, n_dr) for t in sequences_t_o))


def logical_column(t_o_lists: Iterable[Iterable[int]], n_dr: int = N_DR) -> np.ndarray:
    """The M x 1 column (as an (M,) float32 array): one eq.-2 value per sample."""
    return np.array([logical_item(ts, n_dr) for ts in t_o_lists], dtype=np.float32)


def exceeds_one(logical: np.ndarray) -> np.ndarray:
    """Boolean mask of samples whose eq.-2 value exceeds 1 (several sequences near the start)."""
    return np.asarray(logical) > 1.0


def fuse(features: np.ndarray, logical: np.ndarray) -> np.ndarray:
    """Append the logical column to the M x N feature array: M x (N+1), the fused input."""
    x = np.asarray(features)
    col = np.asarray(logical)
    if x.ndim != 2:
        raise ValueError(f"features must be a 2-D (M, N) array, got shape {x.shape}")
    if col.ndim == 2 and col.shape[1] == 1:
        col = col[:, 0]
    if col.ndim != 1 or len(col) != len(x):
        raise ValueError(f"logical must have one value per sample ({len(x)}), got shape "
                         f"{np.shape(logical)}")
    dtype = np.result_type(x.dtype, col.dtype, np.float32)
    return np.concatenate([x.astype(dtype, copy=False), col.astype(dtype)[:, None]], axis=1)
