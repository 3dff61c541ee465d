"""Small helpers the book's chapters share: HTML tables, interval cells, differences and
parameter counts (a notebook's Markdown output is rendered without table support, and the
book has no pandas)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from html import escape

from IPython.display import HTML


def table(header: Sequence[object], rows: Sequence[Sequence[object]]) -> HTML:
    """An HTML table; every cell is shown as ``str(cell)``, escaped."""
    head = "".join(f"<th>{escape(str(h))}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{escape(str(c))}</td>" for c in row) + "</tr>"
                   for row in rows)
    return HTML(f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>")


def interval(summary: Mapping[str, object], digits: int = 1) -> str:
    """``"mean% [low%, high%]"`` of a summary with ``mean`` and ``ci95`` (fractions)."""
    low, high = summary["ci95"]  # type: ignore[misc]
    return f"{summary['mean']:.{digits}%} [{low:.{digits}%}, {high:.{digits}%}]"


def points(a: Mapping[str, Mapping[str, float]], b: Mapping[str, Mapping[str, float]],
           keys: Sequence[str]) -> tuple[float, ...]:
    """``a[k] - b[k]`` for each key, in percentage points (values are fractions)."""
    return tuple(100 * (a[k] - b[k]) for k in keys)  # type: ignore[operator]


def n_parameters(module, trainable_only: bool = True) -> int:
    """Number of (trainable) numbers in a torch module."""
    return sum(p.numel() for p in module.parameters()
               if p.requires_grad or not trainable_only)
