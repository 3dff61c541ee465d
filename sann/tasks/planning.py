"""Run ``rules/blocks.soar`` on block scenes, in our engine or in the real Soar kernel.

One driver serves both engines: the scene goes onto the input-link through the engine's own
API (``sann.soar.Agent.input_link`` handles, or ``soar_sml`` ``Create*WME`` calls), the agent
runs until it halts, and the sequences are read back from the output-link. The input-link
schema is documented at the top of the rule file.

What the rules see is what the networks see, but for the whole scene at once: the Table-1
feature rows of every block (observed centre, distance, size, colour, id and the six noisy
neighbour ids), and the gripper's dimensions (``clearance``, ``margin``, ``z_tolerance``). The
rules compute the blocks' boxes and finger slabs from these themselves; nothing computed from
the true geometry or by the labeller reaches them. From them the rules derive side blockage
for the gripper's clearance, which is wider than the sensor's neighbour gap: a block 3 units
beside another has neighbour feature 0 there, yet the fingers do not fit (see the rule file's
header).

The plans are what Soar's search finds (operators per candidate grasp, preferences, tie
impasses searched by the selection space); the output-link holds each distinct plan once, as
``target:pair:T_o:order`` (:func:`parse_sequence`). Where the search found grasps equally good
the agent picks one at random: ``PlannerConfig.seed`` seeds it (``srand``) before every run,
so traces repeat; the plans found do not depend on the pick.

Speed. One agent is reused across scenes; between runs its working memory is reset with
``init-soar`` (``agent.init()`` in ours). The targets are planned one after another in one
run (each in its own substate), so planning them in one run or in several gives the same
sequences (``targets_per_run``; the scene stays on the input-link meanwhile in the kernel).
"""

from __future__ import annotations

import io
import math
import os
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from sann.tasks.sml_agent import SmlAgent

from .blocks import FEATURE_NAMES, NAMES, SIDES, BlockWorldParams, Scene, features

ENGINES = ("sann", "soar_sml")
DEFAULT_RULES = Path(__file__).resolve().parents[2] / "rules" / "blocks.soar"
DEFAULT_HORIZON = 8
# Two blocks must overlap in height by more than this to block a finger (observed heights: the
# true overlaps are multiples of 5, so 1 unit absorbs the sensor noise).
Z_TOLERANCE = 1.0
_COL = {name: i for i, name in enumerate(FEATURE_NAMES)}
_SIDE_COLS = [_COL[s.capitalize()] for s in SIDES]


class PlanSequence(NamedTuple):
    """One logical sequence: grasp the blocks of ``order`` (names) in turn; the last is the
    target, so ``t_o == len(order)``. ``pair`` is the side pair of the target's grasp."""

    target: int
    pair: str
    t_o: int
    order: str


