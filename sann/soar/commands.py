"""Top-level commands of an agent file, executed against an Agent.

Only the commands an agent file needs exist; anything else is an error that names the
command and where it was written. ``exec``/``cmd`` are refused: a rule file never runs
shell commands or Python.
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, cast

from .chunking.learn import Chunker
from .decision.preference_semantics import POLICIES
from .errors import SoarRuntimeError
from .production import Command, SourceLocation

if TYPE_CHECKING:
    from .agent import Agent

Handler = Callable[["Agent", tuple[str, ...], Path], None]


def execute(agent: Agent, command: Command, base: Path) -> None:
    """Run one command; ``base`` is the directory of the file that holds it."""
    alias = _aliases(agent).get(command.name)
    if alias is not None:
        command = Command(alias[0], alias[1:] + command.args, command.location)
    handler = HANDLERS.get(command.name)
    where = _where(command)
    if command.name in ("exec", "cmd"):
        raise SoarRuntimeError(f"{where}{command.name}: refused, a rule file never runs commands")
    if handler is None:
        raise SoarRuntimeError(f"{where}unknown or unsupported command: {command.name}")
    if handler is _gp:
        handler = functools.partial(_gp, location=command.location)
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
    pushed = agent._pushd
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
    agent._pushd.append(target.resolve())
    agent._dir_stack.append(target.resolve())


def _popd(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    stack = agent._pushd
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


_LEARNING_TRACE = ("noprint", "print", "fullprint")
_TRACE_IGNORED_VALUES = ("0", "1", "2", "on", "off", "remove", "print", "noprint", "fullprint")


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
        elif item in ("--learning", "-L") and items and items[0] in _LEARNING_TRACE:
            # what is printed when a rule is learned
            cast(Chunker, agent.chunker).trace = items.pop(0)
        elif item in _TRACE_IGNORED:
            if items and items[0] in _TRACE_IGNORED_VALUES:
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


#: ``chunk <mode>``: when the kernel would learn (``on`` means ``only``, ``off`` ``never``).
_CHUNK_MODES = {"always": "always", "never": "never", "only": "only", "except": "except",
                "on": "only", "off": "never"}  # fmt: skip
_ON_OFF = ("on", "off")
#: ``chunk <setting> [<value>]``: the kernel's settings (``chunk ?``) and their values
#: (None: an integer).
_CHUNK_SETTINGS: dict[str, tuple[str, ...] | None] = {
    "bottom-only": _ON_OFF, "naming-style": ("numbered", "rule"), "max-chunks": None,
    "max-dupes": None, "interrupt": _ON_OFF, "explain-interrupt": _ON_OFF,
    "warning-interrupt": _ON_OFF, "automatically-create-singletons": _ON_OFF,
    "add-ltm-links": _ON_OFF, "add-osk": _ON_OFF, "allow-local-negations": _ON_OFF,
    "allow-opaque": _ON_OFF,
}  # fmt: skip
_CHUNK_QUERIES = ("?", "help", "stats", "singleton")
_CHUNK_INVALID = "Invalid chunking command.  Use 'chunk ?' to see a list of valid settings."
_CHUNK_BAD_VALUE = (
    "Invalid argument for chunking command. Use 'chunk ?' to see a list of valid settings."
)


def _chunk(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    """``chunk``, as the 9.6 kernel reads it (measured): options (``-x``) are ignored, the
    first word is a mode, a setting with an optional value, or a query; words after the
    mode are ignored. The mode is recorded (`Agent.learning`, see `sann.soar.chunking`);
    ``chunk stats`` prints the counters."""
    words = [word for word in args if not word.startswith("-")]
    if not words:
        return
    first, rest = words[0], words[1:]
    if first in _CHUNK_MODES:
        agent.learning = _CHUNK_MODES[first]
    elif first in _CHUNK_SETTINGS:
        if rest and not _valid_chunk_value(_CHUNK_SETTINGS[first], rest[0]):
            raise SoarRuntimeError(_CHUNK_BAD_VALUE)
    elif first == "stats":
        from .chunking.explain import stats_text

        agent._emit(stats_text(agent))
    elif first not in _CHUNK_QUERIES:
        raise SoarRuntimeError(_CHUNK_INVALID)


def _valid_chunk_value(values: tuple[str, ...] | None, word: str) -> bool:
    if values is None:
        return word.isdigit()
    return word.lower() in values


#: ``learn``'s flags (the kernel's "Syntax: learn [-abdeElonNpP]") and long options.
_LEARN_FLAGS = "abdeElonNpP"
_LEARN_LONG = {"on": "e", "enable": "e", "off": "d", "disable": "d", "only": "o",
               "except": "E", "all-levels": "a", "bottom-up": "b", "list": "l",
               "local-negations": "n"}  # fmt: skip


def _learn(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    """``learn``, the kernel's deprecated form of ``chunk`` (measured in 9.6): only flags,
    any other word is refused; ``-e`` sets always, ``-d`` never, ``-o`` only, applied in
    the order o, e, d whatever the order written (``-de`` and ``-ed`` both end in never);
    ``-E`` (except) is refused by the kernel itself."""
    flags: set[str] = set()
    for word in args:
        if word.startswith("--"):
            if word[2:] not in _LEARN_LONG:
                raise SoarRuntimeError(f"No such option: {word[2:]}")
            flags.add(_LEARN_LONG[word[2:]])
        elif word.startswith("-") and len(word) > 1:
            for flag in word[1:]:
                if flag not in _LEARN_FLAGS:
                    raise SoarRuntimeError(f"No such option: {flag}")
                flags.add(flag)
        else:
            raise SoarRuntimeError(f"Syntax: learn [-{_LEARN_FLAGS}]")
    if "E" in flags:
        raise SoarRuntimeError(_CHUNK_BAD_VALUE)
    for flag, mode in (("o", "only"), ("e", "always"), ("d", "never")):
        if flag in flags:
            agent.learning = mode


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


_EXCISE_GROUPS = {
    "--all": "all", "-a": "all", "--user": "user", "-u": "user", "--default": "default",
    "-d": "default", "--chunks": "chunk", "-c": "chunk", "--rl": "none", "-r": "none",
    "--templates": "none", "-t": "none",
}  # fmt: skip


def _excise(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    """``excise name...`` or a group: ``--all``, ``--user`` (all but ``:default`` rules),
    ``--default``, ``--chunks`` (learned rules, which ``--user`` leaves); ``--rl`` and
    ``--templates`` excise nothing here (this engine has no RL or template rules) and
    succeed, as in the kernel when there are none."""
    for name in args:
        group = _EXCISE_GROUPS.get(name)
        if group is None and name.startswith("-"):
            raise SoarRuntimeError(f"unknown option {name}")
        if group is None:
            agent.excise(name)
        elif group == "all":
            agent.excise_all()
        elif group != "none":
            for rule, info in list(agent._productions.items()):
                flags = info.production.flags
                kind = "default" if "default" in flags else "chunk" if "chunk" in flags else "user"
                if kind == group:
                    agent.excise(rule)


def _explain(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    """``explain [chunk] <name>``: the rule firings a chunk was learned from."""
    from .chunking.explain import explain_text

    try:
        agent._emit(explain_text(agent, args))
    except KeyError as missing:
        raise SoarRuntimeError(f"explain: no chunk named {missing.args[0]} was "
                               "learned") from None


def _init_soar(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    """``init-soar``; the kernel answers with its message, outside the output column."""
    agent.init()
    agent._emit_uncounted("\nAgent reinitialized.\n")


def _aliases(agent: Agent) -> dict[str, tuple[str, ...]]:
    return agent._aliases


def _alias(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    """``alias name command [args]`` defines a command word; ``alias -r name`` removes it;
    ``alias`` or ``alias name`` alone shows nothing here (the kernel lists its aliases)."""
    if args[:1] in (("-r",), ("--remove",)):
        for name in args[1:]:
            _aliases(agent).pop(name, None)
        return
    if len(args) >= 2:
        if args[1] not in HANDLERS and args[1] not in _aliases(agent):
            raise SoarRuntimeError(f"cannot alias {args[0]} to unknown command {args[1]}")
        _aliases(agent)[args[0]] = args[1:]


_MEMORIES = {"rl": "reinforcement learning (RL)", "epmem": "episodic memory (epmem)",
             "smem": "semantic memory (smem)", "wma": "working-memory activation (wma)",
             "svs": "the Spatial Visual System (svs)"}  # fmt: skip

#: The parameter that switches each feature on (``--set <parameter> on``).
_SWITCHES = ("learning", "enabled", "activation")


def _memory(name: str) -> Handler:
    """``rl``, ``epmem``, ``smem``, ``wma`` and ``svs``: this engine has none of them (all
    are off by default in the 9.6 kernel), so only the forms that leave them off are
    accepted; their other parameters do nothing while they are off."""
    feature = _MEMORIES[name]

    def handler(agent: Agent, args: tuple[str, ...], base: Path) -> None:
        items = list(args)
        while items:
            item = items.pop(0)
            if item in ("--enable", "-e", "--on"):
                raise SoarRuntimeError(f"{feature} is not implemented by this engine")
            if item in ("--disable", "-d", "--off"):
                continue
            if item not in ("--set", "-s") or len(items) < 2:
                raise SoarRuntimeError(
                    f"unsupported option {item}: only '--set <parameter> <value>' and "
                    f"'--disable' are accepted ({feature} is not implemented by this engine)"
                )
            param, value = items.pop(0), items.pop(0)
            if param in _SWITCHES and value not in ("off", "0", "false"):
                raise SoarRuntimeError(
                    f"{feature} is not implemented by this engine; only "
                    f"'{param} off' is accepted"
                )

    return handler


def _on_off(args: tuple[str, ...], what: str) -> bool | None:
    """``--on``/``-e``/``on`` -> True, ``--off``/``-d``/``off`` -> False, nothing -> None."""
    if not args:
        return None
    if len(args) == 1 and args[0] in ("--on", "-e", "--enable", "on", "1"):
        return True
    if len(args) == 1 and args[0] in ("--off", "-d", "--disable", "off", "0"):
        return False
    raise SoarRuntimeError(f"{what} expects on or off, got {' '.join(args)}")


def _timers(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    """Timers only measure time; turning them on or off changes nothing else."""
    _on_off(args, "timers")


def _warnings(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    state = _on_off(args, "warnings")
    if state is None:
        agent._emit(f"warnings is {'on' if agent.warnings else 'off'}\n")
    else:
        agent.warnings = state


def _wait_snc(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    """``waitsnc``: with it on, a state that does not change waits instead of impassing."""
    state = _on_off(args, "wait-snc")
    if state is None:
        agent._emit(f"wait-snc is {'on' if agent.wait_snc else 'off'}\n")
    else:
        agent.wait_snc = state


def _max_gp(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    if not args:
        agent._emit(f"max-gp is {_gp_limit(agent)}\n")
        return
    value = _int(args[0])
    if len(args) > 1 or value < 1:
        raise SoarRuntimeError("max-gp expects one positive integer")
    agent.max_gp = value


def _gp_limit(agent: Agent) -> int:
    return agent.max_gp


def _max_goal_depth(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    if not args:
        agent._emit(f"max-goal-depth is {agent.max_goal_depth}\n")
        return
    value = _int(args[0])
    if len(args) > 1 or value < 1:
        raise SoarRuntimeError("max-goal-depth expects one positive integer")
    agent.max_goal_depth = value


_PHASES = ("input", "proposal", "decision", "apply", "output")


def _stop_phase(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    """``soar stop-phase``: where ``run N`` stops. Our runs stop before the apply phase, the
    kernel's default; another phase would change what ``run N`` means, so it is refused."""
    phase = [a.lstrip("-") for a in args if a not in ("--before", "-B")]
    if not phase or phase in (["apply"], ["a"]):
        return
    if len(phase) == 1 and phase[0] in _PHASES:
        raise SoarRuntimeError(
            f"stop-phase {phase[0]} is not supported: this engine's run stops before the "
            "apply phase only (the kernel's default)"
        )
    raise SoarRuntimeError(f"unknown phase {' '.join(args)}")


