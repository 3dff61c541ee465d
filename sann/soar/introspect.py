"""``matches`` and ``preferences``: the kernel's views into the matcher and the decision
procedure, as text in the Soar 9.6 kernel's format (measured with ``soar_sml``).

Everything here is computed on demand from the agent's working memory, match queues and
slots: partial matches are counted by joining the conditions in the kernel's order
(`matching/reorder.py`) over working memory, so the engine keeps no extra bookkeeping for them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

from .decision.preference_semantics import NONE as NO_IMPASSE
from .decision.preference_semantics import numeric_values, run_preference_semantics
from .errors import SoarRuntimeError
from .matching.oracle import PartialMatch, join_condition, negation_matches, test_holds
from .matching.reorder import KCond, format_kcond, kernel_conditions, positive_order, symbol_ages
from .matching.variables import condition_fields
from .memory import WME, Identifier
from .production import Condition, ConjunctiveNegation, Const, Production
from .trace import symbol_text, trace_wme

if TYPE_CHECKING:
    from .agent import Agent

NONE, TIMETAGS, WMES = 0, 1, 2

#: A partial match: the variable bindings and the (condition, WME) pairs joined so far.
Token = PartialMatch


# ----------------------------------------------------------------------------- helpers


def _kernel_order(agent: Agent, production: Production) -> list[KCond]:
    infos = sorted(agent._productions.values(), key=lambda info: info.load_index)
    ages = symbol_ages(info.production for info in infos)
    return kernel_conditions(production, ages, agent.multi_attributes)


def _token_text(wmes: list[WME], level: int) -> str:
    """The kernel's print_whole_token: each WME and a blank."""
    if level == TIMETAGS:
        return "".join(f"{w.timetag} " for w in wmes)
    return "".join(f"{trace_wme(w)}\n " for w in wmes)


def _level(items: list[str]) -> int:
    level = NONE
    for item in items:
        if item in ("-t", "--timetags"):
            level = TIMETAGS
        elif item in ("-w", "--wmes"):
            level = WMES
        elif item in ("-n", "--names", "-c", "--count"):
            level = NONE
        else:
            raise SoarRuntimeError(f"unknown option {item}")
    return level


# ----------------------------------------------------------------------------- match set


def matches_text(agent: Agent, args: tuple[str, ...]) -> str:
    """``matches [options] [production]``."""
    names = [a for a in args if not a.startswith("-")]
    options = [a for a in args if a.startswith("-")]
    show = "both"
    for flag, what in (("-a", "assert"), ("--assertions", "assert"),
                       ("-r", "retract"), ("--retractions", "retract")):
        if flag in options:
            options.remove(flag)
            show = what
    level = _level(options)
    if len(names) > 1:
        raise SoarRuntimeError("expects at most one production name")
    if names:
        info = agent._productions.get(names[0])
        if info is None:
            raise SoarRuntimeError(f"Production not found: {names[0]}")
        return partial_matches_text(agent, info.production, level)
    return match_set_text(agent, show, level)


def _goals(agent: Agent) -> list:
    goals, goal = [], agent._top
    while goal is not None:
        goals.append(goal)
        goal = goal.sub
    return goals


def match_set_text(agent: Agent, show: str, level: int) -> str:
    """The kernel's print_match_set: pending o- and i-assertions and retractions."""
    goals = _goals(agent)
    out: list[str] = []
    if show in ("both", "assert"):
        for label, queue in (("O Assertions:\n", "pending_o"), ("I Assertions:\n", "pending_i")):
            out.append(label)
            pending = [(m, g.id) for g in goals for m in getattr(g, queue)]
            pending.sort(key=lambda item: _ms_key(agent, item[0]))
            entries = [(m.production.name, goal, m) for m, goal in reversed(pending)]
            out.append(_ms_entries(agent, entries, level, _match_wmes))
    if show in ("both", "retract"):
        out.append("Retractions:\n")
        insts = [i for g in goals for i in g.retractions] + list(agent._nil_retractions)
        insts.sort(key=lambda inst: _ms_key(agent, inst.match))
        entries = [(i.name, i.goal.id if i.goal.alive else None, i) for i in reversed(insts)]
        out.append(_ms_entries(agent, entries, level, _inst_wmes))
    return "".join(out)


