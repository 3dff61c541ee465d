"""Corpus benchmark: every classic Soar program, our engine against the real kernel.

Usage::

    .venv/bin/python benchmarks/corpus.py [--repeat 3] [--only NAME ...]

For every program of ``rules/classic/`` and the shipped ``rules/water-jug.soar`` and
``rules/hanoi.soar`` (its own 11 disks), in one process, with
``indifferent-selection --first`` given before sourcing and ``chunk never`` after (the
settings of tests/soar/test_classic_corpus.py, so the runs are deterministic and both
engines make the same decisions):

* the run to halt (sourcing excluded, no trace) is timed in both engines, best of
  ``--repeat`` runs each, the engines taking turns, in a fresh agent each time; the table
  gives ours/kernel;
* ``--repeat`` more runs of ours go decision by decision (``Agent.run(1)``, whose own cost
  is a few microseconds against the milliseconds of a decision); each decision's time is
  the fastest of these runs (so that a moment of another process does not pass for a slow
  decision), and the slowest decision is set against the median decision: a decision far
  above the median is where some working-memory change costs out of proportion (the
  kernel's side is its total time only). The time the cyclic garbage collector took in the
  slowest decision is shown beside it (``gc ms``), and the slowest decision without its
  collections against the median (``no gc``): a full collection is CPython's, not the
  engine's algorithm, and the kernel has none.

A row is flagged ``SLOW`` when ours takes over 10x the kernel's time, ``SPIKE`` when one of
our decisions takes over 20x the run's median decision. A program that ours cannot run (it
refuses the file, or raises) is reported as such, with the error, and the others go on.
The figures are ratios measured in the same run; absolute times are printed too.
"""

from __future__ import annotations

import argparse
import gc
import io
import statistics
import sys
import time
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# This checkout's engine, not whichever sann the interpreter would find first (run as a
# script, sys.path starts with benchmarks/, and the venv's editable install may be another
# worktree's).
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "soar" / "differential"))
import kernel as oracle  # noqa: E402  (the differential harness owns the kernel's lifecycle)

BEFORE = ("indifferent-selection --first",)
AFTER = ("chunk never",)
SLOW_RATIO = 10.0
SPIKE_RATIO = 20.0


def programs() -> list[Path]:
    """The corpus: every rules/classic program, then the two shipped classics."""
    classic = sorted((ROOT / "rules" / "classic").glob("*.soar"))
    return classic + [ROOT / "rules" / "water-jug.soar", ROOT / "rules" / "hanoi.soar"]


@dataclass
class Row:
    """One program's measurements."""

    name: str
    decisions: int = 0
    kernel_s: float = 0.0
    ours_s: float = 0.0
    median_decision_s: float = 0.0
    slowest_decision_s: float = 0.0
    slowest_at: int = 0
    slowest_gc_s: float = 0.0
    slowest_no_gc_s: float = 0.0
    error: str = ""

    @property
    def ratio(self) -> float:
        return self.ours_s / self.kernel_s if self.kernel_s else float("nan")

    @property
    def spike(self) -> float:
        return self.slowest_decision_s / self.median_decision_s if self.median_decision_s else 0.0

    @property
    def spike_no_gc(self) -> float:
        """The slowest decision without its garbage collection, against the median."""
        return self.slowest_no_gc_s / self.median_decision_s if self.median_decision_s else 0.0

    def flags(self) -> str:
        marks = []
        if self.ratio > SLOW_RATIO:
            marks.append("SLOW")
        if self.spike > SPIKE_RATIO:
            marks.append("SPIKE")
        return " ".join(marks)


# --------------------------------------------------------------------------- one run each


def kernel_run(path: Path, limit: int) -> tuple[float, int]:
    """Seconds of the kernel's run to halt (sourcing excluded) and its decisions."""
    spec = oracle.read_spec(path)
    with oracle.KernelAgent() as ka:
        for line in BEFORE:
            ka.cmd(line)
        ka.cmd(f"source {{{path}}}")
        for line in AFTER:
            ka.cmd(line)
        ka.cmd("watch 0")
        ka.add_inputs(spec.inputs)
        t0 = time.perf_counter()
        ka.cmd(f"run {limit}")
        seconds = time.perf_counter() - t0
        return seconds, ka.agent.GetDecisionCycleCounter()


def our_agent(path: Path):  # noqa: ANN201 - sann.soar.agent.Agent, imported late
    """A fresh agent of ours with the program sourced, set up as in the kernel."""
    from sann.soar.agent import Agent

    agent = Agent(out=io.StringIO())
    for line in BEFORE:
        agent.load(line, "<benchmark>")
    agent.source(str(path))
    for line in AFTER:
        agent.load(line, "<benchmark>")
    agent.trace(0)
    oracle._add_our_inputs(agent, oracle.read_spec(path).inputs)
    return agent


def our_run(path: Path, limit: int) -> tuple[float, int]:
    """Seconds of our run to halt (sourcing excluded) and its decisions."""
    agent = our_agent(path)
    t0 = time.perf_counter()
    agent.run(decisions=limit)
    seconds = time.perf_counter() - t0
    return seconds, int(agent.stats["decisions"])


