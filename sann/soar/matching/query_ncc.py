"""Conjunctive negations answered by a query over the alpha memories (``QueryNCCNode``).

A conjunctive negation without a nested one is not a subnetwork of tokens but a compiled
query (query.py) that keeps one witness per blocked token: Python pays per token, and in
rules such as "the top disk of a peg" the subnetwork's partial matches would be most of
the tokens.
"""

from __future__ import annotations

from collections.abc import Callable

from sann.soar.codegen import define, plain
from sann.soar.matching.alpha import AlphaMemory
from sann.soar.matching.nodes import Node, delete_children, delete_tokens
from sann.soar.matching.query import InnerCondition, Solver, compile_query, seed_filters
from sann.soar.matching.symbols import same_symbol
from sann.soar.matching.templates import (
    CHECK_NAMES,
    adopt_lines,
    check_lines,
    filing_lines,
    key_lines,
    token_lines,
    unfiling_lines,
    witness_lines,
)
from sann.soar.matching.tokens import (
    FLOAT,
    GET,
    WITNESSED,
    Token,
    adopt,
    compile_first,
    hash_key,
    index_add,
    index_remove,
    new_token,
)
from sann.soar.memory import WME, mypyc_attr

#: The query NCC node's generated functions (see QueryNCCNode._compile).
QUERY_GENERATED = ("left_activate", "forget", "recheck", "inner_added")