def _ms_key(agent: Agent, match: object) -> tuple[int, int, int]:
    """Position in the kernel's match-set lists, oldest first: by the newest WME, and for
    one WME the earlier-loaded production first (measured)."""
    newest, mask, later_first = agent._creation_key(match)
    return (newest, mask, -later_first)


def _ms_entries(agent: Agent, entries: list, level: int,
                wmes_of: Callable[[Agent, object], list[WME]]) -> str:
    """Newest first with the WMEs; by name (oldest first, counted) without."""
    if level != NONE:
        return "".join(f"  {name}  [{_goal(goal)}] {_token_text(wmes_of(agent, item), level)}\n"
                       for name, goal, item in entries)
    counted: list[list] = []
    for name, goal, _item in entries:
        same = next((c for c in counted if c[0] == name and c[1] is goal), None)
        if same is not None:
            same[2] += 1
        else:
            counted.insert(0, [name, goal, 1])
    return "".join(f"  {name}  [{_goal(goal)}] " + (f"({n})\n" if n > 1 else "\n")
                   for name, goal, n in counted)


def _goal(goal: Identifier | None) -> str:
    return "NIL" if goal is None else goal.name


def _match_wmes(agent: Agent, match: object) -> list[WME]:
    production = match.production  # type: ignore[attr-defined]
    wmes = match.wmes  # type: ignore[attr-defined]
    order = positive_order(_kernel_order(agent, production))
    return [wmes[i] for i in order if wmes[i] is not None]


def _inst_wmes(agent: Agent, inst: object) -> list[WME]:
    return _match_wmes(agent, inst.match)  # type: ignore[attr-defined]


# ----------------------------------------------------------------------------- partial matches


def partial_matches_text(agent: Agent, production: Production, level: int) -> str:
    """The kernel's print_partial_match_information for one production."""
    ordered = _kernel_order(agent, production)
    wm = sorted(agent._wm.values(), key=lambda w: w.timetag)
    out: list[str] = []
    root: list[Token] = [({}, ())]
    tokens = _print_level(ordered, root, wm, level, 0, 1, out)
    out.append(f"\n{len(tokens)} complete matches.\n")
    if tokens and level != NONE:
        out.append("*** Complete Matches ***\n")
        out.extend(_token_text([w for _, w in t[1]], level) + "\n" for t in tokens)
    return "".join(out)


def _print_level(ordered: list[KCond], tokens: list[Token], wm: list[WME], level: int,
                 indent: int, above: int, out: list[str]) -> list[Token]:
    """Print each condition's count of partial matches (``>>>>`` where they stop) and
    return the tokens that pass all of ``ordered``. ``above``: the count printed for the
    level above, 1 at the top of a scope."""
    pad = " " * indent
    for kcond in ordered:
        if kcond.is_ncc:
            out.append(pad + "    -{\n")
            _print_level(kcond.inner, tokens, wm, level, indent + 5, min(above, 1), out)
            passed = [t for t in tokens if not negation_matches(kcond.element, wm, t[0])]
            out.append(f"{pad}{_marker(above, len(passed))} }}\n")
        else:
            passed = _extend(kcond, tokens, wm)
            out.append(f"{pad}{_marker(above, len(passed))} {format_kcond(kcond)}\n")
            if level != NONE and above > 0 and not passed:
                out.append(_left_right(kcond, tokens, wm, level, pad))
        above = len(passed) if above > 0 else 0
        tokens = passed
    return tokens


def _marker(above: int, count: int) -> str:
    if above <= 0:
        return "    "
    return ">>>>" if count == 0 else f"{count:4d}"


def _extend(kcond: KCond, tokens: list[Token], wm: list[WME]) -> list[Token]:
    """The tokens after one condition: joined with a positive one, filtered by a
    negation."""
    element = kcond.element
    if kcond.negated:
        return [t for t in tokens if not negation_matches(element, wm, t[0])]
    assert isinstance(element, Condition)
    return join_condition(element, tokens, wm)


