"""Lark's parse errors as `SoarSyntaxError`: file, line, column, the source line (which the
error prints with a caret under the column) and the expected tokens in words.

No Lark exception escapes `parser.parse`: each becomes one of these, so that a rule-file author
reads "unexpected ')'... expected one of: constant, variable" rather than terminal names.
"""

from __future__ import annotations

from collections.abc import Collection

from lark import Token
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken

from sann.soar.errors import SoarSyntaxError

__all__ = ["end_position", "from_lark", "syntax_error"]

#: Lark terminal names -> words for "expected ..." in error messages.
_READABLE = {
    "SP": "'sp'", "STATE": "'state'", "IMPASSE": "'impasse'", "ARROW": "'-->'",
    "LPAR": "'('", "RPAR": "')'", "LBRACE": "'{'", "RBRACE": "'}'", "CIRCUMFLEX": "'^'",
    "DOT": "'.'", "COMMA": "','", "SEMICOLON": "';'", "BANG": "'!'", "TILDE": "'~'",
    "MINUS": "'-'", "PLUS": "'+'", "LT": "'<'", "GT": "'>'", "EQ": "'='", "NE": "'<>'",
    "LE": "'<='", "GE": "'>='", "LEG": "'<=>'", "LTLT": "'<<'", "GTGT": "'>>'", "AT": "'@'",
    "NOTAT": "'!@'", "FLAG": "flag (:o-support, :i-support, :default, ...)",
    "VARIABLE": "variable", "SYMBOL": "symbol", "IDLIKE": "symbol", "INT": "integer",
    "FLOAT": "float", "QSTRING": "|string|", "DQSTRING": '"string"',
    "COMMAND_NAME": "command", "SHELL_COMMAND": "command", "WORD": "argument",
    "_NL": "end of line", "$END": "end of input",
}  # fmt: skip


_CONSTANTS = {"symbol", "integer", "float", "|string|"}
_RELATIONS = {"'<>'", "'<'", "'>'", "'<='", "'>='", "'<=>'", "'@'", "'!@'", "'='"}


def _readable(names: Collection[str]) -> tuple[str, ...]:
    """Terminal names -> words, with the usual groups said once ("constant", "relation")."""
    words = {_READABLE.get(name, name) for name in names}
    if _CONSTANTS <= words:
        words = (words - _CONSTANTS) | {"constant"}
    if _RELATIONS <= words:
        words = (words - _RELATIONS) | {"relation (<> < > <= >= <=> = @ !@)"}
    return tuple(sorted(words))


def _source_line(text: str, line: int) -> str:
    lines = text.splitlines()
    return lines[line - 1] if 1 <= line <= len(lines) else ""


def syntax_error(
    text: str, file: str, message: str, line: int, column: int, expected: tuple[str, ...] = ()
) -> SoarSyntaxError:
    line, column = max(1, line), max(1, column)
    return SoarSyntaxError(message, file, line, column, _source_line(text, line), expected)


def end_position(text: str) -> tuple[int, int]:
    """Where "unexpected end of input" points: just after the last non-blank character, so
    the message shows the unfinished line rather than an empty one."""
    end = len(text.rstrip())
    line_start = text.rfind("\n", 0, end) + 1
    return text.count("\n", 0, end) + 1, end - line_start + 1


# Terminals that only the root lexer can produce inside a production: when the parser's
# state accepts none of its terminals, Lark retries with every terminal and these long
# command-word patterns win, so the token's text is not what the user wrote as one word.
_FALLBACK_TYPES = ("COMMAND_NAME", "WORD", "SHELL_COMMAND", "SP")


def _describe_token(token: Token) -> str:
    if token.type == "$END":
        return "end of input"
    if token.type == "_NL":
        return "end of line"
    text = str(token)
    if token.type in _FALLBACK_TYPES:  # the root lexer's guess: only its first character counts
        text = text[:1]
    shown = f"'{text}'" if text.isprintable() and "'" not in text else repr(text)
    kind = _READABLE.get(token.type, "")
    if kind.startswith("'") or token.type in ("COMMAND_NAME", "WORD"):
        return shown
    return f"{kind} {shown}"


def from_lark(error: UnexpectedInput, text: str, file: str) -> SoarSyntaxError:
    """Translate any Lark parse error into a SoarSyntaxError with a position."""
    if isinstance(error, UnexpectedToken) and error.token.type != "$END":
        token = error.token
        expected = _readable(error.accepts or error.expected)
        message = f"unexpected {_describe_token(token)}"
        if token.type in _FALLBACK_TYPES and token[:1] in '|"':
            message = f"unterminated string: no closing {token[:1]}"
        return syntax_error(text, file, message, token.line or 1, token.column or 1, expected)
    if isinstance(error, UnexpectedCharacters):
        at = error.pos_in_stream
        char = text[at] if at is not None and at < len(text) else ""
        expected = _readable(error.allowed or ())
        message = f"unexpected character {char!r}"
        return syntax_error(text, file, message, error.line, error.column, expected)
    expected = _readable(getattr(error, "expected", None) or ())
    line, column = end_position(text)
    return syntax_error(text, file, "unexpected end of input", line, column, expected)

