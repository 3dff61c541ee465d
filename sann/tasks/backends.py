"""The two engines a task driver runs its rule file in: ours (``sann.soar.Agent``) and the real
Soar kernel (``soar_sml``, in-process).

A driver describes its input-link as :data:`InputItem` s, ``("cap", 8)`` for a constant and
``("block", [("id", 3), ("x", 1.5), ...])`` for an identifier with its attributes, and reads its
plans back as the fields of every ``^sequence`` on the output-link. Both backends put the items
on in the order given, so a driver that lists them alike gives both engines the same timetags.

The backends differ where the engines do. Our ``init()`` clears the whole working memory, input
included, so :meth:`SannBackend.run` re-initialises and then puts everything on. The kernel's
``init-soar`` keeps what SML put on the input-link (SML re-sends it), so a driver can leave a
scene there with :meth:`SmlBackend.put` and run several groups over it.
"""

from __future__ import annotations

import io
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from sann.soar import Agent

InputValue = int | float | str
#: One WME on the input-link: a constant, or an identifier with its (attribute, constant) pairs
#: (an attribute given several times makes a multi-valued attribute).
InputItem = tuple[str, InputValue | Sequence[tuple[str, InputValue]]]


class SannBackend:
    """Our engine: a fresh working memory per run via ``agent.init()``."""

    def __init__(self, rules: Path) -> None:
        #: What the agent printed in its last run (its `write` output and the halt message):
        #: kept for a reader who asks, never sent to standard output, which would flood the book.
        self.transcript = io.StringIO()
        self.agent: Agent | None = Agent(out=self.transcript)
        self.agent.source(str(rules))

    def run(self, items: Sequence[InputItem], fields: Sequence[str]) -> list[tuple[str, ...]]:
        """Initialise, put ``items`` on the input-link, run until halt: the ``fields`` of each
        output sequence as strings. An error the rules raised (a failed RHS call) is raised."""
        agent = self.agent
        if agent is None:
            raise ValueError("this backend is closed")
        agent.init()
        self.transcript.seek(0)
        self.transcript.truncate()
        errors = len(agent.errors)
        il = agent.input_link
        for attr, value in items:
            if isinstance(value, int | float | str):
                il.add(attr, value)
                continue
            ident = il.add(attr)
            for sub, v in value:
                ident.add(sub, v)
        agent.run()
        if len(agent.errors) > errors:
            raise RuntimeError("the planning rules failed: " + "; ".join(agent.errors[errors:]))
        out = []
        for attr, q in agent.output_link.children():
            if attr == "sequence":
                kv = dict(q.children())
                out.append(tuple(str(kv[f]) for f in fields))
        return out

    def close(self) -> None:
        self.agent = None


class SmlBackend:
    """One soar_sml kernel and agent with ``rules`` sourced and tracing off."""

    def __init__(self, rules: Path, name: str) -> None:
        import soar_sml as sml

        self.kernel = sml.Kernel.CreateKernelInCurrentThread(True, 0)
        self.agent = self.kernel.CreateAgent(f"{name}{id(self)}")
        # The kernel reads the file in C++, which raises no audit event: raise the one Python's
        # open() would, so that recorders of what was read (sann.bookcache) see this read too.
        sys.audit("open", str(rules), "r", 0)
        result = self.agent.ExecuteCommandLine(f"source {{{rules}}}")
        if not self.agent.GetLastCommandLineResult():
            raise RuntimeError(f"soar_sml could not source {rules}: {result}")
        self.agent.ExecuteCommandLine("watch 0")

    def put(self, items: Sequence[InputItem]) -> list:
        """Create ``items`` on the input-link (not yet committed): their top WMEs, for
        :meth:`remove`."""
        a = self.agent
        il = a.GetInputLink()
        top = []
        for attr, value in items:
            if isinstance(value, int | float | str):
                top.append(self._add(il, attr, value))
                continue
            ident = a.CreateIdWME(il, attr)
            top.append(ident)
            for sub, v in value:
                self._add(ident, sub, v)
        return top

    def _add(self, parent: Any, attr: str, value: InputValue) -> Any:
        a = self.agent
        if isinstance(value, str):
            return a.CreateStringWME(parent, attr, value)
        if isinstance(value, int):
            return a.CreateIntWME(parent, attr, value)
        return a.CreateFloatWME(parent, attr, float(value))

    def remove(self, top: list) -> None:
        """Destroy WMEs made by :meth:`put` (with everything under them) and commit."""
        for w in top:
            self.agent.DestroyWME(w)
        self.agent.Commit()

    def run(self, items: Sequence[InputItem], fields: Sequence[str]) -> list[tuple[str, ...]]:
        """Put ``items`` beside what is on the input-link already, run until halt, take them
        off and ``init-soar``: the ``fields`` of each output sequence as strings."""
        top = self.put(items)
        self.agent.Commit()
        self.agent.RunSelf(100_000)
        out = self.output_sequences(fields)
        self.remove(top)
        self.agent.ExecuteCommandLine("init-soar")
        return out

    def output_sequences(self, fields: Sequence[str]) -> list[tuple[str, ...]]:
        """The ``fields`` of every ``^sequence`` on the output-link, as strings."""
        out: list[tuple[str, ...]] = []
        ol = self.agent.GetOutputLink()
        if ol is None:
            return out
        for i in range(ol.GetNumberChildren()):
            child = ol.GetChild(i)
            if child.GetAttribute() == "sequence":
                q = child.ConvertToIdentifier()
                out.append(tuple(q.GetParameterValue(f) for f in fields))
        return out

    def close(self) -> None:
        if self.kernel is not None:
            self.kernel.DestroyAgent(self.agent)
            self.kernel.Shutdown()
            self.kernel = None
