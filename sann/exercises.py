"""The checks of the book's exercises (book/exercises.md), run in the page after each *Run* of
an exercise's live cell and by the test suite against reference solutions kept outside the
chapter (tests/book/solutions/), so a reader's answer and the reference are judged alike.

Each check runs the reader's rules on top of the shipped rule file and asserts behaviour —
what the agent does, decision by decision — never the text of a particular answer.
"""

from __future__ import annotations

import io
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TextIO

from sann import RULES
from sann.live import put_input
from sann.soar import Agent, SoarError
from sann.soar.parsing.parser import parse
from sann.soar.production import ConjunctiveNegation, Production
from sann.soar.rhs import FUNCTIONS


@dataclass(frozen=True)
class Result:
    """One criterion of an exercise: whether it holds, and what was seen."""

    name: str
    passed: bool
    detail: str


@dataclass(frozen=True)
class Exercise:
    """An exercise's live cell: the rule files under it, its input, its starting text."""

    name: str
    title: str
    preload: tuple[str, ...]
    start: str
    decisions: int
    inputs: tuple = ()  # an input tree (sann.live.InputTree) put on the input-link
    judge: Callable[[Exercise, str], list[Result]] = field(default=lambda e, t: [], repr=False)

    def agent(self, text: str, out: TextIO | None = None) -> Agent:
        """A new agent with the shipped rules, the exercise's input and the reader's text."""
        agent = Agent(out=out if out is not None else io.StringIO())
        for name in self.preload:
            agent.load((RULES / name).read_text(encoding="utf-8"), file=f"rules/{name}")
        agent.load(text, file=f"<exercise {self.name}>")
        put_input(agent, list(self.inputs))
        return agent


def check(name: str, text: str) -> dict[str, object]:
    """Judge ``text`` as the answer to exercise ``name``: every criterion, and whether all
    pass. Rules that do not load fail the first criterion with the engine's message."""
    exercise = EXERCISES[name]
    try:
        results = exercise.judge(exercise, text)
    except SoarError as error:
        results = [Result("the rules load", False, str(error))]
    return {"exercise": name, "passed": bool(results) and all(r.passed for r in results),
            "results": [r.__dict__ for r in results]}


def _new_productions(text: str, file: str) -> list[Production]:
    return [item for item in parse(text, file, FUNCTIONS.keys()) if isinstance(item, Production)]


def _shipped_names(exercise: Exercise) -> set[str]:
    names: set[str] = set()
    for name in exercise.preload:
        text = (RULES / name).read_text(encoding="utf-8")
        names |= {p.name for p in _new_productions(text, name)}
    return names


def _adds_a_rule(exercise: Exercise, text: str) -> tuple[Result, list[Production]]:
    added = [p for p in _new_productions(text, f"<exercise {exercise.name}>")
             if p.name not in _shipped_names(exercise)]
    names = ", ".join(p.name for p in added) or "none"
    return Result("the cell adds a rule", bool(added), f"new rules: {names}"), added


# ------------------------------------------------------------------ 2. greedy water jug


def _operators(agent: Agent, state: object, acceptable: bool) -> dict[object, str]:
    wmes = list(agent.wmes())
    names = {w.id: str(w.value) for w in wmes if w.attr == "name"}
    return {w.value: names.get(w.value, "?") for w in wmes
            if w.id is state and w.attr == "operator" and w.acceptable == acceptable}


def _best_values(agent: Agent, state: object) -> set[object]:
    goal = agent._goals[state]
    return {pref.value for pref in goal.op_slot.of_type(">")}


