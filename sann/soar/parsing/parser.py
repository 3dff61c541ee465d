"""Parse Soar 9.6 rule files into the dataclasses of `sann.soar.production`.

API: `parse` (a file's productions and commands, in order), `parse_partial` (what precedes
the first error, and the error: how the kernel loads a file), `parse_file` and
`parse_production`.

The grammar is ``soar.lark`` beside this module (LALR(1), contextual lexer), read as package
data so that an installed package parses as the repository does. This module holds the parser
and what a grammar cannot say about lines: a post-lexer that makes newlines and ``;`` white
space inside braces (commands end at a newline or ``;``, productions span lines). The rules'
meaning is `transformer`'s; the load-time checks are `actions`'s and the Rete's; the
translation of Lark's exceptions is `errors`'s, so that no Lark exception escapes `parse`.
"""

from __future__ import annotations

import sys
import threading
import warnings
from collections.abc import Collection, Iterator
from functools import lru_cache
from importlib import resources
from pathlib import Path
from types import FrameType
from typing import cast

from lark import Lark, Token
from lark.exceptions import LarkError, UnexpectedCharacters, UnexpectedEOF, UnexpectedToken

from sann.soar.errors import SoarSemanticError, SoarSyntaxError, SoarWarning
from sann.soar.parsing.actions import KNOWN_RHS_FUNCTIONS, RhsNames
from sann.soar.parsing.errors import end_position, from_lark, syntax_error
from sann.soar.parsing.transformer import ToDataclasses
from sann.soar.production import Command, Production

__all__ = ["grammar_text", "parse", "parse_file", "parse_partial", "parse_production"]


def grammar_text() -> str:
    """The grammar, ``soar.lark`` of this package."""
    return resources.files(__package__).joinpath("soar.lark").read_text(encoding="utf-8")


class _BraceNewlines:
    """Post-lexer: a newline or `;` ends a command only outside braces; inside them both are
    white space (the kernel reads ``^a b;c`` as two values)."""

    always_accept = ("_NL", "SEMICOLON")

    def process(self, stream: Iterator[Token]) -> Iterator[Token]:
        depth = 0
        for token in stream:
            if token.type == "LBRACE":
                depth += 1
            elif token.type == "RBRACE":
                depth = max(0, depth - 1)
            elif token.type in self.always_accept and depth:
                continue
            yield token


@lru_cache(maxsize=1)
def _parser() -> tuple[Lark, ToDataclasses]:
    """Build the LALR parser once per process (about 0.1 s).

    The transformer runs inline, called by the parser at each reduction, so no parse tree is
    ever built (twice as fast as transforming a tree). Its per-parse state is reset by
    `parse` under `_LOCK`, which makes parsing thread-safe.
    """
    transformer = ToDataclasses()
    parser = Lark(
        grammar_text(),
        parser="lalr",
        lexer="contextual",
        postlex=_BraceNewlines(),
        transformer=transformer,
        maybe_placeholders=False,
    )
    return parser, transformer


_LOCK = threading.Lock()


def _caller_stacklevel() -> int:
    """The warnings stack level of the first frame outside this module (the user's call)."""
    frame: FrameType | None = sys._getframe(1)
    level = 1
    while frame is not None and frame.f_code.co_filename == __file__:
        frame, level = frame.f_back, level + 1
    return level


# ---------------------------------------------------------------------------- public API


def parse(
    text: str, file: str = "<string>", functions: Collection[str] = KNOWN_RHS_FUNCTIONS
) -> list[Production | Command]:
    """Parse a rule file: its productions and commands in file order.

    ``functions`` is the set of RHS function names a production may call. Unless it is an
    `RhsNames` (as the default is), each call of a function the kernel knows is also checked
    as the kernel checks it: stand-alone or value, and the number of arguments. Raises
    SoarSyntaxError (with file, line, column) or SoarSemanticError (naming the production);
    the first error stops the parse, as in the kernel.
    """
    items, error = parse_partial(text, file, functions)
    if error is not None:
        raise error
    return items


def parse_partial(
    text: str, file: str = "<string>", functions: Collection[str] = KNOWN_RHS_FUNCTIONS
) -> tuple[list[Production | Command], SoarSyntaxError | SoarSemanticError | None]:
    """Parse up to the first error: the items complete before it, and the error (or None).

    This is what the kernel does with a file: everything before the first error is loaded,
    then the error is reported. (An item counts as complete once the parser has seen the
    token after it, so text right after a closing brace that cannot even be lexed also
    withholds that production.)
    """
    parser, transformer = _parser()
    if text.startswith("\ufeff"):  # a byte-order mark: white space, so columns stay right
        text = " " + text[1:]
    key = (text, file, frozenset(functions), isinstance(functions, RhsNames))
    with _LOCK:
        done = _PARSED.get(key)
        if done is not None:
            return list(done), None
        transformer.reset(text, file, functions)
        try:
            # The inline transformer's `start` makes the result a list, not a tree.
            items = cast(list[Production | Command], parser.parse(text))
            if not transformer.warnings:  # a file that warns warns again when re-read
                _remember(key, tuple(items))
            return items, None
        except (UnexpectedToken, UnexpectedCharacters, UnexpectedEOF) as error:
            return transformer.completed, from_lark(error, text, file)
        except (SoarSyntaxError, SoarSemanticError) as error:
            return transformer.completed, error
        except LarkError as error:  # defensive: any other Lark failure still gets a position
            line, column = end_position(text)
            message = f"cannot parse: {error}"
            return transformer.completed, syntax_error(text, file, message, line, column)
        finally:
            pending, transformer.warnings = transformer.warnings, []
            transformer.completed = []
            for message in pending:
                warnings.warn(message, SoarWarning, stacklevel=_caller_stacklevel())


# Parsed texts (productions and commands are frozen dataclasses, so agents can share them):
# re-sourcing an unchanged file, as a notebook re-run does, skips the parser.
_PARSED: dict[tuple[str, str, frozenset[str], bool], tuple[Production | Command, ...]] = {}
_PARSED_LIMIT = 256


def _remember(key: tuple[str, str, frozenset[str], bool], items: tuple) -> None:
    if len(_PARSED) >= _PARSED_LIMIT:
        del _PARSED[next(iter(_PARSED))]  # the oldest
    _PARSED[key] = items


def parse_file(path: str | Path, functions: Collection[str] = KNOWN_RHS_FUNCTIONS) -> list:
    """Parse a rule file from disk; errors name the file."""
    path = Path(path)
    return parse(path.read_text(encoding="utf-8"), str(path), functions)


def parse_production(
    text: str, file: str = "<string>", functions: Collection[str] = KNOWN_RHS_FUNCTIONS
) -> Production:
    """Parse text that holds exactly one ``sp {...}`` and nothing else."""
    items = parse(text, file, functions)
    if len(items) != 1 or not isinstance(items[0], Production):
        kinds = ", ".join(type(item).__name__ for item in items) or "nothing"
        location = next((i.location for i in items if i.location), None)
        line, column = (location.line, location.column) if location else (1, 1)
        raise syntax_error(
            text, file, f"expected exactly one production, found {kinds}", line, column
        )
    return items[0]
