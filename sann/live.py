"""The live book's engine side: what a Soar cell of the rendered book does when its *Run* or
*Step* button is pressed.

The page's Web Worker runs this module on Pyodide (book/_static/live/worker.mjs); the tests
and benchmarks/live.py call the same functions in CPython. Every request and answer is plain
JSON-able data, so the worker only passes dicts through. A run is stateless: it builds a new
agent from the cell's text (and the rules the cell depends on) each time, so what a cell shows
does not depend on what the reader clicked before; a stepping session keeps its agent between
steps.
"""

from __future__ import annotations

import contextlib
import io
import shlex
from dataclasses import dataclass, field
from typing import Any

import sann
from sann.soar import Agent, SoarError, SoarSyntaxError
from sann.soar.introspect import preferences_text
from sann.soar.magic import DEFAULT_LIMIT, ReaderStream, parse_line, soar_cell
from sann.soar.memory import Identifier

__all__ = ["Cell", "SoarError", "Stepper", "error_report", "hanoi_rate", "input_tree",
           "put_input", "query", "run_cell", "run_cell_keeping"]

#: Where the rule files are: the package's (in the page: the packed copy).
RULES = sann.RULES

#: Most nodes the working-memory graph shows; a larger memory is cut (and says so).
GRAPH_LIMIT = 160


@dataclass
class Cell:
    """One live cell: what the page shows and where its text comes from.

    ``file`` names the rule file a literal include shows (``water-jug.soar``); ``shipped`` is
    the text the book shipped in the cell, which a run replaces by the reader's text inside
    the whole file, so an edited fragment runs with the rest of its file. A ``%%soar`` cell
    has no file: its first line is the magic's, and ``preload`` lists the rule files sourced
    into its agent first (what the chapter's Python cells sourced), ``before`` the texts of
    the page's earlier ``%%soar`` cells for the same agent, loaded without running. ``input``
    is what the chapter's Python driver put on the input-link (an `input_tree`), put there
    again before the run.
    """

    text: str
    file: str | None = None
    exercise: str | None = None
    shipped: str = ""
    preload: list[str] = field(default_factory=list)
    before: list[str] = field(default_factory=list)
    input: list = field(default_factory=list)
    trace: int = 1
    decisions: int = DEFAULT_LIMIT
    queries: list[str] = field(default_factory=list)

    @classmethod
    def of(cls, request: dict[str, Any]) -> Cell:
        names = cls.__dataclass_fields__
        return cls(**{k: v for k, v in request.items() if k in names})


def rule_text(name: str) -> str:
    """A shipped rule file's text, by its path under rules/ (nothing outside it)."""
    path = (RULES / name).resolve()
    if not path.is_relative_to(RULES.resolve()) or not path.is_file():
        raise SoarError(f"no rule file {name!r} in rules/")
    return path.read_text(encoding="utf-8")


def compose(cell: Cell) -> tuple[str, int]:
    """The rule-file text a cell runs and the line its own text starts at in it (1-based).

    A literal include of a whole file is the cell's text itself; a fragment is put back in
    its file in place of the shipped fragment."""
    if cell.file is None:
        return cell.text, 1
    whole = rule_text(cell.file)
    at = whole.find(cell.shipped) if cell.shipped else -1
    if at < 0 or cell.shipped.strip() == whole.strip():
        return cell.text, 1
    first = whole.count("\n", 0, at) + 1
    return whole[:at] + cell.text + whole[at + len(cell.shipped):], first


def run_cell(request: dict[str, Any]) -> dict[str, Any]:
    """Run a cell as the notebook would and return what to show under it."""
    return run_cell_keeping(request)[0]


def run_cell_keeping(request: dict[str, Any]) -> tuple[dict[str, Any], Agent | None]:
    """`run_cell`, and the agent after the run (the page asks it ``print S1`` later); no
    agent when the rules did not load."""
    cell = Cell.of(request)
    out = io.StringIO()
    answer: dict[str, Any] = {"error": None, "limit": False}
    agent = None
    try:
        if cell.exercise is not None:
            agent = _run_exercise(cell, out, answer)
        elif cell.text.startswith("%%soar"):
            agent = _run_magic(cell, out, answer)
        else:
            agent = _run_file(cell, out, answer)
        answer.update(_summary(agent))
        answer["queries"] = [query(agent, q) for q in cell.queries]
    except SoarError as error:
        answer["error"] = error_report(error, cell)
    answer["output"] = out.getvalue()
    return answer, agent


