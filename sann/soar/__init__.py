"""SANN's Soar engine: a Soar 9.6 production system in Python.

``Agent`` runs rule files (``agent.source``/``agent.load``); ``parse`` and
``parse_production`` read Soar syntax into the dataclasses of `production.py`.
"""

from .agent import Agent
from .errors import SoarError, SoarRuntimeError, SoarSemanticError, SoarSyntaxError
from .syntax import parse, parse_production

__all__ = [
    "Agent",
    "SoarError",
    "SoarRuntimeError",
    "SoarSemanticError",
    "SoarSyntaxError",
    "parse",
    "parse_production",
]
