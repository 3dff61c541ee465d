"""An atomic, keyed on-disk cache of NumPy arrays (datasets of the block and cup tasks).

Key: a SHA-256 over a JSON description of everything that determines the data (parameters,
the sha256 of the rule file that planned it, a code version string), so a change to any of
them misses the cache instead of serving stale data.

Atomicity: an entry is written to a temporary file in the cache directory, flushed and
fsync'ed, then ``os.replace``d onto its final name, which is atomic on POSIX. A crash leaves at
most a ``*.tmp`` file, which is never read (and is swept by later writes once it is old). An
entry that fails to load (truncated, corrupt, wrong format) counts as a miss and is rebuilt.
Every entry carries its own key, checked on load.

Concurrency: an entry being built is locked (``flock`` on a ``.<entry>.lock`` file beside it),
so processes that miss the same entry at once build it once; the others wait and load it.

Directory: ``$SANN_CACHE`` if set, else ``.sann-cache/`` at the repository root.
"""

from __future__ import annotations

import fcntl
import hashlib
import io
import json
import os
import re
import tempfile
import time
import zipfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

_REPO_ROOT = Path(__file__).resolve().parents[1]
_STALE_TMP_SECONDS = 3600.0
_KEY_FIELD = "__cache_key__"


def cache_dir() -> Path:
    """The cache directory (created on demand)."""
    env = os.environ.get("SANN_CACHE")
    return Path(env) if env else _REPO_ROOT / ".sann-cache"


def file_sha256(path: str | os.PathLike[str]) -> str:
    """Hex SHA-256 of a file's bytes (e.g. the rule file a dataset was planned with)."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def soar_code_sha256(path: str | os.PathLike[str]) -> str:
    """Hex SHA-256 of a Soar file's text with its comments removed (a ``#`` outside ``|...|``
    and ``"..."`` up to the end of its line: grammars/soar.lark ignores exactly these, and no
    other token may hold a ``#``), followed by the code of every file it ``source``s (a path
    relative to the sourcing file's directory, as Soar reads it), recursively. Datasets are
    keyed on it, so that editing the comments of a rule file, which cannot change a plan, does
    not plan every scene again, while editing a sourced rule file (rules/blocks.soar sources
    the selection space) does."""
    return hashlib.sha256(_soar_code_tree(Path(path), set()).encode()).hexdigest()


_SOURCE = re.compile(r"^[ \t]*source[ \t]+(\{[^}\n]*\}|\S+)", re.MULTILINE)


def _soar_code_tree(path: Path, seen: set[Path]) -> str:
    """The code of ``path`` and of the files it sources (each file once)."""
    path = path.resolve()
    seen.add(path)
    code = _soar_code(path.read_text(encoding="utf-8"))
    parts = [code]
    for match in _SOURCE.finditer(code):
        target = path.parent / match.group(1).strip("{}").strip()
        if target.resolve() not in seen:
            parts.append(_soar_code_tree(target, seen))
    return "\n".join(parts)


def _soar_code(text: str) -> str:
    """``text`` without its comments."""
    code: list[str] = []
    quote = ""
    i = 0
    while i < len(text):
        c = text[i]
        if quote:
            code.append(text[i:i + 2] if c == "\\" else c)
            i += 2 if c == "\\" else 1
            quote = "" if c == quote else quote
            continue
        if c == "#":
            end = text.find("\n", i)
            i = len(text) if end < 0 else end
            continue
        if c in "|\"":
            quote = c
        code.append(c)
        i += 1
    return "".join(code)


def make_key(description: dict) -> str:
    """A stable hex key for a JSON-serialisable description (sorted keys)."""
    text = json.dumps(description, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def entry_path(name: str, key: str, directory: Path | None = None) -> Path:
    """Where the entry ``name``/``key`` lives: ``<dir>/<name>-<key[:20]>.npz``."""
    if not name or any(c in name for c in "/\\\0"):
        raise ValueError(f"cache entry name must be a plain file name part, got {name!r}")
    return (directory or cache_dir()) / f"{name}-{key[:20]}.npz"


def load(name: str, key: str, directory: Path | None = None) -> dict[str, np.ndarray] | None:
    """The cached arrays, or None on a miss (absent, unreadable, or written for another key)."""
    path = entry_path(name, key, directory)
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, KeyError):
        return None
    stored = arrays.pop(_KEY_FIELD, None)
    if stored is None or str(stored) != key:
        return None
    return arrays


def save(name: str, key: str, arrays: dict[str, np.ndarray],
         directory: Path | None = None) -> Path:
    """Write the entry atomically (temporary file + fsync + os.replace); returns its path."""
    if _KEY_FIELD in arrays:
        raise ValueError(f"{_KEY_FIELD} is reserved")
    path = entry_path(name, key, directory)
    path.parent.mkdir(parents=True, exist_ok=True)
    _sweep_stale_tmp(path.parent)
    buf = io.BytesIO()
    np.savez(buf, **arrays, **{_KEY_FIELD: np.array(key)})
    write_atomically(path, buf.getvalue())
    return path


def write_atomically(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` whole or not at all (a temporary file beside it, fsync,
    os.replace): a build that fails or is killed midway leaves no half-written entry."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def get_or_build(name: str, description: dict,
                 build: Callable[[], dict[str, np.ndarray]],
                 directory: Path | None = None, use_cache: bool = True
                 ) -> tuple[dict[str, np.ndarray], bool]:
    """Load the entry for ``description`` or build and store it. Returns (arrays, was_hit)."""
    key = make_key(description)
    if not use_cache:
        return build(), False
    hit = load(name, key, directory)
    if hit is not None:
        return hit, True
    with _building(entry_path(name, key, directory)):
        hit = load(name, key, directory)  # built by another process while this one waited
        if hit is not None:
            return hit, True
        arrays = build()
        save(name, key, arrays, directory)
    return arrays, False


@contextmanager
def _building(path: Path) -> Iterator[None]:
    """Hold an exclusive lock on ``path``'s entry while it is built, so that two processes
    asking for the same entry (two book chapters executed at once) build it once."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(path.parent / f".{path.name}.lock", os.O_WRONLY | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)


def _sweep_stale_tmp(directory: Path) -> None:
    """Remove temporary files left by interrupted writes more than an hour ago."""
    now = time.time()
    for tmp in directory.glob(".*.tmp"):
        try:
            if now - tmp.stat().st_mtime > _STALE_TMP_SECONDS:
                tmp.unlink()
        except OSError:
            pass
