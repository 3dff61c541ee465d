"""The differential oracle: run one agent file in the real Soar 9.6 kernel and in our engine.

Both halves return a :class:`RunResult` with the same fields, so a test can compare them
field by field. Working memory is compared *modulo identifier renaming*: both memories are
turned into the same neutral graph form (identifier name -> its WMEs with typed values) and
then relabelled canonically (see :func:`canonical_wm`), because nothing obliges two correct
engines to number the identifiers of, say, a substate's operators in the same order.

Agent files may carry header comments that the harness reads (anywhere in the file, one per
line, before or between productions)::

    # differential: random          choices are random: compare only halting and output
    # differential: decisions 500   decision limit for the run (default 20000)
    # differential: warnings        the kernel is expected to print warnings for this agent
    # input: item name=apple price=3     an identifier ^item under the input-link with
                                         constant children (ints and floats are typed)
    # input: disks=5                     a constant directly on the input-link

Input is put on the input-link before the first decision in both engines.

The kernel half keeps one kernel per process (``CreateKernelInCurrentThread`` is expensive
and must be shut down exactly once); every run gets a fresh agent that is destroyed after
the run. :func:`shutdown_kernel` is registered with ``atexit``.
"""

from __future__ import annotations

import atexit
import hashlib
import io
import itertools
import re
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

DEFAULT_DECISIONS = 20000

# A value in the neutral graph: ("id", "S1") | ("int", 3) | ("float", 1.5) | ("str", "a b").
Value = tuple[str, Any]
Graph = dict[str, list[tuple[Value, Value, bool]]]
Triple = tuple[str, str, str, str]
# Header inputs: (attr, constant) or (attr, ((child, constant), ...)).
Inputs = tuple[tuple[str, Any], ...]


@dataclass(frozen=True)
class AgentSpec:
    """What the header comments of an agent file ask of the harness."""

    path: Path
    random: bool = False
    decisions: int = DEFAULT_DECISIONS
    inputs: Inputs = ()
    warnings: bool = False


@dataclass
class RunResult:
    """Everything the differential test compares, from one engine."""

    halted: bool
    decisions: int
    production_firings: int
    elaboration_cycles: int
    wme_changes: int
    wm_size: int
    operators: list[str] = field(default_factory=list)
    output: str = ""
    wm: tuple[Triple, ...] = ()
    trace: str = ""


# --------------------------------------------------------------------------- agent headers

_HEADER = re.compile(r"^\s*#\s*(differential|input)\s*:\s*(.*?)\s*$", re.MULTILINE)


def read_spec(path: str | Path) -> AgentSpec:
    """Parse the ``# differential:`` and ``# input:`` header comments of an agent file."""
    path = Path(path)
    text = path.read_text()
    random, warnings, decisions, inputs = False, False, DEFAULT_DECISIONS, []
    for kind, body in _HEADER.findall(text):
        if kind == "input":
            inputs.append(_parse_input(body, path))
            continue
        words = body.split()
        if words == ["random"]:
            random = True
        elif words == ["warnings"]:
            warnings = True
        elif len(words) == 2 and words[0] == "decisions" and words[1].isdigit():
            decisions = int(words[1])
        else:
            raise ValueError(f"{path}: unknown '# differential:' header {body!r}")
    return AgentSpec(path, random, decisions, tuple(inputs), warnings)


def _parse_input(body: str, path: Path) -> tuple[str, Any]:
    words = body.split()
    if len(words) == 1 and "=" in words[0] and not words[0].startswith("="):
        attr, raw = words[0].split("=", 1)
        return attr, _typed(raw)
    if not words or "=" in words[0]:
        raise ValueError(f"{path}: '# input:' wants 'attr' then name=value pairs, got {body!r}")
    children = []
    for word in words[1:]:
        if "=" not in word:
            raise ValueError(f"{path}: '# input:' child {word!r} is not name=value")
        name, raw = word.split("=", 1)
        children.append((name, _typed(raw)))
    return words[0], tuple(children)


def _typed(raw: str) -> int | float | str:
    for kind in (int, float):
        try:
            return kind(raw)
        except ValueError:
            pass
    return raw


