"""Command line: ``python -m sann.soar FILE... [--decisions N] [--trace LEVEL] [--seed N]``
``[--stats]``.

Sources the files in order into one agent, runs it until it halts (or for N decisions) and
prints the trace and the agent's ``write`` output on standard output.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from .agent import Agent
from .errors import SoarError


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m sann.soar", description="Run Soar agents in SANN's engine."
    )
    parser.add_argument("files", nargs="+", metavar="FILE", help="rule files, sourced in order")
    parser.add_argument("--decisions", "-d", type=int, default=None, help="decision limit")
    parser.add_argument("--trace", "-t", type=int, default=1, choices=range(6), help="0..5")
    parser.add_argument("--seed", "-s", type=int, default=None, help="seed of random choices")
    parser.add_argument("--stats", action="store_true", help="print the run's statistics")
    return parser


def format_stats(agent: Agent) -> str:
    """The kernel's ``stats`` counters that both engines share."""
    s = agent.stats
    lines = [
        f"{s['decisions']} decisions",
        f"{s['elaboration_cycles']} elaboration cycles",
        f"{s['production_firings']} production firings",
        f"{s['wme_changes']} wme changes ({s['wme_additions']} additions,"
        f" {s['wme_removals']} removals)",
        f"WM size: {s['wm_size']} current, {s['wm_max']} maximum",
    ]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if args.decisions is not None and args.decisions < 0:
        print("error: --decisions must be >= 0", file=sys.stderr)
        return 2
    agent = Agent(seed=args.seed, out=sys.stdout)
    try:
        for path in args.files:
            agent.source(path)
        agent.trace(args.trace)
        agent.run(args.decisions)
    except SoarError as error:
        sys.stdout.flush()
        print(f"\nerror: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("\ninterrupted", file=sys.stderr)
        return 130
    print()
    if args.stats:
        print(format_stats(agent))
    return 0


if __name__ == "__main__":
    sys.exit(main())
