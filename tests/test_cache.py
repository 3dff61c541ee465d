"""The atomic keyed cache: hits, misses, interrupted and corrupt writes."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from sann import cache


def _arrays() -> dict[str, np.ndarray]:
    return {"x": np.arange(6, dtype=np.float32).reshape(2, 3), "s": np.array(["a", "bc"])}


def test_roundtrip_and_keying(tmp_path: Path) -> None:
    calls = []

    def build() -> dict[str, np.ndarray]:
        calls.append(1)
        return _arrays()

    desc = {"n": 3, "rules_sha256": "abc", "version": "v1"}
    a, hit = cache.get_or_build("t", desc, build, directory=tmp_path)
    assert not hit and len(calls) == 1
    b, hit = cache.get_or_build("t", desc, build, directory=tmp_path)
    assert hit and len(calls) == 1
    assert np.array_equal(a["x"], b["x"]) and b["s"].tolist() == ["a", "bc"]
    _, hit = cache.get_or_build("t", {**desc, "rules_sha256": "abd"}, build, directory=tmp_path)
    assert not hit and len(calls) == 2  # another rule file: another entry


def test_key_is_order_independent() -> None:
    assert cache.make_key({"a": 1, "b": 2}) == cache.make_key({"b": 2, "a": 1})
    assert cache.make_key({"a": 1}) != cache.make_key({"a": 2})


def test_leftover_temp_file_is_not_trusted(tmp_path: Path) -> None:
    key = cache.make_key({"n": 1})
    final = cache.entry_path("t", key, tmp_path)
    # an interrupted write leaves only a temporary file next to where the entry would be
    tmp = tmp_path / f".{final.name}.xyz.tmp"
    tmp.write_bytes(b"PK\x03\x04 half a zip")
    assert cache.load("t", key, tmp_path) is None
    old = 10_000.0
    os.utime(tmp, (os.path.getmtime(tmp) - old, os.path.getmtime(tmp) - old))
    cache.save("t", key, _arrays(), tmp_path)
    assert not tmp.exists()  # stale temporaries are swept
    assert cache.load("t", key, tmp_path) is not None
    assert not list(tmp_path.glob("*.tmp")) and not list(tmp_path.glob(".*.tmp"))


@pytest.mark.parametrize("damage", ["truncate", "garbage", "empty"])
def test_corrupt_entry_is_rebuilt(tmp_path: Path, damage: str) -> None:
    desc = {"n": 2}
    cache.get_or_build("t", desc, _arrays, directory=tmp_path)
    path = cache.entry_path("t", cache.make_key(desc), tmp_path)
    data = path.read_bytes()
    path.write_bytes({"truncate": data[: len(data) // 2], "garbage": b"not a zip at all",
                      "empty": b""}[damage])
    assert cache.load("t", cache.make_key(desc), tmp_path) is None
    rebuilt, hit = cache.get_or_build("t", desc, _arrays, directory=tmp_path)
    assert not hit and np.array_equal(rebuilt["x"], _arrays()["x"])
    assert cache.load("t", cache.make_key(desc), tmp_path) is not None


def test_entry_for_another_key_is_a_miss(tmp_path: Path) -> None:
    k1, k2 = cache.make_key({"a": 1}), cache.make_key({"a": 2})
    cache.save("t", k1, _arrays(), tmp_path)
    # a file renamed onto k2's name still carries k1 inside: not trusted
    cache.entry_path("t", k1, tmp_path).rename(cache.entry_path("t", k2, tmp_path))
    assert cache.load("t", k2, tmp_path) is None


def test_failed_write_leaves_nothing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    def boom(src: str, dst: str) -> None:
        raise OSError("disk full")

    monkeypatch.setattr(cache.os, "replace", boom)
    with pytest.raises(OSError, match="disk full"):
        cache.save("t", cache.make_key({}), _arrays(), tmp_path)
    assert list(tmp_path.iterdir()) == []


def test_env_var_sets_directory(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("SANN_CACHE", str(tmp_path / "c"))
    assert cache.cache_dir() == tmp_path / "c"
    with pytest.raises(ValueError, match="file name"):
        cache.entry_path("a/b", "k")


def test_soar_code_hash_ignores_comments_only(tmp_path: Path) -> None:
    """A comment edit keeps the hash (datasets stay cached); any code edit changes it, and a
    ``#`` inside a quoted symbol or string is code."""
    rules = tmp_path / "r.soar"

    def code_hash(text: str) -> str:
        rules.write_text(text)
        return cache.soar_code_sha256(rules)

    base = code_hash("# header\nsp {a (state <s>) --> (<s> ^x |#1|)} # tail\n")
    assert code_hash("# header, edited\nsp {a (state <s>) --> (<s> ^x |#1|)} # other\n") == base
    assert code_hash("# header\nsp {a (state <s>) --> (<s> ^x |#2|)} # tail\n") != base
    assert code_hash("# header\nsp {a (state <s>) --> (<s> ^y |#1|)} # tail\n") != base
    assert code_hash('# h\nsp {a (state <s>) --> (write "#1")}\n') != code_hash(
        '# h\nsp {a (state <s>) --> (write "#2")}\n')
    assert code_hash("sp {a (state <s>) --> (<s> ^x |a\\|#b|)}\n") != code_hash(
        "sp {a (state <s>) --> (<s> ^x |a\\|#c|)}\n")


