"""The two engines a task driver runs its rule file in: ours (``sann.soar.Agent``) and the real
Soar kernel (``soar_sml``, in-process).

A driver describes its input-link as :data:`InputItem` s, ``("cap", 8)`` for a constant and
``("block", [("id", 3), ("x", 1.5), ...])`` for an identifier with its attributes, and reads its
plans back as the values of the output-link's ``^sequence`` WMEs (:data:`OutputValue`: the text
of a constant, the attributes of an identifier). Both backends put the items on in the order
given, so a driver that lists them alike gives both engines the same timetags.

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
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from sann.soar import Agent

InputValue = int | float | str
#: One WME on the input-link: a constant, or an identifier with its (attribute, constant) pairs
#: (an attribute given several times makes a multi-valued attribute).
InputItem = tuple[str, InputValue | Sequence[tuple[str, InputValue]]]
#: One ``^sequence`` of the output-link: a constant's text, or an identifier's attributes and
#: their values' texts.
OutputValue = str | dict[str, str]


def sequence_fields(value: OutputValue) -> dict[str, str]:
    """The attributes of an output sequence made as an identifier (a constant is an error of
    the rule file: the driver expected fields)."""
    if isinstance(value, str):
        raise RuntimeError(f"the rules wrote ^sequence {value!r}: an identifier was expected")
    return value


class SannBackend:
    """Our engine: a fresh working memory per run via ``agent.init()``."""

    def __init__(self, rules: Path) -> None:
        # Imported here: a module that imports a driver for its data only (the cups dataset
        # of the vision chapters) does not load the engine, nor depend on its sources.
        from sann.soar import Agent

        #: What the agent printed in its last run (its `write` output and the halt message):
        #: kept for a reader who asks, never sent to standard output, which would flood the book.
        self.transcript = io.StringIO()
        agent = Agent(out=self.transcript)
        agent.source(str(rules))
        self.agent: Agent | None = agent

    def run(self, items: Sequence[InputItem], seed: int | None = None) -> list[OutputValue]:
        """Initialise (and ``srand seed``), put ``items`` on the input-link, run until halt:
        the output sequences. An error the rules raised (a failed RHS call) is raised."""
        agent = self.agent
        if agent is None:
            raise ValueError("this backend is closed")
        agent.init()
        self.transcript.seek(0)
        self.transcript.truncate()
        errors = len(agent.errors)
        if seed is not None:
            agent.srand(seed)
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
        from sann.soar.io import OutputHandle

        return [{str(a): str(v) for a, v in value.children()}
                if isinstance(value, OutputHandle) else str(value)
                for attr, value in agent.output_link.children() if attr == "sequence"]

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

    def run(self, items: Sequence[InputItem], seed: int | None = None) -> list[OutputValue]:
        """Put ``items`` beside what is on the input-link already, ``srand seed``, run until
        halt, take the items off and ``init-soar``: the output sequences."""
        top = self.put(items)
        self.agent.Commit()
        if seed is not None:
            self.agent.ExecuteCommandLine(f"srand {seed}")
        self.agent.RunSelf(100_000)
        out = self.output_sequences()
        self.remove(top)
        self.agent.ExecuteCommandLine("init-soar")
        return out

    def output_sequences(self) -> list[OutputValue]:
        """The values of the output-link's ``^sequence`` WMEs."""
        out: list[OutputValue] = []
        ol = self.agent.GetOutputLink()
        if ol is None:
            return out
        for i in range(ol.GetNumberChildren()):
            child = ol.GetChild(i)
            if child.GetAttribute() != "sequence":
                continue
            if not child.IsIdentifier():
                out.append(child.GetValueAsString())
                continue
            q = child.ConvertToIdentifier()
            out.append({q.GetChild(j).GetAttribute(): q.GetChild(j).GetValueAsString()
                        for j in range(q.GetNumberChildren())})
        return out

    def close(self) -> None:
        if self.kernel is not None:
            self.kernel.DestroyAgent(self.agent)
            self.kernel.Shutdown()
            self.kernel = None
