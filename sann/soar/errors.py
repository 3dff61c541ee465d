"""Errors raised by the Soar engine, each saying where and what."""

from __future__ import annotations

from sann.soar.production import SourceLocation


class SoarError(Exception):
    """Base class of every error the engine reports to a user."""


class SoarSyntaxError(SoarError):
    """A rule file that does not parse: file:line:column, the line, a caret, what was expected."""

    def __init__(
        self,
        message: str,
        file: str = "<string>",
        line: int = 1,
        column: int = 1,
        source_line: str = "",
        expected: tuple[str, ...] = (),
    ) -> None:
        self.message = message
        self.file = file
        self.line = line
        self.column = column
        self.source_line = source_line
        self.expected = tuple(expected)
        super().__init__(self._render())

    def _render(self) -> str:
        text = f"{self.file}:{self.line}:{self.column}: {self.message}"
        if self.source_line:
            # Keep the line's tabs in the caret's indent so the caret lines up in a terminal.
            indent = "".join(c if c == "\t" else " " for c in self.source_line[: self.column - 1])
            caret = indent.ljust(self.column - 1) + "^"
            text += f"\n    {self.source_line.rstrip()}\n    {caret}"
        if self.expected:
            text += "\n  expected one of: " + ", ".join(self.expected)
        return text


class SoarSemanticError(SoarError):
    """A production that parses but cannot be loaded (unbound RHS variable, unlinked
    condition, unknown RHS function); the message names the production."""

    def __init__(
        self, production: str, message: str, location: SourceLocation | None = None
    ) -> None:
        self.production = production
        self.location = location
        where = f"{location.file}:{location.line}: " if location is not None else ""
        super().__init__(f"{where}production {production}: {message}")


class SoarRuntimeError(SoarError):
    """Something went wrong while running an agent (bad RHS arguments, runaway rules, ...)."""


class SoarWarning(UserWarning):
    """Something the kernel accepts with a warning (e.g. a preference other than ``+``/``-``
    on a non-operator attribute, which it ignores). Issued with :func:`warnings.warn`."""
