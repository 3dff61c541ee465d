"""Lines of generated code shared by the nodes' generated activations, and the plain Python
functions that do the same.

Each ``*_lines`` helper returns source lines (indented by ``pad``) that do what a named
Python helper does (``token_lines`` is ``new_token``, ``filing_lines`` is ``index_add``...),
written out so that the generated loops call no function per token.  The names the lines
read (``FLOAT``, ``Token``, ``node``...) are put in the namespace the code runs in by the
node that generates it.  The constant tests of an alpha memory and the beta tests of a
join are generated functions too (``compile_alpha``, ``compile_check``), or their plain
twins (``alpha_tests_hold``, ``beta_tests_hold``) when ``codegen.plain()``.
"""

from __future__ import annotations

import operator
from collections.abc import Callable, Sequence
from functools import partial
from typing import Any

from sann.soar.codegen import define, plain
from sann.soar.matching.plan import BetaSpec
from sann.soar.matching.symbols import RELATIONS, same_symbol
from sann.soar.matching.tokens import WITNESSED, hash_key
from sann.soar.memory import WME

NUMBERS = frozenset((int, float))
_ORDER_OPS: dict[str, Callable[[Any, Any], Any]] = {
    "<": operator.lt, ">": operator.gt, "<=": operator.le, ">=": operator.ge}
_TYPES = {"int": int, "float": float}
#: The names the inlined beta tests read.
CHECK_NAMES: dict[str, object] = {"NUMBERS": NUMBERS, "RELATIONS": RELATIONS}


def token_lines(pad: str, parent: str, wme: str, values: str) -> list[str]:
    """Generated code: ``token`` = a new token of ``node`` (``Token`` in the namespace), what
    ``new_token`` does, inline."""
    return [f"{pad}token = Token(); token.parent = {parent}; token.wme = {wme}; "
            f"token.vals = {values}",
            f"{pad}token.node = node; token.children = token.extra = None"]


def adopt_lines(pad: str, parent: str) -> list[str]:
    """Generated code: ``token`` becomes a child of ``parent`` (what ``adopt`` does)."""
    return [f"{pad}siblings = {parent}.children",
            f"{pad}if siblings is None: {parent}.children = {{token: None}}",
            f"{pad}else: siblings[token] = None"]


def key_lines(value: str, pad: str, floats: bool) -> list[str]:
    """Generated code: ``key`` = the hash key of ``value`` (see ``hash_key``); an identifier
    field (``floats`` false) is never a float."""
    lines = [f"{pad}key = {value}"]
    if floats:
        lines.append(f"{pad}if key.__class__ is float: key = (FLOAT, key)")
    return lines


def filing_lines(index: str, value: str, item: str, pad: str, floats: bool) -> list[str]:
    """Generated code: file ``item`` under ``value`` in the hash index ``index`` (what
    ``index_add`` does, inline)."""
    return key_lines(value, pad, floats) + [
        f"{pad}filed = {index}.get(key)",
        f"{pad}if filed is None: {index}[key] = {{{item}: None}}",
        f"{pad}else: filed[{item}] = None"]


def unfiling_lines(index: str, value: str, item: str, pad: str, floats: bool) -> list[str]:
    """Generated code: take ``item`` out of the hash index ``index`` (what ``index_remove``
    does, inline)."""
    return key_lines(value, pad, floats) + [
        f"{pad}filed = {index}[key]", f"{pad}del filed[{item}]",
        f"{pad}if not filed: del {index}[key]"]


def bucket_lines(k: int, pad: str, key: str | None, seeded: bool) -> list[str]:
    """Generated code: ``candidates_<k>`` = the WMEs of condition ``k`` hashed on the value
    ``key`` (an expression; all of its alpha memory ``alpha_wmes_<k>`` when None), or just
    the seed WME when it fits."""
    if seeded:  # same_symbol(key, the seed's field), inline
        test = (f"(bound := {key}).__class__ is (seeded := get_field_{k}(seed)).__class__ "
                "and bound == seeded" if key is not None else "True")
        return [f"{pad}candidates_{k} = (seed,) if {test} else ()"]
    if key is None:
        return [f"{pad}candidates_{k} = alpha_wmes_{k}"]
    return [f"{pad}key = {key}", f"{pad}if key.__class__ is float: key = (FLOAT, key)",
            f"{pad}candidates_{k} = alpha_index_{k}.get(key, ())"]


