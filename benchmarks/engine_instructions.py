"""Machine instructions the engine executes per unit of work, counted by valgrind.

Usage::

    .venv/bin/python benchmarks/engine_instructions.py [--root DIR] [--scenes 20]

engine.py's seconds swing by tens of percent on these shared VMs and engine_ops.py's bytecode
counts miss what the interpreter does in C (allocation, dict probes, calls, the garbage
collector).  valgrind's callgrind counts every instruction, the same on every run of the same
code whatever else the machine does.  Start-up, sourcing and compiling are taken out by
running each workload at two sizes and keeping the difference: Towers of Hanoi with 9 and 10
disks (the 512 extra moves; with fewer disks the difference would hold the compiling of the
rules' actions, which happens at their 100th firing, see ``COMPILE_AFTER``), and the block
planner of engine.py with 160 warm-up scenes plus ``--scenes`` or twice as many.
The same workloads run in the Soar kernel (soar_sml, driven as engine.py drives it), so the
ratio ours/kernel is printed too: a figure free of the machine's noise, though not of time's
other costs (Python's instructions miss the caches more often than the kernel's: engine.py's
time ratios run above these).  ``--root`` measures another work tree of the project (an A/B
comparison: run it once per tree).  Needs Debian's ``valgrind``; about four minutes on two
cores.
"""

from __future__ import annotations

import argparse
import io
import os
import re
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
WARM_UP = 160  # block scenes before the counted ones: every rule's actions are compiled


def work(root: Path, kind: str, size: int) -> None:
    """The workload itself, run under valgrind: ``size`` disks or counted scenes."""
    sys.path[:0] = [str(root), str(root / "benchmarks")]
    import engine

    from sann.soar.agent import Agent

    if kind == "hanoi":
        agent = Agent(out=io.StringIO())
        agent.source(str(root / "rules" / "hanoi.soar"))
        agent.input_link.add("disks", size)
        agent.run()
        return
    if kind == "kernel-hanoi":
        engine.kernel_hanoi(size)
        return
    planner = engine.KernelPlanner() if kind == "kernel-blocks" else engine.OurPlanner()
    for scene in engine.make_scenes(WARM_UP + size, 26, 0):
        planner.solve(scene)


def instructions(root: Path, kind: str, size: int) -> int:
    """Instructions of one whole run of the workload (start-up included)."""
    command = ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null",
               sys.executable, __file__, "--root", str(root), "--work", kind, str(size)]
    env = {**os.environ, "PYTHONHASHSEED": "0", "PYTHONPATH": str(root)}
    result = subprocess.run(command, capture_output=True, text=True, env=env, check=True)
    found = re.search(r"Collected : (\d+)", result.stderr)
    if found is None:
        raise RuntimeError(f"no instruction count in valgrind's output:\n{result.stderr}")
    return int(found.group(1))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", type=Path, default=ROOT, help="work tree to measure")
    parser.add_argument("--scenes", type=int, default=20)
    parser.add_argument("--work", nargs=2, metavar=("KIND", "SIZE"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.work:
        work(args.root.resolve(), args.work[0], int(args.work[1]))
        return 0
    if shutil.which("valgrind") is None:
        parser.error("valgrind is not installed (Debian: apt-get install valgrind)")
    root = args.root.resolve()
    runs = [(prefix + kind, size) for prefix in ("", "kernel-")
            for kind, sizes in (("hanoi", (9, 10)), ("blocks", (args.scenes, 2 * args.scenes)))
            for size in sizes]
    with ThreadPoolExecutor(os.cpu_count() or 1) as pool:  # counts do not depend on load
        counted = dict(zip(runs, pool.map(lambda run: instructions(root, *run), runs),
                           strict=True))

    def per_unit(kind: str, sizes: tuple[int, int], units: int) -> float:
        return (counted[(kind, sizes[1])] - counted[(kind, sizes[0])]) / units

    decisions = 2 ** 10 - 2 ** 9 + 1  # one decision per move, plus one disk laid down
    print(f"{root}:  ours / Soar kernel (soar_sml, through its bindings)")
    for label, kind, sizes, units, unit in (
            ("hanoi", "hanoi", (9, 10), decisions, "decision (9 -> 10 disks)"),
            ("blocks", "blocks", (args.scenes, 2 * args.scenes), args.scenes,
             f"scene ({args.scenes} scenes)")):
        ours, theirs = per_unit(kind, sizes, units), per_unit("kernel-" + kind, sizes, units)
        print(f"  {label + ':':8s}{ours:13,.0f} / {theirs:11,.0f} instructions per {unit}"
              f" = {ours / theirs:5.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
