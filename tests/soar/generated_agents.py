"""Random Soar agents for differential tests, each a pure function of its seed: what the
decision-count, firing-order and trace tests run in the kernel and in our engine."""

from __future__ import annotations

import random


def generated_agent(seed: int) -> str:
    """A small random agent: proposals with random preferences, applications that count,
    preference rules between proposals, and substate rules for every impasse kind."""
    r = random.Random(seed)
    ops = ["a", "b", "c", "d"][: r.randint(2, 4)]
    lines = [f"indifferent-selection --{r.choice(['first', 'last'])}"]
    lines.append(
        "sp {init (state <s> ^superstate nil -^count) --> (<s> ^operator <o> + >) (<o> ^name init)}"
    )
    lines.append("sp {init*a (state <s> ^operator.name init) --> (<s> ^count 0)}")
    for op in ops:
        prefs = r.choice(["+", "+ =", "+ >", "+ <", "+ = 0.5", "+ !", "+ ~", "+ -", "+ = >"])
        cond = r.choice(["", "^flag yes", "-^flag"])
        lines.append(
            f"sp {{p{op} (state <s> ^superstate nil ^count <c> < 5 {cond})"
            f" --> (<s> ^operator <o> {prefs}) (<o> ^name {op})}}"
        )
        effect = r.choice(["(<s> ^flag yes)", "(<s> ^flag yes -)", f"(<s> ^note {op})", ""])
        lines.append(
            f"sp {{ap{op} (state <s> ^operator.name {op} ^count <c>)"
            f" --> (<s> ^count <c> - (+ <c> 1)) {effect} (write {op} (crlf))}}"
        )
    for _ in range(r.randint(0, 3)):
        x, y = r.sample(ops, 2)
        kind = r.choice([">", "<", "="])
        name = {">": "better", "<": "worse", "=": "same"}[kind]
        lines.append(
            f"sp {{pref*{x}*{y}*{name} (state <s> ^operator <x> + ^operator <y> +)"
            f" (<x> ^name {x}) (<y> ^name {y}) --> (<s> ^operator <x> {kind} <y>)}}"
        )
    first, last = ops[0], ops[-1]
    lines += [
        "sp {tie (state <s> ^impasse << tie conflict >> ^superstate <ss> ^item <i>)"
        f" (<i> ^name {first}) --> (<ss> ^operator <i> >)}}",
        "sp {tie2 (state <s> ^impasse << tie conflict >> ^superstate <ss> ^item <i>)"
        f" (<i> ^name {last}) --> (<ss> ^operator <i> !)}}",
        "sp {elab (state <s> ^superstate nil ^count <c>) --> (<s> ^double (* <c> 2))}",
        "sp {snc (state <s> ^impasse no-change ^attribute state ^superstate <ss>)"
        " (<ss> ^count <c>) --> (<ss> ^count <c> - (+ <c> 1))}",
        "sp {onc (state <s> ^impasse no-change ^attribute operator ^superstate <ss>)"
        " (<ss> ^operator <o>) --> (<s> ^operator <q> +) (<q> ^name fix)}",
        "sp {oncfix (state <s> ^operator.name fix ^superstate <ss>) (<ss> ^count <c>)"
        " --> (<ss> ^count <c> - (+ <c> 10))}",
        "sp {done (state <s> ^superstate nil ^count > 4) --> (write |done| (crlf)) (halt)}",
    ]
    return "\n".join(lines) + "\n"


def generated_substate_agent(seed: int) -> str:
    """A random agent whose top operator is worked out in substates: local o-supported
    structure (goal dependency sets), results of either support, a third level."""
    r = random.Random(seed)
    lines = [f"indifferent-selection --{r.choice(['first', 'last'])}"]
    lines += [
        "sp {init (state <s> ^superstate nil -^count) --> (<s> ^operator <o> + >)"
        " (<o> ^name init)}",
        "sp {init*a (state <s> ^operator.name init) --> (<s> ^count 0 ^weather rain)}",
        f"sp {{top*work (state <s> ^superstate nil ^count <c> < {r.randint(2, 5)})"
        " --> (<s> ^operator <o> +) (<o> ^name work ^at <c>)}",
        "sp {top*weather (state <s> ^superstate nil ^count <c> ^weather <w>)"
        " --> (<s> ^wx (concat <w> <c>))}",
    ]
    if r.random() < 0.5:
        pref = r.choice(["", "=", "<", ">"])
        lines.append(
            "sp {top*work2 (state <s> ^superstate nil ^count <c> < 3)"
            f" --> (<s> ^operator <o> + {pref}) (<o> ^name work2)}}"
        )
    test = r.choice(["^superstate.operator.name work", "^superstate.operator <o>"])
    lines.append(f"sp {{s*elab (state <s> {test}) --> (<s> ^local yes)}}")
    lines.append(
        "sp {s*p (state <s> ^local yes -^done) --> (<s> ^operator <o> +) (<o> ^name step)}"
    )
    kind = r.choice(["o-result", "i-result", "gds"])
    if kind == "o-result":
        lines.append(
            "sp {s*a (state <s> ^operator.name step ^superstate <ss>) (<ss> ^count <c>)"
            " --> (<ss> ^count <c> - (+ <c> 1)) (<s> ^done yes)}"
        )
    elif kind == "i-result":
        lines += [
            "sp {s*a (state <s> ^operator.name step) --> (<s> ^done yes)}",
            "sp {s*res (state <s> ^done yes ^superstate <ss>) (<ss> ^count <c>)"
            " --> (<ss> ^flag (+ <c> 100))}",
            "sp {top*use (state <s> ^superstate nil ^flag <f> ^count <c>)"
            " --> (<s> ^operator <o> + >) (<o> ^name bump)}",
            "sp {top*bump (state <s> ^operator.name bump ^count <c>)"
            " --> (<s> ^count <c> - (+ <c> 1))}",
        ]
    else:
        lines += [
            "sp {s*a (state <s> ^operator.name step ^superstate.wx <w>)"
            " --> (<s> ^done yes ^saw <w>)}",
            "sp {s*p2 (state <s> ^done yes -^finished) --> (<s> ^operator <o> +)"
            " (<o> ^name finish)}",
            "sp {s*a2 (state <s> ^operator.name finish ^superstate <ss>) (<ss> ^count <c>)"
            " --> (<ss> ^count <c> - (+ <c> 1)) (<s> ^finished yes)}",
        ]
    if r.random() < 0.5:
        lines += [
            "sp {s*deep (state <s> ^superstate.superstate.operator.name work)"
            " --> (<s> ^operator <o> +) (<o> ^name deep)}",
            "sp {s*deep*a (state <s> ^operator.name deep ^superstate.superstate <top>)"
            " (<top> ^count <c>) --> (<top> ^count <c> - (+ <c> 1))}",
        ]
    lines += [
        "sp {tie (state <s> ^impasse tie ^superstate <ss> ^item <i>) (<i> ^name work)"
        " --> (<ss> ^operator <i> >)}",
        "sp {done (state <s> ^superstate nil ^count <c> >= 3)"
        " --> (write |done | <c> (crlf)) (halt)}",
    ]
    return "\n".join(lines) + "\n"
