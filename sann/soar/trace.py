"""Text the kernel prints: ``print`` of an identifier, WMEs and preferences in traces.

``print --depth N id`` lists the identifier's augmentations sorted by attribute, wrapping
before column 80 with a 7-space continuation, then the identifiers it links to, depth
first, indented two spaces per level and each printed once.  The kernel counts columns on
its output stream, so a print that starts after unfinished trace output (``     1:
==>S: S2 (state no-change)`` has no newline) wraps its first line that much earlier
(measured).
"""

from __future__ import annotations

from collections.abc import Callable

from .memory import WME, Identifier, Symbol, format_symbol

COLUMNS = 80


def symbol_text(value: Symbol) -> str:
    """A symbol as ``print`` shows it: floats as ``%f``, odd strings in bars
    (`memory.format_symbol`)."""
    return format_symbol(value)


def trace_wme(wme: WME) -> str:
    plus = " +" if wme.acceptable else ""
    return (
        f"({wme.timetag}: {symbol_text(wme.id)} ^{symbol_text(wme.attr)}"
        f" {symbol_text(wme.value)}{plus})"
    )


def trace_preference(sign: str, pref: object) -> str:
    """``+ (S1 ^count 0 +  :O ) (apply*init)\n``: the kernel's watch-5 line for a
    preference asserted (``sign`` '+') or removed ('-'); one made in a substate says its
    level, ``+ (S2 ^local yes +) [level 2] (s*elab)`` (measured in soar_sml)."""
    p = pref  # a Preference; typed loosely to avoid an import cycle
    kind = p.type[-1]  # type: ignore[attr-defined]
    referent = p.referent  # type: ignore[attr-defined]
    ref = f" {symbol_text(referent)}" if referent is not None else ""
    support = "  :O " if p.o_supported else ""  # type: ignore[attr-defined]
    inst = p.inst  # type: ignore[attr-defined]
    level = inst.goal.level
    where = f" [level {level}]" if level > 1 else ""
    return (
        f"{sign} ({symbol_text(p.id)} ^{symbol_text(p.attr)} {symbol_text(p.value)}"  # type: ignore[attr-defined]
        f" {kind}{ref}{support}){where} ({symbol_text(inst.name)})\n"
    )


def _sort_key(wme: WME) -> tuple[str, bool, int]:
    """The kernel sorts by attribute only (stably) over lists kept newest first."""
    return (symbol_text(wme.attr), wme.acceptable, -wme.timetag)


def format_augmentations(ident: Identifier, wmes: list[WME], indent: int,
                         column: int = 0) -> str:
    """One ``(id ^a v ...)`` block with the kernel's line wrapping; ``column``: where the
    output stream's current line already is."""
    line = " " * indent + f"({ident.name}"
    lines: list[str] = []
    for wme in sorted(wmes, key=_sort_key):
        item = f" ^{symbol_text(wme.attr)} {symbol_text(wme.value)}"
        if wme.acceptable:
            item += " +"
        if column + len(line) + len(item) >= COLUMNS - 1:
            lines.append(line)
            line = " " * (indent + 6)
            column = 0
        line += item
    lines.append(line + ")")
    return "\n".join(lines)


def print_identifier(
    ident: Identifier, depth: int, augmentations: Callable[[Identifier], list[WME]],
    column: int = 0,
) -> str:
    """``print --depth depth ident``: the identifier, then linked identifiers depth first;
    ``column``: where the output stream's current line already is."""
    if depth < 1:
        depth = 1
    printed: set[int] = set()
    blocks: list[str] = []

    def visit(node: Identifier, level: int) -> None:
        printed.add(id(node))
        wmes = augmentations(node)
        if not wmes and level > 0:
            return
        blocks.append(format_augmentations(node, wmes, 2 * level, 0 if blocks else column))
        if level + 1 >= depth:
            return
        for wme in sorted(wmes, key=_sort_key):
            value = wme.value
            if isinstance(value, Identifier) and id(value) not in printed:
                visit(value, level + 1)

    visit(ident, 0)
    return "\n".join(blocks) + "\n"