def test_the_code_hash_covers_the_files_a_rule_file_sources(tmp_path: Path) -> None:
    """rules/blocks.soar sources the selection space: editing it must miss the dataset cache,
    editing its comments must not."""
    (tmp_path / "lib").mkdir()
    lib = tmp_path / "lib" / "space.soar"
    main = tmp_path / "main.soar"
    main.write_text("source lib/space.soar\nsp {a (state <s>) --> (<s> ^x 1)}\n")
    lib.write_text("sp {b (state <s>) --> (<s> ^y 1)}  # a note\n")
    base = cache.soar_code_sha256(main)
    lib.write_text("sp {b (state <s>) --> (<s> ^y 1)}  # another note\n")
    assert cache.soar_code_sha256(main) == base
    lib.write_text("sp {b (state <s>) --> (<s> ^y 2)}\n")
    assert cache.soar_code_sha256(main) != base


def test_a_comment_on_every_line_leaves_the_productions_and_the_hash(tmp_path: Path) -> None:
    """What soar_code_sha256 relies on: our parser reads the shipped rules with a comment added
    at the end of every line (outside quotes) as the same productions."""
    from sann.soar.agent import Agent
    from sann.soar.printer import format_production

    def productions(path: Path) -> list[str]:
        agent = Agent()
        agent.source(str(path))
        return [format_production(info.production) for info in agent._productions.values()]

    root = Path(__file__).resolve().parents[1] / "rules"
    paths = sorted(root.glob("*.soar")) + sorted(root.glob("default/*.soar"))
    for path in paths:  # the sourced files first, so that a commented file sources them
        commented = tmp_path / path.relative_to(root)
        commented.parent.mkdir(exist_ok=True)
        commented.write_text("\n".join(
            line if "|" in line or '"' in line or line.endswith("\\") else line + "# added"
            for line in path.read_text().split("\n")))
    for path in paths:
        commented = tmp_path / path.relative_to(root)
        assert productions(commented) == productions(path), path.name
        assert cache.soar_code_sha256(commented) == cache.soar_code_sha256(path), path.name


def _build_once_worker(directory: str, log: str) -> None:
    def build() -> dict[str, np.ndarray]:
        with open(log, "a") as fh:
            fh.write("built\n")
        import time

        time.sleep(0.5)
        return _arrays()

    arrays, _ = cache.get_or_build("shared", {"n": 1}, build, directory=Path(directory))
    assert arrays["x"].shape == (2, 3)


def test_processes_missing_the_same_entry_build_it_once(tmp_path: Path) -> None:
    import multiprocessing as mp

    log = tmp_path / "builds.log"
    ctx = mp.get_context("fork")
    procs = [ctx.Process(target=_build_once_worker, args=(str(tmp_path), str(log)))
             for _ in range(2)]
    for p in procs:
        p.start()
    for p in procs:
        p.join(30)
    assert [p.exitcode for p in procs] == [0, 0]
    assert log.read_text().split() == ["built"]
