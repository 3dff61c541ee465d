"""Bytecodes the engine executes per unit of work: a deterministic companion to engine.py.

Usage::

    .venv/bin/python benchmarks/engine_ops.py [--disks 9] [--scenes 30] [--top 25]

Timings on these shared VMs swing by tens of percent between runs, so a change worth 2% cannot
be seen in engine.py's seconds.  This script runs the same two workloads (the Towers of Hanoi
of ``rules/hanoi.soar``, and the block planner of engine.py fed scene by scene) under a
``sys.settrace`` opcode counter and prints the bytecodes and Python calls per hanoi decision
and per block scene, with the functions that execute most of them.  The counts are the same
on every run of the same code, so two versions of the engine compare exactly (run it in two
work trees).  Bytecodes are a proxy, not time: they miss allocation, garbage collection and
C-level work, which engine.py's ratios include.
"""

from __future__ import annotations

import argparse
import io
import sys
from collections import Counter
from collections.abc import Callable
from pathlib import Path
from types import FrameType

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import engine  # noqa: E402  (the scenes and the planner driver)

from sann.soar.agent import Agent  # noqa: E402
from sann.soar.instantiation import COMPILE_AFTER  # noqa: E402

Key = tuple[str, str, int]  # (file name, function name, first line)


class OpCounter:
    """Counts the bytecodes and calls of every Python function while it is active."""

    def __init__(self) -> None:
        self.ops: Counter[Key] = Counter()
        self.calls: Counter[Key] = Counter()

    def _trace(self, frame: FrameType, event: str, arg: object) -> Callable | None:
        code = frame.f_code
        key = (Path(code.co_filename).name, code.co_name, code.co_firstlineno)
        if event == "call":
            frame.f_trace_opcodes = True
            frame.f_trace_lines = False
            self.calls[key] += 1
        elif event == "opcode":
            self.ops[key] += 1
        return self._trace

    def count(self, work: Callable[[], object]) -> None:
        sys.settrace(self._trace)
        try:
            work()
        finally:
            sys.settrace(None)

    def report(self, unit: str, units: int, top: int) -> None:
        total = sum(self.ops.values())
        print(f"    {total / units:,.0f} bytecodes and {sum(self.calls.values()) / units:,.0f}"
              f" Python calls per {unit}")
        for key, ops in self.ops.most_common(top):
            name = f"{key[1]} ({key[0]}:{key[2]})"
            print(f"    {100 * ops / total:5.1f}%  {ops / units:9.1f} ops"
                  f"  {self.calls[key] / units:6.1f} calls  {name}")


def hanoi(disks: int, top: int) -> None:
    """Count a hanoi run after its first 20 decisions (sourcing and start-up excluded)."""
    agent = Agent(out=io.StringIO())
    agent.source(str(engine.HANOI))
    agent.input_link.add("disks", disks)
    agent.run(decisions=20)
    counter = OpCounter()
    counter.count(agent.run)
    decisions = int(agent.stats["decisions"]) - 20
    print(f"(a) Towers of Hanoi, {disks} disks: {decisions} decisions counted")
    counter.report("decision", decisions, top)


WARM_UP = COMPILE_AFTER + 50  # scenes run before counting


def blocks(scenes: int, top: int, seed: int) -> None:
    """Count block scenes after ``WARM_UP`` scenes, as in the steady state of engine.py's
    2,000: by then every rule that fires once a scene has its actions compiled."""
    planner = engine.OurPlanner()
    work = engine.make_scenes(scenes + WARM_UP, 26, seed)
    for scene in work[:WARM_UP]:
        planner.solve(scene)
    counter = OpCounter()
    counter.count(lambda: [planner.solve(scene) for scene in work[WARM_UP:]])
    print(f"(b) Blocks planner: {scenes} scenes counted")
    counter.report("scene", scenes, top)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--disks", type=int, default=9)
    parser.add_argument("--scenes", type=int, default=30)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--top", type=int, default=25, help="functions listed per workload")
    args = parser.parse_args(argv)
    if not 1 <= args.disks <= 14 or args.scenes < 1 or args.top < 0:
        parser.error("--disks must be 1..14, --scenes positive, --top not negative")
    hanoi(args.disks, args.top)
    blocks(args.scenes, args.top, args.seed)
    return 0


if __name__ == "__main__":
    sys.exit(main())
