"""SANN's Soar engine: a Soar 9.6 production system in Python.

``Agent`` runs rule files (``agent.source``/``agent.load``); ``parse`` and
``parse_production`` read Soar syntax into the dataclasses of `production.py`. The hot modules
run compiled by mypyc when ``make`` has built them (see `compiled.py`).
"""

from .compiled import choose_engine

choose_engine()  # before the engine's modules: a stale compiled build must not shadow them

from .agent import Agent  # noqa: E402
from .errors import SoarError, SoarRuntimeError, SoarSemanticError, SoarSyntaxError  # noqa: E402
from .parsing.parser import parse, parse_production  # noqa: E402

__all__ = [
    "Agent",
    "SoarError",
    "SoarRuntimeError",
    "SoarSemanticError",
    "SoarSyntaxError",
    "parse",
    "parse_production",
]
