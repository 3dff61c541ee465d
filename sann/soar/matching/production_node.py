"""The bottom of a production in the beta network: its tokens are its matches."""

from __future__ import annotations

from collections.abc import Callable

from sann.soar.codegen import define, plain
from sann.soar.matching.matches import Changes, Match
from sann.soar.matching.nodes import Node
from sann.soar.matching.templates import adopt_lines, token_lines
from sann.soar.matching.tokens import Token, adopt, compile_first, new_object, new_token
from sann.soar.memory import WME, mypyc_attr
from sann.soar.production import Production


@mypyc_attr(native_class=False)  # methods and generated functions in the same places
class ProductionNode(Node):
    """Bottom of a production: each token is a Match.

    Both activations are generated for the production (on first use) as straight-line
    code, the Match made inline (``Layout.match_lines``): most matches are fired, which
    needs all their fields, and compiled methods of this class would reach the tokens'
    and matches' slots through the generic attribute lookup, slower than the interpreter's
    specialized slot access.  ``plain_left_activate`` and ``plain_forget`` are their plain
    Python twins."""

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
        if plain():
            self.left_activate = self.plain_left_activate
            self.forget = self.plain_forget
            return
        namespace: dict[str, object] = {
            "new_object": new_object, "Match": Match, "production": self.production,
            "Token": Token, "node": self, "tokens": self.tokens, "added": self.added,
            "removed": self.removed}
        left = ["def left_activate(parent):", *self.layout.match_lines("parent", "    "),
                *token_lines("    ", "parent", "None", "None"), "    token.extra = match",
                *adopt_lines("    ", "parent"), "    tokens[token] = None",
                "    added[match] = None"]
        forget = ["def forget(token):", "    del tokens[token]", "    match = token.extra",
                  "    if match is not None:", "        if match in added: del added[match]",
                  "        else: removed[match] = None"]
        self.left_activate = define(left, namespace, "left_activate", "rete:production")
        self.forget = define(forget, dict(namespace), "forget", "rete:production")

    def plain_left_activate(self, parent: Token) -> None:
        """Plain Python: the Match of a new token, reported."""
        match = self.layout.make_match(parent)
        token = new_token(parent, None, None, self, match)
        adopt(parent, token)
        self.tokens[token] = None
        self.added[match] = None

    def plain_forget(self, token: Token) -> None:
        """Plain Python: the token goes, and its Match is retracted."""
        del self.tokens[token]
        match = token.extra
        if match is not None:
            if match in self.added:
                del self.added[match]
            else:
                self.removed[match] = None


class Layout:
    """Where a production's WMEs and variables sit in its tokens, and the generated lines
    that make the Match of a token (``match_lines``, straight-line code rather than a loop
    over the levels that tests each one's kind; ``make_match`` is that loop)."""

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

    def match_lines(self, token: str, pad: str) -> list[str]:
        """Generated code: ``match`` = the Match of ``token`` (``new_object``, ``Match`` and
        the ``production`` in the namespace): the WMEs in written order (``None`` for
        negations), ``newest`` (the first index of the newest WME, found in written
        order), and the variables' values as a dict literal."""
        items = "".join(f"{name!r}: values[{pos}], " for name, pos in self.bindings)
        lines = ["match = new_object(Match)", "match.production = production",
                 f"values = {token}.vals", f"match.bindings = {{{items}}}", f"level = {token}"]
        last = len(self.levels) - 1
        for k, level in enumerate(self.levels):
            if len(level) > 1:
                lines.append(f"{', '.join(f'wme_{i}' for i in level)}, = level.wme")
            elif level[0] in self.positive:
                lines.append(f"wme_{level[0]} = level.wme")
            if k < last:
                lines.append("level = level.parent")
        lines.append("newest, at = 0, -1")
        for i in sorted(self.positive):
            lines.append(f"if wme_{i}.timetag > newest: newest, at = wme_{i}.timetag, {i}")
        written = "".join(f"wme_{i}, " if i in self.positive else "None, "
                          for i in range(self.size))
        lines += [f"match.wmes = ({written})", "match.newest = (newest, at)"]
        return [pad + line for line in lines]

    def make_match(self, token: Token) -> Match:
        """Plain Python: the Match of ``token`` (what ``match_lines`` writes out)."""
        match = new_object(Match)
        match.production = self.production
        values = token.vals
        match.bindings = {name: values[pos] for name, pos in self.bindings}
        wmes: list[WME | None] = [None] * self.size
        level = token
        last = len(self.levels) - 1
        for k, indexes in enumerate(self.levels):
            if len(indexes) > 1:
                for i, wme in zip(indexes, level.wme, strict=True):
                    wmes[i] = wme
            elif indexes[0] in self.positive:
                wmes[indexes[0]] = level.wme
            if k < last:
                level = level.parent
        newest, at = 0, -1
        for i in sorted(self.positive):
            timetag = wmes[i].timetag  # type: ignore[union-attr]
            if timetag > newest:
                newest, at = timetag, i
        match.wmes = tuple(wmes)
        match.newest = (newest, at)
        return match