def hanoi_rate(disks: int | None = None) -> dict[str, float]:
    """Decisions per second of rules/hanoi.soar run to halt (the file's disk count unless
    ``disks`` is given): the benchmark's measure, the same in the page and in CPython."""
    import time

    agent = Agent(out=io.StringIO())
    agent.load(rule_text("hanoi.soar"), file="rules/hanoi.soar")
    if disks is not None:
        agent.input_link.add("disks", disks)
    start = time.perf_counter()
    agent.run(1_000_000)
    seconds = time.perf_counter() - start
    decisions = agent.stats["decisions"]
    return {"decisions": decisions, "seconds": seconds, "rate": decisions / seconds,
            "halted": agent.halted}


def _run_file(cell: Cell, out: io.StringIO, answer: dict[str, Any]) -> Agent:
    text, first = compose(cell)
    agent = Agent(out=ReaderStream(out))
    agent.trace(cell.trace)
    answer["first_line"] = first
    agent.load(text, file=_file_label(cell))
    put_input(agent, cell.input)
    before = agent.stats["decisions"]
    agent.run(cell.decisions)
    done = agent.stats["decisions"] - before
    if not agent.halted and done >= cell.decisions:
        answer["limit"] = True
        out.write(f"\nstopped at the {cell.decisions}-decision limit (no halt).\n")
    elif agent.halted:
        out.write(f"\nhalted after {done} decisions.\n")
    return agent


def _file_label(cell: Cell) -> str:
    """The file name errors of a cell's text name: its rule file's path (relative, so that
    ``source`` inside it resolves from the rules' folder), or ``<cell>``."""
    return f"rules/{cell.file}" if cell.file is not None else "<cell>"


def _run_exercise(cell: Cell, out: io.StringIO, answer: dict[str, Any]) -> Agent:
    """An exercise's rules on top of its shipped file, then the exercise's check."""
    from sann.exercises import EXERCISES, check

    exercise = EXERCISES[cell.exercise]
    answer["first_line"] = 1
    agent = exercise.agent(cell.text, ReaderStream(out))
    agent.trace(cell.trace)
    limit = min(cell.decisions, exercise.decisions)
    agent.run(limit)
    if agent.halted:
        out.write(f"\nhalted after {agent.stats['decisions']} decisions.\n")
    else:
        answer["limit"] = True
        out.write(f"\nstopped at the {limit}-decision limit (no halt).\n")
    answer["check"] = check(exercise.name, cell.text)
    return agent


def _run_magic(cell: Cell, out: io.StringIO, answer: dict[str, Any]) -> Agent:
    line, _, body = cell.text.partition("\n")
    if not line.startswith("%%soar"):
        raise SoarError("a %%soar cell starts with its %%soar line")
    options = parse_line(line[len("%%soar"):])
    agent = Agent(options.agent, seed=options.seed)
    for name in cell.preload:
        agent.load(rule_text(name), file=f"rules/{name}")
    for earlier in cell.before:
        agent.load(earlier.partition("\n")[2], file=f"<%%soar {options.agent}: earlier cell>")
    namespace: dict[str, Any] = {options.agent: agent}
    answer["first_line"] = 2
    limit = options.decisions if options.decisions is not None else cell.decisions
    with contextlib.redirect_stdout(out):
        soar_cell(_with_limit(line, cell.decisions), body, namespace)
    agent = namespace[options.agent]
    answer["limit"] = not agent.halted and agent.stats["decisions"] >= limit
    return agent


def _with_limit(line: str, decisions: int) -> str:
    """The magic's default limit is the notebook's; the page may ask for a smaller one."""
    words = shlex.split(line[len("%%soar"):])
    if decisions >= DEFAULT_LIMIT or "--decisions" in words or "-d" in words:
        return line[len("%%soar"):]
    return line[len("%%soar"):] + f" --decisions {decisions}"


def _summary(agent: Agent) -> dict[str, Any]:
    return {"stats": agent.stats, "halted": agent.halted,
            "operators": agent.operator_sequence}


