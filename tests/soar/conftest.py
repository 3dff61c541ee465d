"""Fixtures the engine's tests share: the real Soar 9.6 kernel (``soar_sml``), our engine, and
one rule text run in each with what it writes captured, so that a test compares the two.

pytest puts this directory on ``sys.path`` (it is not a package), which is how every test here
imports the differential harness as ``differential``.
"""

from __future__ import annotations

import io
from collections.abc import Callable
from types import ModuleType
from typing import Any

import pytest

from sann.soar import Agent

# Helper modules whose asserts are checks of a test: pytest explains their failures too.
pytest.register_assert_rewrite("side_by_side")


@pytest.fixture
def kernel() -> ModuleType:
    """The differential harness (``differential.kernel``): fresh agents in the process's one
    kernel, and our engine run the same way. Skips the test where soar-sml is not installed."""
    pytest.importorskip("soar_sml")
    from differential import kernel

    return kernel


def _load_rules(ka: Any, text: str) -> None:
    """Load ``text`` into a ``KernelAgent`` one production at a time (a production starts a
    line with ``sp``), so that a refused one fails with the kernel's message."""
    for rule in text.strip().split("\nsp "):
        ka.cmd(rule if rule.startswith("sp ") else "sp " + rule)


@pytest.fixture
def kernel_writes(kernel: ModuleType) -> Callable[..., str]:
    """``kernel_writes(text, decisions=1)``: what the kernel writes in ``decisions``
    decisions of the productions in ``text`` at watch 0 (what loading printed left out)."""

    def writes(text: str, decisions: int = 1) -> str:
        with kernel.KernelAgent() as ka:
            _load_rules(ka, text)
            ka.cmd("watch 0")
            ka.take_log()
            ka.cmd(f"run {decisions}")
            return ka.take_log()

    return writes


@pytest.fixture
def our_writes() -> Callable[..., str]:
    """``our_writes(text, decisions=1)``: what a fresh agent of ours writes in ``decisions``
    decisions of ``text`` (loaded whole, at our default watch 0)."""

    def writes(text: str, decisions: int = 1) -> str:
        out = io.StringIO()
        agent = Agent(out=out)
        agent.load(text)
        agent.run(decisions)
        return out.getvalue()

    return writes
