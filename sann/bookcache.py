"""Cached execution of the book's chapters that stays correct when what a chapter reads changes.

myst-nb's cache (jupyter-cache) keys an executed notebook on its code cells only: an edit of
``rules/blocks.soar`` or of a ``sann`` module would be served the old outputs. This module
executes the chapters itself, before Sphinx reads them, and makes the cache honest:

* While a chapter executes, its kernel records every project file it opens for reading (an
  audit hook, also inherited by the processes the chapter forks) and, at the end, every
  project module it imported. The hashes of those files, and a fingerprint of the Python
  environment (interpreter, installed distributions, ``SANN_*`` variables), are stored beside
  the jupyter-cache entry, in ``<cache>/sann-inputs/<hashkey>.json``.
* Before a build, an entry whose recorded inputs changed, or that has no record (executed by
  someone else, or by a build that stopped half-way), is removed: when in doubt, re-execute.
* The missing chapters are executed ``jobs`` at a time (kernels are separate processes), each
  cached only when every cell succeeded; the entry is written before its record, so a crash
  in between leaves an entry without a record, which the next build removes.
* Sphinx then reads every chapter from the cache (``nb_execution_mode = "cache"``), and is
  told to re-read the chapters whose entries are newer than the doctrees it keeps; the
  executed notebooks are written to ``jupyter_execute`` (myst-nb writes them without outputs
  when it takes them from the cache).

Not seen as inputs: files outside the repository (and ``$SANN_CACHE``) other than the
installed distributions, and directory listings (a chapter that globs a directory notices a
changed file, not an added one).
"""

from __future__ import annotations

import asyncio
import hashlib
import inspect
import json
import os
import sys
import tempfile
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from sann.cache import write_atomically

ROOT = Path(__file__).resolve().parents[1]
#: Folders of the repository whose files are never inputs (build output, VCS, byte code).
SKIP_PARTS = frozenset({".git", "__pycache__", ".ipynb_checkpoints", "_build", ".venv"})
RECORDS = "sann-inputs"
TIMINGS = "sann-timings.json"


# --- the kernel side ------------------------------------------------------------------------