@dataclass(frozen=True)
class PlannerConfig:
    """``horizon``: largest T_o a plan may reach; ``clearance``/``margin``/``z_tolerance``:
    the gripper as the robot knows it (the defaults are ``BlockWorldParams``';
    :func:`sann.tasks.blocks.make_dataset` passes the dataset's); ``seed``: the seed of the
    agent's random generator (``srand``, before every run), which picks among operators the
    search found equally good; the sequences do not depend on it, the trace does."""

    engine: str = "sann"
    rules: str | os.PathLike[str] = DEFAULT_RULES
    horizon: int = DEFAULT_HORIZON
    clearance: float = BlockWorldParams.gripper_finger_width
    margin: float = BlockWorldParams.finger_margin
    z_tolerance: float = Z_TOLERANCE
    seed: int = 0
    targets_per_run: int | None = None  # None: every target of the scene in one run

    def __post_init__(self) -> None:
        if self.engine not in ENGINES:
            raise ValueError(f"engine must be one of {ENGINES}, got {self.engine!r}")
        for name in ("horizon", "seed"):
            value = getattr(self, name)
            low = 1 if name == "horizon" else 0
            if isinstance(value, bool) or not isinstance(value, int) or value < low:
                raise ValueError(f"{name} must be an integer >= {low}, got {value!r}")
        tpr = self.targets_per_run
        if tpr is not None and (isinstance(tpr, bool) or not isinstance(tpr, int) or tpr < 1):
            raise ValueError(f"targets_per_run must be an integer >= 1 or None, got {tpr!r}")
        for name in ("clearance", "margin", "z_tolerance"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and not isinstance(value, bool)
                    and math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
        if not Path(self.rules).is_file():
            raise ValueError(f"rules file not found: {self.rules}")

    def gripper(self) -> list[tuple[str, float]]:
        """The ``^gripper`` object of the input-link."""
        return [("clearance", float(self.clearance)), ("margin", float(self.margin)),
                ("z-tolerance", float(self.z_tolerance))]


def parse_sequence(text: str) -> PlanSequence:
    """A plan as the rules write it on the output-link, ``target:pair:T_o:order``."""
    try:
        target, pair, t_o, order = text.split(":")
        return PlanSequence(int(target), pair, int(t_o), order)
    except ValueError:
        raise ValueError(f"not a plan of rules/blocks.soar (target:pair:T_o:order): "
                         f"{text!r}") from None


def _block_rows(feats: np.ndarray) -> list[tuple]:
    """(id, name, size, x, y, z, [(side, neighbour id) ...], [(attribute, value) ...]) per
    feature row: the row as the networks see it (the attributes are its distance and colour);
    the rules derive the boxes and finger slabs themselves."""
    feats = np.asarray(feats, dtype=np.float64)
    if feats.ndim != 2 or feats.shape[1] != len(FEATURE_NAMES):
        raise ValueError(f"features must be an (n, {len(FEATURE_NAMES)}) array, "
                         f"got shape {feats.shape}")
    rows = []
    for f in feats:
        bid = int(f[_COL["Target"]])
        if not 1 <= bid <= len(NAMES):
            raise ValueError(f"block id {bid} is not in 1..{len(NAMES)}")
        rel = [(side, int(f[c])) for side, c in zip(SIDES, _SIDE_COLS, strict=True) if f[c]]
        rest = [("distance", float(f[_COL["Distance"]])), ("color", int(f[_COL["Color"]]))]
        rows.append((bid, NAMES[bid - 1], int(f[_COL["Size"]]), float(f[0]), float(f[1]),
                     float(f[2]), rel, rest))
    return rows


class _SannBackend:
    """Our engine: a fresh working memory per run via ``agent.init()``."""

    default_group = 26

    def __init__(self, rules: Path) -> None:
        from sann.soar.agent import Agent

        #: What the agent printed in its last run (its `write` output and the halt message):
        #: kept for a reader who asks, never sent to standard output, which would flood the book.
        self.transcript = io.StringIO()
        self.agent = Agent(out=self.transcript)
        self.agent.source(str(rules))

    def run(self, rows: list[tuple], targets: Sequence[int], config: PlannerConfig
            ) -> list[PlanSequence]:
        agent = self.agent
        agent.init()
        self.transcript.seek(0)
        self.transcript.truncate()
        errors = len(agent.errors)
        il = agent.input_link
        agent.srand(config.seed)
        il.add("horizon", config.horizon)
        g = il.add("gripper")
        for attr, value in config.gripper():
            g.add(attr, value)
        for t in targets:
            il.add("target", int(t))
        for bid, name, size, x, y, z, rel, rest in rows:
            b = il.add("block")
            b.add("id", bid)
            b.add("name", name)
            b.add("size", size)
            b.add("x", x)
            b.add("y", y)
            b.add("z", z)
            for side, other in rel:
                b.add(side, other)
            for attr, value in rest:
                b.add(attr, value)
        agent.run()
        if len(agent.errors) > errors:
            raise RuntimeError("the planning rules failed: " + "; ".join(agent.errors[errors:]))
        return [parse_sequence(str(value)) for attr, value in agent.output_link.children()
                if attr == "sequence"]

    def close(self) -> None:
        self.agent = None


class _SmlBackend(SmlAgent):
    """The real Soar kernel through soar_sml: the scene stays on the input-link while groups of
    targets are planned; ``init-soar`` between groups (SML re-sends the input-link)."""

    default_group = 26

    def __init__(self, rules: Path) -> None:
        super().__init__(rules, "blocks")

    def put_scene(self, rows: list[tuple], config: PlannerConfig) -> list:
        a, il = self.agent, self.agent.GetInputLink()
        self.seed = config.seed
        g = a.CreateIdWME(il, "gripper")
        top = [a.CreateIntWME(il, "horizon", config.horizon), g]
        for attr, value in config.gripper():
            a.CreateFloatWME(g, attr, value)
        for bid, name, size, x, y, z, rel, rest in rows:
            b = a.CreateIdWME(il, "block")
            top.append(b)
            a.CreateIntWME(b, "id", bid)
            a.CreateStringWME(b, "name", name)
            a.CreateIntWME(b, "size", size)
            a.CreateFloatWME(b, "x", x)
            a.CreateFloatWME(b, "y", y)
            a.CreateFloatWME(b, "z", z)
            for side, other in rel:
                a.CreateIntWME(b, side, other)
            for attr, value in rest:
                (a.CreateIntWME if isinstance(value, int) else a.CreateFloatWME)(b, attr, value)
        return top

    def run_group(self, targets: Sequence[int]) -> list[PlanSequence]:
        a = self.agent
        il = a.GetInputLink()
        wmes = [a.CreateIntWME(il, "target", int(t)) for t in targets]
        a.Commit()
        a.ExecuteCommandLine(f"srand {self.seed}")
        a.RunSelf(100_000)
        ol = a.GetOutputLink()
        children = [] if ol is None else [ol.GetChild(i) for i in range(ol.GetNumberChildren())]
        out = [parse_sequence(c.GetValueAsString()) for c in children
               if c.GetAttribute() == "sequence"]
        for w in wmes:
            a.DestroyWME(w)
        a.ExecuteCommandLine("init-soar")
        return out

    def clear(self, top: list) -> None:
        for w in top:
            self.agent.DestroyWME(w)
        self.agent.Commit()


class Planner:
    """A reusable planner: one agent, many scenes.

    ``plan(feats, targets)`` returns ``{target id: [PlanSequence, ...]}`` with every target
    present (an empty list when no plan reached the target), sequences sorted by (pair, T_o,
    order) so that both engines give equal results.
    """

    def __init__(self, config: PlannerConfig | None = None, **kwargs: object) -> None:
        self.config = config or PlannerConfig(**kwargs)  # type: ignore[arg-type]
        rules = Path(self.config.rules)
        self._backend = (_SannBackend(rules) if self.config.engine == "sann"
                         else _SmlBackend(rules))
        self.group = self.config.targets_per_run or self._backend.default_group

    def plan(self, feats: np.ndarray, targets: Iterable[int] | None = None
             ) -> dict[int, list[PlanSequence]]:
        rows = _block_rows(feats)
        ids = [r[0] for r in rows]
        if len(set(ids)) != len(ids):
            raise ValueError("block ids in a scene must be unique")
        wanted = ids if targets is None else [int(t) for t in targets]
        missing = sorted(set(wanted) - set(ids))
        if missing:
            raise ValueError(f"targets {missing} are not blocks of the scene")
        cfg = self.config
        found: list[PlanSequence] = []
        if isinstance(self._backend, _SmlBackend):
            top = self._backend.put_scene(rows, cfg)
            for g in range(0, len(wanted), self.group):
                found += self._backend.run_group(wanted[g:g + self.group])
            self._backend.clear(top)
        else:
            for g in range(0, len(wanted), self.group):
                found += self._backend.run(rows, wanted[g:g + self.group], cfg)
        result: dict[int, list[PlanSequence]] = {t: [] for t in wanted}
        for seq in found:
            result[seq.target].append(seq)
        return {t: sorted(v, key=lambda s: (s.pair, s.t_o, s.order)) for t, v in result.items()}

    def traced(self, feats: np.ndarray, targets: Iterable[int] | None = None, level: int = 1
               ) -> tuple[dict[int, list[PlanSequence]], str]:
        """Plan one scene as :meth:`plan` does, with the engine's trace at watch ``level``
        (1: decisions -- operators, impasses, substates): ``(plans, trace text)``."""
        if isinstance(self._backend, _SannBackend):
            agent = self.agent
            agent.trace(level)
            try:
                plans = self.plan(feats, targets)
            finally:
                agent.trace(0)
            return plans, self._backend.transcript.getvalue()
        import soar_sml

        log: list[str] = []
        kernel_agent = self._backend.agent
        handler = kernel_agent.RegisterForPrintEvent(
            soar_sml.smlEVENT_PRINT, lambda _mid, _ud, _ag, msg: log.append(msg), None)
        kernel_agent.ExecuteCommandLine(f"watch {level}")
        try:
            plans = self.plan(feats, targets)
        finally:
            kernel_agent.ExecuteCommandLine("watch 0")
            kernel_agent.UnregisterForPrintEvent(handler)
        # the init-soar that follows each run traces the new top state: not part of the plan
        return plans, re.sub(r"\n +0: ==>S: S1 ?", "", "".join(log))

    @property
    def agent(self):  # -> sann.soar.Agent (imported lazily, as the backend does)
        """Our engine's agent, its working memory as the last run left it (the scene on the
        input-link, the plans on the output-link): what a reader inspects or draws."""
        if not isinstance(self._backend, _SannBackend) or self._backend.agent is None:
            raise ValueError("only a planner of engine 'sann' that is not closed has an agent")
        return self._backend.agent

    def close(self) -> None:
        self._backend.close()

    def __enter__(self) -> Planner:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def plan_scene(
    scene: Scene | np.ndarray,
    targets: Iterable[int] | None = None,
    engine: str = "sann",
    rules: str | os.PathLike[str] = DEFAULT_RULES,
    horizon: int = DEFAULT_HORIZON,
    seed: int = 0,
) -> dict[int, list[PlanSequence]]:
    """Plan one scene: ``{target id: sequences}``.

    ``scene`` is a Scene (planned on its true features, no noise) or an (n, 13) array of
    Table-1 feature rows. ``targets``: block ids, default every block.
    """
    feats = features(scene) if isinstance(scene, Scene) else np.asarray(scene)
    with Planner(PlannerConfig(engine=engine, rules=rules, horizon=horizon, seed=seed)) as p:
        return p.plan(feats, targets)


def t_o_lists(plans: dict[int, list[PlanSequence]]) -> dict[int, list[int]]:
    """``{target: [T_o of each sequence]}``, the input of :func:`sann.fusion.logical_item`."""
    return {t: [s.t_o for s in seqs] for t, seqs in plans.items()}
