"""``python -m sann.soar``."""

from __future__ import annotations

import subprocess
import sys

from sann.soar.__main__ import main

RULES = """
sp {p (state <s> ^superstate nil -^done) --> (<s> ^operator <o> +) (<o> ^name hello)}
sp {a (state <s> ^operator.name hello) --> (<s> ^done yes) (write |Hello| (crlf))}
sp {h (state <s> ^done yes) --> (halt)}
"""


def test_runs_files_and_prints_stats(tmp_path, capsys) -> None:
    path = tmp_path / "hello.soar"
    path.write_text(RULES)
    assert main([str(path), "--stats"]) == 0
    out = capsys.readouterr().out
    assert "     1:    O: O1 (hello)Hello\n" in out
    assert "System halted." in out
    assert "1 decisions" in out and "production firings" in out


def test_decision_limit_and_trace_level(tmp_path, capsys) -> None:
    path = tmp_path / "hello.soar"
    path.write_text(RULES)
    assert main([str(path), "--decisions", "1", "--trace", "0"]) == 0
    out = capsys.readouterr().out
    assert "O1" not in out and "Hello" not in out


def test_errors_exit_non_zero(tmp_path, capsys) -> None:
    bad = tmp_path / "bad.soar"
    bad.write_text("sp {broken (state <s>) --> }\n")
    assert main([str(bad)]) == 1
    assert "error" in capsys.readouterr().err
    assert main([str(tmp_path / "missing.soar")]) == 1


def test_module_entry_point(tmp_path) -> None:
    path = tmp_path / "hello.soar"
    path.write_text(RULES)
    done = subprocess.run(
        [sys.executable, "-m", "sann.soar", str(path), "--seed", "3"],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert done.returncode == 0 and "Hello" in done.stdout
