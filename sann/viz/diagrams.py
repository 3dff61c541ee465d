"""The SANN architecture (the paper's Fig. 2) drawn from the sizes of the real objects.

The book draws the diagram from the network it trains — the layer widths are read off the
torch module — so the picture cannot drift from the code.
"""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib.pyplot as plt
from matplotlib.figure import Figure
from matplotlib.patches import Circle, FancyArrowPatch, FancyBboxPatch

SOAR_COLOUR, FUSION_COLOUR, ANN_COLOUR, DATA_COLOUR = "#fbe3c2", "#dbe9f6", "#e3f1de", "#eeeeee"
#: The Soar planning cycle as the paper runs it (Fig. 4): four of Soar's five phases.
SOAR_PHASES = ("input", "elaborate + propose", "decide", "apply", "output")


def linear_widths(model: object) -> list[int]:
    """Widths of the layers a torch model really uses: the input, then each Linear's output.

    The model is run once on a zero input with hooks on its Linear layers, so layers that exist
    but are skipped in ``forward`` (a shared shallow net's own head inside the deep net) are
    not drawn.
    """
    import torch
    from torch import nn

    linears = [m for m in model.modules() if isinstance(m, nn.Linear)]  # type: ignore[attr-defined]
    if not linears:
        raise ValueError("the model has no Linear layer to draw")
    used: list[nn.Linear] = []
    hooks = [m.register_forward_hook(lambda mod, _i, _o: used.append(mod)) for m in linears]
    try:
        with torch.no_grad():
            model(torch.zeros(1, linears[0].in_features))  # type: ignore[operator]
    finally:
        for hook in hooks:
            hook.remove()
    return [used[0].in_features] + [layer.out_features for layer in used]


def _box(ax, x: float, y: float, w: float, h: float, colour: str, title: str, body: str) -> None:
    ax.add_patch(
        FancyBboxPatch((x, y), w, h, boxstyle="round,pad=0.02,rounding_size=0.08",
                       fc=colour, ec="#555555", lw=1.2)
    )
    ax.text(x + w / 2, y + h - 0.12, title, ha="center", va="top", fontsize=11, weight="bold")
    ax.text(x + w / 2, y + h - 0.45, body, ha="center", va="top", fontsize=8.5, linespacing=1.4)


def _arrow(ax, start: tuple[float, float], end: tuple[float, float], label: str = "",
           below: bool = False) -> None:
    ax.add_patch(FancyArrowPatch(start, end, arrowstyle="-|>", mutation_scale=14, lw=1.3,
                                 color="#333333", connectionstyle="arc3,rad=0.0"))
    if label:
        mid = ((start[0] + end[0]) / 2, (start[1] + end[1]) / 2)
        offset, align = (-0.1, "top") if below else (0.08, "bottom")
        ax.text(mid[0], mid[1] + offset, label, ha="center", va=align, fontsize=8,
                style="italic")


def _network(ax, x0: float, x1: float, y0: float, y1: float, widths: Sequence[int],
             max_drawn: int = 16) -> None:
    """Neurons as circles, every layer fully connected to the next (capped at ``max_drawn``)."""
    columns = []
    for i, width in enumerate(widths):
        x = x0 + (x1 - x0) * i / max(1, len(widths) - 1)
        shown = min(width, max_drawn)
        ys = [y0 + (y1 - y0) * (k + 0.5) / shown for k in range(shown)]
        columns.append((x, ys))
        label = f"{width}" + (" (…)" if width > shown else "")
        ax.text(x, y0 - 0.12, label, ha="center", va="top", fontsize=8.5)
    for (xa, ya), (xb, yb) in zip(columns, columns[1:], strict=False):
        for a in ya:
            for b in yb:
                ax.plot([xa, xb], [a, b], color="#8aa58a", lw=0.4, zorder=1)
    radius = min(0.07, (y1 - y0) / (2.6 * min(max(widths), max_drawn)))
    for x, ys in columns:
        for y in ys:
            ax.add_patch(Circle((x, y), radius, fc="white", ec="#2e7d32", lw=1.0, zorder=2))


def architecture_figure(
    layer_widths: Sequence[int],
    n_features: int,
    n_decisions: int = 2,
    title: str = "SANN: Soar module, fusion, ANN",
) -> Figure:
    """Draw Fig. 2 for a network with the given layer widths.

    ``n_features`` is N, the width of the task's raw feature rows; the network's input width
    must be N + 1 (the fused logical item), which is checked so the diagram never lies.
    """
    widths = list(layer_widths)
    if len(widths) < 2 or min(widths) < 1:
        raise ValueError(f"need at least an input and an output layer, got {widths}")
    if widths[0] != n_features + 1:
        raise ValueError(
            f"a SANN net takes N + 1 = {n_features + 1} inputs (features + logical item), "
            f"this one takes {widths[0]}"
        )
    fig, ax = plt.subplots(figsize=(11, 4.6))
    ax.set_xlim(0, 11)
    ax.set_ylim(-0.4, 4.6)
    ax.axis("off")
    _box(ax, 0.1, 1.3, 1.9, 1.8, DATA_COLOUR, "Task data",
         f"scene or pile\nM samples\n× N = {n_features} features")
    phases = "\n".join(f"{i + 1}. {p}" for i, p in enumerate(SOAR_PHASES))
    _box(ax, 2.6, 2.3, 2.4, 2.2, SOAR_COLOUR, "Soar module",
         f"rules plan the grasps\n{phases}\n→ R logical sequences")
    _box(ax, 5.6, 2.3, 2.1, 2.2, FUSION_COLOUR, "Fusion",
         "p = (1/N$_{dr}$)$^{T_o-1}$\n"
         f"N$_{{dr}}$ = {n_decisions}\n"
         "P$_{target}$ = Σ$_{i=1}^{R}$ p(i)\n"
         f"M × {n_features} ⊕ M × 1\n= M × {n_features + 1}")
    _box(ax, 8.1, -0.1, 2.8, 4.6, ANN_COLOUR, "ANN", "")
    _network(ax, 8.5, 10.5, 0.35, 3.85, widths)
    _arrow(ax, (2.0, 2.6), (2.6, 3.3), "input-link")
    _arrow(ax, (5.0, 3.4), (5.6, 3.4), "T$_o$")
    _arrow(ax, (2.0, 1.8), (5.6, 2.45), "features", below=True)
    _arrow(ax, (7.7, 3.0), (8.1, 2.4))
    ax.text(9.5, -0.32, f"{n_decisions} outputs: graspable or not", ha="center", fontsize=8.5)
    ax.set_title(title, fontsize=12)
    fig.tight_layout()
    return fig