def witness_lines(pad: str) -> list[str]:
    """Generated code: keep ``found`` as the witness of the blocked ``token`` (what
    ``QueryNCCNode._witness`` does, inline; ``wme_records`` is the Rete's WME records)."""
    return [f"{pad}token.extra = found", f"{pad}for witness in found[1]:",
            f"{pad}    record = wme_records[witness]", f"{pad}    witnessed = record[{WITNESSED}]",
            f"{pad}    if witnessed is None: record[{WITNESSED}] = {{token: None}}",
            f"{pad}    else: witnessed[token] = None"]


def compile_alpha(specs: list[tuple]) -> Callable[[WME], bool] | None:
    """One function for a condition's constant tests: generated, or ``alpha_tests_hold``."""
    if not specs:
        return None
    if plain():
        return partial(alpha_tests_hold, tuple(specs))
    lines = ["def accept(wme):"]
    namespace: dict[str, object] = {"NUMBERS": NUMBERS}
    for n, spec in enumerate(specs):
        kind = spec[0]
        if kind == "state":
            lines.append("    if wme.id.level is None: return False")
            continue
        if kind == "never":
            lines.append("    return False")
            continue
        lines.append(f"    value = wme.{spec[1]}")
        if kind == "type":
            lines.append(f"    if value.__class__ is not {spec[2]}: return False")
        elif kind == "eq":
            namespace[f"constant_{n}"] = spec[2][1]
            lines.append(f"    if not (value.__class__ is constant_{n}.__class__ "
                         f"and value == constant_{n}): return False")
        elif kind == "rel":
            namespace[f"constant_{n}"] = spec[3][1]
            namespace[f"relation_{n}"] = RELATIONS[spec[2]]
            lines.append(f"    if not relation_{n}(value, constant_{n}): return False")
        else:  # disjunction of typed constants
            namespace[f"choices_{n}"] = frozenset(spec[2])
            lines.append(f"    if (value.__class__.__name__, value) not in choices_{n}: "
                         "return False")
    lines.append("    return True")
    return define(lines, namespace, "accept", "rete:alpha-tests")


def alpha_tests_hold(specs: tuple, wme: WME) -> bool:
    """Plain Python: whether ``wme`` passes a condition's constant tests (``compile_alpha``)."""
    for spec in specs:
        kind = spec[0]
        if kind == "state":
            if wme.id.level is None:  # type: ignore[union-attr]
                return False
            continue
        if kind == "never":
            return False
        value = getattr(wme, spec[1])
        if kind == "type":
            if value.__class__ is not _TYPES[spec[2]]:
                return False
        elif kind == "eq":
            if not same_symbol(value, spec[2][1]):
                return False
        elif kind == "rel":
            if not RELATIONS[spec[2]](value, spec[3][1]):
                return False
        elif (value.__class__.__name__, value) not in frozenset(spec[2]):
            return False
    return True


