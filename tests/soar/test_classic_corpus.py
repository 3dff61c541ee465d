"""The corpus of classic Soar programs (``rules/classic/``) runs alike in the kernel and here.

Every program runs in the real Soar kernel (``soar_sml``) and in our engine, each time in a
fresh agent, with ``chunk never`` given after sourcing (count-test turns chunking on in its
file, as Soar's does; neither engine may learn):

* with ``indifferent-selection --first`` the run is deterministic, and decisions, production
  firings, the operator-name sequence (from the kernel's watch-1 trace), halting and the
  written output must all be equal;
* with the default (softmax) selection after ``srand N`` for N in 1..5, choices among
  indifferent operators are random but seeded, and halting and written output must be equal.

The shipped ``rules/water-jug.soar`` and ``rules/hanoi.soar`` (6 disks, as in
test_differential) run the same checks. Each run is made once per process and shared by the
tests that look at it. Every ``rules/classic`` file starts with a header: ``# <Title>`` on
its first line, then one or more ``# Teaches: ...`` lines.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from differential.kernel import Inputs, RunResult, read_spec, run_kernel, run_ours

ROOT = Path(__file__).resolve().parents[2]
CLASSIC = sorted((ROOT / "rules" / "classic").glob("*.soar"))
PROGRAMS = CLASSIC + [ROOT / "rules" / "water-jug.soar", ROOT / "rules" / "hanoi.soar"]
INPUTS: dict[str, Inputs] = {"hanoi.soar": (("disks", 6),)}
SEEDS = (1, 2, 3, 4, 5)
FIRST = "first"
AFTER_SOURCE = ("chunk never",)
# Our run may take this many decisions more than the kernel's before it counts as a runaway.
MARGIN = 50

_RUNS: dict[tuple[Path, str, str], RunResult | Exception] = {}


def setting_commands(setting: str) -> tuple[str, ...]:
    """The commands given before sourcing for a setting: ``first`` or ``seed<N>``."""
    if setting == FIRST:
        return ("indifferent-selection --first",)
    return (f"srand {int(setting.removeprefix('seed'))}",)


def settings() -> list[str]:
    return [FIRST] + [f"seed{n}" for n in SEEDS]


def kernel_run(path: Path, setting: str) -> RunResult:
    """The kernel's run of a program in a setting, made once per process."""
    key = (path, "kernel", setting)
    if key not in _RUNS:
        _RUNS[key] = run_kernel(
            path, inputs=INPUTS.get(path.name), before=setting_commands(setting),
            commands=AFTER_SOURCE,
        )
    result = _RUNS[key]
    assert isinstance(result, RunResult)
    return result


def our_run(path: Path, setting: str) -> RunResult:
    """Our engine's run, capped a little beyond the kernel's decisions; an error it raised
    is kept and raised again for every test that asks."""
    key = (path, "ours", setting)
    if key not in _RUNS:
        limit = kernel_run(path, setting).decisions + MARGIN
        try:
            _RUNS[key] = run_ours(
                path, decisions=limit, inputs=INPUTS.get(path.name),
                before=setting_commands(setting), commands=AFTER_SOURCE,
            )
        except Exception as exc:  # noqa: BLE001 - reported by each test that asks
            _RUNS[key] = exc
    result = _RUNS[key]
    if isinstance(result, Exception):
        raise result
    return result


def _id(path: Path) -> str:
    return path.stem if path.parent.name == "classic" else f"rules-{path.stem}"


def first_difference(ours: str, theirs: str) -> str:
    """Where two texts part, with some context, for a readable failure."""
    pairs = zip(ours, theirs, strict=False)
    at = next((i for i, (a, b) in enumerate(pairs) if a != b), min(len(ours), len(theirs)))
    start, end = max(0, at - 120), at + 120
    return f"at character {at}:\n  kernel: {theirs[start:end]!r}\n  ours:   {ours[start:end]!r}"


# --------------------------------------------------------------------------- the corpus


def test_corpus_has_at_least_fifteen_programs() -> None:
    assert len(CLASSIC) >= 15, [p.name for p in CLASSIC]


