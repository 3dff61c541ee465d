"""Top-level commands of an agent file, executed against an Agent.

Only the commands an agent file needs exist; anything else is an error that names the
command and where it was written. ``exec``/``cmd`` are refused: a rule file never runs
shell commands or Python.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from .decide import POLICIES
from .errors import SoarRuntimeError
from .production import Command

if TYPE_CHECKING:
    from .agent import Agent

Handler = Callable[["Agent", tuple[str, ...], Path], None]


def execute(agent: Agent, command: Command, base: Path) -> None:
    """Run one command; ``base`` is the directory of the file that holds it."""
    handler = HANDLERS.get(command.name)
    where = _where(command)
    if command.name in ("exec", "cmd"):
        raise SoarRuntimeError(f"{where}{command.name}: refused, a rule file never runs commands")
    if handler is None:
        raise SoarRuntimeError(f"{where}unknown or unsupported command: {command.name}")
    try:
        handler(agent, command.args, base)
    except SoarRuntimeError as error:
        if str(error).startswith(where) and where:
            raise
        raise SoarRuntimeError(f"{where}{command.name}: {error}") from error


def _where(command: Command) -> str:
    loc = command.location
    return f"{loc.file}:{loc.line}: " if loc is not None else ""


def _source(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    files = [a for a in args if not a.startswith("-")]
    if len(files) != 1:
        raise SoarRuntimeError("expects one file name")
    path = Path(files[0])
    if not path.is_absolute():
        path = _current_dir(agent, base) / path
    agent.source(path)


def _current_dir(agent: Agent, base: Path) -> Path:
    pushed = getattr(agent, "_pushd", None)
    if pushed:
        return pushed[-1]
    return base


def _pushd(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    if len(args) != 1:
        raise SoarRuntimeError("expects one directory")
    target = Path(args[0])
    if not target.is_absolute():
        target = _current_dir(agent, base) / target
    if not target.is_dir():
        raise SoarRuntimeError(f"no such directory: {args[0]}")
    stack = agent.__dict__.setdefault("_pushd", [])
    stack.append(target.resolve())
    agent._dir_stack.append(target.resolve())


def _popd(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    stack = agent.__dict__.get("_pushd")
    if not stack:
        raise SoarRuntimeError("directory stack is empty")
    stack.pop()
    agent._dir_stack.pop()


def _srand(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    if len(args) > 1:
        raise SoarRuntimeError("expects at most one seed")
    agent.srand(_int(args[0]) if args else None)


def _int(text: str) -> int:
    try:
        return int(text)
    except ValueError as error:
        raise SoarRuntimeError(f"expected an integer, got {text!r}") from error


def _float(text: str) -> float:
    try:
        return float(text)
    except ValueError as error:
        raise SoarRuntimeError(f"expected a number, got {text!r}") from error


_TRACE_FLAGS = {
    "--decisions": 1, "-d": 1, "--phases": 2, "-p": 2, "--productions": 3, "-P": 3,
    "--wmes": 4, "-w": 4, "--preferences": 5, "-r": 5,
}  # fmt: skip
_TRACE_IGNORED = (
    "--timetags", "--fullwmes", "--nowmes", "-t", "-f", "-n", "--user", "-u", "--default",
    "-D", "--chunks", "-c", "--justifications", "-j", "--gds", "-g", "--consistency", "-o",
    "--backtracing", "-b", "--indifferent-selection", "-i", "--rl", "-R", "--epmem", "-e",
    "--smem", "-s", "--wma", "-a", "--learning", "-L", "--waterfall", "-W", "--template",
    "-T", "--assertions", "-A", "--gds-wmes", "-G", "--chunk-warnings", "-C",
)  # fmt: skip


def _watch(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    if not args:
        return
    items = list(args)
    level: int | None = None
    while items:
        item = items.pop(0)
        if item in ("-l", "--level"):
            if not items:
                raise SoarRuntimeError("--level needs a number")
            level = _int(items.pop(0))
        elif item.lstrip("-").isdigit():
            level = _int(item)
        elif item in ("--none", "-N"):
            level = 0
        elif item in _TRACE_FLAGS:
            enable = not (items and items[0] in ("0", "off", "remove"))
            if items and items[0] in ("0", "1", "on", "off", "remove"):
                items.pop(0)
            flag_level = _TRACE_FLAGS[item]
            level = (
                max(agent.trace_level, flag_level)
                if enable
                else min(agent.trace_level, flag_level - 1)
            )
        elif item in _TRACE_IGNORED:
            if items and items[0] in ("0", "1", "2", "on", "off", "remove"):
                items.pop(0)
        else:
            raise SoarRuntimeError(f"unknown option {item}")
    if level is not None:
        if not 0 <= level <= 5:
            raise SoarRuntimeError("Expected trace level from 0 to 5.")
        agent.trace(level)


def _multi_attributes(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    if not args or len(args) > 2:
        raise SoarRuntimeError("expects an attribute and an optional count")
    agent.multi_attributes[args[0]] = _int(args[1]) if len(args) == 2 else 10


def _max_elaborations(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    if not args:
        agent._emit(f"\nmax-elaborations is {agent.max_elaborations}")
        return
    value = _int(args[0])
    if value < 1:
        raise SoarRuntimeError("max-elaborations must be a positive integer")
    agent.max_elaborations = value


def _indifferent_selection(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    items = list(args)
    exploration = agent.exploration
    while items:
        item = items.pop(0)
        name = item.lstrip("-")
        aliases = {"g": "epsilon-greedy", "b": "boltzmann", "s": "softmax", "f": "first",
                   "l": "last", "x": "random"}  # fmt: skip
        name = aliases.get(name, name)
        if name in POLICIES and item.startswith("-"):
            exploration.policy = name
        elif name in ("e", "epsilon", "t", "temperature"):
            if not items:
                continue
            value = _float(items.pop(0))
            if name in ("e", "epsilon"):
                if not 0 <= value <= 1:
                    raise SoarRuntimeError("epsilon must be between 0 and 1")
                exploration.epsilon = value
            else:
                if value <= 0:
                    raise SoarRuntimeError("temperature must be positive")
                exploration.temperature = value
        elif name in ("auto-reduce", "a", "stats"):
            if items and items[0] in ("on", "off"):
                items.pop(0)
        else:
            raise SoarRuntimeError(f"unknown option {item}")


def _numeric_indifferent_mode(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    for item in args:
        if item in ("--avg", "-a"):
            agent.exploration.numeric_mode = "avg"
        elif item in ("--sum", "-s"):
            agent.exploration.numeric_mode = "sum"
        else:
            raise SoarRuntimeError(f"unknown option {item}")


def _decide(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    if not args:
        return
    sub, rest = args[0], args[1:]
    if sub == "indifferent-selection":
        _indifferent_selection(agent, rest, base)
    elif sub == "numeric-indifferent-mode":
        _numeric_indifferent_mode(agent, rest, base)
    elif sub in ("set-random-seed", "srand"):
        _srand(agent, rest, base)
    else:
        raise SoarRuntimeError(f"unsupported sub-command {sub}")


_LEARN_OFF = ("--off", "-d", "--disable", "off", "never", "--never")
_LEARN_ON = ("--on", "-e", "--enable", "on", "always", "--always", "only", "except",
             "--only", "--except")  # fmt: skip


def _learn(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    for item in args:
        if item in _LEARN_ON:
            raise SoarRuntimeError(
                "learning (chunking) is not supported by this engine; only 'off' is allowed"
            )
        if item not in _LEARN_OFF and not item.startswith("--") and item not in ("-l",):
            raise SoarRuntimeError(f"unknown option {item}")


def _echo(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    newline = "--nonewline" not in args and "-n" not in args
    text = " ".join(a for a in args if a not in ("--nonewline", "-n"))
    agent._emit(text + ("\n" if newline else ""))


def _output(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    if not args:
        return
    setting, rest = args[0], args[1:]
    known = ("console", "callbacks", "enabled", "warnings", "agent-writes", "echo-commands",
             "print-depth", "log", "command-to-file")  # fmt: skip
    if setting not in known:
        raise SoarRuntimeError(f"unknown setting {setting}")
    if setting == "warnings" and rest:
        agent.warnings = rest[0] in ("on", "1", "yes")


def _excise(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    for name in args:
        if name in ("--all", "-a", "--user", "-u"):
            agent.excise_all()
        else:
            agent.excise(name)


def _init_soar(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    agent.init()


HANDLERS: dict[str, Handler] = {
    "source": _source,
    "pushd": _pushd,
    "popd": _popd,
    "srand": _srand,
    "watch": _watch,
    "trace": _watch,
    "multi-attributes": _multi_attributes,
    "max-elaborations": _max_elaborations,
    "indifferent-selection": _indifferent_selection,
    "numeric-indifferent-mode": _numeric_indifferent_mode,
    "decide": _decide,
    "learn": _learn,
    "chunk": _learn,
    "echo": _echo,
    "output": _output,
    "excise": _excise,
    "init-soar": _init_soar,
}
