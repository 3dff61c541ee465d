"""Every way the engine writes a symbol as text, side by side, because the kernel has several
and they differ in exactly the cases a reader trips on (a float, a string with a space, a
string that reads as a number):

==================  ==============================  =========  =========  ===========
rendering           used by                         ``|a b|``  ``|2|``    ``1.5``
==================  ==============================  =========  =========  ===========
`format_symbol`     print, traces, error messages   ``|a b|``  ``|2|``    ``1.500000``
`format_value`      write, concat, log              ``a b``    ``2``      ``1.500000``
`format_constant`   production text                 ``|a b|``  ``|2|``    ``1.5``
`string_text`       the ``string`` function         ``a b``    ``2``      ``1.50000000000000000``
==================  ==============================  =========  =========  ===========

(The kernel's error messages show a symbol as ``print`` does: ``non-number (|2|) passed as
'count'``, measured.) The float column is the one that differs most: only production text
keeps every digit, so that printing a production and reading it back gives it again.

`format_symbol`, `float_text` (C's ``%f``) and `string_needs_bars` live with the symbols in
`sann.soar.memory`, whose ``WME`` prints itself with them; they are named here too so that this
module is the one place to look.
"""

from __future__ import annotations

from sann.soar.memory import Identifier, Symbol, float_text, format_symbol, string_needs_bars

__all__ = [
    "float_text",
    "format_constant",
    "format_symbol",
    "format_value",
    "string_needs_bars",
    "string_text",
]

_KEYWORDS = ("state", "impasse")


def format_value(value: Symbol) -> str:
    """A symbol as ``write``/``concat`` render it: identifiers by name, floats as ``%f``."""
    if isinstance(value, Identifier):
        return value.name
    if isinstance(value, float):
        return float_text(value)
    return str(value)


def string_text(value: Symbol) -> str:
    """A symbol as the kernel's ``string`` function makes it a string: a float with 17
    decimals (``(string 0.1)`` is ``0.10000000000000001``), not as ``write`` shows it."""
    if type(value) is float:
        return f"{value:.17f}"
    return format_value(value)


def format_constant(value: str | int | float, keyword_safe: bool = False) -> str:
    """A constant as Soar reads it back: a string as the kernel prints it
    (`string_needs_bars`), floats always with a decimal point and every digit (the kernel
    prints six decimals, which loses precision). ``keyword_safe`` puts bars around ``state``
    and ``impasse``, which as an identifier test would read as the keyword."""
    if isinstance(value, bool):
        raise TypeError(f"Soar has no boolean constants: {value!r}")
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return _full_float(value)
    if keyword_safe and value in _KEYWORDS:
        return f"|{value}|"
    return format_symbol(value)


def _full_float(value: float) -> str:
    if value != value or value in (float("inf"), float("-inf")):
        raise ValueError(f"Soar cannot write the float {value!r}")
    text = repr(value)
    if "." not in text:  # 1e+20 -> 1.0e+20: Soar reads a run without '.' as a symbol
        mantissa, _, exponent = text.partition("e")
        text = f"{mantissa}.0" + (f"e{exponent}" if exponent else "")
    return text