def _max_nil_output_cycles(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    """Accepted so that agent files load: the limit only bounds the kernel's
    ``run --output`` (run until output), which this engine does not offer."""
    if len(args) > 1 or (args and _int(args[0]) < 1):
        raise SoarRuntimeError("max-nil-output-cycles expects one positive integer")


def _tcl(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    """``soar tcl off``: there is no Tcl interpreter here, so only off is accepted."""
    if _on_off(args, "tcl"):
        raise SoarRuntimeError("Tcl mode is not available in this engine")


def _production(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    """The umbrella ``production`` command of Soar 9.6: its ``excise`` sub-command."""
    if not args or args[0] != "excise":
        what = args[0] if args else "(none)"
        raise SoarRuntimeError(f"unsupported sub-command {what}: only 'production excise'")
    _excise(agent, args[1:], base)


def _soar(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    """The umbrella ``soar`` command of Soar 9.6; with no argument it prints nothing here."""
    if not args:
        return
    handler = _SOAR_SUBCOMMANDS.get(args[0])
    if handler is None:
        raise SoarRuntimeError(f"unsupported sub-command {args[0]}")
    handler(agent, args[1:], base)


def _run(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    """``run``, ``run N``, ``run -d N``: run as the kernel does when a file says so (the
    kernel runs an agent file's ``run`` at source time). Other units are refused."""
    counts = [a for a in args if not a.startswith("-")]
    options = [a for a in args if a.startswith("-")]
    if any(o not in ("-d", "--decision") for o in options) or len(counts) > 1:
        raise SoarRuntimeError(
            f"unsupported form 'run {' '.join(args)}': use run, run N or run -d N (decisions)"
        )
    agent.run(_int(counts[0]) if counts else None)


def _stats(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    """The counting lines of the kernel's ``stats`` (the timing lines are meaningless)."""
    if args:
        raise SoarRuntimeError(f"unsupported option {args[0]}")
    st = agent.stats
    agent._emit(
        f"{st['decisions']} decisions\n{st['elaboration_cycles']} elaboration cycles\n"
        f"{st['production_firings']} production firings\n"
        f"{st['wme_changes']} wme changes ({st['wme_additions']} additions, "
        f"{st['wme_removals']} removals)\nWM size: {st['wm_size']} current\n"
    )


def _print(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    """``print`` / ``print --all`` (rule names, newest first, as the kernel), ``print rule``
    and ``print [-d N] id``."""
    from .printer import format_production

    items, depth, names = list(args), 1, []
    chunks = full = False
    while items:
        item = items.pop(0)
        if item in ("-c", "--chunks"):
            chunks = True
        elif item in ("-f", "--full"):
            full = True
        elif item in ("-j", "--justifications"):
            return  # justifications are not rules here: the kernel lists none either
        elif item in ("-d", "--depth"):
            if not items:
                raise SoarRuntimeError(f"{item} needs a number")
            depth = _int(items.pop(0))
        elif item in ("-a", "--all"):
            continue
        elif item.startswith("-"):
            raise SoarRuntimeError(f"unsupported option {item}")
        else:
            names.append(item)
    if chunks:
        learned = [name for name, info in agent._productions.items()
                   if "chunk" in info.production.flags]
        names = learned[::-1] if full else []
        if not full:
            agent._emit("".join(f"{name} \n" for name in reversed(learned)))
            return
    elif not names:
        agent._emit("".join(f"{name} \n" for name in reversed(agent.productions)))
    for name in names:
        info = agent._productions.get(name)
        if info is not None:
            agent._emit(format_production(info.production) + "\n")
        else:
            agent._emit(agent.print(name, depth) + "\n")


def _matches(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    """``matches``: the match set, or a production's partial matches (introspect.py)."""
    from .introspect import matches_text

    agent._emit(matches_text(agent, args))


def _preferences(agent: Agent, args: tuple[str, ...], base: Path) -> None:
    """``preferences``: a slot's preferences, by type, with their support (introspect.py)."""
    from .introspect import preferences_text

    agent._emit(preferences_text(agent, args))


def _gp(
    agent: Agent, args: tuple[str, ...], base: Path, location: SourceLocation | None = None
) -> None:
    """``gp {name conditions --> actions}`` with ``[a b c]`` value lists: one production per
    combination, named ``name*1``, ``name*2``... with the first list varying fastest, as the
    kernel numbers them. Each is parsed as ``sp {...}`` at the gp's own line and column, so
    an error in one points into the file."""
    if len(args) != 1:
        raise SoarRuntimeError("expects one {braced} production")
    pieces = _gp_pieces(args[0])
    lists = [piece for piece in pieces if isinstance(piece, list)]
    total = math.prod(len(values) for values in lists)
    if total > _gp_limit(agent):
        raise SoarRuntimeError(
            f"gp-max of {_gp_limit(agent)} exceeded: this gp produces {total} productions "
            "('soar max-gp N' sets a higher limit)"
        )
    body = "".join(p for p in pieces if isinstance(p, str))
    name = body.split(None, 1)[0] if body.strip() else ""
    if not name:
        raise SoarRuntimeError("expects a production name")
    prefix = _gp_prefix(location)
    file = location.file if location is not None else "<string>"
    for number, combination in enumerate(_combinations(lists), 1):
        values = iter(combination)
        text = "".join(p if isinstance(p, str) else next(values) for p in pieces)
        text = text.replace(name, f"{name}*{number}", 1)
        agent.load(f"{prefix}sp {{{text}}}", file)


def _gp_prefix(location: SourceLocation | None) -> str:
    """Blank text that puts the generated ``sp {`` where the ``gp {`` was written."""
    if location is None:
        return ""
    return "\n" * (location.line - 1) + " " * (location.column - 1)


def _combinations(lists: list[list[str]]) -> list[tuple[str, ...]]:
    """Every choice of one value per list, the first list varying fastest."""
    combos = itertools.product(*reversed(lists))
    return [tuple(reversed(combo)) for combo in combos]


def _gp_pieces(text: str) -> list[str | list[str]]:
    """Split a gp body into literal text and ``[...]`` value lists; ``|strings|`` and
    ``#`` comments are literal, brackets in them do not count."""
    pieces: list[str | list[str]] = []
    literal = 0
    i = 0
    while i < len(text):
        char = text[i]
        if char in "|#":
            i = _skip_literal(text, i)
            continue
        if char == "]":
            raise SoarRuntimeError("gp syntax error: ']' without '['")
        if char == "[":
            pieces.append(text[literal:i])
            end, values = _value_list(text, i + 1)
            pieces.append(values)
            literal = i = end
            continue
        i += 1
    pieces.append(text[literal:])
    return pieces


def _skip_literal(text: str, start: int) -> int:
    """Index just after the ``|string|`` or ``# comment`` that starts at ``start``."""
    if text[start] == "#":
        end = text.find("\n", start)
        return len(text) if end < 0 else end
    i = start + 1
    while i < len(text) and text[i] != "|":
        i += 2 if text[i] == "\\" else 1
    return i + 1


def _value_list(text: str, start: int) -> tuple[int, list[str]]:
    """The values of a ``[...]`` list whose first value starts at ``start``, and the index
    after its ``]``."""
    values: list[str] = []
    i = start
    while i < len(text):
        char = text[i]
        if char == "]":
            if not values:
                raise SoarRuntimeError("gp can't have empty value collections")
            return i + 1, values
        if char == "[":
            raise SoarRuntimeError("gp syntax error: nested '[' in a value list")
        if char.isspace():
            i += 1
            continue
        end = _skip_literal(text, i) if char == "|" else i
        while end < len(text) and not text[end].isspace() and text[end] not in "[]":
            end += 1
        values.append(text[i:end])
        i = end
    raise SoarRuntimeError("gp syntax error, unmatched values bracket")


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
    "chunk": _chunk,
    "echo": _echo,
    "output": _output,
    "excise": _excise,
    "explain": _explain,
    "init-soar": _init_soar,
    "init": _init_soar,
    "alias": _alias,
    "rl": _memory("rl"),
    "epmem": _memory("epmem"),
    "smem": _memory("smem"),
    "wma": _memory("wma"),
    "svs": _memory("svs"),
    "max-nil-output-cycles": _max_nil_output_cycles,
    "production": _production,
    "timers": _timers,
    "warnings": _warnings,
    "waitsnc": _wait_snc,
    "max-gp": _max_gp,
    "gp-max": _max_gp,
    "max-goal-depth": _max_goal_depth,
    "set-stop-phase": _stop_phase,
    "soar": _soar,
    "run": _run,
    "stats": _stats,
    "print": _print,
    "p": _print,
    "gp": _gp,
    "matches": _matches,
    "preferences": _preferences,
}

_SOAR_SUBCOMMANDS: dict[str, Handler] = {
    "init": _init_soar,
    "max-elaborations": _max_elaborations,
    "max-goal-depth": _max_goal_depth,
    "max-gp": _max_gp,
    "wait-snc": _wait_snc,
    "stop-phase": _stop_phase,
    "timers": _timers,
    "max-nil-output-cycles": _max_nil_output_cycles,
    "tcl": _tcl,
}
