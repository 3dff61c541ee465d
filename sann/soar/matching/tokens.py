"""Tokens (partial matches in the beta network) and the hash indices that file them.

Tokens carry a flat tuple ``vals`` of the variable values bound so far (one slot per
binding join), so that a join test or a hash key is one tuple index.  Every beta node keeps
its own output memory (``tokens``) and, on demand, hash indices of it on the value positions
its children join on; alpha memories keep hash indices on the WME fields their join nodes
test.  Removal is tree-based: each WME knows its alpha memories, the tokens built on it and
the negative-node tokens it blocks; each token knows its children.
"""

from __future__ import annotations

from operator import attrgetter
from typing import Any, Final

from sann.soar.memory import mypyc_attr

FLOAT = object()  # hash keys of floats are (FLOAT, x): 1.0 must never meet 1 in a join
ANY = object()  # alpha index: no constant test on this field
IDENT = object()  # alpha cache: any identifier
UNTESTED = object()  # alpha cache: any value no alpha memory tests for
FIELDS = ("id", "attr", "value")
GET = {name: attrgetter(name) for name in FIELDS}
_INDEX_PREFERENCE = {"id": 0, "value": 1, "attr": 2}
ALPHA_CACHE_LIMIT = 100_000

#: A WME's record in the Rete (``Rete._wme_info``) is a list indexed by these: its alpha
#: memories, the tokens built on it, the negative-node tokens it blocks and the query NCC
#: tokens it is a witness of (a list, not an object: the generated code indexes it).
AMEMS: Final = 0
BUILT: Final = 1
BLOCKED: Final = 2
WITNESSED: Final = 3


def hash_key(value: object) -> object:
    return (FLOAT, value) if type(value) is float else value


def typed(value: object) -> tuple[str, object]:
    """A constant inside a sharing key: 1, 1.0 and "1" must give different keys."""
    return (value.__class__.__name__, value)


def index_add(index: dict, value: object, item: object) -> None:
    """File ``item`` under ``value`` (hashed as ``hash_key`` does, inline: this is hot)."""
    key = (FLOAT, value) if type(value) is float else value
    bucket = index.get(key)
    if bucket is None:
        index[key] = {item: None}
    else:
        bucket[item] = None


def index_remove(index: dict, value: object, item: object) -> None:
    key = (FLOAT, value) if type(value) is float else value
    bucket = index[key]
    del bucket[item]
    if not bucket:
        del index[key]


@mypyc_attr(native_class=False)  # made and read by generated code
class Token:
    """A partial match: ``parent`` token, ``wme`` (or the tuple of a run node's WMEs),
    ``vals`` the tuple of variable values bound so far, ``node`` the beta node that owns it
    (``None`` once deleted), ``children`` a dict of child tokens or None, and ``extra``
    depends on the node: the blocking WMEs of a negative-node token, the results of an NCC
    owner, the owner of an NCC partner result, the witness of a query-NCC token, the Match
    of a production-node token.  Hashed by identity.

    Slots, not a list: CPython 3.11 specializes slot reads and writes, not the subscripts of
    a list subclass, and the hot paths read tokens all the time.  No
    ``__init__``: tokens are made by calling the bare class and storing the six slots
    (inline in generated code, ``token_lines``), cheaper than passing them to ``__init__``
    and than ``object.__new__(Token)``."""

    __slots__ = ("parent", "wme", "vals", "node", "children", "extra")
    parent: Any
    wme: Any
    vals: Any
    node: Any
    children: Any
    extra: Any


new_object = object.__new__


def new_token(parent: Token | None, wme: object, vals: tuple, node: object,
               extra: object = None) -> Token:
    tok = Token()
    tok.parent, tok.wme, tok.vals, tok.node = parent, wme, vals, node
    tok.children = None
    tok.extra = extra
    return tok




def adopt(parent: Token, tok: Token) -> None:
    children = parent.children
    if children is None:
        parent.children = {tok: None}
    else:
        children[tok] = None


class CompileFirst:
    """Stands in for a node's generated function until the node generates its code: the
    first call runs the node's ``_compile`` (which replaces every stand-in) and then the
    function it made. Nodes reset their functions to stand-ins when what the code was
    generated from changes."""

    __slots__ = ("node", "name")

    def __init__(self, node: object, name: str) -> None:
        self.node = node
        self.name = name

    def __call__(self, *args: object) -> None:
        self.node._compile()  # type: ignore[attr-defined]
        getattr(self.node, self.name)(*args)


def compile_first(node: object, *names: str) -> None:
    """Set the node's generated functions ``names`` to stand-ins (``CompileFirst``)."""
    for name in names:
        setattr(node, name, CompileFirst(node, name))



def unlink_tokens(root: Token) -> None:
    """Cut the links from every token below ``root`` to its children and to what its node
    keeps in ``extra`` (results, owners, matches), leaving only child-to-parent links: the
    dropped tokens then hold no cycle, and reference counting frees them at once instead of
    the cyclic garbage collector later."""
    stack = [root]
    while stack:
        tok = stack.pop()
        children = tok.children
        if children:
            stack.extend(children)
        tok.children = tok.extra = None