def _left_right(kcond: KCond, tokens: list[Token], wm: list[WME], level: int,
                pad: str) -> str:
    """Where a condition has no match: the partial matches that reach it (left) and the
    WMEs that pass its constant tests (right)."""
    out = [pad + "*** Matches For Left ***\n"]
    out.extend(pad + _token_text([w for _, w in t[1]], level) + "\n" for t in tokens)
    out.append(pad + "*** Matches for Right ***\n")
    right = [wme for wme in reversed(wm) if _alpha_accepts(kcond.element, wme)]
    out.append(pad + _token_text(right, level) + "\n")
    return "".join(out)


def _alpha_accepts(element: ConjunctiveNegation | Condition, wme: WME) -> bool:
    """The kernel's alpha memory: constant id, attribute and value tests, and the ``+``."""
    assert isinstance(element, Condition)
    if wme.acceptable != element.acceptable:
        return False
    for test, value in zip(condition_fields(element), (wme.id, wme.attr, wme.value), strict=True):
        if isinstance(test, Const) and not test_holds(test, value, {}, final=False):
            return False
    return True


__all__ = ["matches_text", "symbol_text"]


# ----------------------------------------------------------------------------- preferences

#: The kernel's preference types in its print order, with its section names.
_SECTIONS = (
    ("+", "acceptables"), ("!", "requires"), ("-", "rejects"), ("~", "prohibits"),
    ("@", "reconsiders"), ("=", "unary indifferents"), (">", "bests"), ("<", "worsts"),
    ("b=", "binary indifferents"), ("b>", "betters"), ("b<", "worses"),
    ("n=", "numeric indifferents"),
)  # fmt: skip


def preferences_text(agent: Agent, args: tuple[str, ...]) -> str:
    """``preferences [--names|--timetags|--wmes] [id attr]``; with no id, the operator slot
    of the bottom state."""
    items = [a for a in args if not a.startswith("-")]
    level = 0
    for option in (a for a in args if a.startswith("-")):
        if option in ("-n", "--names", "-1"):
            level = 1
        elif option in ("-t", "--timetags", "-2"):
            level = 2
        elif option in ("-w", "--wmes", "-3"):
            level = 3
        elif option in ("-0", "--none"):
            level = 0
        else:
            raise SoarRuntimeError(f"unsupported option {option}")
    if len(items) == 1 or len(items) > 2:
        raise SoarRuntimeError(
            "only 'preferences [options]' and 'preferences [options] <id> <attribute>' "
            "are supported")
    if items:
        ident, attr = _find_id(agent, items[0]), _attribute(items[1])
    else:
        ident, attr = _goals(agent)[-1].id, "operator"
    return _slot_text(agent, ident, attr, level)


def _find_id(agent: Agent, text: str) -> Identifier:
    try:
        return agent.find_identifier(text.upper())
    except Exception as error:
        raise SoarRuntimeError(f"Could not find the id '{text}'") from error


def _attribute(text: str) -> str | int | float:
    text = text.lstrip("^")
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def _slot_text(agent: Agent, ident: Identifier, attr: object, level: int) -> str:
    slot = agent._slot(ident, attr, create=False)  # type: ignore[arg-type]
    is_op = attr == "operator" and ident.level is not None
    if slot is None or (not slot.prefs and not is_op):
        if not _known_symbol(agent, attr):
            raise SoarRuntimeError(
                f"Could not find prefs for the id,attribute pair: {ident} {attr}")
        if not is_op:
            return "  This is probably an io- or arch-wme and does not have preferences\n"
    out = [f"\nPreferences for {ident} ^{symbol_text(attr)}:\n"]  # type: ignore[arg-type]
    if slot is not None:
        for ptype, label in _SECTIONS:
            prefs = slot.of_type(ptype)
            if prefs:
                out.append(f"\n{label}:\n")
                out.extend(_pref_text(agent, p, is_op, level) for p in prefs)
        if is_op:
            out.append(_probabilities(agent, slot, level))
    return "".join(out)


