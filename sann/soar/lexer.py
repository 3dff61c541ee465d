"""A Pygments lexer for Soar rule files, so the book highlights ``.soar`` code.

Nothing is registered globally: the book's ``conf.py`` adds it with
``app.add_lexer("soar", SoarLexer)``. Tokens follow the parser's lexical rules (a run of
constituent characters is a variable, number, relation or symbol; ``|...|`` is a string;
``#`` starts a comment outside strings), so highlighting never disagrees with parsing.
"""

from __future__ import annotations

from pygments.lexer import RegexLexer, bygroups, include
from pygments.token import (
    Comment,
    Keyword,
    Name,
    Number,
    Operator,
    Punctuation,
    String,
    Text,
    Whitespace,
)

__all__ = ["SoarLexer"]

_C = r"A-Za-z0-9$%&*+\-/:<=>?_@"
_END = rf"(?![{_C}])"


class SoarLexer(RegexLexer):
    """Soar 9.6 productions (``sp {...}``) and the commands of an agent file."""

    name = "Soar"
    aliases = ["soar"]
    filenames = ["*.soar"]
    mimetypes = ["text/x-soar"]

    tokens = {
        "root": [
            (r"[ \t\r\f]+", Whitespace),
            (r"\n", Whitespace),
            (r"#[^\n]*", Comment.Single),
            (r";", Punctuation),
            (r"(sp)(\s*)(\{)", bygroups(Keyword.Declaration, Whitespace, Punctuation), "name"),
            (r'"(\\.|[^"\\])*"', String.Double),
            (r"[^\s;{}\"#]+", Name.Builtin, "command"),
        ],
        "command": [
            (r"\n", Whitespace, "#pop"),
            (r";", Punctuation, "#pop"),
            (r"[ \t\r\f]+", Whitespace),
            (r"#[^\n]*", Comment.Single),
            (r'"(\\.|[^"\\])*"', String.Double),
            (r"[^\s;#\"]+", Text),
        ],
        "name": [
            (r"\s+", Whitespace),
            (r"#[^\n]*", Comment.Single),
            (r"\|(\\.|[^|\\])*\|", Name.Function, ("#pop", "body")),
            (rf"[{_C}]+", Name.Function, ("#pop", "body")),
        ],
        "body": [
            (r"\s+", Whitespace),
            (r"#[^\n]*", Comment.Single),
            (r'"(\\.|[^"\\])*"', String.Doc),
            (rf":(o-support|i-support|default|chunk|template|interrupt){_END}", Keyword),
            (rf"-->{_END}", Keyword),
            (r"\{", Punctuation, "braces"),
            (r"\}", Punctuation, "#pop"),
            include("tokens"),
        ],
        "braces": [
            (r"\s+", Whitespace),
            (r"#[^\n]*", Comment.Single),
            (r"\{", Punctuation, "#push"),
            (r"\}", Punctuation, "#pop"),
            include("tokens"),
        ],
        "tokens": [
            (r"\|(\\.|[^|\\])*\|", String),
            (rf"(\()(\s*)(state|impasse){_END}", bygroups(Punctuation, Whitespace, Keyword)),
            (r"(\^)(<[^\s()]+?>)", bygroups(Operator, Name.Variable)),
            (rf"(\^)([{_C}]+)", bygroups(Operator, Name.Attribute)),
            (r"\^", Operator),
            (rf"(\.)([A-Za-z][{_C}]*)", bygroups(Punctuation, Name.Attribute)),
            (rf"(<>|<=>|<=|>=|<<|>>|!@|[<>=@+\-!~]){_END}", Operator),
            (rf"<[{_C}]+>{_END}", Name.Variable),
            (rf"[+-]?(\d+\.\d*|\.\d+)([eE][+-]?\d*)?{_END}", Number.Float),
            (rf"[+-]?\d+{_END}", Number.Integer),
            (
                r"(\()(\s*)(write|crlf|halt|interrupt|concat|make-constant-symbol|timestamp"
                rf"|div|mod|abs|int|float|[+\-*/]){_END}",
                bygroups(Punctuation, Whitespace, Name.Builtin),
            ),  # fmt: skip
            (r"[(),.]", Punctuation),
            (rf"[{_C}]+", Name.Constant),
            (r".", Text),
        ],
    }
