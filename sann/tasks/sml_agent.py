"""The real Soar kernel (soar_sml) as a planner backend, shared by the block and cup drivers:
an in-process kernel with the rule file sourced, plans read back from the output-link."""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path


class SmlAgent:
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

    def output_sequences(self, fields: Sequence[str]) -> list[tuple[str, ...]]:
        """The ``fields`` of every ``^sequence`` on the output-link, as strings."""
        out = []
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