def error_report(error: SoarError, cell: Cell) -> dict[str, Any]:
    """An engine error as the page shows it: the engine's message (file:line:column and a
    caret for syntax) and, for a syntax error in the cell's own text, the line within the
    cell (``cell_line``; None when the error is in another file or outside the cell)."""
    report: dict[str, Any] = {"message": str(error), "kind": type(error).__name__}
    if isinstance(error, SoarSyntaxError):
        if cell.exercise is not None:
            own, first = f"<exercise {cell.exercise}>", 1
        elif not cell.text.startswith("%%soar"):
            own, first = _file_label(cell), compose(cell)[1]
        else:
            own, first = f"<%%soar {_agent_name(cell.text)}>", 0  # the body is line 2 on
        line = error.line - first + 1
        inside = error.file == own and 1 <= line <= cell.text.count("\n") + 1
        report.update(line=error.line, column=error.column, file=error.file,
                      cell_line=line if inside else None)
    return report


def _agent_name(text: str) -> str:
    try:
        return parse_line(text.partition("\n")[0][len("%%soar"):]).agent
    except SoarError:
        return "soar"


def query(agent: Agent, command: str) -> dict[str, str]:
    """One of the notebook's looks into an agent: ``print S1``, ``matches``, ``preferences``
    (any print/matches/preferences command line), as the kernel prints it."""
    words = command.split()
    if not words or words[0] not in ("print", "p", "matches", "preferences", "stats"):
        return {"command": command, "text": "only print, matches, preferences and stats"}
    out = io.StringIO()
    previous, agent.out = agent.out, out
    try:
        agent.load(command, file="<query>")
    except SoarError as error:
        out.write(str(error))
    finally:
        agent.out = previous
    return {"command": command, "text": out.getvalue()}


# --------------------------------------------------------------------------- input-link

#: A leaf of an input tree: [attribute, kind, text] with kind "i" (int), "f" (float) or "s";
#: a node: [attribute, [children...]]. Numbers travel as text so that JSON in the page keeps
#: 3.0 a float (JavaScript writes it as 3, which Python would read back as an int).
InputTree = list


def input_tree(agent: Agent) -> InputTree:
    """The agent's input-link as an `InputTree`: the WMEs a driver put there (the agent's
    architecture WMEs below the link; rules may have elaborated the same objects), even
    after a run, to replay them in the page."""
    arch = agent._arch

    def walk(ident: Identifier, above: frozenset) -> InputTree:
        tree: InputTree = []
        for wme in arch.get(ident, ()):
            value = wme.value
            if isinstance(value, Identifier):
                if value not in above:
                    tree.append([str(wme.attr), walk(value, above | {value})])
            else:
                kind = {int: "i", float: "f"}.get(type(value), "s")
                tree.append([str(wme.attr), kind, repr(value) if kind == "f" else str(value)])
        return tree

    link = agent.input_link.identifier
    return walk(link, frozenset([link]))


def put_input(agent: Agent, tree: InputTree, handle: Any = None) -> None:
    """Add an `InputTree` under the input-link (or under ``handle``)."""
    handle = agent.input_link if handle is None else handle
    for item in tree:
        if len(item) == 2:
            put_input(agent, item[1], handle.add(item[0]))
        else:
            attr, kind, text = item
            handle.add(attr, int(text) if kind == "i" else float(text) if kind == "f" else text)


# ------------------------------------------------------------------------------ stepping