def _judge_greedy(exercise: Exercise, text: str) -> list[Result]:
    added, _ = _adds_a_rule(exercise, text)
    agent = exercise.agent(text)
    top = agent.top_state
    seen_empty = unpreferred = 0
    tie = None
    for _ in range(exercise.decisions):
        if agent.halted:
            break
        proposed = _operators(agent, top, acceptable=True)
        empties = [o for o, n in proposed.items() if n == "empty"]
        best = _best_values(agent, top)
        seen_empty += len(empties)
        unpreferred += sum(1 for o in empties if o not in best)
        agent.step()
        ties = [w for w in agent.wmes() if w.attr == "impasse" and str(w.value) == "tie"]
        if ties and tie is None:
            tie = agent.stats["decisions"]
    return [
        added,
        Result("every proposed empty operator is best", seen_empty > 0 and unpreferred == 0,
               f"{seen_empty} empty proposals seen, {unpreferred} without a best preference"),
        Result("two best operators tie", tie is not None,
               f"tie impasse at decision {tie}" if tie else "no tie impasse"),
        Result(f"the puzzle stays unsolved for {exercise.decisions} decisions",
               not agent.halted,
               "halted" if agent.halted else f"{agent.stats['decisions']} decisions, no halt"),
    ]


# ------------------------------------------------------------ 3. a negated conjunction


def _all_have_water(agent: Agent) -> tuple[bool, bool]:
    """(the state carries ^all-have-water yes, no jug holds 0) right now."""
    wmes = list(agent.wmes())
    top = agent.top_state
    jugs = {w.value for w in wmes if w.id is top and w.attr == "jug"}
    contents = [w.value for w in wmes if w.id in jugs and w.attr == "contents"]
    marked = any(w.id is top and w.attr == "all-have-water" and str(w.value) == "yes"
                 for w in wmes)
    return marked, bool(contents) and 0 not in contents


def _judge_all_have_water(exercise: Exercise, text: str) -> list[Result]:
    added, rules = _adds_a_rule(exercise, text)
    negated = [p.name for p in rules
               if any(isinstance(c, ConjunctiveNegation) for c in p.conditions)]
    agent = exercise.agent(text)
    wrong, marked_at, full_at = [], [], []
    for _ in range(exercise.decisions):
        agent.step()
        marked, full = _all_have_water(agent)
        decision = agent.stats["decisions"]
        if marked:
            marked_at.append(decision)
        if full:
            full_at.append(decision)
        if marked != full:
            wrong.append(decision)
    return [
        added,
        Result("it uses a negated conjunction -{ ... }", bool(negated),
               f"rules with one: {', '.join(negated) or 'none'}"),
        Result("^all-have-water yes is on the state exactly when no jug is empty",
               not wrong and bool(full_at),
               f"no jug empty at decisions {full_at}; marked at {marked_at}"
               + (f"; wrong at {wrong}" if wrong else "")),
    ]


# ------------------------------------------------------------------ 5. your own monitor


def _judge_monitor(exercise: Exercise, text: str) -> list[Result]:
    added, _ = _adds_a_rule(exercise, text)
    out = io.StringIO()
    agent = exercise.agent(text, out)
    agent.run(exercise.decisions)
    lines = [line.split() for line in out.getvalue().splitlines()]
    missing = [f"{d} {name}" for d, name in enumerate(agent.operator_sequence, 1)
               if not any(str(d) in words and name in words for words in lines)]
    shown = ", ".join(missing[:4]) + (" ..." if len(missing) > 4 else "")
    return [
        added,
        Result("every selected operator is written with its decision number",
               bool(agent.operator_sequence) and not missing,
               f"{len(agent.operator_sequence) - len(missing)} of "
               f"{len(agent.operator_sequence)} written" + (f"; missing {shown}" if missing
                                                             else "")),
        Result("the puzzle is still solved", agent.halted,
               f"halted after {agent.stats['decisions']} decisions" if agent.halted
               else "no halt"),
    ]


# ------------------------------------------------------------ 4. cups: one order per target


