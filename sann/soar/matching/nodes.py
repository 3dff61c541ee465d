"""The beta network's nodes: the root, join nodes and negative nodes, NCC nodes with their
partners, and the deletion of tokens below them.

Join nodes generate their activations (``_compile``); the other nodes here are ordinary
methods.  The query NCC node, the run node and the production node have modules of their own.
"""

from __future__ import annotations

from collections.abc import Callable

from sann.soar.codegen import define, plain
from sann.soar.matching.alpha import AlphaMemory
from sann.soar.matching.templates import (
    CHECK_NAMES,
    EXTEND_VALUE,
    adopt_lines,
    check_lines,
    filing_lines,
    index_of,
    token_lines,
)
from sann.soar.matching.tokens import (
    BLOCKED,
    BUILT,
    FLOAT,
    GET,
    Token,
    adopt,
    compile_first,
    hash_key,
    index_add,
    index_remove,
    new_token,
)
from sann.soar.memory import WME, mypyc_attr


@mypyc_attr(native_class=False)  # methods and generated functions in the same places
class Node:
    """A beta node with its memory of (active) output tokens and hash indices on it."""

    __slots__ = ("registry", "parent", "key", "children", "child_map", "tokens", "indexes",
                 "index_list")

    def __init__(self, registry: dict[WME, list], parent: Node | None, key: object = None) -> None:
        self.registry = registry
        self.parent = parent
        self.key = key
        self.children: list[Node] = []
        self.child_map: dict[object, Node] = {}
        self.tokens: dict[Token, None] = {}
        self.indexes: dict[int, dict] = {}
        self.index_list: list[tuple[int, dict]] = []

    def index(self, pos: int) -> dict:
        index = self.indexes.get(pos)
        if index is None:
            index = {}
            for tok in self.tokens:
                index_add(index, tok.vals[pos], tok)
            self.indexes[pos] = index
            self.index_list.append((pos, index))
        return index

    def store(self, tok: Token) -> None:
        """Add an active output token and pass it to the children."""
        self.tokens[tok] = None
        if self.index_list:
            vals = tok.vals
            for pos, index in self.index_list:
                key = vals[pos]
                if type(key) is float:
                    key = (FLOAT, key)
                bucket = index.get(key)
                if bucket is None:
                    index[key] = {tok: None}
                else:
                    bucket[tok] = None
        for child in self.children:
            child.left_activate(tok)

    def forget(self, tok: Token) -> None:
        """Drop an active output token from the memory and its indices."""
        del self.tokens[tok]
        if self.index_list:
            vals = tok.vals
            for pos, index in self.index_list:
                key = vals[pos]
                if type(key) is float:
                    key = (FLOAT, key)
                bucket = index[key]
                del bucket[tok]
                if not bucket:
                    del index[key]

    def unstore(self, tok: Token) -> None:
        """`Node.forget` whatever the subclass's ``forget`` (not ``unstore = forget``: mypyc
        fails on that in a non-native class)."""
        Node.forget(self, tok)

    def all_tokens(self) -> list[Token]:
        return list(self.tokens)

    def activation(self, amem: AlphaMemory) -> Callable[[WME], None]:
        """What a WME entering ``amem`` calls (a join or negative node: right_activate)."""
        return self.right_activate  # type: ignore[attr-defined]

    def left_activate(self, tok: Token) -> None:  # the root has no parent
        raise AssertionError("the root node is never activated")