class Stepper:
    """A stepping session of one cell: its agent, advanced one phase or one decision."""

    def __init__(self, request: dict[str, Any]) -> None:
        self.cell = cell = Cell.of(request)
        self.out = io.StringIO()
        if cell.exercise is not None:
            from sann.exercises import EXERCISES

            self.agent = EXERCISES[cell.exercise].agent(cell.text, self.out)
        elif cell.text.startswith("%%soar"):
            self.agent = self._magic_agent(cell)
        else:
            self.agent = Agent(out=ReaderStream(self.out))
            self.agent.load(compose(cell)[0], file=_file_label(cell))
            put_input(self.agent, cell.input)
        self.agent.trace(cell.trace)

    def _magic_agent(self, cell: Cell) -> Agent:
        """The agent a ``%%soar`` cell would run, loaded but not run."""
        line, _, body = cell.text.partition("\n")
        options = parse_line(line[len("%%soar"):])
        agent = Agent(options.agent, seed=options.seed, out=ReaderStream(self.out))
        for name in cell.preload:
            agent.load(rule_text(name), file=f"rules/{name}")
        for earlier in cell.before:
            agent.load(earlier.partition("\n")[2], file=f"<%%soar {options.agent}: earlier cell>")
        agent.load(body, file=f"<%%soar {options.agent}>")
        return agent

    def step(self, unit: str) -> dict[str, Any]:
        """Advance by ``phase`` or ``decision`` and describe the agent after it."""
        start = len(self.out.getvalue())
        if not self.agent.halted:
            if unit == "phase":
                self.agent._run_phase()
            else:
                self.agent.step()
        return {"output": self.out.getvalue()[start:], **describe(self.agent)}


def describe(agent: Agent) -> dict[str, Any]:
    """What the stepping view shows: the phase, the goal stack with each state's impasse,
    selected operator and operator preferences, and working memory as a graph."""
    return {
        "phase": agent.phase,
        "decisions": agent.stats["decisions"],
        "halted": agent.halted,
        "goals": goal_stack(agent),
        "graph": wm_graph(agent),
    }


def goal_stack(agent: Agent) -> list[dict[str, Any]]:
    """The states from the top down, read from working memory."""
    wmes = list(agent.wmes())
    goals = []
    state: Identifier | None = agent.top_state
    while state is not None:
        own = [w for w in wmes if w.id is state]
        selected = [w.value for w in own if w.attr == "operator" and not w.acceptable]
        operator = selected[0] if selected else None
        goals.append({
            "id": str(state),
            "impasse": next((str(w.value) for w in own if w.attr == "impasse"), None),
            "attribute": next((str(w.value) for w in own if w.attr == "attribute"), None),
            "operator": str(operator) if operator is not None else None,
            "operator_name": _name_of(wmes, operator),
            "proposed": [f"{w.value} ({_name_of(wmes, w.value)})" for w in own
                         if w.attr == "operator" and w.acceptable],
            "preferences": preferences_text(agent, (str(state), "operator")),
        })
        state = next((w.id for w in wmes if w.attr == "superstate" and w.value is state
                      and isinstance(w.id, Identifier)), None)
    return goals


def _name_of(wmes: list, operator: object) -> str | None:
    if operator is None:
        return None
    return next((str(w.value) for w in wmes if w.id is operator and w.attr == "name"), None)


def wm_graph(agent: Agent) -> dict[str, Any]:
    """Working memory as a graph: identifiers as nodes, attributes as edges, constants as
    leaf nodes of their own (one per WME, so equal values do not merge), reached from the top
    state breadth first; ``depth`` is the distance from it, for the page's layout."""
    by_id: dict[Identifier, list] = {}
    for wme in agent.wmes():
        by_id.setdefault(wme.id, []).append(wme)
    top = agent.top_state
    depth = {top: 0}
    order = [top]
    nodes = [{"id": str(top), "label": str(top), "kind": "state", "depth": 0}]
    edges = []
    cut = False
    for ident in order:
        for wme in by_id.get(ident, ()):
            if len(nodes) >= GRAPH_LIMIT:
                cut = True
                break
            value = wme.value
            if isinstance(value, Identifier):
                target = str(value)
                if value not in depth:
                    depth[value] = depth[ident] + 1
                    order.append(value)
                    kind = "state" if value.is_state else "id"
                    nodes.append({"id": target, "label": target, "kind": kind,
                                  "depth": depth[value]})
            else:
                target = f"t{wme.timetag}"
                nodes.append({"id": target, "label": _constant(value), "kind": "constant",
                              "depth": depth[ident] + 1})
            edges.append({"from": str(ident), "to": target, "attr": str(wme.attr),
                          "acceptable": wme.acceptable, "timetag": wme.timetag})
    return {"nodes": nodes, "edges": edges, "cut": cut, "wm_size": agent.stats["wm_size"]}


def _constant(value: object) -> str:
    from sann.soar.memory import format_symbol

    return format_symbol(value)