# --------------------------------------------------------------------------- canonical WM


def canonical_wm(graph: Graph, roots: Iterable[str]) -> tuple[Triple, ...]:
    """Relabel identifiers canonically and return the sorted WMEs as string triples.

    Identifiers are renamed by discovery order in a breadth-first walk from the roots (the
    states, top first). Children are visited in an order that does not depend on the
    original names: attribute, then value, where an identifier value is ordered by a
    structural signature (Weisfeiler-Lehman refinement, a few rounds). The new name keeps
    Soar's letter, so a letter that differs is still a difference.
    """
    signature = _signatures(graph, rounds=4)
    names: dict[str, str] = {}
    counters: dict[str, itertools.count] = {}
    queue = [root for root in roots if root in graph]
    for root in queue:
        _name(root, names, counters)
    triples: list[Triple] = []
    head = 0
    while head < len(queue):
        ident = queue[head]
        head += 1
        for attr, value, acc in sorted(graph.get(ident, ()), key=lambda e: _edge_key(e, signature)):
            for sym in (attr, value):
                if sym[0] == "id" and sym[1] not in names:
                    _name(sym[1], names, counters)
                    queue.append(sym[1])
            triples.append(
                (names[ident], _show(attr, names), _show(value, names), "+" if acc else "")
            )
    return tuple(sorted(triples))


def _name(ident: str, names: dict[str, str], counters: dict[str, itertools.count]) -> None:
    letter = ident[0]
    names[ident] = f"{letter}{next(counters.setdefault(letter, itertools.count(1)))}"


def _signatures(graph: Graph, rounds: int) -> dict[str, str]:
    """Weisfeiler-Lehman refinement over the edges leaving and entering each identifier:
    two identifiers with the same augmentations but different referrers (``T1`` and ``T3``
    both ``^kind b``, only ``T1`` the value of ``(T2 ^link T1)``) get different signatures,
    so that their order, and so the canonical names, does not fall to the walk's order."""
    incoming: dict[str, list[tuple[str, Value, bool]]] = {ident: [] for ident in graph}
    for ident, edges in graph.items():
        for attr, value, acc in edges:
            if value[0] == "id" and value[1] in incoming:
                incoming[value[1]].append((ident, attr, acc))
    sig = {ident: ident[0] for ident in graph}
    for _ in range(rounds):
        new = {}
        for ident, edges in graph.items():
            parts = sorted(f"{_plain(a, sig)}|{_plain(v, sig)}|{int(acc)}" for a, v, acc in edges)
            parts += sorted(f"<{sig[source]}|{_plain(a, sig)}|{int(acc)}"
                            for source, a, acc in incoming[ident])
            digest = hashlib.sha1((sig[ident] + "\n" + "\n".join(parts)).encode()).hexdigest()
            new[ident] = ident[0] + digest[:16]
        sig = new
    return sig


def _plain(sym: Value, sig: dict[str, str]) -> str:
    if sym[0] == "id":
        return "#" + sig.get(sym[1], sym[1][0])
    return f"{sym[0]}:{_const_text(sym)}"


def _edge_key(edge: tuple[Value, Value, bool], sig: dict[str, str]) -> tuple[str, str, bool]:
    attr, value, acc = edge
    return _plain(attr, sig), _plain(value, sig), acc


def _const_text(sym: Value) -> str:
    kind, val = sym
    if kind == "float":
        return f"{val:.6f}"
    return str(val)


def _show(sym: Value, names: dict[str, str]) -> str:
    if sym[0] == "id":
        return names[sym[1]]
    if sym[0] == "str":
        return "|" + sym[1] + "|"
    return _const_text(sym)


# --------------------------------------------------------------------------- Soar print format

_TOKEN = re.compile(r"\|(?:[^|\\]|\\.)*\||[^\s|()]+")
_INTERNAL_LINE = re.compile(r"^\s*\((\d+): (\S+) (.*)\)\s*$")
_ID = re.compile(r"^[A-Z]\d+$")
_INT = re.compile(r"^[+-]?\d+$")
_FLOAT = re.compile(r"^[+-]?(\d+\.\d*|\.\d+|\d+)([eE][+-]?\d+)?$")