@mypyc_attr(native_class=False)  # methods and generated functions in the same places
class JoinNode(Node):
    """Joins parent tokens with the WMEs of an alpha memory, hashed on one equality test.

    This is the innermost loop of the matcher, so both activations are generated for the
    node as straight-line code (its test, what a new token binds and the indices on its
    tokens are fixed when it is compiled).  They are compiled on first use, and again after
    an index is added to the node's memory; the alpha memory then picks up the new
    ``right_activate``.  ``plain_left_activate`` and ``plain_right_activate`` do the same
    in plain Python (``codegen.plain()``)."""

    __slots__ = ("amem", "pos", "field", "check", "extend", "left_activate",
                 "right_activate")

    def __init__(self, registry: dict[WME, list], parent: Node, key: object, amem: AlphaMemory,
                 index: tuple[int, str] | None, check: Callable | None,
                 extend: Callable | None) -> None:
        super().__init__(registry, parent, key)
        self.amem = amem
        self.check = check
        self.extend = extend
        self.pos, self.field = (-1, "") if index is None else index
        if index is not None:  # the hashes both activations look up
            amem.index(self.field)
            parent.index(self.pos)
        self.left_activate: Callable[[Token], None]
        self.right_activate: Callable[[WME], None]
        compile_first(self, "left_activate", "right_activate")

    def index(self, pos: int) -> dict:
        known = pos in self.indexes
        index = super().index(pos)
        if not known:  # the generated code updates the indices it knew of
            compile_first(self, "left_activate", "right_activate")
            self.amem._relink()  # it holds the right activation
        return index

    def _compile(self) -> None:
        if plain():
            self.left_activate = self.plain_left_activate
            self.right_activate = self.plain_right_activate
            self.amem._relink()
            return
        hashed = self.pos >= 0
        namespace: dict[str, object] = {
            **CHECK_NAMES, "FLOAT": FLOAT, "Token": Token, "node": self,
            "extend": self.extend, "wme_records": self.registry, "tokens": self.tokens,
            "children": self.children}
        if hashed:
            namespace["alpha_index"] = self.amem.indexes[self.field]
            namespace["parent_index"] = self.parent.indexes[self.pos]  # type: ignore[union-attr]
        else:
            namespace["alpha_wmes"] = self.amem.wmes
            namespace["parent_tokens"] = self.parent.tokens  # type: ignore[union-attr]
        grow = ("values" if self.extend is None else "values + (wme.value,)"
                if self.extend is EXTEND_VALUE else "extend(values, wme)")

        left = ["def left_activate(parent):", "    values = parent.vals"]
        if hashed:
            left += [f"    key = values[{self.pos}]",
                     "    if key.__class__ is float: key = (FLOAT, key)",
                     "    bucket = alpha_index.get(key)", "    if bucket is None: return"]
        left += [f"    for wme in {'bucket' if hashed else 'alpha_wmes'}:"] + join_body(
            self, namespace, grow, f"wme_records[wme][{BUILT}][token] = None")
        right = ["def right_activate(wme):"]
        if hashed:
            right.append(f"    key = wme.{self.field}")
            if self.field != "id":  # identifiers are never floats
                right.append("    if key.__class__ is float: key = (FLOAT, key)")
            right += ["    bucket = parent_index.get(key)", "    if bucket is None: return"]
        right += [f"    built = wme_records[wme][{BUILT}]",
                  f"    for parent in {'bucket' if hashed else 'parent_tokens'}:",
                  "        values = parent.vals"] + join_body(
            self, namespace, grow, "built[token] = None")
        self.left_activate = define(left, namespace, "left_activate", "rete:join")
        self.right_activate = define(right, namespace, "right_activate", "rete:join")
        self.amem._relink()  # the alpha memory calls the compiled right_activate from now on

    def plain_left_activate(self, parent: Token) -> None:
        """Plain Python: a new parent token joins each WME of the alpha memory it fits."""
        values = parent.vals
        if self.pos >= 0:
            bucket = index_of(self.amem.indexes[self.field], values[self.pos])
            if bucket is None:
                return
        else:
            bucket = self.amem.wmes
        for wme in bucket:  # type: ignore[attr-defined]
            self._plain_join(parent, values, wme, self.registry[wme][BUILT])

    def plain_right_activate(self, wme: WME) -> None:
        """Plain Python: a new WME joins each parent token it fits."""
        if self.pos >= 0:
            bucket = index_of(self.parent.indexes[self.pos],  # type: ignore[union-attr]
                              getattr(wme, self.field))
            if bucket is None:
                return
        else:
            bucket = self.parent.tokens  # type: ignore[union-attr]
        built = self.registry[wme][BUILT]
        for parent in bucket:  # type: ignore[attr-defined]
            self._plain_join(parent, parent.vals, wme, built)

    def _plain_join(self, parent: Token, values: tuple, wme: WME, built: dict) -> None:
        """Test the pair, make the token, register it with its WME (``built``), store it in
        the memory and its indices and pass it on (``join_body``)."""
        check = self.check
        if check is not None and not check(values, wme):
            return
        extend = self.extend
        extended = values if extend is None else extend(values, wme)
        token = new_token(parent, wme, extended, self)
        adopt(parent, token)
        built[token] = None
        self.tokens[token] = None
        for pos, index in self.index_list:
            index_add(index, extended[pos], token)
        for child in self.children:
            child.left_activate(token)


