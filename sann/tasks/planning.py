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

import math
import os
import re
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from sann import RULES

from .backends import InputItem, OutputValue, SannBackend, SmlBackend
from .blocks.features import features
from .blocks.world import FEATURE_NAMES, NAMES, SIDES, BlockWorldParams, Scene

ENGINES = ("sann", "soar_sml")
DEFAULT_RULES = RULES / "blocks.soar"
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


def _scene_items(rows: list[tuple]) -> list[InputItem]:
    """The blocks of :func:`_block_rows` as input-link items."""
    return [("block", [("id", bid), ("name", name), ("size", size), ("x", x), ("y", y),
                       ("z", z), *rel, *rest])
            for bid, name, size, x, y, z, rel, rest in rows]


def _plans(found: list[OutputValue]) -> list[PlanSequence]:
    """The plans of the output-link's ``^sequence`` values (symbols, :func:`parse_sequence`)."""
    plans = []
    for value in found:
        if not isinstance(value, str):
            raise RuntimeError(f"the rules wrote ^sequence {value!r}: a plan symbol "
                               "target:pair:T_o:order was expected")
        plans.append(parse_sequence(value))
    return plans


#: Targets per run when the config says none, in either engine.
_DEFAULT_GROUP = 26


class Planner:
    """A reusable planner: one agent, many scenes.

    ``plan(feats, targets)`` returns ``{target id: [PlanSequence, ...]}`` with every target
    present (an empty list when no plan reached the target), sequences sorted by (pair, T_o,
    order) so that both engines give equal results.
    """

    def __init__(self, config: PlannerConfig | None = None, **kwargs: object) -> None:
        self.config = config or PlannerConfig(**kwargs)  # type: ignore[arg-type]
        rules = Path(self.config.rules)
        self._backend = (SannBackend(rules) if self.config.engine == "sann"
                         else SmlBackend(rules, "blocks"))
        self.group = self.config.targets_per_run or _DEFAULT_GROUP

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
        top: list[InputItem] = [("horizon", cfg.horizon), ("gripper", cfg.gripper())]
        groups = [[("target", t) for t in wanted[g:g + self.group]]
                  for g in range(0, len(wanted), self.group)]
        if isinstance(self._backend, SmlBackend):
            # The scene stays on the input-link while groups of targets are planned.
            scene = self._backend.put(top + _scene_items(rows))
            for group in groups:
                found += _plans(self._backend.run(group, seed=cfg.seed))
            self._backend.remove(scene)
        else:
            for group in groups:
                found += _plans(self._backend.run(top + group + _scene_items(rows),
                                                  seed=cfg.seed))
        result: dict[int, list[PlanSequence]] = {t: [] for t in wanted}
        for seq in found:
            result[seq.target].append(seq)
        return {t: sorted(v, key=lambda s: (s.pair, s.t_o, s.order)) for t, v in result.items()}

    def traced(self, feats: np.ndarray, targets: Iterable[int] | None = None, level: int = 1
               ) -> tuple[dict[int, list[PlanSequence]], str]:
        """Plan one scene as :meth:`plan` does, with the engine's trace at watch ``level``
        (1: decisions -- operators, impasses, substates): ``(plans, trace text)``."""
        if isinstance(self._backend, SannBackend):
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
        if not isinstance(self._backend, SannBackend) or self._backend.agent is None:
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
