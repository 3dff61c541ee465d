"""No blow-ups: a steady agent's decisions must cost what its working-memory changes cost,
not more and more as the run goes on.

The Towers of Hanoi of ``rules/classic`` (the Soar 9.0 demos' representation: ``^holds``
objects with ``^disk ^above ^on``, elaborated ``^larger``, ``^upper-disk`` and ``^clear``)
run in the real kernel and in ours to the same end. What kept the engine's decisions from
being steady was the model of the kernel's right unlinking (``Agent._join_link``): each
join on record keeps the tokens of its parent memory seen so far, and looks one up in
working memory when the one on record goes. The look-up listed every partial match of the
memory's conditions, each condition over all the WMEs of its attribute (a prefix of a few
multi-valued attributes of the state has thousands), and the seen tokens were never
dropped. The tests below pin the behaviour that fixes it: the look-up stops at the first
token it finds, and the records stay small however long the run."""

from __future__ import annotations

import io
import re
from pathlib import Path

import pytest
from differential.kernel import run_kernel, run_ours

from sann.soar import Agent
from sann.soar.matching.kernel_prefix import prefix_token

pytest.importorskip("soar_sml")

CLASSIC = Path(__file__).resolve().parents[2] / "rules" / "classic"
COLLAPSED = CLASSIC / "hanoi-collapsed.soar"
FAST = CLASSIC / "hanoi-fast.soar"


def hanoi_with(disks: int, path: Path) -> str:
    """The rules of ``path`` with ``disks`` disks instead of eleven: the initialisation is
    written anew (the tower on peg a, the smallest disk's cycle a -> c -> b for an odd
    number of disks, a -> b -> c for an even one)."""
    order = ["a", "c", "b"] if disks % 2 else ["a", "b", "c"]
    following = {peg: order[(k + 1) % 3] for k, peg in enumerate(order)}
    lines = ["sp {towers-of-hanoi*apply*initialize",
             "   (state <s> ^operator.name initialize)", "-->",
             "   (<s> ^name towers-of-hanoi", "        ^last-moved none",
             "        ^peg <a> <b> <c>",
             "        ^disk " + " ".join(f"<d{i}>" for i in range(1, disks + 1)),
             "        ^holds " + " ".join(f"<h{i}>" for i in range(1, disks + 1)) + ")"]
    lines += [f"   (<{peg}> ^name {peg} ^next <{following[peg]}>)" for peg in order]
    lines += [f"   (<d{i}> ^size {i})" for i in range(1, disks + 1)]
    lines += [f"   (<h{i}> ^disk <d{i}> ^above {f'<d{i + 1}>' if i < disks else 'none'} ^on <a>)"
              for i in range(1, disks + 1)]
    text, count = re.subn(r"sp \{towers-of-hanoi\*apply\*initialize\n.*?\)\}",
                          lambda _: "\n".join(lines) + "}", path.read_text(), count=1,
                          flags=re.S)
    assert count == 1, f"{path} has no towers-of-hanoi*apply*initialize rule"
    return text


@pytest.mark.parametrize("path", [COLLAPSED, FAST], ids=["collapsed", "fast"])
def test_hanoi_agrees_with_the_kernel(path: Path) -> None:
    """Eleven disks: 2,047 moves after one decision of initialisation, the same firings,
    elaboration cycles, WM changes and final working memory as the kernel's."""
    theirs, ours = run_kernel(path), run_ours(path)
    assert theirs.halted and ours.halted
    assert theirs.decisions == 2048
    assert theirs.operators == ["initialize"] + ["move-disk"] * 2047
    assert ours.operators == theirs.operators
    for field in ("decisions", "production_firings", "elaboration_cycles", "wme_changes",
                  "wm_size", "output", "wm"):
        assert getattr(ours, field) == getattr(theirs, field), field


@pytest.mark.parametrize("disks", [3, 4, 6])
def test_fewer_disks_agree_with_the_kernel(disks: int, tmp_path: Path) -> None:
    """The growth curve's small end: 2^n decisions for n disks, as in the kernel."""
    path = tmp_path / f"hanoi-{disks}.soar"
    path.write_text(hanoi_with(disks, COLLAPSED))
    theirs, ours = run_kernel(path), run_ours(path)
    assert theirs.halted and ours.halted
    assert theirs.decisions == ours.decisions == 2 ** disks
    assert ours.production_firings == theirs.production_firings
    assert ours.wm == theirs.wm