def join_body(node: JoinNode, namespace: dict[str, object], grow: str,
              register: str) -> list[str]:
    """Test the pair, make the token, register, index and pass it on (a function of its
    own, not nested in ``JoinNode._compile``: mypyc fails on a closure there)."""
    lines = [] if node.check is None else check_lines(
        node.check.specs, "values", "wme", "continue", "")  # type: ignore[attr-defined]
    lines += [f"extended = {grow}", *token_lines("", "parent", "wme", "extended"),
              *adopt_lines("", "parent"), register, "tokens[token] = None"]
    for k, (pos, index) in enumerate(node.index_list):
        namespace[f"token_index_{k}"] = index
        lines += filing_lines(f"token_index_{k}", f"extended[{pos}]", "token", "", True)
    lines += ["for child in children:", "    child.left_activate(token)"]
    return ["        " + line for line in lines]


@mypyc_attr(native_class=False)  # methods and generated functions in the same places
class NegativeNode(Node):
    """Passes a parent token on while no WME of its alpha memory joins with it."""

    __slots__ = ("amem", "pos", "getter", "amem_index", "check", "every", "every_index")

    def __init__(self, registry: dict[WME, list], parent: Node, key: object, amem: AlphaMemory,
                 index: tuple[int, str] | None, check: Callable | None) -> None:
        super().__init__(registry, parent, key)
        self.amem = amem
        self.check = check
        self.every: dict[Token, None] = {}  # blocked and active tokens
        self.every_index: dict = {}
        if index is None:
            self.pos = -1
            self.getter = None
            self.amem_index = None
        else:
            self.pos, field = index
            self.getter = GET[field]
            self.amem_index = amem.index(field)

    def all_tokens(self) -> list[Token]:
        return list(self.every)

    def left_activate(self, t: Token) -> None:
        vals = t.vals
        tok = new_token(t, None, vals, self)
        adopt(t, tok)
        self.every[tok] = None
        if self.pos >= 0:
            value = vals[self.pos]
            index_add(self.every_index, value, tok)
            bucket = self.amem_index.get((FLOAT, value) if type(value) is float else value)
        else:
            bucket = self.amem.wmes
        blockers: dict[WME, None] | None = None
        if bucket:
            check = self.check
            for wme in bucket:
                if check is None or check(vals, wme):
                    if blockers is None:
                        blockers = {}
                    blockers[wme] = None
        if blockers is None:
            self.store(tok)
            return
        tok.extra = blockers
        info = self.registry
        for wme in blockers:
            _blocked_by(info[wme], tok)

    def right_activate(self, wme: WME) -> None:
        if self.pos >= 0:
            bucket = self.every_index.get(hash_key(self.getter(wme)))
            if bucket is None:
                return
        else:
            bucket = self.every
        check = self.check
        info = self.registry[wme]
        for tok in bucket:
            if check is None or check(tok.vals, wme):
                blockers = tok.extra
                if blockers is None:
                    tok.extra = {wme: None}
                    self.unstore(tok)
                    delete_children(self.registry, tok)
                else:
                    blockers[wme] = None
                _blocked_by(info, tok)

    def unblock(self, tok: Token) -> None:
        tok.extra = None
        self.store(tok)

    def forget(self, tok: Token) -> None:
        del self.every[tok]
        if self.pos >= 0:
            index_remove(self.every_index, tok.vals[self.pos], tok)
        if tok.extra is None:
            self.unstore(tok)
            return
        info = self.registry
        for wme in tok.extra:
            record = info.get(wme)
            if record is not None and record[BLOCKED]:
                record[BLOCKED].pop(tok, None)


def _blocked_by(record: list, tok: Token) -> None:
    """Note in a WME's record that it blocks the negative-node token ``tok``."""
    blocked = record[BLOCKED]
    if blocked is None:
        record[BLOCKED] = {tok: None}
    else:
        blocked[tok] = None


