"""What learning costs: the same agents with chunking on and off, in SANN's engine and soar_sml.

Usage::

    .venv/bin/python benchmarks/chunking.py [--repeat 3]

For each agent (classic programs whose chunks agree with the kernel's, see
tests/soar/test_chunking_kernel.py), in one process, the engines taking turns, best of
``--repeat`` runs each, from a fresh agent with ``indifferent-selection --first`` and
``srand 1``: the time of one ``run`` to halt with ``chunk always`` and with ``chunk never``.
Printed per agent and engine: decisions and firings both ways (equal between the engines),
the learning run over the non-learning run (the engine's relative cost of learning, which
includes what the chunks save within the run), and ours over the kernel's of that ratio
(target <= 2). Absolute times are printed too; the ratios are the figures.
"""

from __future__ import annotations

import argparse
import io
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
AGENTS = ("water-jug-lookahead", "eight-puzzle-lookahead", "arithmetic", "hierarchical-task",
          "blocks-world-operator-subgoaling")
BEFORE = ("indifferent-selection --first", "srand 1")
LIMIT = 20000

sys.path.insert(0, str(ROOT))  # this checkout's engine, not an installed one
sys.path.insert(0, str(ROOT / "tests" / "soar" / "differential"))
import kernel as oracle  # noqa: E402  (the differential harness owns the kernel's lifecycle)


def kernel_run(path: Path, mode: str) -> tuple[float, int, int]:
    """Seconds of one ``run`` to halt, decisions, firings."""
    with oracle.KernelAgent() as ka:
        for line in (*BEFORE, f"chunk {mode}"):
            ka.cmd(line)
        ka.cmd(f"source {{{path}}}")
        ka.cmd(f"chunk {mode}")  # after the file, whose own setting it overrides
        ka.cmd("watch 0")
        start = time.perf_counter()
        ka.cmd(f"run {LIMIT}")
        seconds = time.perf_counter() - start
        stats = ka.stats()
        return seconds, stats["decisions"], stats["production_firings"]


def our_run(path: Path, mode: str) -> tuple[float, int, int]:
    from sann.soar.agent import Agent

    agent = Agent(out=io.StringIO())
    for line in BEFORE:
        agent.load(line)
    agent.source(path)
    agent.load(f"chunk {mode}")
    start = time.perf_counter()
    agent.run(LIMIT)
    seconds = time.perf_counter() - start
    return seconds, agent.stats["decisions"], agent.stats["production_firings"]


def best(run: object, path: Path, mode: str, repeat: int) -> tuple[float, int, int]:
    results = [run(path, mode) for _ in range(repeat)]  # type: ignore[operator]
    return min(results, key=lambda r: r[0])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    print(f"{'agent':<34}{'engine':<8}{'on: dec/fire':>14}{'off: dec/fire':>15}"
          f"{'on s':>9}{'off s':>9}{'on/off':>8}")
    ratios = []
    for name in AGENTS:
        path = ROOT / "rules" / "classic" / f"{name}.soar"
        per_engine = {}
        for engine, run in (("kernel", kernel_run), ("ours", our_run)):
            on = best(run, path, "always", args.repeat)
            off = best(run, path, "never", args.repeat)
            per_engine[engine] = (on, off)
            print(f"{name:<34}{engine:<8}{f'{on[1]}/{on[2]}':>14}{f'{off[1]}/{off[2]}':>15}"
                  f"{on[0]:>9.4f}{off[0]:>9.4f}{on[0] / off[0]:>8.2f}")
        (k_on, k_off), (o_on, o_off) = per_engine["kernel"], per_engine["ours"]
        if k_on[1:] != o_on[1:] or k_off[1:] != o_off[1:]:
            print(f"  {name}: the engines disagree on decisions/firings")
        ratio = (o_on[0] / o_off[0]) / (k_on[0] / k_off[0])
        ratios.append(ratio)
        print(f"  {name}: our learning cost ratio over the kernel's = {ratio:.2f} (target <= 2)")
    print(f"worst: {max(ratios):.2f}, mean: {sum(ratios) / len(ratios):.2f} (target <= 2)")


if __name__ == "__main__":
    main()
