"""Parsing benchmark: reading a file of 200 productions, SANN against the real Soar 9.6 kernel.

Usage::

    .venv/bin/python benchmarks/parsing.py [--productions 200] [--repeat 7]

In one process, on one file (the productions of ``tests/soar/test_syntax.py``'s 200-production
test: a path, a disjunction, a negation, a conjunctive test, an operator with two preferences,
a computed value and a ``write``), best of ``--repeat`` runs each, the engines taking turns:

- ``parse``: our parser (``sann.soar.parse``: Lark, the transformer running inline), after one
  warm-up parse so that building the grammar's parser is not counted (printed apart); each run
  parses a text no run parsed before (a comment line numbers it), since ``parse`` keeps the
  productions of texts it has read;
- ``load``: our agent's whole load (``Agent.load``: parse, load-time checks, Rete);
- the kernel's ``source`` of the file into a fresh agent (its parse, reorder and Rete).

The figures are the ratios ours/kernel for parse and for load; absolute CPU times are printed
too.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # this checkout's engine, not an installed one
sys.path.insert(0, str(ROOT / "tests" / "soar" / "differential"))
import kernel as oracle  # noqa: E402  (the differential harness owns the kernel's lifecycle)

from sann.soar import Agent, parse  # noqa: E402

RULE = (
    "sp {{rule-{i} (state <s> ^a.b <x> ^c {{ <y> > 3 }} -^d e) (<x> ^f << g h >>)\n"
    "--> (<s> ^operator <o> + =) (<o> ^name n{i} ^value (+ <y> 1))\n"
    "    (write <y> (crlf))}}\n"
)


def rule_text(count: int) -> str:
    return "".join(RULE.format(i=i) for i in range(count))


def seconds(run: Callable[[], object]) -> float:
    """CPU seconds of this process: the kernel runs in this thread, and on a busy machine the
    wall clock also counts the other processes (a 2 ms source then reads 20-40 ms)."""
    start = time.process_time()
    run()
    return time.process_time() - start


def kernel_source(path: Path, count: int) -> float:
    """Seconds the kernel takes to source ``path`` into a fresh agent (agent made untimed)."""
    with oracle.KernelAgent() as ka:
        ka.cmd("watch 0")
        elapsed = seconds(lambda: ka.cmd(f"source {{{path}}}"))
        loaded = len(ka.cmd("print").split())
    if loaded != count:
        raise RuntimeError(f"the kernel loaded {loaded} productions, not {count}")
    return elapsed


def our_load(text: str, count: int) -> float:
    agent = Agent()
    elapsed = seconds(lambda: agent.load(text))
    if len(agent.productions) != count:
        raise RuntimeError(f"our agent loaded {len(agent.productions)} productions, not {count}")
    return elapsed


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--productions", type=int, default=200)
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args(argv)
    count = args.productions
    text = rule_text(count)
    first = seconds(lambda: parse("sp {warm (state <s> ^a b) --> }"))
    if [p.name for p in parse(text)] != [f"rule-{i}" for i in range(count)]:
        raise RuntimeError("our parse did not produce the productions in order")
    times: dict[str, list[float]] = {"parse": [], "load": [], "kernel": []}
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "rules.soar"
        path.write_text(text)
        for run in range(args.repeat):
            times["kernel"].append(kernel_source(path, count))
            times["parse"].append(seconds(partial(parse, f"# parse {run}\n{text}")))
            times["load"].append(our_load(f"# load {run}\n{text}", count))
    best = {name: min(values) for name, values in times.items()}
    print(f"{count} productions, best of {args.repeat} (first parse in the process, which "
          f"builds the parser: {first * 1e3:.0f} ms)")
    print(f"  kernel source  {best['kernel'] * 1e3:8.1f} ms")
    print(f"  our parse      {best['parse'] * 1e3:8.1f} ms   ours/kernel "
          f"{best['parse'] / best['kernel']:6.1f}x")
    print(f"  our load       {best['load'] * 1e3:8.1f} ms   ours/kernel "
          f"{best['load'] / best['kernel']:6.1f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