def test_link_records_stay_small_through_a_long_run() -> None:
    """The right-unlinking records of the collapsed hanoi, decision after decision: as
    many joins on record and as many tokens seen at the end of the 2,048 decisions as in
    the first hundred (the tokens seen grew by one every three decisions, to 653)."""
    agent = Agent(out=io.StringIO())
    agent.source(str(COLLAPSED))
    agent.trace(0)
    records: list[int] = []
    seen: list[int] = []
    while not agent.halted and len(records) < 2100:
        agent.run(decisions=1)
        records.append(len(agent._join_links))
        seen.append(sum(len(record.seen) for record in agent._join_links.values()))
    assert agent.halted and agent.stats["decisions"] == 2048
    early, late = slice(0, 100), slice(1948, 2048)
    assert max(records[late]) <= max(records[early])
    assert max(seen[late]) <= max(seen[early])
    assert max(seen) <= 16 * max(records)  # a record drops its dead tokens as they double


WIDE = """
sp {propose (state <s> ^superstate nil -^name) --> (<s> ^operator <o> +) (<o> ^name fill)}
sp {apply (state <s> ^operator.name fill)
-->
   (<s> ^name wide ^item 1 2 3 4 5 6 7 8 9 10 ^go <g>)
   (<g> ^size 2)}
sp {wide (state <s> ^name wide ^item <a> ^item <b> ^item <c> ^go <g>)
         (<g> ^size <> 1)
-->
   (<s> ^seen <g>)}
sp {missing (state <s> ^name wide ^item <a> ^item 11 ^go <g>)
-->
   (<s> ^never <g>)}
sp {blocked (state <s> ^name wide -^name wide ^item <a> ^item <b> ^go <g>)
-->
   (<s> ^never <g>)}
"""


def _wide_agent() -> Agent:
    agent = Agent(out=io.StringIO())
    agent.load(WIDE)
    agent.trace(0)
    agent.run(decisions=2)
    return agent


def _last_join(ordered: list) -> int:
    """The kernel position of the last condition, a positive ``^item`` one in these rules."""
    last = ordered[-1]
    assert not last.negated and not last.is_ncc and last.element.attr_test.value == "item"
    return len(ordered) - 1


def test_a_memory_is_searched_for_one_token_not_listed() -> None:
    """The memory above the last ``^item`` join of ``wide`` holds 100 tokens (the two
    other ``^item`` conditions over ten values): finding that it is not empty looks at one
    WME per condition above it, not at every partial match (the breadth-first join made
    all 100 and tried each on every ``^item`` WME)."""
    agent = _wide_agent()
    ordered = agent._kernel_order.ordered("wide")
    looked: list[int] = []

    def candidates(cond, bindings):
        found = list(agent._candidates(cond, bindings))
        looked.append(len(found))
        return found

    position = _last_join(ordered)
    token = prefix_token(ordered, position, candidates, (0, 1, 2, 3, 4, 5))
    assert token is not None and token[1] is None  # ^item <a> is below the memory
    assert all(wme is not None for k, wme in enumerate(token) if k != 1)
    assert len(looked) == position  # one candidate list per condition above the join
    assert sum(looked) <= 1 + 1 + 1 + 10 + 10


@pytest.mark.parametrize("name", ["missing", "blocked"])
def test_an_empty_memory_is_found_empty(name: str) -> None:
    """No token above the last join: a condition above it matches nothing (``^item 11``),
    or a negation above it (not right above: that node keeps its blocked tokens) blocks
    every partial match; ``wide``'s memory there is not empty."""
    agent = _wide_agent()
    ordered = agent._kernel_order.ordered(name)
    assert prefix_token(ordered, _last_join(ordered), agent._candidates, (0,)) is None
    wide = agent._kernel_order.ordered("wide")
    assert prefix_token(wide, _last_join(wide), agent._candidates, (0,)) is not None