@mypyc_attr(native_class=False)  # methods and generated functions in the same places
class QueryNCCNode(Node):
    """Conjunctive negation answered by a query over the alpha memories instead of a
    subnetwork of tokens.

    A subnetwork keeps, under every parent token, a token for every partial match of the
    negated conditions; when a WME those partial matches join on changes (a disk moving in
    the Towers of Hanoi) they are all deleted and rebuilt, and every token is a Python
    object made and freed.  This node keeps, per blocked parent token, one *witness*: the
    WMEs and bindings of one match of the inner conditions (``token.extra = (values,
    wmes)``).  The query runs again for a token only when a WME of its witness goes, or a
    WME arrives that an inner negated condition rejects the witness with.  A WME entering
    the memory of an inner positive condition is tried as a seed against the unblocked
    tokens it could join (hashed on the parent variable the condition is joined on, when
    there is one); a WME leaving an inner negated condition's memory sends the unblocked
    tokens that could join it back to the query.  Conjunctive negations with a nested one
    keep the subnetwork.  The ``plain_*`` methods do in plain Python what the generated
    functions do."""

    __slots__ = ("levels", "width", "owners", "owner_index", "amems", "owner_tests",
                 "seed_filters", "solvers", "left_activate", "forget", "recheck",
                 "inner_added")

    def __init__(self, registry: dict[WME, list], parent: Node, key: object,
                 levels: list[InnerCondition], width: int, amems: list[AlphaMemory],
                 owner_tests: list[list[tuple[Callable, int]]]) -> None:
        super().__init__(registry, parent, key)
        self.amems = amems
        self.levels = levels  # the inner conditions, in join order
        self.width = width  # the parent tokens' number of values
        # per inner condition: its equality tests against parent values, (getter, position)
        self.owner_tests = owner_tests
        # per inner condition: (getter, hashed alpha memory) pairs that a WME entering it
        # must find itself in to be part of any inner match (see seed_filters)
        self.seed_filters = seed_filters(levels, width, amems, owner_tests)
        # solvers[0](values, None): one match of the inner conditions as (values, wmes), or
        # None; solvers[k + 1](values, wme): one in which inner condition k matches wme
        self.solvers: list[Solver | None] = [
            compile_query(levels, seed, width)  # negated levels are never seeds
            if seed < 0 or not levels[seed].negated else None
            for seed in range(-1, len(levels))]
        self.owners: dict[Token, Token] = {}  # parent token -> this node's token
        self.owner_index: dict[int, dict] = {}  # parent value position -> hashed owners
        for tests in owner_tests:
            if tests:
                self.owner_index.setdefault(tests[0][1], {})
        # generated on first use, and again after an index is added to the node's tokens
        self.left_activate: Callable[[Token], None]
        self.forget: Callable[[Token], None]
        # recheck(token): the witness of a blocked token is gone: find another, or pass the
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

    # ----- generated code -----

    def _compile(self) -> None:
        """Generate ``left_activate`` (a parent token arrives: make its token, file it
        among the owners, search once, then pass it on or keep the witness), ``forget``
        (its undoing), ``recheck`` (the witness of a blocked token is gone: drop it,
        search again, then pass the token on or keep the new witness) and ``inner_added``
        (see ``_inner_added_lines``) as straight-line code, with the node's indices fixed
        in it.  Generated, not compiled: they read and write token slots, which compiled
        code reaches through the generic attribute lookup."""
        if plain():
            self.left_activate = self.plain_left_activate  # type: ignore[method-assign]
            self.forget = self.plain_forget  # type: ignore[method-assign]
            self.recheck = self.plain_recheck  # type: ignore[method-assign]
            self.inner_added = self.plain_inner_added  # type: ignore[method-assign]
            return
        namespace: dict[str, object] = {
            "FLOAT": FLOAT, "Token": Token, "node": self, "owners": self.owners,
            "tokens": self.tokens, "children": self.children, "wme_records": self.registry,
            "solve": self.solvers[0]}
        left = ["def left_activate(parent):", "    values = parent.vals",
                *token_lines("    ", "parent", "None", "values"), *adopt_lines("    ", "parent"),
                "    owners[parent] = token"]
        forget = ["def forget(token):", "    del owners[token.parent]", "    values = token.vals"]
        for k, (pos, index) in enumerate(self.owner_index.items()):
            namespace[f"owner_index_{k}"] = index
            left += filing_lines(f"owner_index_{k}", f"values[{pos}]", "token", "    ", True)
            forget += unfiling_lines(f"owner_index_{k}", f"values[{pos}]", "token", "    ",
                                     True)
        left += ["    found = solve(values, None)", "    if found is None:",
                 "        tokens[token] = None"]
        recheck = ["def recheck(token):", *_unwitness_lines("    "), "    values = token.vals",
                   "    found = solve(values, None)", "    if found is None:",
                   "        tokens[token] = None"]
        forget += ["    found = token.extra", "    if found is None:", "        del tokens[token]"]
        for k, (pos, index) in enumerate(self.index_list):
            namespace[f"token_index_{k}"] = index
            filing = filing_lines(f"token_index_{k}", f"values[{pos}]", "token", "        ",
                                  True)
            left += filing
            recheck += filing
            forget += unfiling_lines(f"token_index_{k}", f"values[{pos}]", "token",
                                     "        ", True)
        pass_on = ["        for child in children:", "            child.left_activate(token)",
                   "        return", *witness_lines("    ")]
        left += pass_on
        recheck += pass_on
        forget += ["        return", *_unwitness_lines("    ")]
        self.left_activate = define(  # type: ignore[method-assign]
            left, namespace, "left_activate", "rete:query-ncc")
        self.forget = define(  # type: ignore[method-assign]
            forget, dict(namespace), "forget", "rete:query-ncc")
        self.recheck = define(  # type: ignore[method-assign]
            recheck, dict(namespace), "recheck", "rete:query-ncc")
        namespace = {**CHECK_NAMES, "FLOAT": FLOAT, "node": self, "owners": self.owners,
                     "tokens": self.tokens, "wme_records": self.registry,
                     "same_symbol": same_symbol, "delete_tokens": delete_tokens}
        self.inner_added = define(  # type: ignore[method-assign]
            self._inner_added_lines(namespace), namespace, "inner_added", "rete:query-ncc")

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
            if not level.negated:
                for n, (getter, index) in enumerate(self.seed_filters[k]):
                    field = fields[getter]
                    namespace[f"filter_{k}_{n}"] = index
                    lines += key_lines(f"wme.{field}", pad, field != "id")
                    lines.append(f"{pad}if key not in filter_{k}_{n}: return")
            lines += self._candidate_lines(k, namespace, pad)
            lines.append(f"{pad}for token in candidates:")
            if level.negated:
                lines += [f"{pad}    found = token.extra",
                          f"{pad}    if found is None or token.node is None: continue",
                          f"{pad}    values = found[0]"]
                if level.position >= 0:
                    lines += [f"{pad}    bound = values[{level.position}]; "
                              f"tested = wme.{level.equalities[0][0]}",
                              f"{pad}    if not (bound.__class__ is tested.__class__ "
                              "and bound == tested): continue"]
                if level.check is not None:
                    lines += check_lines(level.check.specs,  # type: ignore[attr-defined]
                                         "values", "wme", "continue", pad + "    ")
                lines += [f"{pad}    node.recheck(token)", f"{pad}return"]
                continue
            namespace[f"solve_with_{k}"] = self.solvers[k + 1]
            inner = pad + "        "
            lines += [f"{pad}    if token.extra is None and token.node is not None:",
                      f"{pad}        found = solve_with_{k}(token.vals, wme)",
                      f"{pad}        if found is not None:",  # block it (see _block)
                      f"{inner}    del tokens[token]"]
            for n, (pos, index) in enumerate(self.index_list):
                namespace[f"token_index_{n}"] = index
                lines += unfiling_lines(f"token_index_{n}", f"token.vals[{pos}]", "token",
                                        inner + "    ", True)
            lines += [f"{inner}    below = token.children", f"{inner}    if below:",
                      f"{inner}        token.children = None",
                      f"{inner}        delete_tokens(wme_records, list(below))",
                      *witness_lines(inner + "    ")]
            lines.append(f"{pad}return")
        return lines

    def _candidate_lines(self, k: int, namespace: dict[str, object], pad: str) -> list[str]:
        """Generated code: ``candidates`` = the owner tokens whose values could let ``wme``
        match inner condition ``k`` (what ``_candidates`` does)."""
        tests = [(field, p) for field, p in self.levels[k].equalities if p < self.width]
        if not tests:
            return [f"{pad}candidates = list(owners.values())"]
        field, p = tests[0]
        namespace[f"owners_by_value_{p}"] = self.owner_index[p]
        lines = key_lines(f"wme.{field}", pad, field != "id")
        lines += [f"{pad}found = owners_by_value_{p}.get(key)", f"{pad}if not found: return"]
        if len(tests) == 1:
            return [*lines, f"{pad}candidates = list(found)"]
        rest = tests[1:]
        lines += [f"{pad}tested_{n} = wme.{field}" for n, (field, _) in enumerate(rest)]
        same = " and ".join(f"same_symbol(token.vals[{p}], tested_{n})"
                            for n, (_, p) in enumerate(rest))
        return [*lines, f"{pad}candidates = [token for token in found if {same}]"]

    # ----- plain Python -----

    def plain_left_activate(self, parent: Token) -> None:
        """Plain Python: a parent token arrives (see ``_compile``)."""
        values = parent.vals
        token = new_token(parent, None, values, self)
        adopt(parent, token)
        self.owners[parent] = token
        for pos, index in self.owner_index.items():
            index_add(index, values[pos], token)
        found = self.solvers[0](values, None)  # type: ignore[misc]
        if found is None:
            self.store(token)
            return
        self._witness(token, found)

    def plain_forget(self, token: Token) -> None:
        """Plain Python: a parent token goes."""
        del self.owners[token.parent]
        values = token.vals
        for pos, index in self.owner_index.items():
            index_remove(index, values[pos], token)
        if token.extra is None:
            self.unstore(token)
            return
        self._unwitness(token)

    def plain_recheck(self, token: Token) -> None:
        """Plain Python: the witness of a blocked token is gone."""
        self._unwitness(token)
        found = self.solvers[0](token.vals, None)  # type: ignore[misc]
        if found is None:
            self.store(token)
            return
        self._witness(token, found)

    def plain_inner_added(self, k: int, wme: WME) -> None:
        """Plain Python: ``wme`` entered the memory of inner condition ``k``."""
        level = self.levels[k]
        if level.negated:
            for token in self._candidates(k, wme):
                found = token.extra
                if found is None or token.node is None:
                    continue
                values = found[0]
                if level.position >= 0 and not same_symbol(
                        values[level.position], getattr(wme, level.equalities[0][0])):
                    continue
                if level.check is not None and not level.check(values, wme):
                    continue
                self.recheck(token)
            return
        for getter, index in self.seed_filters[k]:
            if hash_key(getter(wme)) not in index:
                return
        solve = self.solvers[k + 1]
        for token in self._candidates(k, wme):
            if token.extra is None and token.node is not None:
                found = solve(token.vals, wme)  # type: ignore[misc]
                if found is not None:
                    self._block(token, found)

    # ----- witnesses -----

    def _witness(self, token: Token, found: tuple[tuple, tuple]) -> None:
        """Keep ``found`` as the witness of the blocked ``token`` (``witness_lines``)."""
        token.extra = found
        records = self.registry
        for witness in found[1]:
            record = records[witness]
            if record[WITNESSED] is None:
                record[WITNESSED] = {token: None}
            else:
                record[WITNESSED][token] = None

    def _unwitness(self, token: Token) -> None:
        """Drop the witness of ``token`` (``_unwitness_lines``)."""
        for witness in token.extra[1]:
            record = self.registry.get(witness)
            if record is not None and record[WITNESSED]:
                record[WITNESSED].pop(token, None)
        token.extra = None

    def _block(self, token: Token, found: tuple[tuple, tuple]) -> None:
        self.unstore(token)
        delete_children(self.registry, token)
        self._witness(token, found)

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
        return [token for token in found
                if all(same_symbol(token.vals[pos], value) for value, pos in rest)]

    def inner_removed(self, k: int, wme: WME) -> None:
        """A WME left a negated inner condition's memory: results may appear."""
        for token in self._candidates(k, wme):
            if token.extra is None and token.node is not None:
                found = self.solvers[0](token.vals, None)  # type: ignore[misc]
                if found is not None:
                    self._block(token, found)


def _unwitness_lines(pad: str) -> list[str]:
    """Generated code: drop the witness of ``token`` (what ``_unwitness`` does)."""
    return [f"{pad}for witness in token.extra[1]:", f"{pad}    record = wme_records.get(witness)",
            f"{pad}    if record is not None and record[{WITNESSED}]:",
            f"{pad}        record[{WITNESSED}].pop(token, None)",
            f"{pad}token.extra = None"]