def parse_symbol(token: str) -> Value:
    """Type a symbol as Soar prints it: ``|x|`` string, ``S1`` identifier, number, symbol."""
    if token.startswith("|") and token.endswith("|") and len(token) >= 2:
        return ("str", re.sub(r"\\(.)", r"\1", token[1:-1]))
    if _ID.match(token):
        return ("id", token)
    if _INT.match(token):
        return ("int", int(token))
    if _FLOAT.match(token):
        return ("float", float(token))
    return ("str", token)


def parse_internal(text: str) -> list[tuple[str, Value, Value, bool]]:
    """Parse ``print --internal`` lines ``(12: S1 ^attr value [+])`` into WMEs."""
    wmes = []
    for line in text.splitlines():
        match = _INTERNAL_LINE.match(line)
        if not match:
            continue
        ident, rest = match.group(2), match.group(3)
        if not rest.startswith("^"):
            raise ValueError(f"unexpected WME line from the kernel: {line!r}")
        tokens = _TOKEN.findall(rest[1:])
        if len(tokens) not in (2, 3) or (len(tokens) == 3 and tokens[2] != "+"):
            raise ValueError(f"unexpected WME line from the kernel: {line!r}")
        acc = len(tokens) == 3
        wmes.append((ident, parse_symbol(tokens[0]), parse_symbol(tokens[1]), acc))
    return wmes


# --------------------------------------------------------------------------- trace and output

_TRACE_LINE = re.compile(r"\n? *\d+: +(O|==>S): (\S+)(?: \(([^\n]*?)\))?")
# Nothing is stripped any more: our engine prints the kernel's halt and interrupt messages
# ("\nSystem halted.\nInterrupt received.This Agent halted.") at every watch level.
_KERNEL_NOISE: tuple[str, ...] = ()


def split_trace(text: str) -> tuple[list[str], str]:
    """Separate a watch-1 decision trace from what ``write`` printed.

    Returns the operator-name sequence and the written output. Soar interleaves both on one
    print channel (``     1:    O: O2 (hello)Hi hello``): decision lines start with a
    newline, a right-aligned decision number and ``O:`` or ``==>S:``.
    """
    operators = [m.group(3) or "" for m in _TRACE_LINE.finditer(text) if m.group(1) == "O"]
    output = _TRACE_LINE.sub("", text)
    for noise in _KERNEL_NOISE:
        output = output.replace(noise, "")
    return operators, output


def _stat(text: str, pattern: str) -> int:
    match = re.search(pattern, text, re.MULTILINE)
    if not match:
        raise ValueError(f"kernel stats lack {pattern!r}:\n{text}")
    return int(match.group(1))


# --------------------------------------------------------------------------- the real kernel

_KERNEL: Any = None
_AGENT_IDS = itertools.count(1)


def kernel() -> Any:
    """The process's one in-thread Soar kernel, created on first use."""
    global _KERNEL
    if _KERNEL is None:
        import soar_sml

        _KERNEL = soar_sml.Kernel.CreateKernelInCurrentThread(True, 0)
        if _KERNEL.HadError():
            raise RuntimeError(f"Soar kernel: {_KERNEL.GetLastErrorDescription()}")
        atexit.register(shutdown_kernel)
    return _KERNEL


def shutdown_kernel() -> None:
    """Shut the kernel down once (safe to call twice)."""
    global _KERNEL
    if _KERNEL is not None:
        _KERNEL.Shutdown()
        _KERNEL = None


