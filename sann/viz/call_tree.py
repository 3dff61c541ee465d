"""The engine's function calls while it runs, as an indented tree: how one decision cycle
goes through the modules of ``sann.soar``.

The calls are recorded with ``sys.setprofile``, which sees only Python functions: the
engine must run from its sources (``SANN_INTERPRETED=1`` before ``sann.soar`` is first
imported), not compiled by mypyc. Generated code (the Rete's node activations, see
``sann.soar.codegen``) is recorded under its kind, ``<rete:join>`` for a join node's.
"""

from __future__ import annotations

import re
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import FrameType

import sann.soar
from sann.soar.compiled import is_compiled

PACKAGE = Path(sann.soar.__file__).resolve().parent
_GENERATED = re.compile(r"<sann-(?P<kind>[^:>]+(?::[a-z-]+)?):\d+>")


@dataclass(frozen=True)
class Call:
    """A call to ``function`` of ``module`` (relative to ``sann.soar``), ``depth`` calls of
    the engine deep, ``count`` times in a row."""

    depth: int
    module: str
    function: str
    count: int = 1


def module_of(filename: str) -> str | None:
    """``decision.cycle`` for sann/soar/decision/cycle.py, ``<rete:join>`` for generated
    code, None for anything else."""
    generated = _GENERATED.fullmatch(filename)
    if generated:
        return f"<{generated['kind']}>"
    path = Path(filename)
    if path.suffix != ".py" or not path.is_relative_to(PACKAGE):
        return None
    return ".".join(path.relative_to(PACKAGE).with_suffix("").parts)


def makes_code(module: str, function: str) -> bool:
    """Calls that generate a node's code on first use (``codegen``, ``templates``, a node's
    ``_compile``): neither they nor what they call are recorded."""
    return module in ("codegen", "matching.templates") or function.endswith("._compile")


def passes_through(function: str) -> bool:
    """Calls not recorded whose callees are, one level up: the stand-in that compiles a
    node's code and then calls it (``CompileFirst``), and comprehensions."""
    return function == "CompileFirst.__call__" or "<" in function


def record_calls(action: Callable[[], object]) -> list[Call]:
    """Run ``action`` and return the engine functions it called, in order (see
    ``makes_code`` and ``passes_through`` for the calls left out)."""
    if is_compiled():
        raise RuntimeError("the engine is compiled, so its calls cannot be recorded: set "
                           "SANN_INTERPRETED=1 before sann.soar is first imported")
    calls: list[Call] = []
    stack: list[FrameType] = []  # the recorded calls still running
    silent: list[FrameType] = []  # the code-making calls still running

    def profile(frame: FrameType, event: str, _arg: object) -> None:
        if event == "call" and not silent:
            module = module_of(frame.f_code.co_filename)
            function = frame.f_code.co_qualname
            if module is None or passes_through(function):
                return
            if makes_code(module, function):
                silent.append(frame)
            else:
                calls.append(Call(len(stack), module, function))
                stack.append(frame)
        elif event == "return":
            if silent and silent[-1] is frame:
                silent.pop()
            elif not silent and stack and stack[-1] is frame:
                stack.pop()

    previous = sys.getprofile()
    sys.setprofile(profile)
    try:
        action()
    finally:
        sys.setprofile(previous)
    return calls


def collapse(calls: list[Call], max_depth: int) -> list[Call]:
    """The calls at most ``max_depth`` deep, the same call repeated in a row counted once."""
    shown: list[Call] = []
    for call in calls:
        if call.depth > max_depth:
            continue
        last = shown[-1] if shown else None
        if last is not None and (last.depth, last.module, last.function) == (
                call.depth, call.module, call.function):
            shown[-1] = Call(last.depth, last.module, last.function, last.count + 1)
        else:
            shown.append(call)
    return shown


def format_calls(calls: list[Call]) -> str:
    """One line per call, indented by depth: ``module.function`` and ``×n`` when repeated."""
    return "\n".join(f"{'    ' * call.depth}{call.module}.{call.function}"
                     + (f"  ×{call.count}" if call.count > 1 else "") for call in calls)