def _known_symbol(agent: Agent, attr: object) -> bool:
    """The kernel only knows symbols it has made: the architecture's, the rules', WM's."""
    infos = agent._productions.values()
    if (type(attr), attr) in symbol_ages(info.production for info in infos):
        return True
    return any(w.attr == attr and type(w.attr) is type(attr) for w in agent._wm.values())


def _value_text(agent: Agent, value: object) -> str:
    """An operator as ``O1 (name)``, as the kernel shows candidates."""
    text = symbol_text(value)  # type: ignore[arg-type]
    if isinstance(value, Identifier):
        names = [w.value for w in agent._augmentations(value) if w.attr == "name"]
        if names:
            text += f" ({symbol_text(names[0])})"
    return text


def _pref_text(agent: Agent, pref: object, is_op: bool, level: int) -> str:
    p = pref
    char = p.type[-1]  # type: ignore[attr-defined]
    ref = p.referent  # type: ignore[attr-defined]
    if p.type == "n=":  # type: ignore[attr-defined]
        ref_text = f"{float(ref):f}"
    else:
        ref_text = _value_text(agent, ref) if ref is not None else ""
    support = ":O" if p.o_supported else ":I"  # type: ignore[attr-defined]
    if is_op:
        head = f"{_value_text(agent, p.value)} {char}"  # type: ignore[attr-defined]
    else:
        head = (f"({symbol_text(p.id)} ^{symbol_text(p.attr)} "  # type: ignore[attr-defined]
                f"{symbol_text(p.value)})")  # type: ignore[attr-defined]
        head += "" if char == "+" else f" {char}"
    return f"  {head} {ref_text} {support} \n" + _source_text(agent, p, level)


def _source_text(agent: Agent, pref: object, level: int) -> str:
    """``From rule`` and the instantiation's WMEs, in the kernel's condition order."""
    inst = pref.inst  # type: ignore[attr-defined]
    if level == 0 or inst is None:
        return ""
    out = f"    From {inst.name}\n"
    wmes = _inst_wmes(agent, inst) if hasattr(inst, "match") else []
    if level == 3:
        return out + "".join(f"WME with time tag {w.timetag}\n" for w in wmes) + "\n"
    if level == 2:
        return out + "".join(f" {w.timetag}" for w in wmes) + "\n"
    return out + "\n"


def _probabilities(agent: Agent, slot: object, level: int) -> str:
    """The exploration policy's chance of each candidate, when the slot would choose."""
    impasse, candidates = run_preference_semantics(slot, None, consistency=True)  # type: ignore[arg-type]
    if impasse != NO_IMPASSE or not candidates:
        return ""
    exploration = agent.exploration
    values = numeric_values(slot, candidates, exploration.numeric_mode)  # type: ignore[arg-type]
    chances = _chances(exploration, values)
    out = ["\nselection probabilities:\n"]
    for value, number, chance in zip(candidates, values, chances, strict=True):
        pref = next(p for p in slot.of_type("+") if p.value == value)  # type: ignore[attr-defined]
        support = ":O" if pref.o_supported else ":I"
        shown = f"{number:f}".rstrip("0")
        out.append(f"  {_value_text(agent, value)} +  = {shown} {support} "
                   f"({100 * chance:.2f}%)\n" + _source_text(agent, pref, level))
    return "".join(out)


def _chances(exploration: object, values: list[float]) -> list[float]:
    n = len(values)
    policy = exploration.policy  # type: ignore[attr-defined]
    if n == 1:
        return [1.0]
    if policy == "first":
        return [1.0] + [0.0] * (n - 1)
    if policy == "last":
        return [0.0] * (n - 1) + [1.0]
    if policy == "softmax":
        total = sum(v for v in values if v > 0)
        return [max(v, 0) / total if total > 0 else 1 / n for v in values]
    if policy == "boltzmann":
        top = max(values)
        weights = [math.exp((v - top) / exploration.temperature) for v in values]  # type: ignore[attr-defined]
        return [w / sum(weights) for w in weights]
    if policy == "epsilon-greedy":
        top = max(values)
        best = sum(1 for v in values if v == top)
        eps = exploration.epsilon  # type: ignore[attr-defined]
        return [eps / n + ((1 - eps) / best if v == top else 0.0) for v in values]
    return [1 / n] * n
