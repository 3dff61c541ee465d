"""How long `make book` takes: from a fresh clone, after a prose edit, after a rule edit.

Usage::

    .venv/bin/python benchmarks/book_build.py [--keep] [--copy-engine] [--jobs 2]
        [--edits "prose edit,rule edit,production edit"] [--clone KEPT_CLONE]

Everything happens in a temporary ``git clone`` of this repository's HEAD, so the working tree
is never edited and no cache of it is used. The clone runs ``make book`` with this checkout's
virtual environment (``VENV=``, its install stamp taken as up to date: nothing is installed)
and imports its own sources (``PYTHONPATH``). Four builds, in order:

1. fresh: no execution cache, no dataset cache, no compiled engine (``--copy-engine`` copies
   this checkout's compiled engine when it was built from the same sources, to skip gcc).
   ``make engine`` runs first and is timed apart, then ``make book``: the fresh build is the
   sum;
2. prose edit: one sentence added to a paragraph of ``book/networks.md``;
3. rule edit: one comment line of ``rules/blocks.soar`` changed. The file changed, so every
   chapter that read it executes again; the datasets planned with it are keyed on its code
   without comments (``sann.cache.soar_code_sha256``) and come from the cache;
4. production edit: a documentation string added to the first production of
   ``rules/blocks.soar``, one line: its code changed, so the block datasets and evaluations
   are computed again as well (the plans come out the same).

It prints each build's wall and CPU seconds (this process's children: on a shared machine the
wall time also counts other users, so the 1-minute load average is printed before and after
each build), its ratio to the fresh build (the anchor, measured in the same run), the
chapters it executed with their seconds, and the issue's targets.
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TARGETS = {"fresh": 600.0, "prose edit": 60.0, "rule edit": 240.0,
           "production edit": 240.0}
EXECUTED = re.compile(r"\[bookcache\] executed (\S+) in ([0-9.]+) s \(([0-9.]+) s CPU\)")


def cpu_seconds() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def load() -> str:
    return f"load {os.getloadavg()[0]:.1f}"


def make_book(clone: Path, venv: Path, jobs: int, target: str = "book"
              ) -> tuple[float, float, dict[str, tuple[float, float]]]:
    """Run ``make <target>`` in the clone: (wall s, CPU s, {chapter: (execution wall s,
    its kernel's CPU s)})."""
    env = {k: v for k, v in os.environ.items() if k not in ("JPY_SESSION_NAME", "SANN_CACHE")}
    env.update(PYTHONPATH=str(clone), SANN_BOOK_JOBS=str(jobs))
    cmd = ["make", f"VENV={venv}", "-o", str(venv / ".installed"), target]
    wall, cpu = time.perf_counter(), cpu_seconds()
    done = subprocess.run(cmd, cwd=clone, env=env, capture_output=True, text=True)
    wall, cpu = time.perf_counter() - wall, cpu_seconds() - cpu
    if done.returncode != 0:
        sys.exit(f"make book failed in {clone}:\n{done.stdout[-4000:]}\n{done.stderr[-4000:]}")
    chapters = {Path(uri).stem: (float(w), float(u))
                for uri, w, u in EXECUTED.findall(done.stdout + done.stderr)}
    return wall, cpu, chapters


def copy_engine(clone: Path) -> bool:
    """Copy this checkout's compiled engine into the clone when built from the same sources."""
    sys.path.insert(0, str(ROOT / "sann" / "soar"))
    import compiled  # the standard-library-only module setup.py loads the same way

    here, there = ROOT / "sann" / "soar", clone / "sann" / "soar"
    if compiled.read_manifest(here / "_engine.sha256") != compiled.source_hashes(there):
        return False
    for path in [*here.glob("*.so"), here / "_engine.sha256"]:
        shutil.copy2(path, there / path.name)
    return True


def prose_edit(clone: Path) -> None:
    path = clone / "book" / "networks.md"
    text = path.read_text(encoding="utf-8")
    anchor = "## Standardisation on the training set\n\n"
    if anchor not in text:
        sys.exit(f"{path}: the paragraph to edit is gone ({anchor.strip()!r})")
    path.write_text(text.replace(anchor, anchor + "A sentence added by the benchmark. ", 1),
                    encoding="utf-8")


def rule_edit(clone: Path) -> None:
    path = clone / "rules" / "blocks.soar"
    lines = path.read_text(encoding="utf-8").splitlines(keepends=True)
    index = next(i for i, line in enumerate(lines) if line.startswith("# "))
    lines[index] = lines[index].rstrip("\n") + " (edited by the benchmark)\n"
    path.write_text("".join(lines), encoding="utf-8")


def production_edit(clone: Path) -> None:
    """A documentation string added to the first production: its code changed (so every
    dataset planned with the file is planned again), what it does did not."""
    path = clone / "rules" / "blocks.soar"
    lines = path.read_text(encoding="utf-8").splitlines(keepends=True)
    index = next(i for i, line in enumerate(lines) if line.startswith("sp {"))
    lines[index] = lines[index].rstrip("\n") + ' "Edited by the benchmark."\n'
    path.write_text("".join(lines), encoding="utf-8")


EDITS = {"prose edit": prose_edit, "rule edit": rule_edit, "production edit": production_edit}


def report(step: str, before: str, result: tuple) -> None:
    wall, cpu, chapters = result
    ran = ", ".join(f"{c} {w:.0f} s ({u:.0f} s CPU)"
                    for c, (w, u) in sorted(chapters.items())) or "none"
    print(f"{step:>15s}: {wall:7.1f} s wall, {cpu:7.1f} s CPU ({before}, then {load()}); "
          f"executed: {ran}", flush=True)


def fresh_build(clone: Path, venv: Path, jobs: int) -> tuple:
    """``make engine`` then ``make book`` in a clone without caches: their sum."""
    before = load()
    engine = make_book(clone, venv, jobs, "engine")
    report("engine", before, engine)
    before = load()
    book = make_book(clone, venv, jobs)
    report("book", before, book)
    return engine[0] + book[0], engine[1] + book[1], book[2]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--keep", action="store_true", help="keep the temporary clone")
    parser.add_argument("--copy-engine", action="store_true",
                        help="copy the compiled engine instead of compiling it")
    parser.add_argument("--jobs", type=int, default=2, help="chapters executed at a time")
    parser.add_argument("--edits", default="prose edit,rule edit,production edit",
                        help="the edits built after the fresh build, in order")
    parser.add_argument("--clone", type=Path,
                        help="go on in this clone, kept (--keep) after its fresh build: only "
                             "the edits are built (pull the commits to measure first)")
    args = parser.parse_args()
    edits = [e.strip() for e in args.edits.split(",") if e.strip()]
    unknown = sorted(set(edits) - set(EDITS))
    if unknown:
        parser.error(f"unknown edits {unknown}: choose from {', '.join(EDITS)}")
    venv = Path(sys.prefix)
    work = None if args.clone else Path(tempfile.mkdtemp(prefix="sann-book-build-"))
    clone = args.clone or work / "sann"
    try:
        results = {}
        if work is not None:
            subprocess.run(["git", "clone", "--quiet", str(ROOT), str(clone)], check=True)
            if args.copy_engine:
                print("compiled engine copied" if copy_engine(clone)
                      else "compiled engine not copied (other sources): make compiles it")
            results["fresh"] = fresh_build(clone, venv, args.jobs)
            print(f"{'fresh':>15s}: engine + book {results['fresh'][0]:.1f} s wall, "
                  f"{results['fresh'][1]:.1f} s CPU")
        for step in edits:
            EDITS[step](clone)
            before = load()
            results[step] = make_book(clone, venv, args.jobs)
            report(step, before, results[step])
        anchor = results.get("fresh", (None,))[0]
        print(f"\n{'build':>15s} {'wall s':>8s} {'/ fresh':>8s} {'target s':>9s}")
        for step, (wall, _, _) in results.items():
            verdict = "ok" if wall <= TARGETS[step] else "over"
            ratio = f"{wall / anchor:8.3f}" if anchor else f"{'-':>8s}"
            print(f"{step:>15s} {wall:8.1f} {ratio} {TARGETS[step]:9.0f} {verdict}")
        print(f"load average at the end: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    finally:
        if work is not None:
            if args.keep:
                print(f"clone kept at {clone}")
            else:
                shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
