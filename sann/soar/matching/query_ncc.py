"""Conjunctive negations answered by a query over the alpha memories (``QueryNCCNode``).

A conjunctive negation without a nested one is not a subnetwork of tokens but a compiled
query that keeps one witness per blocked token: Python pays per token, and the subnetwork's
partial matches were most of the tokens in rules such as "the top disk of a peg".
"""

from __future__ import annotations

from collections.abc import Callable

from sann.soar.codegen import define
from sann.soar.matching.alpha import AlphaMemory
from sann.soar.matching.nodes import Node, delete_children, delete_tokens
from sann.soar.matching.symbols import same_symbol
from sann.soar.matching.templates import (
    CHECK_NAMES,
    bucket_lines,
    check_lines,
    filing_lines,
    key_lines,
    token_lines,
    witness_lines,
)
from sann.soar.matching.tokens import FLOAT, GET, Token, compile_first, hash_key
from sann.soar.memory import WME, mypyc_attr


def compile_query(levels: list[tuple], seed: int,
                   width: int) -> Callable[[tuple, WME | None], tuple | None]:
    """A search for one match of a query NCC's inner conditions as nested loops, one per
    condition (a negated one as ``for ... break / else``), with condition ``seed`` (if
    any) matching only the WME passed in: the search runs for every parent token that
    could change, and generated loops cost a third of an interpreted walk over the levels.
    The owner's ``width`` values are read from ``v0``; what the inner conditions bind is
    kept in locals, and the values tuple is built only for the match returned."""
    namespace: dict[str, object] = {**CHECK_NAMES, "FLOAT": FLOAT}
    lines = ["def solve(v0, seed):"]
    depth = 1
    matched: list[str] = []
    names: dict[int, str] = {}  # value position bound inside -> local name

    def value(pos: int) -> str:
        return names.get(pos, f"v0[{pos}]")

    for k, (wmes, index, pos, getter, check, fields, negated, _) in enumerate(levels):
        pad = "    " * depth
        namespace.update({f"W{k}": wmes, f"I{k}": index, f"G{k}": getter})
        lines += bucket_lines(k, pad, value(pos) if pos >= 0 else None, k == seed)
        lines.append(f"{pad}for w{k} in b{k}:")
        inner = pad + "    "
        if check is not None:
            lines += check_lines(check.specs, "v0", f"w{k}", "continue", inner, value)
        if negated:  # the levels below are the body of the else: no WME matched
            lines += [f"{inner}break", f"{pad}else:"]
        else:
            for field in fields:
                name = names[width + len(names)] = f"x{width + len(names)}"
                lines.append(f"{inner}{name} = w{k}.{field}")
            matched.append(f"w{k}")
        depth += 1
    pad = "    " * depth
    bound = "".join(f"{names[p]}, " for p in sorted(names))
    lines.append(f"{pad}return {f'v0 + ({bound})' if bound else 'v0'},"
                 f" ({''.join(w + ', ' for w in matched)})")
    lines.append("    return None")
    return define(lines, namespace, "solve")


#: The query NCC node's generated functions (see QueryNCCNode._compile).
QUERY_GENERATED = ("left_activate", "forget", "recheck", "inner_added")


