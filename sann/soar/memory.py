"""Symbols and working-memory elements.

Constants are plain Python values (``str`` for symbolic constants, ``int``, ``float``) so
that matching compares and hashes them at C speed. Identifiers are objects compared by
identity; their printed name is a letter and a number as in Soar (S1, I2, O3).
"""

from __future__ import annotations

from collections import defaultdict


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

    __str__ = __repr__


Symbol = Identifier | str | int | float


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
    """Print a symbol as Soar does: strings that would not re-read as the same symbol get
    vertical bars."""
    if isinstance(value, Identifier):
        return value.name
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, int):
        return str(value)
    return value if _is_plain_symbol(value) else "|" + value.replace("|", "\\|") + "|"


def _is_plain_symbol(text: str) -> bool:
    if not text or text[0] in "<>^()+-{}|@~!=&;\"" and text not in ("<", ">", "=", "+", "-"):
        return False
    if any(ch.isspace() or ch in "()|^{};\"" for ch in text):
        return False
    if text[0] == "<" and text[-1] == ">" and len(text) > 2:
        return False
    try:
        float(text)
        return False
    except ValueError:
        pass
    return not (len(text) >= 2 and text[0].isalpha() and text[0].isupper() and text[1:].isdigit())
