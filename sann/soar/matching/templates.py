"""Lines of generated code shared by the nodes' generated activations.

Each helper returns source lines (indented by ``pad``) that do what a named Python helper
does (``token_lines`` is ``new_token``, ``filing_lines`` is ``index_add``...), written out so
that the generated loops call no function per token.  The names the lines read (``FLOAT``,
``Tok``, ``N``...) are put in the namespace the code runs in by the node that generates it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from sann.soar.codegen import define
from sann.soar.matching.plan import BetaSpec
from sann.soar.matching.symbols import RELATIONS
from sann.soar.memory import WME


def token_lines(pad: str, parent: str, wme: str, vals: str) -> list[str]:
    """Generated code: ``tok`` = a new token of node ``N`` (``Tok`` in the namespace), what
    ``new_token`` does, inline."""
    return [f"{pad}tok = Tok(); tok.parent = {parent}; tok.wme = {wme}; tok.vals = {vals}",
            f"{pad}tok.node = N; tok.children = tok.extra = None"]




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
        f"{pad}b = {index}.get(key)", f"{pad}if b is None: {index}[key] = {{{item}: None}}",
        f"{pad}else: b[{item}] = None"]




def bucket_lines(k: int, pad: str, key: str | None, seeded: bool) -> list[str]:
    """Generated code: ``b<k>`` = the WMEs of condition ``k`` hashed on the value ``key``
    (an expression; its alpha memory ``W<k>`` when None), or just the seed WME when it
    fits."""
    if seeded:  # same_symbol(key, the seed's field), inline
        test = (f"(x := {key}).__class__ is (y := G{k}(seed)).__class__ and x == y"
                if key is not None else "True")
        return [f"{pad}b{k} = (seed,) if {test} else ()"]
    if key is None:
        return [f"{pad}b{k} = W{k}"]
    return [f"{pad}key = {key}", f"{pad}if key.__class__ is float: key = (FLOAT, key)",
            f"{pad}b{k} = I{k}.get(key, ())"]


def witness_lines(pad: str) -> list[str]:
    """Generated code: keep ``found`` as the witness of the blocked ``tok`` (what
    ``QueryNCCNode._witness`` does, inline; ``R`` is the Rete's WME records)."""
    return [f"{pad}tok.extra = found", f"{pad}for w in found[1]:", f"{pad}    record = R[w]",
            f"{pad}    s = record[3]", f"{pad}    if s is None: record[3] = {{tok: None}}",
            f"{pad}    else: s[tok] = None"]


def compile_alpha(specs: list[tuple]) -> Callable[[WME], bool] | None:
    """One generated function for a condition's constant tests (as for the join tests)."""
    if not specs:
        return None
    lines = ["def accept(w):"]
    namespace: dict[str, object] = {"NUMBERS": NUMBERS}
    for n, spec in enumerate(specs):
        kind = spec[0]
        if kind == "state":
            lines.append("    if w.id.level is None: return False")
            continue
        if kind == "never":
            lines.append("    return False")
            continue
        lines.append(f"    x = w.{spec[1]}")
        if kind == "type":
            lines.append(f"    if x.__class__ is not {spec[2]}: return False")
        elif kind == "eq":
            namespace[f"c{n}"] = spec[2][1]
            lines.append(f"    if not (x.__class__ is c{n}.__class__ and x == c{n}): return False")
        elif kind == "rel":
            namespace[f"c{n}"] = spec[3][1]
            namespace[f"r{n}"] = RELATIONS[spec[2]]
            lines.append(f"    if not r{n}(x, c{n}): return False")
        else:  # disjunction of typed constants
            namespace[f"d{n}"] = frozenset(spec[2])
            lines.append(f"    if (x.__class__.__name__, x) not in d{n}: return False")
    lines.append("    return True")
    return define(lines, namespace, "accept")


NUMBERS = frozenset((int, float))
_ORDER_OPS = {"<": "<", ">": ">", "<=": "<=", ">=": ">="}
CHECK_NAMES: dict[str, object] = {"NUMBERS": NUMBERS, "RELATIONS": RELATIONS}


def check_lines(specs: Sequence[BetaSpec], vals: str, w: str, fail: str, pad: str,
                 value: Callable[[int], str] | None = None) -> list[str]:
    """Generated code testing every beta test of a join on the values ``vals`` and the WME
    ``w``, running ``fail`` (``return False``, ``continue``) at the first that does not
    hold.  The join and query loops inline these lines: in the innermost loop a call per
    pair costs more than the tests themselves.  ``value(pos)`` may name a value position
    otherwise than ``vals[pos]``."""
    if value is None:
        value = f"{vals}[{{}}]".format  # not a nested def: mypyc fails on one rebinding a parameter
    lines = []
    for n, ((lk, la), op, (rk, ra)) in enumerate(specs):
        left = f"{w}.{la}" if lk == "w" else value(la)  # type: ignore[arg-type]
        right = f"{w}.{ra}" if rk == "w" else value(ra)  # type: ignore[arg-type]
        x, y = f"cx{n}", f"cy{n}"
        lines.append(f"{x} = {left}; {y} = {right}")
        if op == "=":
            lines.append(f"if {x} is not {y} and not ({x}.__class__ is {y}.__class__ "
                         f"and {x} == {y}): {fail}")
        elif op == "<>":
            lines.append(f"if {x} is {y} or ({x}.__class__ is {y}.__class__ "
                         f"and {x} == {y}): {fail}")
        elif op == "<=>":
            lines.append(f"if {x}.__class__ is not {y}.__class__: {fail}")
        elif op == "@":
            lines.append(fail)
        elif op in _ORDER_OPS:
            lines.append(f"if {x}.__class__ in NUMBERS and {y}.__class__ in NUMBERS:")
            lines.append(f"    if not ({x} {op} {y}): {fail}")
            lines.append(f"elif not RELATIONS[{op!r}]({x}, {y}): {fail}")
        elif op != "!@":
            raise AssertionError(f"unknown relation {op!r}")
    return [pad + line for line in lines]


def compile_check(specs: list[BetaSpec]) -> Callable[[tuple, WME], bool] | None:
    """One Python function testing every beta test of a join, for the nodes that call it
    per WME; its ``specs`` attribute lets generated loops inline the same tests."""
    if not specs:
        return None
    lines = ["def check(vals, w):", *check_lines(specs, "vals", "w", "return False", "    "),
             "    return True"]
    check = define(lines, dict(CHECK_NAMES), "check")
    check.specs = tuple(specs)  # type: ignore[attr-defined]
    return check


def EXTEND_VALUE(vals: tuple, w: WME) -> tuple:  # noqa: N802 -- a marker as much as a function
    return vals + (w.value,)


def extender(fields: tuple[str, ...]) -> Callable | None:
    """How a join extends a token's values with what the WME binds."""
    if not fields:
        return None
    if fields == ("value",):
        return EXTEND_VALUE
    code = "lambda vals, w: vals + (" + "".join(f"w.{f}, " for f in fields) + ")"
    return eval(code)  # noqa: S307 -- field names from FIELDS only