class KernelAgent:
    """A fresh agent in the shared kernel with a captured print channel.

    Use as a context manager; the agent is destroyed on exit so runs do not leak memory or
    productions into each other.
    """

    def __init__(self) -> None:
        import soar_sml

        self.kernel = kernel()
        self.agent = self.kernel.CreateAgent(f"differential-{next(_AGENT_IDS)}")
        if self.agent is None:
            raise RuntimeError(f"Soar kernel: {self.kernel.GetLastErrorDescription()}")
        self.log: list[str] = []
        self._callback = self.agent.RegisterForPrintEvent(
            soar_sml.smlEVENT_PRINT, lambda _mid, _ud, _ag, msg: self.log.append(msg), None
        )

    def __enter__(self) -> KernelAgent:
        return self

    def __exit__(self, *exc: object) -> None:
        self.agent.UnregisterForPrintEvent(self._callback)
        self.kernel.DestroyAgent(self.agent)

    def cmd(self, line: str) -> str:
        """Execute a command line; raise with the kernel's message when it fails."""
        result = self.agent.ExecuteCommandLine(line)
        if not self.agent.GetLastCommandLineResult():
            raise RuntimeError(f"Soar kernel refused {line!r}: {result}")
        return result

    def take_log(self) -> str:
        text = "".join(self.log)
        self.log.clear()
        return text

    def add_inputs(self, inputs: Iterable[tuple[str, Any]]) -> None:
        """Put header inputs on the input-link (see the module docstring)."""
        il = self.agent.GetInputLink()
        for attr, value in inputs:
            if isinstance(value, tuple):
                ident = self.agent.CreateIdWME(il, attr)
                for name, child in value:
                    self.add_constant(ident, name, child)
            else:
                self.add_constant(il, attr, value)
        self.agent.Commit()

    def add_constant(self, ident: Any, attr: str, value: Any) -> Any:
        if isinstance(value, bool) or not isinstance(value, int | float | str):
            raise TypeError(f"input value {value!r} is not an int, float or str")
        if isinstance(value, int):
            return self.agent.CreateIntWME(ident, attr, value)
        if isinstance(value, float):
            return self.agent.CreateFloatWME(ident, attr, value)
        return self.agent.CreateStringWME(ident, attr, value)

    def states(self) -> list[str]:
        """The goal stack, top state first."""
        return re.findall(r"==>S: (S\d+)", self.cmd("print --stack"))

    def graph(self) -> tuple[Graph, list[str]]:
        """Working memory reachable from the states, as a neutral graph."""
        roots = self.states() or ["S1"]
        graph: Graph = {}
        queue = list(roots)
        while queue:
            ident = queue.pop()
            if ident in graph:
                continue
            graph[ident] = []
            for _, attr, value, acc in parse_internal(self.cmd(f"print --internal {ident}")):
                graph[ident].append((attr, value, acc))
                for sym in (attr, value):
                    if sym[0] == "id" and sym[1] not in graph:
                        queue.append(sym[1])
        return graph, roots

    def stats(self) -> dict[str, int]:
        text = self.cmd("stats")
        return {
            "decisions": _stat(text, r"^(\d+) decisions"),
            "elaboration_cycles": _stat(text, r"^(\d+) elaboration cycles"),
            "production_firings": _stat(text, r"^(\d+) production firings"),
            "wme_changes": _stat(text, r"^(\d+) wme changes"),
            "wm_size": _stat(text, r"^WM size: (\d+) current"),
        }


def run_kernel(
    path: str | Path, decisions: int | None = None, inputs: Inputs | None = None,
    commands: Iterable[str] = (), *, before: Iterable[str] = (),
) -> RunResult:
    """Run an agent file in the real Soar kernel and collect a :class:`RunResult`.

    ``decisions`` and ``inputs`` override the file's header comments; ``commands`` run
    after the file is sourced (``srand 3``, ``indifferent-selection --first``), ``before``
    before it (so that a file's own ``chunk always`` can be overridden by a ``chunk never``
    in ``commands``, or a seed given before the file's productions are loaded); what they
    print is dropped like sourcing's output.
    """
    spec = read_spec(path)
    limit = decisions if decisions is not None else spec.decisions
    with KernelAgent() as ka:
        for line in before:
            ka.cmd(line)
        ka.cmd(f"source {{{Path(path).resolve()}}}")
        for line in commands:
            ka.cmd(line)
        ka.take_log()
        ka.cmd("watch 1")
        ka.add_inputs(spec.inputs if inputs is None else inputs)
        summary = ka.cmd(f"run {limit}")
        trace = ka.take_log()
        operators, output = split_trace(trace)
        graph, roots = ka.graph()
        stats = ka.stats()
        return RunResult(
            halted="halted" in summary or "This Agent halted" in trace,
            operators=operators,
            output=output,
            wm=canonical_wm(graph, roots),
            trace=trace,
            **stats,
        )


