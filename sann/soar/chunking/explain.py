"""The text of ``chunk stats`` and ``explain``: what was learned, and from which firings.

``chunk stats`` shows the kernel's layout with the counters this engine keeps (the kernel's
identity-analysis counters are not kept: they would need its identity bookkeeping, which is
not how identities are found here). ``explain chunk <name>`` (or ``explain <name>``) lists
the rule firings whose explanation made the chunk, the state and decision it was learned
in, and the chunk itself.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, cast

from ..printer import format_production
from .learn import Chunker

if TYPE_CHECKING:
    from ..agent import Agent

_RULE = "=" * 75
_LINE = "-" * 75


def _row(label: str, value: int) -> str:
    return f"{label:<60}{value:>12}\n"


def stats_text(agent: Agent) -> str:
    """``chunk stats``, in the kernel's layout."""
    s = cast(Chunker, agent.chunker).stats
    return "".join([
        _RULE + "\n", f"{'Explanation-Based Chunking Statistics':^75}".rstrip() + "\n",
        _RULE + "\n",
        _row("Rules learned", s.learned),
        _row("Justifications learned", s.justifications), "\n",
        _LINE + "\n", f"{'Work Performed':^75}".rstrip() + "\n", _LINE + "\n",
        _row("Sub-states analyzed", s.substates),
        _row("Number of rule firings analyzed during backtracing", s.firings_analyzed), "\n",
        _LINE + "\n", f"{'Problem-Solving Characteristics':^75}".rstrip() + "\n", _LINE + "\n",
        _row("Chunk used negated reasoning about sub-state", s.local_negations), "\n",
        _LINE + "\n", f"{'Learning Skipped or Unsuccessful':^75}".rstrip() + "\n", _LINE + "\n",
        _row("Ignored duplicate of existing rule", s.duplicates),
        _row("Skipped because problem-solving tested ^quiescence true", s.quiescence),
        _row("Skipped because no super-state knowledge tested", s.no_grounds),
        _row("Chunks that failed to form (see the messages)", s.failed),
    ])


def explain_text(agent: Agent, args: tuple[str, ...]) -> str:
    """``explain``: a summary of what was recorded, or one chunk's formation."""
    words = [word for word in args if word != "chunk"]
    records = cast(Chunker, agent.chunker).records
    if not words:
        names = "".join(f"  {name}\n" for name in records) or "  (none)\n"
        return f"Chunks recorded: {len(records)}\n{names}"
    name = words[0]
    record = records.get(name)
    info = agent._productions.get(name)
    if record is None:
        raise KeyError(name)
    lines = [f"Chunk {name}: learned in decision {record.decision} from the results of "
             f"state {record.state}\n",
             "Rule firings backtraced through (the explanation), the result's first:\n"]
    lines += [f"  {k + 1}: {firing}\n" for k, firing in enumerate(record.firings)]
    if info is not None:
        lines.append(format_production(info.production) + "\n")
    else:
        lines.append("(the chunk has been excised)\n")
    return "".join(lines)
