"""Run nodes: consecutive independent positive conditions joined as one node."""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import NamedTuple

from sann.soar.codegen import define, plain
from sann.soar.matching.alpha import AlphaMemory
from sann.soar.matching.nodes import Node
from sann.soar.matching.plan import Plan
from sann.soar.matching.symbols import same_symbol
from sann.soar.matching.templates import (
    CHECK_NAMES,
    adopt_lines,
    bucket_lines,
    check_lines,
    filing_lines,
    index_of,
    token_lines,
    unfiling_lines,
)
from sann.soar.matching.tokens import BUILT, FLOAT, Token, adopt, hash_key, index_add, new_token
from sann.soar.memory import WME, mypyc_attr


class Member(NamedTuple):
    """One condition of a run."""

    amem: AlphaMemory
    #: the alpha memory's hash index on the field the condition is joined on
    index: dict
    #: the position of the parent token's value that field must equal
    position: int
    #: reads that field of a WME
    getter: Callable[[WME], object]
    #: the condition's other tests against the parent's values (``compile_check``)
    check: Callable | None
    #: the fields whose values the condition binds
    fields: tuple[str, ...]


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
    its WMEs and stored as it is found.  ``seed`` < 0: ``make(parent)``, every combination
    below a new parent token; otherwise ``right_activate(seed)``, the combinations in which
    member ``seed`` matches the WME just added, below every parent token it joins."""
    members = node.members
    namespace: dict[str, object] = {**CHECK_NAMES, "FLOAT": FLOAT, "Token": Token,
                                    "node": node, "wme_records": node.registry,
                                    "tokens": node.tokens, "children": node.children}
    if seed < 0:
        lines, depth = ["def make(parent):", "    values = parent.vals"], 1
    else:
        namespace["parent_index"] = node.parent.index(members[seed].position)  # type: ignore[union-attr]
        lines = ["def right_activate(seed):", f"    key = get_field_{seed}(seed)",
                 "    if key.__class__ is float: key = (FLOAT, key)",
                 "    bucket = parent_index.get(key)", "    if not bucket: return",
                 "    for parent in list(bucket):", "        values = parent.vals"]
        depth = 2
    for k, member in enumerate(members):
        pad = "    " * depth
        namespace.update({f"alpha_index_{k}": member.index, f"get_field_{k}": member.getter})
        lines += bucket_lines(k, pad, f"values[{member.position}]", k == seed)
        lines.append(f"{pad}for wme_{k} in candidates_{k}:")
        if member.check is not None:
            lines += check_lines(member.check.specs,  # type: ignore[attr-defined]
                                 "values", f"wme_{k}", "continue", pad + "    ")
        depth += 1
    pad = "    " * depth
    bound = "".join(f"wme_{k}.{field}, " for k, member in enumerate(members)
                    for field in member.fields)
    wmes = "".join(f"wme_{k}, " for k in range(len(members)))
    lines += [*token_lines(pad, "parent", f"({wmes})",
                           f"values + ({bound})" if bound else "values"),
              *adopt_lines(pad, "parent")]
    lines += [f"{pad}wme_records[wme_{k}][{BUILT}][token] = None" for k in range(len(members))]
    lines.append(f"{pad}tokens[token] = None")
    for k, (pos, index) in enumerate(node.index_list):
        namespace[f"token_index_{k}"] = index
        lines += filing_lines(f"token_index_{k}", f"token.vals[{pos}]", "token", pad, True)
    lines += [f"{pad}for child in children:", f"{pad}    child.left_activate(token)"]
    return define(lines, namespace, "make" if seed < 0 else "right_activate", "rete:run")


@mypyc_attr(native_class=False)  # methods and generated functions in the same places
class RunNode(Node):
    """Consecutive positive conditions that test only values the parent token already has,
    joined as one node: ``(<c> ^zmax > <zl>)`` filters after ``<c>`` and ``<zl>`` are bound,
    or ``(<o> ^disk <d>) (<o> ^from <f>)`` once ``<o>`` is.

    Such conditions are independent of one another, so their join is the product of their
    matches: one token per combination (``token.wme`` is the tuple of its WMEs,
    ``token.vals`` the values extended by what they bind), instead of a chain of nodes with
    a token per condition, most of which die a level or two further down (in the block
    planner's geometry rules, every pair of blocks goes through six such filters).  The
    ``plain_*`` methods do in plain Python what the generated makers do."""

    __slots__ = ("members", "amems", "makers", "left_activate", "forget")

    def __init__(self, registry: dict[WME, list], parent: Node, key: object,
                 members: list[Member]) -> None:
        super().__init__(registry, parent, key)
        self.members = members
        self.amems = [member.amem for member in members]
        for member in members:
            parent.index(member.position)
        self.makers: list[Callable] = []
        self.left_activate: Callable[[Token], None]
        self.forget: Callable[[Token], None]
        self._compile()

    def _compile(self) -> None:
        """Generate the makers: ``makers[0](parent)`` makes every combination below a parent
        token (the left activation), ``makers[k + 1](wme)`` those with condition k matching
        a new WME (the right activation for its alpha memory); and ``forget``, which drops a
        token from the memory, its indices and its WMEs' records."""
        if plain():
            self.makers = [self.plain_make, *(partial(self.plain_right_activate, k)
                                              for k in range(len(self.members)))]
            self.left_activate = self.plain_make
            self.forget = self.plain_forget
            return
        self.makers = [compile_run(self, seed) for seed in range(-1, len(self.members))]
        self.left_activate = self.makers[0]
        namespace: dict[str, object] = {"FLOAT": FLOAT, "tokens": self.tokens,
                                        "wme_records": self.registry}
        lines = ["def forget(token):", "    del tokens[token]"]
        for k, (pos, index) in enumerate(self.index_list):
            namespace[f"token_index_{k}"] = index
            lines += unfiling_lines(f"token_index_{k}", f"token.vals[{pos}]", "token", "    ",
                                    True)
        wmes = [f"wme_{k}" for k in range(len(self.members))]
        lines.append(f"    {', '.join(wmes)}, = token.wme")
        for wme in wmes:
            lines += [f"    record = wme_records.get({wme})",
                      f"    if record is not None: record[{BUILT}].pop(token, None)"]
        self.forget = define(lines, namespace, "forget", "rete:run")

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
        return self.makers[self.amems.index(amem) + 1]  # type: ignore[no-any-return]

    def plain_make(self, parent: Token) -> None:
        """Plain Python: every combination below a new parent token."""
        self._plain_combinations(parent, parent.vals, 0, -1, None, [])

    def plain_right_activate(self, seed: int, wme: WME) -> None:
        """Plain Python: the combinations in which member ``seed`` matches ``wme``."""
        member = self.members[seed]
        bucket = index_of(self.parent.indexes[member.position],  # type: ignore[union-attr]
                          member.getter(wme))
        if not bucket:
            return
        for parent in list(bucket):  # type: ignore[call-overload]
            self._plain_combinations(parent, parent.vals, 0, seed, wme, [])

    def _plain_combinations(self, parent: Token, values: tuple, k: int, seed: int,
                            seed_wme: WME | None, chosen: list[WME]) -> None:
        """The combinations of members ``k`` on, ``chosen`` the WMEs of those before."""
        if k == len(self.members):
            self._plain_token(parent, values, chosen)
            return
        member = self.members[k]
        if k == seed:
            candidates: object = ((seed_wme,) if same_symbol(
                values[member.position], member.getter(seed_wme)) else ())  # type: ignore[arg-type]
        else:
            candidates = member.index.get(hash_key(values[member.position]), ())
        check = member.check
        for wme in candidates:  # type: ignore[attr-defined]
            if check is not None and not check(values, wme):
                continue
            chosen.append(wme)
            self._plain_combinations(parent, values, k + 1, seed, seed_wme, chosen)
            chosen.pop()

    def _plain_token(self, parent: Token, values: tuple, chosen: list[WME]) -> None:
        bound = tuple(getattr(wme, field) for wme, member in zip(chosen, self.members, strict=True)
                      for field in member.fields)
        token = new_token(parent, tuple(chosen), values + bound, self)
        adopt(parent, token)
        for wme in chosen:
            self.registry[wme][BUILT][token] = None
        self.tokens[token] = None
        for pos, index in self.index_list:
            index_add(index, token.vals[pos], token)
        for child in self.children:
            child.left_activate(token)

    def plain_forget(self, token: Token) -> None:
        """Plain Python: drop a token from the memory, its indices and its WMEs' records."""
        self.unstore(token)
        for wme in token.wme:
            record = self.registry.get(wme)
            if record is not None:
                record[BUILT].pop(token, None)