# --------------------------------------------------------------------------- our engine


def run_ours(
    path: str | Path, decisions: int | None = None, inputs: Inputs | None = None,
    commands: Iterable[str] = (), *, before: Iterable[str] = (),
) -> RunResult:
    """Run an agent file in SANN's engine (``sann.soar.Agent``) and collect a RunResult
    (``commands`` and ``before`` as for :func:`run_kernel`).

    The engine writes only ``write`` output to ``out`` (trace level 0); the operator-name
    sequence comes from ``agent.operator_sequence`` and working memory from ``agent.wmes()``.
    """
    from sann.soar.agent import Agent

    spec = read_spec(path)
    limit = decisions if decisions is not None else spec.decisions
    out = io.StringIO()
    agent = Agent(out=out)
    for line in before:
        agent.load(line)
    agent.source(str(path))
    for line in commands:
        agent.load(line)
    # The kernel half drops what sourcing printed (``source`` returns the text of ``echo``,
    # ``print`` or ``stats`` and the trace of a ``run`` goes to the discarded log); so do we.
    out.seek(0)
    out.truncate()
    agent.trace(0)
    _add_our_inputs(agent, spec.inputs if inputs is None else inputs)
    agent.run(decisions=limit)
    graph, roots = our_graph(agent)
    stats = {key: int(agent.stats[key]) for key in _STAT_KEYS}
    return RunResult(
        halted=bool(agent.halted),
        operators=[str(name) for name in agent.operator_sequence],
        output=out.getvalue(),
        wm=canonical_wm(graph, roots),
        trace="",
        **stats,
    )


_STAT_KEYS = ("decisions", "elaboration_cycles", "production_firings", "wme_changes", "wm_size")


def _add_our_inputs(agent: Any, inputs: Iterable[tuple[str, Any]]) -> None:
    for attr, value in inputs:
        if isinstance(value, tuple):
            handle = agent.input_link.add(attr)
            for name, child in value:
                handle.add(name, child)
        else:
            agent.input_link.add(attr, value)


def our_graph(agent: Any) -> tuple[Graph, list[str]]:
    """Working memory of our engine as a neutral graph, and its states (top first)."""
    from sann.soar.memory import Identifier

    graph: Graph = {}
    states: dict[str, int] = {}
    for wme in agent.wmes():
        for sym in (wme.id, wme.attr, wme.value):
            if isinstance(sym, Identifier) and sym.is_state:
                states[sym.name] = sym.level
        triple = (_our_symbol(wme.attr), _our_symbol(wme.value), bool(wme.acceptable))
        graph.setdefault(wme.id.name, []).append(triple)
        if isinstance(wme.value, Identifier):
            graph.setdefault(wme.value.name, [])
    roots = sorted(states, key=lambda name: (states[name], name))
    return graph, roots


def _our_symbol(sym: Any) -> Value:
    if isinstance(sym, bool):
        raise TypeError(f"a bool is not a Soar symbol: {sym!r}")
    if isinstance(sym, int):
        return ("int", sym)
    if isinstance(sym, float):
        return ("float", sym)
    if isinstance(sym, str):
        return ("str", sym)
    return ("id", sym.name)


def assert_agree(path: str | Path, decisions: int) -> None:
    """Run a rule file in both engines: both halt, the kernel reports no error, and the
    written output, working memory, firings and WM size are equal."""
    theirs, ours = run_kernel(path, decisions=decisions), run_ours(path, decisions=decisions)
    assert theirs.halted and ours.halted
    assert "Error" not in theirs.trace
    assert ours.output == theirs.output
    assert ours.wm == theirs.wm
    assert (ours.production_firings, ours.wm_size) == (theirs.production_firings, theirs.wm_size)
