"""Run nodes: consecutive independent positive conditions joined as one node."""

from __future__ import annotations

from collections.abc import Callable

from sann.soar.codegen import define
from sann.soar.matching.alpha import AlphaMemory
from sann.soar.matching.nodes import Node
from sann.soar.matching.plan import Plan
from sann.soar.matching.templates import (
    CHECK_NAMES,
    bucket_lines,
    check_lines,
    filing_lines,
    key_lines,
    token_lines,
)
from sann.soar.matching.tokens import FLOAT, Token
from sann.soar.memory import WME, mypyc_attr


def joins_within(plan: Plan, base: int, amem: AlphaMemory, run: list[tuple]) -> bool:
    """Whether a condition can join a run that started with ``base`` values: it is hashed
    on one of them and tests no other value bound after them (so it is independent of the
    run's other conditions), and its alpha memory is not one of theirs."""
    if plan.index is None or plan.index[0] >= base:
        return False
    if any(ref[0] == "v" and ref[1] >= base for spec in plan.beta for ref in (spec[0], spec[2])):
        return False
    return all(other is not amem for _, _, other in run)


def compile_run(node: RunNode, seed: int) -> Callable:
    """Generate what makes a run node's tokens: one per combination of WMEs matching its run
    of independent conditions, found in nested loops, each token adopted, registered with
    its WMEs and stored as it is found.  ``seed`` < 0: ``make(t)``, every combination
    below a new parent token ``t``; otherwise ``right_activate(seed)``, the combinations in
    which member ``seed`` matches the WME just added, below every parent token it joins."""
    members = node.members
    namespace: dict[str, object] = {**CHECK_NAMES, "FLOAT": FLOAT, "Tok": Token,
                                    "N": node, "R": node.registry, "T": node.tokens,
                                    "CH": node.children}
    if seed < 0:
        lines, depth = ["def make(t):", "    vals = t.vals"], 1
    else:
        namespace["PI"] = node.parent.index(members[seed][2])  # type: ignore[union-attr]
        lines = ["def right_activate(seed):", f"    key = G{seed}(seed)",
                 "    if key.__class__ is float: key = (FLOAT, key)",
                 "    bucket = PI.get(key)", "    if not bucket: return",
                 "    for t in list(bucket):", "        vals = t.vals"]
        depth = 2
    for k, (_, index, pos, getter, check, _) in enumerate(members):
        pad = "    " * depth
        namespace.update({f"I{k}": index, f"G{k}": getter})
        lines += bucket_lines(k, pad, f"vals[{pos}]" if pos >= 0 else None, k == seed)
        lines.append(f"{pad}for w{k} in b{k}:")
        if check is not None:
            lines += check_lines(check.specs, "vals", f"w{k}", "continue", pad + "    ")
        depth += 1
    pad = "    " * depth
    bound = "".join(f"w{k}.{field}, " for k, member in enumerate(members) for field in member[5])
    wmes = "".join(f"w{k}, " for k in range(len(members)))
    lines += [*token_lines(pad, "t", f"({wmes})", f"vals + ({bound})" if bound else "vals"),
              f"{pad}s = t.children",
              f"{pad}if s is None: t.children = {{tok: None}}",
              f"{pad}else: s[tok] = None"]
    lines += [f"{pad}R[w{k}][1][tok] = None" for k in range(len(members))]
    lines.append(f"{pad}T[tok] = None")
    for k, (pos, index) in enumerate(node.index_list):
        namespace[f"X{k}"] = index
        lines += filing_lines(f"X{k}", f"tok.vals[{pos}]", "tok", pad, True)
    lines += [f"{pad}for child in CH:", f"{pad}    child.left_activate(tok)"]
    return define(lines, namespace, "make" if seed < 0 else "right_activate")


@mypyc_attr(native_class=False)  # methods and generated functions in the same places
class RunNode(Node):
    """Consecutive positive conditions that test only values the parent token already has,
    joined as one node: ``(<c> ^zmax > <zl>)`` filters after ``<c>`` and ``<zl>`` are bound,
    or ``(<o> ^disk <d>) (<o> ^from <f>)`` once ``<o>`` is.

    Such conditions are independent of one another, so their join is the product of their
    matches: one token per combination (``tok.wme`` is the tuple of its WMEs, ``tok.vals`` the
    values extended by what they bind), instead of a chain of nodes with a token per
    condition, most of which die a level or two further down.  In the block planner's
    geometry rules every pair of blocks goes through six filters; as a chain they made three
    tokens per pair."""

    __slots__ = ("members", "amems", "makers", "left_activate", "forget")

    def __init__(self, registry: dict[WME, list], parent: Node, key: object,
                 members: list[tuple]) -> None:
        super().__init__(registry, parent, key)
        # per condition: (alpha memory, its hash index, parent value position, getter,
        # check, fields it binds)
        self.members = members
        self.amems = [member[0] for member in members]
        for member in members:
            parent.index(member[2])
        self.makers: list[Callable] = []
        self.left_activate: Callable[[Token], None]
        self.forget: Callable[[Token], None]
        self._compile()

    def _compile(self) -> None:
        """Generate the makers: ``makers[0](t)`` makes every combination below a parent
        token (the left activation), ``makers[k + 1](wme)`` those with condition k matching
        a new WME (the right activation for its alpha memory); and ``forget``, which drops a
        token from the memory, its indices and its WMEs' records."""
        self.makers = [compile_run(self, seed) for seed in range(-1, len(self.members))]
        self.left_activate = self.makers[0]
        namespace: dict[str, object] = {"FLOAT": FLOAT, "T": self.tokens, "R": self.registry}
        lines = ["def forget(tok):", "    del T[tok]"]
        for k, (pos, index) in enumerate(self.index_list):
            namespace[f"I{k}"] = index
            lines += key_lines(f"tok.vals[{pos}]", "    ", True) + [
                f"    b = I{k}[key]", "    del b[tok]", f"    if not b: del I{k}[key]"]
        wmes = [f"w{k}" for k in range(len(self.members))]
        lines.append(f"    {', '.join(wmes)}, = tok.wme")
        for w in wmes:
            lines += [f"    r = R.get({w})", "    if r is not None: r[1].pop(tok, None)"]
        self.forget = define(lines, namespace, "forget")

    def index(self, pos: int) -> dict:
        """The makers file new tokens in the node's indices: a new one means new makers,
        and the alpha memories relink to their new right activations."""
        known = pos in self.indexes
        index = super().index(pos)
        if not known:
            self._compile()
            for amem in set(self.amems):
                amem._relink()
        return index

    def activation(self, amem: AlphaMemory) -> Callable[[WME], None]:
        return self.makers[self.amems.index(amem) + 1]