def _kernel_recorder(log: str, roots: Sequence[str], skip: Sequence[str]) -> None:
    """Runs in the chapter's kernel (sent as source): append to ``log`` the path of each file
    under ``roots`` opened for reading. The hook is inherited by forked processes, which append
    to the same log; a thread-local flag keeps the hook's own writes out of it."""
    import os
    import sys
    import threading

    prefixes = tuple(os.path.join(os.path.abspath(r), "") for r in roots)
    skipped = frozenset(skip)
    excluded = tuple(os.path.join(os.path.abspath(p), "") for p in
                     {sys.prefix, sys.base_prefix, sys.exec_prefix})
    seen: set[str] = set()
    local = threading.local()

    def wanted(path: object) -> str | None:
        if isinstance(path, int):
            return None
        name = os.path.abspath(os.fsdecode(os.fspath(path)))  # type: ignore[arg-type]
        if not name.startswith(prefixes) or name.startswith(excluded):
            return None
        if skipped.intersection(name.split(os.sep)):
            return None
        return name

    def note(name: str) -> None:
        seen.add(name)
        local.busy = True
        try:
            fd = os.open(log, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
            try:
                os.write(fd, os.fsencode(name) + b"\n")
            finally:
                os.close(fd)
        finally:
            local.busy = False

    def reads(mode: object, flags: object) -> bool:
        if isinstance(mode, str):
            return "r" in mode or ("+" in mode and "w" not in mode)
        if isinstance(flags, int):  # os.open; O_CREAT | O_EXCL makes a new (temporary) file
            new = flags & os.O_CREAT and flags & os.O_EXCL
            return flags & os.O_ACCMODE != os.O_WRONLY and not flags & os.O_TRUNC and not new
        return True

    def hook(event: str, args: tuple) -> None:
        if event != "open" or getattr(local, "busy", False):
            return
        path, mode, flags = (tuple(args) + (None, None))[:3]
        if not reads(mode, flags):
            return
        try:
            name = wanted(path)
        except (TypeError, ValueError):
            return
        if name is not None and name not in seen:
            note(name)

    def modules() -> None:
        """Every project module imported (a compiled one with its source)."""
        for module in list(sys.modules.values()):
            file = getattr(module, "__file__", None)
            if not file:
                continue
            name = wanted(file)
            if name is None:
                continue
            names = [name]
            if not name.endswith(".py"):
                names.append(os.path.join(os.path.dirname(name),
                                          os.path.basename(name).split(".")[0] + ".py"))
            for n in names:
                if n not in seen and os.path.exists(n):
                    note(n)

    sys.addaudithook(hook)
    globals()["_sann_record_modules"] = modules


def _kernel_code(log: Path, roots: Sequence[Path]) -> tuple[str, str]:
    """The hidden code run before the first cell and after the last."""
    source = inspect.getsource(_kernel_recorder)
    call = f"_kernel_recorder({str(log)!r}, {[str(r) for r in roots]!r}, {sorted(SKIP_PARTS)!r})"
    start = f"from __future__ import annotations\n{source}\n{call}\ndel _kernel_recorder\n"
    return start, "_sann_record_modules()\n"


# --- what a chapter read --------------------------------------------------------------------


def file_stamp(path: Path) -> list | None:
    """``[size, mtime_ns, sha256]`` of a file, or None when it does not exist."""
    try:
        st = path.stat()
        digest = hashlib.sha256(path.read_bytes()).hexdigest()
    except FileNotFoundError:
        return None
    return [st.st_size, st.st_mtime_ns, digest]


def unchanged(path: Path, stamp: list | None) -> bool:
    """Whether ``path`` still has the content it had when ``stamp`` was taken (a file whose
    size and mtime are the same is trusted; otherwise its content is hashed again)."""
    try:
        st = path.stat()
    except FileNotFoundError:
        return stamp is None
    if stamp is None:
        return False
    size, mtime_ns, digest = stamp
    if st.st_size != size:
        return False
    if st.st_mtime_ns == mtime_ns:
        return True
    return hashlib.sha256(path.read_bytes()).hexdigest() == digest


def environment() -> str:
    """A fingerprint of what executes the chapters besides the project's files: the
    interpreter, every installed distribution's version and the SANN_* / PYTHONPATH
    variables the kernel inherits (not SANN_BOOK_*, which say how to build, not what)."""
    from importlib import metadata

    dists = sorted({f"{d.metadata['Name']}=={d.version}" for d in metadata.distributions()})
    env = sorted((k, v) for k, v in os.environ.items()
                 if (k.startswith("SANN_") and not k.startswith("SANN_BOOK_"))
                 or k == "PYTHONPATH")
    text = json.dumps([sys.version, os.path.realpath(sys.executable), dists, env])
    return hashlib.sha256(text.encode()).hexdigest()


def roots(base: Sequence[Path] = (ROOT,)) -> list[Path]:
    """Where inputs live: ``base`` (the repository), and ``$SANN_CACHE`` when it is set."""
    found = [Path(b).absolute() for b in base]
    if os.environ.get("SANN_CACHE"):
        found.append(Path(os.environ["SANN_CACHE"]).absolute())
    return found


def _relative(path: Path) -> str:
    try:
        return str(path.relative_to(ROOT))
    except ValueError:
        return str(path)


def _absolute(name: str) -> Path:
    path = Path(name)
    return path if path.is_absolute() else ROOT / path


def _write_json(path: Path, data: dict) -> None:
    """Write ``data`` whole or not at all (temporary file + os.replace)."""
    write_atomically(path, json.dumps(data, indent=1, sort_keys=True).encode("utf-8"))


def record_path(cache_path: Path, hashkey: str) -> Path:
    """Where the inputs of the cache entry ``hashkey`` are recorded."""
    return Path(cache_path) / RECORDS / f"{hashkey}.json"


def stale_reason(record: dict | None, env: str) -> str | None:
    """Why a cache entry with this inputs record must be executed again (None: it is valid)."""
    if record is None:
        return "no record of the files it read"
    if record.get("environment") != env:
        return "the Python environment changed"
    for name, stamp in record.get("files", {}).items():
        if not unchanged(_absolute(name), stamp):
            return f"{name} changed"
    return None


def _read_record(path: Path) -> dict | None:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def invalidate(cache_path: Path, env: str | None = None) -> dict[str, str]:
    """Remove every cache entry whose recorded inputs changed; ``{uri: reason}`` of those.
    Records left without an entry are removed too."""
    from jupyter_cache import get_cache
    from jupyter_cache.cache.db import NbCacheRecord

    cache_path = Path(cache_path)
    cache = get_cache(str(cache_path))
    env = environment() if env is None else env
    dropped: dict[str, str] = {}
    kept: set[str] = set()
    for entry in cache.list_cache_records():
        notebook = cache_path / "executed" / entry.hashkey / "base.ipynb"
        reason = (stale_reason(_read_record(record_path(cache_path, entry.hashkey)), env)
                  if notebook.exists() else "its notebook file is missing")
        if reason is None:
            kept.add(entry.hashkey)
            continue
        dropped[entry.uri] = reason
        try:
            cache.remove_cache(entry.pk)
        except KeyError:
            NbCacheRecord.remove_records([entry.pk], cache.db)
        record_path(cache_path, entry.hashkey).unlink(missing_ok=True)
    for orphan in (cache_path / RECORDS).glob("*.json"):
        if orphan.stem not in kept:
            orphan.unlink(missing_ok=True)
    return dropped


# --- executing chapters ---------------------------------------------------------------------


@dataclass
class Chapter:
    """A notebook to execute: ``uri`` is its source file, ``cwd`` where its kernel runs."""

    uri: str
    notebook: Any
    cwd: Path
    timeout: int | None = None
    kernel_name: str = "python3"
    roots: Sequence[Path] = (ROOT,)


@dataclass
class Outcome:
    """What executing the chapters did: seconds per executed chapter (wall, and the CPU
    seconds of its kernel and the processes it waited for: on a shared machine the wall time
    also counts other users), tracebacks of the failed ones, and the chapters already in the
    cache."""

    executed: dict[str, float] = field(default_factory=dict)
    cpu: dict[str, float] = field(default_factory=dict)
    failed: dict[str, str] = field(default_factory=dict)
    cached: list[str] = field(default_factory=list)
    dropped: dict[str, str] = field(default_factory=dict)


#: The kernel's CPU seconds, its own and its waited-for children's (evaluated in the kernel).
_CPU = ("sum(getattr(__import__('resource').getrusage(who), part) for who in (0, -1) "
        "for part in ('ru_utime', 'ru_stime'))")


async def _hidden(client: Any, code: str, expressions: dict[str, str] | None = None
                  ) -> dict[str, str]:
    """Run ``code`` in the kernel outside the notebook (no history, no outputs); the values
    of ``expressions`` evaluated after it, as text."""
    msg_id = client.kc.execute(code, silent=True, store_history=False,
                               user_expressions=expressions or {})
    reply = await client.async_wait_for_reply(msg_id)
    content = (reply or {}).get("content", {})
    if content.get("status") != "ok":
        raise RuntimeError("the input recorder failed in the kernel: "
                           f"{content.get('ename')}: {content.get('evalue')}")
    values = content.get("user_expressions", {})
    return {name: values.get(name, {}).get("data", {}).get("text/plain", "")
            for name in expressions or {}}


async def _execute(chapter: Chapter, log: Path) -> float:
    """Execute every cell of ``chapter.notebook`` in place (as nbclient's execute does),
    with the input recorder around the cells; the kernel's CPU seconds."""
    from nbclient import NotebookClient

    client = NotebookClient(chapter.notebook, timeout=chapter.timeout,
                            kernel_name=chapter.kernel_name, allow_errors=False,
                            record_timing=False,
                            resources={"metadata": {"path": str(chapter.cwd)}})
    start, finish = _kernel_code(log, roots(chapter.roots))
    client.reset_execution_trackers()
    async with client.async_setup_kernel():
        info = await client.async_wait_for_reply(client.kc.kernel_info())
        if info is not None:
            chapter.notebook.metadata["language_info"] = info["content"]["language_info"]
        await _hidden(client, start)
        for index, cell in enumerate(chapter.notebook.cells):
            await client.async_execute_cell(cell, index,
                                            execution_count=client.code_cells_executed + 1)
        cpu = await _hidden(client, finish, {"cpu": _CPU})
        client.set_widgets_metadata()
    return float(cpu["cpu"])


def _inputs(log: Path) -> dict[str, list | None]:
    names = sorted(set(log.read_text(encoding="utf-8", errors="surrogateescape").split("\n"))
                   - {""})
    return {_relative(Path(n)): file_stamp(Path(n)) for n in names}


def _store(cache_path: Path, chapter: Chapter, seconds: float, cpu: float, inputs: dict,
           env: str) -> None:
    """Cache the executed notebook, then record its inputs (in that order: see the module)."""
    from jupyter_cache import get_cache
    from jupyter_cache.base import CacheBundleIn

    cache = get_cache(str(cache_path))
    entry = cache.cache_notebook_bundle(
        CacheBundleIn(chapter.notebook, chapter.uri, data={"execution_seconds": seconds}),
        check_validity=False, overwrite=True)
    _write_json(record_path(cache_path, entry.hashkey),
                {"uri": chapter.uri, "environment": env, "files": inputs,
                 "execution_seconds": seconds, "execution_cpu_seconds": cpu})


def _traceback(error: BaseException) -> str:
    import traceback

    return "".join(traceback.format_exception(error))


async def _run_all(chapters: Sequence[Chapter], cache_path: Path, jobs: int, env: str,
                   outcome: Outcome, logger: Any) -> None:
    slots = asyncio.Semaphore(max(1, jobs))
    work = Path(tempfile.mkdtemp(prefix="sann-bookcache-"))

    async def one(number: int, chapter: Chapter) -> None:
        async with slots:
            log = work / f"{number}.inputs"
            log.touch()
            if logger:
                logger(f"executing {chapter.uri}")
            t0 = time.perf_counter()
            try:
                cpu = await _execute(chapter, log)
            except Exception as error:  # a failing cell, a timeout, a dead kernel
                outcome.failed[chapter.uri] = _traceback(error)
                if logger:
                    logger(f"failed: {chapter.uri}")
                return
            seconds = time.perf_counter() - t0
            _store(cache_path, chapter, seconds, cpu, _inputs(log), env)
            outcome.executed[chapter.uri] = seconds
            outcome.cpu[chapter.uri] = cpu
            if logger:
                logger(f"executed {chapter.uri} in {seconds:.1f} s ({cpu:.1f} s CPU)")

    try:
        await asyncio.gather(*(one(i, c) for i, c in enumerate(chapters)))
    finally:
        for path in work.iterdir():
            path.unlink()
        work.rmdir()


def cached(cache_path: Path, notebook: Any) -> Any | None:
    """The cache entry matching ``notebook``'s code, or None."""
    from jupyter_cache import get_cache

    try:
        return get_cache(str(cache_path)).match_cache_notebook(notebook)
    except KeyError:
        return None


def _by_expected_time(chapters: Sequence[Chapter], cache_path: Path,
                      first: Sequence[str] = ()) -> list[Chapter]:
    """Longest first, so that the last chapter to finish is a short one: the chapters named
    in ``first`` (by file stem) whose time is not known yet, then the other unknown ones,
    then the known ones by the time their last execution took (``TIMINGS``)."""
    timings = _read_record(Path(cache_path) / TIMINGS) or {}

    def rank(chapter: Chapter) -> tuple[int, float]:
        stem = Path(chapter.uri).stem
        if chapter.uri in timings:
            return 2, -timings[chapter.uri]
        return (0, list(first).index(stem)) if stem in first else (1, 0.0)

    return sorted(chapters, key=rank)


def prepare(chapters: Iterable[Chapter], cache_path: str | os.PathLike[str], jobs: int = 2,
            logger: Any = None, first: Sequence[str] = ()) -> Outcome:
    """Make the cache hold a valid executed notebook for every chapter: drop stale entries,
    execute the missing chapters ``jobs`` at a time. Failed chapters are not cached."""
    cache_path = Path(cache_path)
    env = environment()
    outcome = Outcome(dropped=invalidate(cache_path, env))
    missing = []
    for chapter in chapters:
        if cached(cache_path, chapter.notebook) is None:
            missing.append(chapter)
        else:
            outcome.cached.append(chapter.uri)
    if missing:
        asyncio.run(_run_all(_by_expected_time(missing, cache_path, first), cache_path, jobs, env,
                             outcome, logger))
        timings_file = cache_path / TIMINGS
        timings = _read_record(timings_file) or {}
        _write_json(timings_file, {**timings, **outcome.executed})
    return outcome


# --- Sphinx ---------------------------------------------------------------------------------


def _chapter(env: Any, docname: str, base: Sequence[Path]) -> Chapter | None:
    """The notebook of ``docname`` exactly as myst-nb reads it (so that its cache key is the
    one myst-nb looks up), or None when myst-nb would not execute it from the cache."""
    import re
    from fnmatch import fnmatch

    from myst_nb.core.read import create_nb_reader

    path = Path(env.doc2path(docname))
    text = path.read_text(encoding="utf-8")
    config = env.mystnb_config
    reader = create_nb_reader(str(path), env.myst_config, config, text)
    if reader is None:
        return None
    notebook = reader.read(text)
    kernel = notebook.metadata.get("kernelspec", {})
    for pattern, alias in config.kernel_rgx_aliases.items():
        if kernel.get("name") is not None and re.fullmatch(pattern, kernel["name"]):
            kernel["name"] = alias
            break
    if config.metadata_key in notebook.metadata:
        overrides = dict(notebook.metadata[config.metadata_key])
        overrides.pop("output_folder", None)
        config = config.copy(**overrides)
    if config.execution_mode != "cache" or any(
            fnmatch(docname, p) for p in config.execution_excludepatterns):
        return None
    return Chapter(str(path), notebook, path.parent, config.execution_timeout,
                   kernel.get("name", "python3"), base)


def _jobs() -> int:
    value = os.environ.get("SANN_BOOK_JOBS", "2")
    if not value.isdigit() or int(value) < 1:
        raise ValueError(f"SANN_BOOK_JOBS must be a positive integer, got {value!r}")
    return int(value)


def _on_get_outdated(app: Any, env: Any, added: set, changed: set, removed: set) -> list[str]:
    """Bring the cache up to date; return the chapters Sphinx must read again because their
    entry is not the one their stored doctree was rendered from."""
    from sphinx.errors import ExtensionError
    from sphinx.util import logging

    logger = logging.getLogger(__name__)
    if env.mystnb_config.execution_mode != "cache":
        return []
    base = [Path(app.confdir, r) for r in app.config.sann_bookcache_roots]
    chapters = {d: c for d in sorted(env.found_docs - removed)
                if (c := _chapter(env, d, base)) is not None}
    cache_path = Path(env.mystnb_config.execution_cache_path)
    outcome = prepare(chapters.values(), cache_path, jobs=_jobs(),
                      logger=lambda m: logger.info(f"[bookcache] {m}"),
                      first=app.config.sann_bookcache_first)
    for uri, reason in outcome.dropped.items():
        logger.info(f"[bookcache] {_relative(Path(uri))}: cached outputs dropped, {reason}")
    if outcome.failed:
        for uri, error in outcome.failed.items():
            logger.error(f"executing {uri} failed:\n{error}")
        raise ExtensionError(f"{len(outcome.failed)} chapter(s) failed to execute: "
                             + ", ".join(sorted(_relative(Path(u)) for u in outcome.failed)))
    metadata = getattr(env, "nb_metadata", {})
    again = []
    for docname, chapter in chapters.items():
        entry = cached(cache_path, chapter.notebook)
        shown = metadata.get(docname, {}).get("exec_data") or {}
        if entry is None or shown.get("mtime") != entry.created.timestamp():
            again.append(docname)
    app.env.sann_bookcache_path = str(cache_path)
    app.env.sann_bookcache_chapters = sorted(chapters)
    return [d for d in again if d not in added and d not in changed]


def _write_executed(app: Any, env: Any) -> None:
    """Write each chapter's executed notebook (outputs from the cache) to myst-nb's output
    folder, ``jupyter_execute``: myst-nb writes the notebook it read there, without outputs,
    when it reads a chapter from the cache."""
    import nbformat
    from jupyter_cache import get_cache

    cache_path = getattr(env, "sann_bookcache_path", None)
    if cache_path is None:
        return
    cache = get_cache(cache_path)
    base = [Path(app.confdir, r) for r in app.config.sann_bookcache_roots]
    folder = Path(env.mystnb_config.output_folder)
    for docname in getattr(env, "sann_bookcache_chapters", []):
        chapter = _chapter(env, docname, base)
        if chapter is None or cached(Path(cache_path), chapter.notebook) is None:
            continue
        _, executed = cache.merge_match_into_notebook(chapter.notebook)
        target = folder.joinpath(*f"{docname}.ipynb".split("/"))
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(nbformat.writes(executed), encoding="utf-8")


def _check_no_foreign_entries(app: Any, env: Any) -> None:
    """Warn when myst-nb executed a chapter itself: its notebook then differs from the one
    read here (a ``source-read`` handler?), and its entry, without a record, would be
    executed again by every build."""
    from jupyter_cache import get_cache
    from sphinx.util import logging

    cache_path = getattr(env, "sann_bookcache_path", None)
    if cache_path is None:
        return
    for entry in get_cache(cache_path).list_cache_records():
        if not record_path(Path(cache_path), entry.hashkey).exists():
            logging.getLogger(__name__).warning(
                f"{entry.uri} was executed by myst-nb, not by sann.bookcache: the notebook "
                "myst-nb read differs from the one sann.bookcache read")


def setup(app: Any) -> dict:
    """The Sphinx extension: conf.py lists ``sann.bookcache`` after ``myst_nb``.
    ``sann_bookcache_roots``: the folders (relative to conf.py) whose files are inputs;
    ``sann_bookcache_first``: the chapters to start first while their times are unknown."""
    app.add_config_value("sann_bookcache_roots", [str(ROOT)], "env")
    app.add_config_value("sann_bookcache_first", [], "env")
    app.connect("env-get-outdated", _on_get_outdated)
    app.connect("env-updated", _check_no_foreign_entries)
    app.connect("env-updated", _write_executed)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
