"""Symbols and working-memory elements.

Constants are plain Python values (``str`` for symbolic constants, ``int``, ``float``) so
that matching compares and hashes them at C speed. Identifiers are objects compared by
identity; their printed name is a letter and a number as in Soar (S1, I2, O3).
"""

from __future__ import annotations

import math
import re
from collections import defaultdict

from mypy_extensions import mypyc_attr


@mypyc_attr(native_class=False)  # weak references, and read by generated code
class Identifier:
    """A Soar identifier. ``level`` is the goal-stack depth of a state (1 = top), ``None``
    for identifiers that are not states; substate links and GDS live in the agent."""

    __slots__ = ("letter", "number", "level", "__weakref__")

    def __init__(self, letter: str, number: int, level: int | None = None) -> None:
        self.letter = letter
        self.number = number
        self.level = level

    @property
    def is_state(self) -> bool:
        return self.level is not None

    @property
    def name(self) -> str:
        return f"{self.letter}{self.number}"

    def __repr__(self) -> str:
        return self.name

    def __str__(self) -> str:  # not ``__str__ = __repr__``: mypyc's non-native classes
        return f"{self.letter}{self.number}"


Symbol = Identifier | str | int | float


def rhs_id_hint(variable: str) -> str:
    """The naming hint of an identifier that an unbound RHS variable makes: the variable
    itself, except that the kernel keeps the letter S for states and names an identifier
    made by ``<s...>`` with I (measured in soar_sml: ``(<s> ^x <small>)`` makes I4)."""
    return "I" if variable[:1] in ("s", "S") else variable


class IdentifierFactory:
    """Hands out identifiers named like Soar: the first letter of the attribute that
    created them (upper-cased, ``I`` for non-letters) and the next number for that letter."""

    def __init__(self) -> None:
        self._counters: defaultdict[str, int] = defaultdict(int)
        self._letters: dict[object, str] = {}  # hint -> letter (the same few hints recur)

    def new(self, hint: object = "I", level: int | None = None) -> Identifier:
        letter = self._letters.get(hint)
        if letter is None:
            text = str(hint)
            letter = text[0].upper() if text and text[0].isalpha() else "I"
            if type(hint) is str:
                self._letters[hint] = letter
        number = self._counters[letter] + 1
        self._counters[letter] = number
        return Identifier(letter, number, level)

    def reset(self) -> None:
        self._counters.clear()


@mypyc_attr(native_class=False)  # weak references, and read by generated code
class WME:
    """``(id ^attr value)`` with a timetag. ``acceptable`` marks an acceptable operator
    preference shown in working memory as ``(S1 ^operator O1 +)``."""

    __slots__ = ("id", "attr", "value", "timetag", "acceptable", "__weakref__")

    def __init__(
        self, id: Identifier, attr: Symbol, value: Symbol, timetag: int, acceptable: bool = False
    ) -> None:
        self.id = id
        self.attr = attr
        self.value = value
        self.timetag = timetag
        self.acceptable = acceptable

    def __repr__(self) -> str:
        plus = " +" if self.acceptable else ""
        attr, value = format_symbol(self.attr), format_symbol(self.value)
        return f"({self.timetag}: {self.id} ^{attr} {value}{plus})"


def format_symbol(value: Symbol) -> str:
    """A symbol as the kernel prints it in working memory, traces and messages (its
    ``to_string`` with ``rereadable``): identifiers by name, floats as ``%f``
    (`float_text`), strings in bars where `string_needs_bars`."""
    kind = type(value)
    if kind is str:
        if string_needs_bars(value):  # type: ignore[arg-type]
            return "|" + value.replace("\\", "\\\\").replace("|", "\\|") + "|"  # type: ignore[union-attr]
        return value  # type: ignore[return-value]
    if kind is Identifier:
        return value.name  # type: ignore[union-attr]
    if kind is float:
        return float_text(value)  # type: ignore[arg-type]
    return str(value)


def float_text(value: float) -> str:
    """C's ``%f``, as the kernel prints a float: a NaN with its sign bit set is ``-nan``
    (measured: ``(sqrt -1)``), infinities ``inf``/``-inf``."""
    if value != value:
        return "-nan" if math.copysign(1.0, value) < 0 else "nan"
    return f"{value:f}"


# The kernel's lexer reads a run of these characters as one symbol (lexer.cpp's
# ``constituent_char``: letters, digits and ``$%&*+-/:<=>?_@``).
_CONSTITUENTS = re.compile(r"[A-Za-z0-9$%&*+\-/:<=>?_@]+")
# Runs it would read as an integer, an identifier or a variable.
_NOT_A_STRING = re.compile(r"[+-]?[0-9]+|[A-Za-z][0-9]+|<.*>")
_ALPHANUMERIC = re.compile(r"[A-Za-z0-9]+")


def string_needs_bars(text: str) -> bool:
    """Whether the kernel prints the string in vertical bars: when it is empty, holds a
    character that is not a constituent (space, ``.``, ``^``, ``|``, ``~``, ``!``, ``,``,
    non-ASCII ...), reads as an integer, identifier (a letter and digits, any case) or
    variable (``<...>``), or is shorter than four characters and holds a constituent that is
    not a letter or digit, ``*`` excepted (it could be a special lexeme like ``-->`` or
    ``<=``). Measured in soar_sml 9.6 on ~150 strings: ``|S1|``, ``|s1|``, ``|1|``, ``|1.5|``,
    ``|a-b|``, ``|***|``, ``|<x|`` but ``1e5``, ``a-bc``, ``****``, ``<=>a``, ``S1a``, ``*``.
    (Floats never need bars: a float text always holds a ``.``.)"""
    if not _CONSTITUENTS.fullmatch(text) or _NOT_A_STRING.fullmatch(text):
        return True
    return len(text) < 4 and text != "*" and not _ALPHANUMERIC.fullmatch(text)