class GcClock:
    """Seconds the cyclic garbage collector ran, read through ``gc.callbacks``: a collection
    of the oldest generation traverses every tracked object, so it lands on whichever
    decision allocates at that moment (the same one each run, allocation being
    deterministic) and would pass for a decision that costs out of proportion."""

    def __init__(self) -> None:
        self.seconds = 0.0
        self._start = 0.0

    def __enter__(self) -> GcClock:
        gc.callbacks.append(self._tick)
        return self

    def __exit__(self, *exc: object) -> None:
        gc.callbacks.remove(self._tick)

    def _tick(self, phase: str, info: dict) -> None:
        if phase == "start":
            self._start = time.perf_counter()
        else:
            self.seconds += time.perf_counter() - self._start


def our_decision_times(path: Path, limit: int) -> list[tuple[float, float]]:
    """Seconds of each of our decisions, one ``run(1)`` at a time, until halt, with the
    seconds of garbage collection in it. The last call, which halts in the next cycle's
    phases before its decision, is timed with the decision before it."""
    agent = our_agent(path)
    times: list[tuple[float, float]] = []
    with GcClock() as clock:
        while not agent.halted and len(times) < limit:
            before = agent.stats["decisions"]
            collected = clock.seconds
            t0 = time.perf_counter()
            agent.run(1)
            seconds = time.perf_counter() - t0
            spent = (seconds, clock.seconds - collected)
            if agent.stats["decisions"] > before or not times:
                times.append(spent)
            else:
                times[-1] = (times[-1][0] + spent[0], times[-1][1] + spent[1])
    return times


def steadiest(runs: Iterable[list[tuple[float, float]]]) -> list[tuple[float, float]]:
    """Decision by decision, the fastest of several runs' (time, GC time): another process
    taking the machine for a moment makes one run's decision slow, a decision that costs is
    slow in all (the runs are deterministic, so decision i is the same decision in each)."""
    return [min(times) for times in zip(*runs, strict=False)]


def measure(path: Path, repeat: int) -> Row:
    """Best of ``repeat`` turns per engine, then ``repeat`` decision-by-decision runs of
    ours."""
    row = Row(path.stem if path.parent.name == "classic" else f"rules/{path.name}")
    limit = oracle.read_spec(path).decisions
    kernel_times, our_times = [], []
    try:
        for _ in range(repeat):
            seconds, row.decisions = kernel_run(path, limit)
            kernel_times.append(seconds)
            seconds, ours = our_run(path, limit)
            our_times.append(seconds)
            if ours != row.decisions:
                row.error = f"ours made {ours} decisions, the kernel {row.decisions}"
        per_decision = steadiest(our_decision_times(path, limit) for _ in range(repeat))
    except Exception as exc:  # noqa: BLE001 - one program's failure is reported, not fatal
        row.error = f"{type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''}"
        row.kernel_s = min(kernel_times) if kernel_times else 0.0
        return row
    row.kernel_s, row.ours_s = min(kernel_times), min(our_times)
    totals = [seconds for seconds, _ in per_decision]
    row.median_decision_s = statistics.median(totals)
    slowest = max(range(len(totals)), key=totals.__getitem__)
    row.slowest_decision_s, row.slowest_at = totals[slowest], slowest + 1
    row.slowest_gc_s = per_decision[slowest][1]
    row.slowest_no_gc_s = max(seconds - collecting for seconds, collecting in per_decision)
    return row


# --------------------------------------------------------------------------- report


def table(rows: list[Row]) -> str:
    head = (f"{'program':34} {'dec':>6} {'kernel ms':>10} {'ours ms':>10} {'ours/k':>7} "
            f"{'median ms':>10} {'slowest ms':>11} {'at':>5} {'gc ms':>7} {'max/med':>8} "
            f"{'no gc':>7}  flags")
    lines = [head, "-" * len(head)]
    for r in rows:
        if r.error and not r.ours_s:
            lines.append(f"{r.name:34} {r.decisions:>6} {r.kernel_s * 1e3:>10.2f}  ours failed: "
                         f"{r.error}")
            continue
        lines.append(
            f"{r.name:34} {r.decisions:>6} {r.kernel_s * 1e3:>10.2f} {r.ours_s * 1e3:>10.2f} "
            f"{r.ratio:>6.1f}x {r.median_decision_s * 1e3:>10.3f} "
            f"{r.slowest_decision_s * 1e3:>11.3f} {r.slowest_at:>5} {r.slowest_gc_s * 1e3:>7.2f} "
            f"{r.spike:>7.1f}x {r.spike_no_gc:>6.1f}x  "
            f"{r.flags()}{'  ' + r.error if r.error else ''}")
    timed = [r for r in rows if r.ours_s and r.kernel_s]
    if timed:
        total_k = sum(r.kernel_s for r in timed)
        total_o = sum(r.ours_s for r in timed)
        lines.append("-" * len(head))
        lines.append(f"{'all timed programs':34} {'':>6} {total_k * 1e3:>10.2f} "
                     f"{total_o * 1e3:>10.2f} {total_o / total_k:>6.1f}x")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="timed runs per engine")
    parser.add_argument("--only", nargs="*", default=None, help="program stems to run")
    args = parser.parse_args(argv)
    import sann
    from sann.soar.compiled import is_compiled

    paths = [p for p in programs() if not args.only or p.stem in args.only]
    print(f"engine: {'compiled' if is_compiled() else 'interpreted'} "
          f"({Path(sann.__file__).parent}); best of {args.repeat}; flags: SLOW ours > "
          f"{SLOW_RATIO:g}x kernel, SPIKE decision > {SPIKE_RATIO:g}x median")
    rows = []
    for path in paths:
        rows.append(measure(path, args.repeat))
        print(f"  {rows[-1].name}: done", file=sys.stderr, flush=True)
    print(table(rows))


if __name__ == "__main__":
    main()
