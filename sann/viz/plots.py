"""The paper's 2D figures, drawn with matplotlib from numbers the experiments computed.

Each function takes the data, returns the Figure (so a chapter can show it) and optionally
writes a PNG (so `python -m sann reproduce ...` leaves files behind).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

ANN_COLOUR, SANN_COLOUR = "#2e9e44", "#d6336c"  # the paper's green ANN and pink SANN lines


def _save(fig: Figure, path: str | Path | None) -> Figure:
    if path is not None:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=120, bbox_inches="tight")
    return fig


def error_curves(
    curves: Mapping[str, Sequence[Sequence[float]]],
    title: str,
    path: str | Path | None = None,
    colours: Mapping[str, str] | None = None,
) -> Figure:
    """Test error per epoch (eq. 4), mean over seeds with the min-max band (Figs. 8, 12)."""
    colours = colours or {"ann": ANN_COLOUR, "dnn": ANN_COLOUR, "sann": SANN_COLOUR}
    fig, ax = plt.subplots(figsize=(6, 3.6))
    for name, runs in curves.items():
        data = np.asarray(runs, dtype=float)
        epochs = np.arange(1, data.shape[1] + 1)
        colour = colours.get(name)
        ax.plot(epochs, data.mean(axis=0), label=name.upper(), color=colour)
        ax.fill_between(epochs, data.min(axis=0), data.max(axis=0), color=colour, alpha=0.2)
    ax.set_xlabel("epoch")
    ax.set_ylabel("test error")
    ax.set_title(title)
    ax.legend()
    ax.grid(alpha=0.3)
    return _save(fig, path)


def accuracy_bars(
    table: Mapping[str, Mapping[str, Mapping[str, object]]],
    title: str,
    path: str | Path | None = None,
) -> Figure:
    """Mean accuracy with 95% intervals per mode, ANN vs SANN side by side (Fig. 9)."""
    modes = list(table)
    nets = list(next(iter(table.values())))
    fig, ax = plt.subplots(figsize=(6, 3.6))
    width = 0.8 / len(nets)
    for i, net in enumerate(nets):
        means = np.array([table[m][net]["mean"] for m in modes]) * 100
        lows = np.array([table[m][net]["ci95"][0] for m in modes]) * 100
        highs = np.array([table[m][net]["ci95"][1] for m in modes]) * 100
        x = np.arange(len(modes)) + (i - (len(nets) - 1) / 2) * width
        colour = SANN_COLOUR if net == "sann" else ANN_COLOUR
        ax.bar(x, means, width, yerr=[means - lows, highs - means], label=net.upper(),
               color=colour, capsize=3)
        for xi, m in zip(x, means, strict=True):
            ax.text(xi, m + 0.3, f"{m:.1f}", ha="center", va="bottom", fontsize=7)
    ax.set_xticks(np.arange(len(modes)), modes)
    floor = min(table[m][n]["ci95"][0] for m in modes for n in nets) * 100
    ax.set_ylim(max(0.0, floor - 5), 100.5)
    ax.set_ylabel("test accuracy (%)")
    ax.set_title(title)
    ax.legend(loc="lower left")
    return _save(fig, path)


def tsne_pair(
    embeddings: Mapping[str, np.ndarray],
    labels: np.ndarray,
    title: str,
    path: str | Path | None = None,
) -> Figure:
    """Two t-SNE maps side by side (ANN left, SANN right), coloured by label (Figs. 13, 14)."""
    fig, axes = plt.subplots(1, len(embeddings), figsize=(4.2 * len(embeddings), 4))
    for ax, (name, points) in zip(np.atleast_1d(axes), embeddings.items(), strict=True):
        for label, colour, text in ((0, "#868e96", "not graspable"), (1, SANN_COLOUR, "graspable")):
            chosen = labels == label
            ax.scatter(points[chosen, 0], points[chosen, 1], s=4, color=colour, label=text)
        ax.set_title(name)
        ax.set_xticks([])
        ax.set_yticks([])
    np.atleast_1d(axes)[0].legend(loc="best", markerscale=3, fontsize=8)
    fig.suptitle(title)
    return _save(fig, path)


def learning_curves(
    curves: Mapping[str, Mapping[str, object]],
    title: str,
    path: str | Path | None = None,
) -> Figure:
    """Test accuracy against training size, one panel per dataset: ANN and SANN (mean with
    the 95% interval as a band) and the rules alone (flat: they do not learn). ``curves``
    maps a dataset name to its ``learning_curve`` entry of the blocks results."""
    names = list(curves)
    cols = min(3, len(names))
    rows = math.ceil(len(names) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 3 * rows), squeeze=False,
                             sharex=True)
    for ax, name in zip(axes.flat, names, strict=False):
        curve = curves[name]
        sizes = np.asarray(curve["sizes"], dtype=float)
        for net, colour in (("ann", ANN_COLOUR), ("sann", SANN_COLOUR)):
            points = curve[net]
            mean = np.array([p["mean"] for p in points]) * 100
            low = np.array([p["ci95"][0] for p in points]) * 100
            high = np.array([p["ci95"][1] for p in points]) * 100
            ax.plot(sizes, mean, marker="o", ms=3, color=colour, label=net.upper())
            ax.fill_between(sizes, low, high, color=colour, alpha=0.2)
        rules = curve["rules"]
        ax.axhline(rules["mean"] * 100, color="#444444", ls="--", lw=1, label="rules alone")
        ax.set_xscale("log")
        ax.set_title(name, fontsize=9)
        ax.grid(alpha=0.3)
    for ax in axes.flat[len(names):]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("training samples")
    for ax in axes[:, 0]:
        ax.set_ylabel("test accuracy (%)")
    axes.flat[0].legend(fontsize=7, loc="lower right")
    fig.suptitle(title)
    fig.tight_layout()
    return _save(fig, path)
