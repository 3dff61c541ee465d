"""`python -m sann reproduce blocks|cups --out DIR [--quick] [--seeds N]`.

``reproduce blocks`` scores the majority guess, the rules alone, ANN, SANN and the control
net on the six block datasets at the paper's size (10,000 training and 2,000 test samples
per dataset, three data seeds, five initialisation seeds) with learning curves; each
dataset's evaluation is cached, so a second run (or the book) reads it back."""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import replace


def _reproduce(args: argparse.Namespace) -> int:
    progress = sys.stderr.isatty()
    start = time.perf_counter()
    if args.task == "blocks":
        from sann.experiments import blocks

        config = blocks.BlocksExperiment.quick() if args.quick else blocks.BlocksExperiment()
        if args.seeds is not None:
            config = replace(config, seeds=args.seeds)
        results = blocks.run(args.out, config, progress=progress)
        summary = {kind: {mode: {m: round(cell["baselines"][m]["mean"] * 100, 2)
                                 for m in blocks.METHODS}
                          for mode, cell in modes.items()}
                   for kind, modes in results["datasets"].items()}
    else:
        from sann.experiments import cups

        config = cups.CupsExperiment.quick() if args.quick else cups.CupsExperiment()
        if args.seeds is not None:
            config = replace(config, seeds=args.seeds)
        results = cups.run(args.out, config, progress=progress)
        summary = {net: round(cell["mean"] * 100, 2) for net, cell in results["accuracy"].items()}
    print(f"test accuracy (%), mean over seeds: {json.dumps(summary)}")
    print(f"wrote {args.out}/results.json and figures in {time.perf_counter() - start:.1f} s")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m sann", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)
    reproduce = commands.add_parser("reproduce", help="reproduce one of the paper's experiments")
    reproduce.add_argument("task", choices=("blocks", "cups"))
    reproduce.add_argument("--out", required=True, help="directory for results.json and PNGs")
    reproduce.add_argument("--quick", action="store_true", help="small sets, few seeds")
    reproduce.add_argument("--seeds", type=int, default=None, help="number of training seeds")
    args = parser.parse_args(argv)
    if args.seeds is not None and args.seeds < 1:
        parser.error("--seeds must be at least 1")
    return _reproduce(args)


if __name__ == "__main__":
    sys.exit(main())