_TITLE = re.compile(r"^# \S.*$")
_TEACHES = re.compile(r"^# Teaches: \S.*$")


@pytest.mark.parametrize("path", CLASSIC, ids=_id)
def test_program_has_a_header(path: Path) -> None:
    lines = path.read_text().splitlines()
    assert len(lines) >= 2 and _TITLE.match(lines[0]), f"{path.name}: first line is not '# Title'"
    assert not lines[0].startswith("# Teaches:"), f"{path.name}: the title is missing"
    assert _TEACHES.match(lines[1]), f"{path.name}: second line is not '# Teaches: ...'"


@pytest.mark.parametrize("setting", settings())
@pytest.mark.parametrize("path", PROGRAMS, ids=_id)
def test_kernel_runs_program_to_halt(path: Path, setting: str) -> None:
    result = kernel_run(path, setting)
    assert result.halted, f"{path.name} ({setting}) did not halt:\n{result.trace[-2000:]}"
    assert result.decisions < read_spec(path).decisions
    for alarm in ("Error", "Goal stack depth exceeded", "Warning"):
        assert alarm not in result.trace, f"{path.name} ({setting}): {alarm}\n{result.trace}"


@pytest.mark.parametrize("path", PROGRAMS, ids=_id)
def test_first_selection_agrees(path: Path) -> None:
    theirs, ours = kernel_run(path, FIRST), our_run(path, FIRST)
    assert ours.output == theirs.output, first_difference(ours.output, theirs.output)
    assert ours.operators == theirs.operators
    assert ours.halted == theirs.halted
    assert (ours.decisions, ours.production_firings) == (
        theirs.decisions, theirs.production_firings)


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("path", PROGRAMS, ids=_id)
def test_random_selection_agrees(path: Path, seed: int) -> None:
    theirs, ours = kernel_run(path, f"seed{seed}"), our_run(path, f"seed{seed}")
    assert ours.output == theirs.output, first_difference(ours.output, theirs.output)
    assert ours.halted == theirs.halted


# --------------------------------------------------------------------------- the harness


def test_settings_give_the_kernel_commands() -> None:
    assert setting_commands(FIRST) == ("indifferent-selection --first",)
    assert [setting_commands(s) for s in settings()[1:]] == [
        (f"srand {n}",) for n in SEEDS]


def test_first_difference_points_at_the_parting() -> None:
    assert "at character 3:" in first_difference("abcX", "abcY")
    assert "at character 2:" in first_difference("ab", "abc")


THREE_WAY = """
sp {pick*propose*a (state <s> ^superstate nil) --> (<s> ^operator <o> + =) (<o> ^name a)}
sp {pick*propose*b (state <s> ^superstate nil) --> (<s> ^operator <o> + =) (<o> ^name b)}
sp {pick*propose*c (state <s> ^superstate nil) --> (<s> ^operator <o> + =) (<o> ^name c)}
sp {pick*apply (state <s> ^operator <o>) (<o> ^name <n>) --> (<s> ^done <o>) (write <n>)}
sp {pick*reject-done (state <s> ^operator <o> + ^done <o>) --> (<s> ^operator <o> -)}
sp {pick*forget (state <s> ^operator <o> ^done { <d> <> <o> }) --> (<s> ^done <d> -)}
"""


@pytest.mark.parametrize("policy", ["softmax", "epsilon-greedy", "boltzmann"])
def test_random_choices_are_the_kernels(tmp_path: Path, policy: str) -> None:
    """The random half of the corpus rests on this: after ``srand N``, each policy picks
    among indifferent operators exactly what the kernel picks (same draws, same use)."""
    agent = tmp_path / "three-way.soar"
    agent.write_text(THREE_WAY)
    for seed in (1, 2):
        before = (f"indifferent-selection --{policy}", f"srand {seed}")
        theirs = run_kernel(agent, decisions=30, before=before)
        ours = run_ours(agent, decisions=30, before=before)
        assert len(theirs.output) == 29  # the 30th decision stops before its application
        assert ours.output == theirs.output
