"""How near is the planner's verdict to the label? (issue 17: "the planner's output almost is the
label").

Usage::

    .venv/bin/python benchmarks/planner_label.py [--n-train 10000] [--n-test 2000] [--seed 0]
                                                 [--engine soar_sml] [--workers 1]

For every dataset (D1/D2 x C1/C2/C3) it builds (or loads from the cache) the dataset and
prints, on the test samples: how often "some sequence has T_o = 1" (the rules-alone verdict)
equals the label, the majority-class rate beside it (the anchor: what no knowledge achieves),
how many sequences the search found per sample (R of eq. 2), and the share of samples with a
tie between plans of different length. The datasets do not depend on the engine (the tests
check both engines plan alike), so the real kernel, the faster of the two, builds them by
default.
"""

from __future__ import annotations

import argparse
from collections import Counter

import numpy as np

from sann.experiments.blocks import rules_verdict
from sann.tasks.blocks import KINDS, MODES, make_dataset


def sequences_per_sample(plans: np.ndarray) -> Counter:
    """R of every sample: how many sequences its plan text holds."""
    return Counter(len(text.split()) for text in plans)


def report(kind: str, mode: str, n_train: int, n_test: int, seed: int, engine: str,
           workers: int) -> dict[str, float]:
    """Print and return one dataset's agreement figures."""
    data = make_dataset(kind, mode, n_train=n_train, n_test=n_test, seed=seed, engine=engine,
                        workers=workers)
    verdict = rules_verdict(data.plans_test)
    agree = float(np.mean(verdict == data.y_test))
    majority = float(np.mean(data.y_test == int(data.y_train.mean() >= 0.5)))
    r = sequences_per_sample(data.plans_test)
    lengths = [len({part.split(":")[1] for part in text.split()}) for text in data.plans_test]
    mixed = float(np.mean(np.array(lengths) > 1))
    print(f"{kind}-{mode}: rules verdict = label on {agree:.2%} of {len(verdict)} test samples "
          f"(majority class {majority:.2%}); R per sample {dict(sorted(r.items()))}; "
          f"plans of different T_o for {mixed:.1%}")
    return {"agree": agree, "majority": majority, "mixed": mixed}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n-train", type=int, default=10_000)
    parser.add_argument("--n-test", type=int, default=2_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--engine", default="soar_sml", choices=["sann", "soar_sml"])
    parser.add_argument("--workers", type=int, default=1)
    args = parser.parse_args(argv)
    for kind in KINDS:
        for mode in MODES:
            report(kind, mode, args.n_train, args.n_test, args.seed, args.engine, args.workers)


if __name__ == "__main__":
    main()
