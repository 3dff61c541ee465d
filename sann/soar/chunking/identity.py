"""Identities of Soar 9.6's explanation-based chunking, as a union-find.

Every variable of every rule firing behind a result has an *identity*; backtracing through
a local WME unifies the identities of the condition that tested it with those of the action
that made it, so that one variable of the chunk stands for everything the explanation says
must be the same symbol. An identity unified with a constant (a literal on the right-hand
side, or the value of a function) is *literalized*: the chunk tests that constant
(measured in soar_sml: ``(<ss> ^x <x>)`` behind ``(<s> ^sum (+ <x> <y>))`` becomes ``^x
3``). States are one identity per state: the kernel gives the superstate one variable
however many rules reached it.
"""

from __future__ import annotations

from collections.abc import Hashable

Key = Hashable


class Identities:
    """Union-find over identity keys, with the set of literalized roots."""

    def __init__(self) -> None:
        self.parent: dict[Key, Key] = {}
        self.literal: set[Key] = set()

    def find(self, key: Key) -> Key:
        parent = self.parent
        root = key
        up = parent.get(root)
        while up is not None:
            root = up
            up = parent.get(root)
        while key != root:  # path compression
            up = parent[key]
            parent[key] = root
            key = up
        return root

    def union(self, a: Key, b: Key) -> None:
        """Make ``a`` and ``b`` one identity (literal if either was)."""
        ra, rb = self.find(a), self.find(b)
        if ra == rb:
            return
        self.parent[rb] = ra
        if rb in self.literal:
            self.literal.discard(rb)
            self.literal.add(ra)

    def literalize(self, key: Key) -> None:
        self.literal.add(self.find(key))

    def is_literal(self, key: Key) -> bool:
        return self.find(key) in self.literal