def small_pile() -> list:
    """The input-link of the chapter's hand-made pile (A and B on C, D on A, so D lies over C
    too; upright cups 100 mm apart in height), every cup a target, as the cups driver
    (sann.tasks.cups) writes it; tests/book/test_exercises.py checks that it still does."""
    positions = [(0.0, 0.0, 100.0), (60.0, 0.0, 100.0), (30.0, 0.0, 0.0), (0.0, 0.0, 200.0)]
    over = {0: [2], 1: [2], 3: [0, 2]}
    on = {0: [2], 1: [2], 3: [0]}
    tree: list = [["target", "i", str(i)] for i in range(4)]
    for i, (x, y, z) in enumerate(positions):
        cup = [["index", "i", str(i)], ["name", "s", "ABCD"[i]], ["score", "f", "1.0"],
               ["x", "f", repr(x)], ["y", "f", repr(y)], ["z", "f", repr(z)],
               ["ax", "f", "0.0"], ["ay", "f", "0.0"], ["az", "f", "1.0"]]
        cup += [["over", "i", str(k)] for k in over.get(i, [])]
        cup += [["on", "i", str(k)] for k in on.get(i, [])]
        tree.append(["cup", cup])
    return tree


def cup_sequences(agent: Agent) -> dict[str, list[str]]:
    """Per target cup's name, the orders the agent wrote on its output-link (the symbols
    target:T_o:order of rules/cups.soar), sorted."""
    found: dict[str, list[str]] = {name: [] for name in "ABCD"}
    for attr, sequence in agent.output_link.children():
        if attr == "sequence":
            target, _, order = str(sequence).split(":")
            found["ABCD"[int(target)]].append(order)
    return {name: sorted(orders) for name, orders in found.items()}


def _tie_impasses(agent: Agent, limit: int) -> int:
    """Run ``agent`` (at most ``limit`` decisions): how many decisions saw a new tie impasse."""
    seen: set[object] = set()
    for _ in range(limit):
        if agent.halted:
            break
        agent.step()
        seen |= {w.id for w in agent.wmes() if w.attr == "impasse" and str(w.value) == "tie"}
    return len(seen)


def _judge_one_order(exercise: Exercise, text: str) -> list[Result]:
    added, _ = _adds_a_rule(exercise, text)
    agent = exercise.agent(text)
    ties = _tie_impasses(agent, exercise.decisions)
    edited = cup_sequences(agent)
    reference = exercise.agent("")
    reference.run(exercise.decisions)
    searched = cup_sequences(reference)
    lowest = {name: orders[:1] for name, orders in searched.items()}
    counts = {name: len(orders) for name, orders in edited.items()}
    return [
        added,
        Result("the planner still halts", agent.halted,
               f"{agent.stats['decisions']} decisions" + ("" if agent.halted else ", no halt")),
        Result("no tie impasse is left to search", agent.halted and ties == 0,
               f"{ties} tie impasses"),
        Result("every cup gets exactly one sequence", all(n == 1 for n in counts.values()),
               ", ".join(f"{name}: {n}" for name, n in counts.items())),
        Result("each is the shipped search's plan that takes the lowest free cup first",
               edited == lowest,
               f"C: {', '.join(edited['C']) or 'none'} (the search found "
               f"{', '.join(searched['C'])})"),
    ]


EXERCISES: dict[str, Exercise] = {
    e.name: e
    for e in (
        Exercise(
            "greedy-empty", "A greedy water-jug strategy", ("water-jug.soar",),
            "# rules/water-jug.soar is loaded. Add a rule that makes every proposed\n"
            "# empty operator best, then Run (30 decisions at most).\n",
            30, judge=_judge_greedy),
        Exercise(
            "all-have-water", "A negated conjunction", ("water-jug.soar",),
            "# rules/water-jug.soar is loaded. Write water-jug*elaborate*all-have-water:\n"
            "# ^all-have-water yes on the state exactly when no jug is empty.\n",
            9, judge=_judge_all_have_water),
        Exercise(
            "hanoi-monitor", "Your own monitor", ("hanoi.soar",),
            "# rules/hanoi.soar is loaded, with ^disks 4 on the input-link. Add a rule that\n"
            "# writes each selected operator's name and the decision count, (dc).\n",
            10_000, inputs=(("disks", "i", "4"),), judge=_judge_monitor),
        Exercise(
            "cups-one-order", "Cups: let the planner keep a single order", ("cups.soar",),
            "# rules/cups.soar is loaded, with the four-cup pile on the input-link. Add a\n"
            "# rule that leaves no tie among the grasps: one order per target.\n",
            10_000, inputs=tuple(small_pile()), judge=_judge_one_order),
    )
}
