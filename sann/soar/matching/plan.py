"""What one condition compiles to at its place in the join order (``Plan``): its alpha
memory's key and constant tests, the equality test its join is hashed on, the other tests
against earlier bindings (beta tests), and the fields whose values it binds."""

from __future__ import annotations

from sann.soar.matching.tokens import ANY, FIELDS, typed
from sann.soar.matching.variables import atoms, condition_fields, equality_vars
from sann.soar.production import (
    Condition,
    Const,
    Disjunction,
    Var,
)

#: A value the beta tests read: ("v", position in the token's values) or ("w", field of the
#: WME being joined).
Ref = tuple[str, object]
#: One beta test: (left value, operator, right value).
BetaSpec = tuple[Ref, str, Ref]
#: Which field a join is hashed on, when several equality tests could serve.
_INDEX_PREFERENCE = {"id": 0, "value": 1, "attr": 2}


class Plan:
    """What one condition compiles to at its place in the join order."""

    __slots__ = ("alpha_key", "lookup", "alpha_tests", "index", "beta", "new_fields")

    def __init__(self) -> None:
        self.alpha_key: tuple = ()
        self.lookup: tuple = ()
        self.alpha_tests: list[tuple] = []
        self.index: tuple[int, str] | None = None
        self.beta: list[BetaSpec] = []
        self.new_fields: list[str] = []


def plan_condition(cond: Condition, var_pos: dict[str, int], nvals: int,
                    deferred: list[tuple[int, str, str]], states: set[str]) -> Plan:
    """Compile ``cond`` given the variables bound so far (``var_pos``, updated in place for a
    positive condition).  Relational tests on variables bound only later are appended to
    ``deferred`` and placed at the join that binds them."""
    plan = Plan()
    attr_key: object = ANY
    value_key: object = ANY
    alpha: list[tuple] = []
    local: dict[str, Ref] = {}  # variables first bound by this condition -> their field
    field_ref: dict[str, Ref] = {}
    relational: list[tuple[str, str, str]] = []
    if cond.goal is not None and not any(
            name in var_pos and name in states for name in equality_vars(cond.id_test)):
        alpha.append(("state",))  # (a variable already tested as a state needs no retest)
    for field, test in zip(FIELDS, condition_fields(cond), strict=True):
        ref: Ref | None = None
        new_names: list[str] = []
        for atom in atoms(test):
            if isinstance(atom, Var):
                known = ("v", var_pos[atom.name]) if atom.name in var_pos else local.get(atom.name)
                if known is None:
                    new_names.append(atom.name)
                elif ref is None:
                    ref = known
                    if known != ("w", field):
                        plan.beta.append((("w", field), "=", known))
                elif known != ref:
                    plan.beta.append((("w", field), "=", known))
            elif isinstance(atom, Const):
                value = atom.value
                if field == "attr" and attr_key is ANY:
                    attr_key = value
                elif field == "value" and value_key is ANY:
                    value_key = value
                else:
                    alpha.append(("eq", field, typed(value)))
                    continue
                if value.__class__ in (int, float):
                    alpha.append(("type", field, value.__class__.__name__))
            elif isinstance(atom, Disjunction):
                alpha.append(("disj", field, tuple(sorted({typed(c.value) for c in atom.values},
                                                         key=repr))))
            elif isinstance(atom.operand, Const):
                if atom.op == "@":
                    alpha.append(("never",))
                elif atom.op != "!@":
                    alpha.append(("rel", field, atom.op, typed(atom.operand.value)))
            elif atom.op == "@":
                alpha.append(("never",))
            elif atom.op != "!@":
                relational.append((field, atom.op, atom.operand.name))
        if new_names:
            if ref is None:
                ref = ("w", field)
                if not cond.negated:
                    plan.new_fields.append(field)
            for name in new_names:
                local[name] = ref
        if ref is not None:
            field_ref[field] = ref
    for field, op, name in relational:
        if name in var_pos:
            plan.beta.append((("w", field), op, ("v", var_pos[name])))
        elif name in local:
            plan.beta.append((("w", field), op, local[name]))
        else:  # bound by a later condition: keep this field's value in the token
            ref = field_ref.get(field)
            if ref is None:
                plan.new_fields.append(field)
                ref = field_ref[field] = ("w", field)
            lhs = nvals + plan.new_fields.index(ref[1]) if ref[0] == "w" else ref[1]
            deferred.append((lhs, op, name))  # type: ignore[arg-type]
    if not cond.negated:
        for name, ref in local.items():
            var_pos[name] = ref[1] if ref[0] == "v" else nvals + plan.new_fields.index(ref[1])
        for item in list(deferred):
            lhs, op, name = item
            if name in local and lhs < nvals:
                plan.beta.append((("v", lhs), op, local[name]))
                deferred.remove(item)
    _choose_index(plan)
    tests = tuple(sorted(set(alpha), key=repr))
    acc = bool(cond.acceptable)
    plan.alpha_tests = list(tests)
    plan.lookup = (attr_key, value_key, acc)
    plan.alpha_key = (typed(attr_key) if attr_key is not ANY else None,
                      typed(value_key) if value_key is not ANY else None, acc, tests)
    return plan


def _choose_index(plan: Plan) -> None:
    """Hash the join on one equality test between the WME and an earlier binding."""
    candidates = [spec for spec in plan.beta
                  if spec[1] == "=" and spec[0][0] == "w" and spec[2][0] == "v"]
    if not candidates:
        return
    # The most recently bound variable is usually the most selective key: joining
    # (<il> ^block <o>) with both bound should look up <o>, not every block of <il>.
    best = max(candidates, key=lambda spec: (spec[2][1], -_INDEX_PREFERENCE[spec[0][1]]))
    plan.beta.remove(best)
    plan.index = (best[2][1], best[0][1])  # type: ignore[assignment]