def check_lines(specs: Sequence[BetaSpec], values: str, wme: str, fail: str, pad: str,
                value: Callable[[int], str] | None = None) -> list[str]:
    """Generated code testing every beta test of a join on the values ``values`` and the WME
    ``wme``, running ``fail`` (``return False``, ``continue``) at the first that does not
    hold.  The join and query loops inline these lines: in the innermost loop a call per
    pair costs more than the tests themselves.  ``value(pos)`` may name a value position
    otherwise than ``values[pos]``."""
    if value is None:
        # not a nested def: mypyc fails on one rebinding a parameter
        value = f"{values}[{{}}]".format
    lines = []
    for n, ((lk, la), op, (rk, ra)) in enumerate(specs):
        left_value = f"{wme}.{la}" if lk == "w" else value(la)  # type: ignore[arg-type]
        right_value = f"{wme}.{ra}" if rk == "w" else value(ra)  # type: ignore[arg-type]
        left, right = f"left_{n}", f"right_{n}"
        lines.append(f"{left} = {left_value}; {right} = {right_value}")
        if op == "=":
            lines.append(f"if {left} is not {right} and not ({left}.__class__ is "
                         f"{right}.__class__ and {left} == {right}): {fail}")
        elif op == "<>":
            lines.append(f"if {left} is {right} or ({left}.__class__ is {right}.__class__ "
                         f"and {left} == {right}): {fail}")
        elif op == "<=>":
            lines.append(f"if {left}.__class__ is not {right}.__class__: {fail}")
        elif op == "@":
            lines.append(fail)
        elif op in _ORDER_OPS:
            lines.append(f"if {left}.__class__ in NUMBERS and {right}.__class__ in NUMBERS:")
            lines.append(f"    if not ({left} {op} {right}): {fail}")
            lines.append(f"elif not RELATIONS[{op!r}]({left}, {right}): {fail}")
        elif op != "!@":
            raise AssertionError(f"unknown relation {op!r}")
    return [pad + line for line in lines]


def beta_tests_hold(specs: tuple[BetaSpec, ...], values: tuple, wme: WME) -> bool:
    """Plain Python: whether every beta test of a join holds (``check_lines``)."""
    for (lk, la), op, (rk, ra) in specs:
        left = getattr(wme, la) if lk == "w" else values[la]  # type: ignore[arg-type, index]
        right = getattr(wme, ra) if rk == "w" else values[ra]  # type: ignore[arg-type, index]
        if op == "=":
            if left is not right and not same_symbol(left, right):
                return False
        elif op == "<>":
            if left is right or same_symbol(left, right):
                return False
        elif op == "<=>":
            if left.__class__ is not right.__class__:
                return False
        elif op == "@":
            return False
        elif op in _ORDER_OPS:
            if left.__class__ in NUMBERS and right.__class__ in NUMBERS:
                if not _ORDER_OPS[op](left, right):
                    return False
            elif not RELATIONS[op](left, right):
                return False
        elif op != "!@":
            raise AssertionError(f"unknown relation {op!r}")
    return True


def compile_check(specs: list[BetaSpec]) -> Callable[[tuple, WME], bool] | None:
    """One function testing every beta test of a join, for the nodes that call it per WME
    (generated, or ``beta_tests_hold``); its ``specs`` attribute lets generated loops inline
    the same tests."""
    if not specs:
        return None
    if plain():
        check: Callable = partial(beta_tests_hold, tuple(specs))
    else:
        lines = ["def check(values, wme):",
                 *check_lines(specs, "values", "wme", "return False", "    "), "    return True"]
        check = define(lines, dict(CHECK_NAMES), "check", "rete:beta-tests")
    check.specs = tuple(specs)  # type: ignore[attr-defined]
    return check


def EXTEND_VALUE(values: tuple, wme: WME) -> tuple:  # noqa: N802 -- a marker as much as a function
    return values + (wme.value,)


def extend_values(fields: tuple[str, ...], values: tuple, wme: WME) -> tuple:
    """Plain Python: ``values`` extended with the fields of ``wme`` a join binds."""
    return values + tuple(getattr(wme, field) for field in fields)


def extender(fields: tuple[str, ...]) -> Callable | None:
    """How a join extends a token's values with what the WME binds."""
    if not fields:
        return None
    if fields == ("value",):
        return EXTEND_VALUE
    if plain():
        return partial(extend_values, fields)
    lines = ["def extend(values, wme):",
             "    return values + (" + "".join(f"wme.{field}, " for field in fields) + ")"]
    return define(lines, {}, "extend", "rete:extend")


def index_of(index: dict, value: object) -> object:
    """Plain Python: what ``index`` files under ``value`` (None if nothing)."""
    return index.get(hash_key(value))