@mypyc_attr(native_class=False)  # methods and generated functions in the same places
class QueryNCCNode(Node):
    """Conjunctive negation answered by a query over the alpha memories instead of a
    subnetwork of tokens.

    A subnetwork keeps, under every parent token, a token for every partial match of the
    negated conditions; when a WME those partial matches join on changes (a disk moving in
    the Towers of Hanoi) they are all deleted and rebuilt, and in Python a token costs a few
    microseconds.  This node keeps, per blocked parent token, one *witness*: the WMEs and
    bindings of one match of the inner conditions (``tok.extra = (vals, wmes)``).  The query
    runs again for a token only when a WME of its witness goes, or a WME arrives that an
    inner negated condition rejects the witness with.  A WME entering the memory of an
    inner positive condition is tried as a seed against the unblocked tokens it could join
    (hashed on the parent variable the condition is joined on, when there is one); a WME
    leaving an inner negated condition's memory sends the unblocked tokens that could join
    it back to the query.  Conjunctive negations with a nested one keep the subnetwork."""

    __slots__ = ("levels", "width", "owners", "owner_index", "amems", "owner_tests",
                 "seed_filters", "solvers", "left_activate", "forget", "recheck",
                 "inner_added")

    def __init__(self, registry: dict[WME, list], parent: Node, key: object, levels: list[tuple],
                 width: int, amems: list[AlphaMemory],
                 owner_tests: list[list[tuple[Callable, int]]]) -> None:
        super().__init__(registry, parent, key)
        self.amems = amems
        # per inner condition, in join order:
        # (amem.wmes, hash index or None, vals position or -1, getter, check, fields bound,
        #  negated, equality tests as (field, vals position))
        self.levels = levels
        self.width = width  # the parent tokens' number of values
        # per inner condition: its equality tests against parent values, (getter, position)
        self.owner_tests = owner_tests
        # per inner condition: (getter, hashed alpha memory) pairs that a WME entering it
        # must find itself in to be part of any inner match (see seed_filters)
        self.seed_filters = seed_filters(levels, width, amems, owner_tests)
        # solvers[0](vals, None): one match of the inner conditions as (vals, wmes), or
        # None; solvers[k + 1](vals, wme): one in which inner condition k matches wme
        self.solvers = [compile_query(levels, seed, width)  # negated levels are never seeds
                        if seed < 0 or not levels[seed][6] else None
                        for seed in range(-1, len(levels))]
        self.owners: dict[Token, Token] = {}  # parent token -> this node's token
        self.owner_index: dict[int, dict] = {}  # parent value position -> hashed owners
        for tests in owner_tests:
            if tests:
                self.owner_index.setdefault(tests[0][1], {})
        # generated on first use, and again after an index is added to the node's tokens
        self.left_activate: Callable[[Token], None]
        self.forget: Callable[[Token], None]
        # recheck(tok): the witness of a blocked token is gone: find another, or pass the
        # token on
        self.recheck: Callable[[Token], None]
        # inner_added(k, wme): wme entered the memory of inner condition k (see _compile)
        self.inner_added: Callable[[int, WME], None]
        compile_first(self, *QUERY_GENERATED)

    def all_tokens(self) -> list[Token]:
        return list(self.owners.values())

    def index(self, pos: int) -> dict:
        if pos not in self.indexes:
            compile_first(self, *QUERY_GENERATED)
        return super().index(pos)

    # ----- parent tokens -----

    def _compile(self) -> None:
        """Generate ``left_activate`` (a parent token arrives: make its token, file it
        among the owners, search once, then pass it on or keep the witness), ``forget``
        (its undoing), ``recheck`` (the witness of a blocked token is gone: drop it,
        search again, then pass the token on or keep the new witness) and ``inner_added``
        (see ``_inner_added_lines``) as straight-line code, with the node's indices fixed
        in it.  Generated, not compiled: they read and write token slots, which compiled
        code reaches through the generic attribute lookup."""
        namespace: dict[str, object] = {
            "FLOAT": FLOAT, "Tok": Token, "N": self, "OWN": self.owners,
            "T": self.tokens, "CH": self.children, "R": self.registry,
            "SOLVE": self.solvers[0]}
        left = ["def left_activate(t):", "    vals = t.vals",
                *token_lines("    ", "t", "None", "vals"), "    s = t.children",
                "    if s is None: t.children = {tok: None}", "    else: s[tok] = None",
                "    OWN[t] = tok"]
        forget = ["def forget(tok):", "    del OWN[tok.parent]", "    vals = tok.vals"]
        for k, (pos, index) in enumerate(self.owner_index.items()):
            namespace[f"O{k}"] = index
            left += filing_lines(f"O{k}", f"vals[{pos}]", "tok", "    ", True)
            forget += key_lines(f"vals[{pos}]", "    ", True) + [
                f"    b = O{k}[key]", "    del b[tok]", f"    if not b: del O{k}[key]"]
        left += ["    found = SOLVE(vals, None)", "    if found is None:", "        T[tok] = None"]
        recheck = ["def recheck(tok):", "    for w in tok.extra[1]:", "        record = R.get(w)",
                   "        if record is not None and record[3]: record[3].pop(tok, None)",
                   "    tok.extra = None", "    vals = tok.vals", "    found = SOLVE(vals, None)",
                   "    if found is None:", "        T[tok] = None"]
        forget += ["    found = tok.extra", "    if found is None:", "        del T[tok]"]
        for k, (pos, index) in enumerate(self.index_list):
            namespace[f"I{k}"] = index
            left += filing_lines(f"I{k}", f"vals[{pos}]", "tok", "        ", True)
            recheck += filing_lines(f"I{k}", f"vals[{pos}]", "tok", "        ", True)
            forget += key_lines(f"vals[{pos}]", "        ", True) + [
                f"        b = I{k}[key]", "        del b[tok]", f"        if not b: del I{k}[key]"]
        witness = witness_lines("    ")
        left += ["        for child in CH:", "            child.left_activate(tok)",
                 "        return", *witness]
        recheck += ["        for child in CH:", "            child.left_activate(tok)",
                    "        return", *witness]
        forget += ["        return", "    for w in found[1]:", "        record = R.get(w)",
                   "        if record is not None and record[3]: record[3].pop(tok, None)",
                   "    tok.extra = None"]
        self.left_activate = define(left, namespace, "left_activate")  # type: ignore[method-assign]
        self.forget = define(forget, dict(namespace), "forget")  # type: ignore[method-assign]
        self.recheck = define(recheck, dict(namespace), "recheck")  # type: ignore[method-assign]
        namespace = {**CHECK_NAMES, "FLOAT": FLOAT, "N": self, "OWN": self.owners,
                     "T": self.tokens, "R": self.registry, "SAME": same_symbol,
                     "DT": delete_tokens}
        self.inner_added = define(  # type: ignore[method-assign]
            self._inner_added_lines(namespace), namespace, "inner_added")

    def _inner_added_lines(self, namespace: dict[str, object]) -> list[str]:
        """Generated ``inner_added(k, wme)``: ``wme`` entered the memory of inner condition
        k.  Negated: the witnesses it rejects (of the tokens whose values it could join)
        are no longer results, and their tokens are searched again.  Positive: unless a
        seed filter rules it out, each unblocked token it could join is searched with it
        as inner condition k; a match blocks the token (dropped from the memory, its
        descendants deleted, the match kept as its witness)."""
        lines = ["def inner_added(k, wme):"]
        fields = {getter: field for field, getter in GET.items()}
        for k, level in enumerate(self.levels):
            lines.append(f"    if k == {k}:")
            pad = "        "
            if not level[6]:
                for n, (getter, index) in enumerate(self.seed_filters[k]):
                    field = fields[getter]
                    namespace[f"F{k}_{n}"] = index
                    lines += key_lines(f"wme.{field}", pad, field != "id")
                    lines.append(f"{pad}if key not in F{k}_{n}: return")
            tests = [(field, p) for field, p in level[7] if p < self.width]
            if not tests:
                lines.append(f"{pad}candidates = list(OWN.values())")
            else:
                field, p = tests[0]
                namespace[f"Q{p}"] = self.owner_index[p]
                lines += key_lines(f"wme.{field}", pad, field != "id")
                lines += [f"{pad}found = Q{p}.get(key)", f"{pad}if not found: return"]
                if len(tests) == 1:
                    lines.append(f"{pad}candidates = list(found)")
                else:
                    rest = tests[1:]
                    lines += [f"{pad}v{n} = wme.{field}" for n, (field, _) in enumerate(rest)]
                    same = " and ".join(f"SAME(tok.vals[{p}], v{n})"
                                        for n, (_, p) in enumerate(rest))
                    lines.append(f"{pad}candidates = [tok for tok in found if {same}]")
            lines.append(f"{pad}for tok in candidates:")
            if level[6]:
                pos, check = level[2], level[4]
                lines += [f"{pad}    found = tok.extra",
                          f"{pad}    if found is None or tok.node is None: continue",
                          f"{pad}    vals = found[0]"]
                if pos >= 0:
                    lines += [f"{pad}    x = vals[{pos}]; y = wme.{level[7][0][0]}",
                              f"{pad}    if not (x.__class__ is y.__class__ and x == y): "
                              "continue"]
                if check is not None:
                    lines += check_lines(check.specs, "vals", "wme", "continue", pad + "    ")
                lines += [f"{pad}    N.recheck(tok)", f"{pad}return"]
                continue
            namespace[f"S{k}"] = self.solvers[k + 1]
            inner = pad + "        "
            lines += [f"{pad}    if tok.extra is None and tok.node is not None:",
                      f"{pad}        found = S{k}(tok.vals, wme)",
                      f"{pad}        if found is not None:",  # block it (see _block)
                      f"{inner}    del T[tok]"]
            for n, (pos, index) in enumerate(self.index_list):
                namespace[f"I{n}"] = index
                lines += key_lines(f"tok.vals[{pos}]", inner + "    ", True) + [
                    f"{inner}    b = I{n}[key]", f"{inner}    del b[tok]",
                    f"{inner}    if not b: del I{n}[key]"]
            lines += [f"{inner}    s = tok.children", f"{inner}    if s:",
                      f"{inner}        tok.children = None", f"{inner}        DT(R, list(s))",
                      *witness_lines(inner + "    ")]
            lines.append(f"{pad}return")
        return lines

    def _witness(self, tok: Token, found: tuple[tuple, tuple]) -> None:
        tok.extra = found
        info = self.registry
        for w in found[1]:
            record = info[w]
            if record[3] is None:
                record[3] = {tok: None}
            else:
                record[3][tok] = None

    def _block(self, tok: Token, found: tuple[tuple, tuple]) -> None:
        self.unstore(tok)
        delete_children(self.registry, tok)
        self._witness(tok, found)

    # ----- inner WME changes -----

    def _candidates(self, k: int, wme: WME) -> list[Token]:
        """The tokens whose values could let ``wme`` match inner condition ``k``: those
        passing its equality tests against parent values (the first one hashed)."""
        tests = self.owner_tests[k]
        if not tests:
            return list(self.owners.values())
        getter, pos = tests[0]
        found = self.owner_index[pos].get(hash_key(getter(wme)))
        if not found:
            return []
        if len(tests) == 1:
            return list(found)
        rest = [(getter(wme), pos) for getter, pos in tests[1:]]
        return [tok for tok in found
                if all(same_symbol(tok.vals[pos], value) for value, pos in rest)]

    def inner_removed(self, k: int, wme: WME) -> None:
        """A WME left a negated inner condition's memory: results may appear."""
        for tok in self._candidates(k, wme):
            if tok.extra is None and tok.node is not None:
                found = self.solvers[0](tok.vals, None)
                if found is not None:
                    self._block(tok, found)



