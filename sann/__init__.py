"""SANN: a Soar production system, plan fusion and graspability networks (Zuo et al.)."""

from pathlib import Path

__version__ = "0.1.0"

#: The rule files shipped with the package, found beside it (so an installed package has them
#: too): ``sann/rules``, which in the repository links to the top-level ``rules/`` that the book
#: and the tests read.
RULES = Path(__file__).resolve().parent / "rules"
