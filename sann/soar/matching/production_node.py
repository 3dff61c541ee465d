"""The bottom of a production in the beta network: its tokens are its matches."""

from __future__ import annotations

from collections.abc import Callable

from sann.soar.codegen import define
from sann.soar.matching.matches import Changes, Match
from sann.soar.matching.nodes import Node
from sann.soar.matching.templates import token_lines
from sann.soar.matching.tokens import Token, compile_first, new_object
from sann.soar.memory import WME, mypyc_attr
from sann.soar.production import Production


@mypyc_attr(native_class=False)  # methods and generated functions in the same places
class ProductionNode(Node):
    """Bottom of a production: each token is a Match.

    Both activations are generated for the production (on first use) as straight-line
    code, the Match made inline (``Layout.match_lines``): most matches are fired, which
    needs all their fields, and compiled methods of this class would reach the tokens'
    and matches' slots through the generic attribute lookup, several times slower than
    the interpreter's specialized slot access."""

    __slots__ = ("production", "layout", "added", "removed", "left_activate", "forget")

    def __init__(self, registry: dict[WME, list], parent: Node, production: Production,
                 layout: Layout, changes: Changes) -> None:
        super().__init__(registry, parent, ("production", production.name))
        self.production = production
        self.layout = layout
        # the Rete's Changes, whose dicts are emptied in place (never replaced)
        self.added = changes.added
        self.removed = changes.removed
        self.left_activate: Callable[[Token], None]
        self.forget: Callable[[Token], None]
        compile_first(self, "left_activate", "forget")

    def _compile(self) -> None:
        """Generate ``left_activate`` (make the Match and its token, report it) and
        ``forget`` (drop the token; retract its Match, or cancel its appearance in this
        interval, as ``Changes.retract`` does; a token without a Match is one whose Match
        moved to a rebuilt network, see Rete._rebuild)."""
        namespace: dict[str, object] = {
            "NEW": new_object, "Match": Match, "P": self.production, "Tok": Token, "N": self,
            "T": self.tokens, "A": self.added, "D": self.removed}
        left = ["def left_activate(t):", *self.layout.match_lines("t", "    "),
                *token_lines("    ", "t", "None", "None"), "    tok.extra = m",
                "    s = t.children", "    if s is None: t.children = {tok: None}",
                "    else: s[tok] = None", "    T[tok] = None", "    A[m] = None"]
        forget = ["def forget(tok):", "    del T[tok]", "    m = tok.extra",
                  "    if m is not None:", "        if m in A: del A[m]",
                  "        else: D[m] = None"]
        self.left_activate = define(left, namespace, "left_activate")
        self.forget = define(forget, dict(namespace), "forget")


class Layout:
    """Where a production's WMEs and variables sit in its tokens, and the generated lines
    that make the Match of a token (``match_lines``): a loop over the levels that tests
    each one's kind costs twice as much as straight-line code."""

    __slots__ = ("production", "levels", "size", "bindings", "positive")

    def __init__(self, production: Production, levels: list[tuple[int, ...]],
                 bindings: list[tuple[str, int]], positive: set[int]) -> None:
        self.production = production
        # levels[k] = written indices of the elements matched at token level k: one, or
        # several for a run of independent conditions (whose token holds a tuple of WMEs)
        self.levels = levels[::-1]
        self.size = sum(len(level) for level in levels)
        self.bindings = bindings
        self.positive = positive  # written indices of the positive conditions

    def match_lines(self, tok: str, pad: str) -> list[str]:
        """Generated code: ``m`` = the Match of the token ``tok`` (``NEW``, ``Match`` and the
        production ``P`` in the namespace): the WMEs in written order (``None`` for
        negations), ``newest`` (the first index of the newest WME, found in written
        order), and the variables' values as a dict literal."""
        items = "".join(f"{name!r}: v[{pos}], " for name, pos in self.bindings)
        lines = ["m = NEW(Match)", "m.production = P", f"v = {tok}.vals",
                 f"m.bindings = {{{items}}}", f"k = {tok}"]
        last = len(self.levels) - 1
        for k, level in enumerate(self.levels):
            if len(level) > 1:
                lines.append(f"{', '.join(f'w{i}' for i in level)}, = k.wme")
            elif level[0] in self.positive:
                lines.append(f"w{level[0]} = k.wme")
            if k < last:
                lines.append("k = k.parent")
        lines.append("newest, at = 0, -1")
        for i in sorted(self.positive):
            lines.append(f"if w{i}.timetag > newest: newest, at = w{i}.timetag, {i}")
        written = "".join(f"w{i}, " if i in self.positive else "None, " for i in range(self.size))
        lines += [f"m.wmes = ({written})", "m.newest = (newest, at)"]
        return [pad + line for line in lines]