def seed_filters(levels: list[tuple], width: int, amems: list[AlphaMemory],
                  owner_tests: list[list[tuple[Callable, int]]]
                  ) -> list[list[tuple[Callable, dict]]]:
    """Semi-join filters for the WMEs that enter a query NCC's inner conditions.

    A WME entering inner condition k is tried against every unblocked owner token that
    could use it, a search each; when k tests no owner value, that is every owner.  But
    when k tests a field against a variable that another positive inner condition j binds
    (or j tests a field against one that k binds), no inner match can use the WME unless
    some WME of j's alpha memory has the same value in the corresponding field: one hash
    lookup rules out a search per owner (in the block planner, every output command and
    operator name entering ``(<above> ^name <m>)`` and ``(<il> ^block <above>)``).
    Conditions that test an owner value already narrow their candidates by hash and get no
    filter.  ``levels`` are as in :class:`QueryNCCNode`; ``levels[k][7]`` are their
    equality tests ``(field, vals position)``."""
    bound_at: dict[int, tuple[int, str]] = {}
    position = width
    for j, level in enumerate(levels):
        for field in level[5]:
            bound_at[position] = (j, field)
            position += 1
    filters: list[list[tuple[Callable, dict]]] = [[] for _ in levels]
    for k, level in enumerate(levels):
        if level[6]:  # a negated condition needs no match
            continue
        for field, p in level[7]:
            if p in bound_at and bound_at[p][0] != k:
                j, bound_field = bound_at[p]
                if not owner_tests[k]:
                    filters[k].append((GET[field], amems[j].index(bound_field)))
                if not owner_tests[j]:
                    filters[j].append((GET[bound_field], amems[k].index(field)))
    return filters