@mypyc_attr(native_class=False)  # methods and generated functions in the same places
class NCCNode(Node):
    """Conjunctive negation: passes a parent token on while its subnetwork has no result
    for it.  Results arrive through the partner node at the bottom of the subnetwork."""

    __slots__ = ("partner", "owners")

    def __init__(self, registry: dict[WME, list], parent: Node, key: object) -> None:
        super().__init__(registry, parent, key)
        self.partner: PartnerNode | None = None
        self.owners: dict[Token, Token] = {}  # parent token -> this node's token

    def all_tokens(self) -> list[Token]:
        return list(self.owners.values())

    def left_activate(self, t: Token) -> None:
        tok = new_token(t, None, t.vals, self)
        adopt(t, tok)
        self.owners[t] = tok
        results = self.partner.buffer.pop(t, None)  # type: ignore[union-attr]
        if results:
            tok.extra = results
            for result in results:
                result.extra = tok
        else:
            self.store(tok)

    def block(self, owner: Token, result: Token) -> None:
        results = owner.extra
        if results is None:
            owner.extra = {result: None}
            self.unstore(owner)
            delete_children(self.registry, owner)
        else:
            results[result] = None

    def release(self, owner: Token, result: Token) -> None:
        results = owner.extra
        del results[result]
        # An owner whose parent is being deleted stays blocked (and unstored) until its turn.
        if not results and owner.parent.node is not None:
            owner.extra = None
            self.store(owner)

    def forget(self, tok: Token) -> None:
        del self.owners[tok.parent]
        if tok.extra is None:
            self.unstore(tok)
            return
        for result in tok.extra:
            result.extra = None


@mypyc_attr(native_class=False)  # methods and generated functions in the same places
class PartnerNode(Node):
    """Bottom of an NCC subnetwork: each token reaching it is a result for the NCC token
    ``levels`` levels up."""

    __slots__ = ("ncc", "levels", "buffer")

    def __init__(self, registry: dict[WME, list], parent: Node, ncc: NCCNode, levels: int) -> None:
        super().__init__(registry, parent, ("partner", id(ncc)))
        self.ncc = ncc
        self.levels = levels
        self.buffer: dict[Token, dict[Token, None]] = {}

    def _owner_key(self, bottom: Token) -> Token:
        t = bottom
        for _ in range(self.levels):
            t = t.parent
        return t

    def left_activate(self, bottom: Token) -> None:
        result = new_token(bottom, None, (), self)
        adopt(bottom, result)
        self.tokens[result] = None
        t = self._owner_key(bottom)
        owner = self.ncc.owners.get(t)
        if owner is None:  # the NCC node sees this parent token right after us
            waiting = self.buffer.get(t)
            if waiting is None:
                self.buffer[t] = {result: None}
            else:
                waiting[result] = None
            return
        result.extra = owner
        self.ncc.block(owner, result)

    def forget(self, result: Token) -> None:
        del self.tokens[result]
        owner = result.extra
        if owner is None:
            waiting = self.buffer.get(self._owner_key(result.parent))
            if waiting is not None:
                waiting.pop(result, None)
        elif owner.node is not None:
            self.ncc.release(owner, result)


def delete_children(registry: dict[WME, list], tok: Token) -> None:
    """Delete the descendants of ``tok`` (a token that stays)."""
    children = tok.children
    if children:
        tok.children = None
        delete_tokens(registry, list(children))

def delete_tokens(registry: dict[WME, list], stack: list[Token]) -> None:
    """Delete tokens (already detached from their parents) and all their descendants.
    A token is marked dead (node None) before its descendants are visited, which an NCC
    owner relies on (see NCCNode.release).  Join-node tokens, the bulk, are dropped
    inline."""
    info = registry
    join = JoinNode
    while stack:
        tok = stack.pop()
        node = tok.node
        if node is None:
            continue
        if type(node) is join:
            del node.tokens[tok]
            if node.index_list:
                vals = tok.vals
                for pos, index in node.index_list:
                    key = vals[pos]
                    if type(key) is float:
                        key = (FLOAT, key)
                    bucket = index[key]
                    del bucket[tok]
                    if not bucket:
                        del index[key]
            record = info.get(tok.wme)
            if record is not None:
                del record[BUILT][tok]
        else:
            node.forget(tok)
        tok.node = None
        children = tok.children
        if children:
            tok.children = None
            for child in children:  # not stack.extend: compiled, it copies the dict first
                stack.append(child)
