"""Run ``rules/blocks.soar`` on block scenes, in our engine or in the real Soar kernel.

One driver serves both engines: the scene goes onto the input-link through the engine's own
API (``sann.soar.Agent.input_link`` handles, or ``soar_sml`` ``Create*WME`` calls), the agent
runs until it halts, and the sequences are read back from the output-link. The input-link
schema is documented at the top of the rule file.

What the rules see is what the networks see, but for the whole scene at once: the Table-1
feature rows of every block (observed positions, size, id and the six noisy neighbour ids),
with each block's observed box faces (``^xmin .. ^zmax``, centre -/+ size/2) and its finger
slabs for the gripper's ``clearance`` and ``margin`` (computed here from the same rows); they
never see the true geometry. From them the rules derive side blockage for the gripper's
clearance, which is wider than the sensor's neighbour gap: a block 3 units beside another has
neighbour feature 0 there, yet the fingers do not fit (see the rule file's header).

Speed. One agent is reused across scenes; between runs its working memory is reset with
``init-soar`` (``agent.init()`` in ours). Plans of different targets never interact, so the
targets of a scene can be planned in one run or in several: the sequences are the same. The
real kernel gets slower than linearly with the number of live plans in one run (its P-node
bookkeeping scans a production's pending matches), so the driver plans a few targets per run
there (``targets_per_run``; the scene stays on the input-link meanwhile).
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from sann import RULES

from .backends import InputItem, OutputValue, SannBackend, SmlBackend, sequence_fields
from .blocks import FEATURE_NAMES, NAMES, SIDES, BlockWorldParams, Scene, features

ENGINES = ("sann", "soar_sml")
DEFAULT_RULES = RULES / "blocks.soar"
DEFAULT_CAP = 8
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
    """``cap``: most sequences per target; ``horizon``: largest T_o a plan may reach;
    ``clearance``/``margin``: the gripper's finger width and pad margin (the defaults are
    ``BlockWorldParams``'; :func:`sann.tasks.blocks.make_dataset` passes the dataset's)."""

    engine: str = "sann"
    rules: str | os.PathLike[str] = DEFAULT_RULES
    cap: int = DEFAULT_CAP
    horizon: int = DEFAULT_HORIZON
    clearance: float = BlockWorldParams.gripper_finger_width
    margin: float = BlockWorldParams.finger_margin
    targets_per_run: int | None = None  # None: the engine's best (all in ours, 3 in soar_sml)

    def __post_init__(self) -> None:
        if self.engine not in ENGINES:
            raise ValueError(f"engine must be one of {ENGINES}, got {self.engine!r}")
        for name in ("cap", "horizon"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"{name} must be an integer >= 1, got {value!r}")
        tpr = self.targets_per_run
        if tpr is not None and (isinstance(tpr, bool) or not isinstance(tpr, int) or tpr < 1):
            raise ValueError(f"targets_per_run must be an integer >= 1 or None, got {tpr!r}")
        for name in ("clearance", "margin"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and not isinstance(value, bool)
                    and math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
        if not Path(self.rules).is_file():
            raise ValueError(f"rules file not found: {self.rules}")


def _block_rows(feats: np.ndarray, clearance: float, margin: float) -> list[tuple]:
    """(id, name, size, x, y, z, [(side, neighbour id) ...], [(attribute, value) ...]) per
    feature row. The attributes are the observed box's faces (centre -/+ size/2) and the bounds
    of its finger slabs (faces -/+ ``clearance``; the pad: the faces shrunk by ``margin``; the
    height range shrunk by ``Z_TOLERANCE``), computed here once per block so that the rules
    compare pairs of blocks with predicates only."""
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
        size = int(f[_COL["Size"]])
        rows.append((bid, NAMES[bid - 1], size, float(f[0]), float(f[1]), float(f[2]), rel,
                     _geometry(f[:3], size, clearance, margin)))
    return rows


def _geometry(centre: np.ndarray, size: int, clearance: float, margin: float
              ) -> list[tuple[str, float]]:
    """The input-link geometry of one block (see the rule file's header)."""
    lo, hi = centre - size / 2, centre + size / 2
    out = [(f"{axis}{end}", float(v)) for k, axis in enumerate("xyz")
           for end, v in (("min", lo[k]), ("max", hi[k]))]
    for k, axis in enumerate("xy"):
        out += [(f"{axis}slab-lo", float(lo[k] - clearance)),
                (f"{axis}slab-hi", float(hi[k] + clearance)),
                (f"{axis}pad-lo", float(lo[k] + margin)),
                (f"{axis}pad-hi", float(hi[k] - margin))]
    return out + [("zin-lo", float(lo[2] + Z_TOLERANCE)), ("zin-hi", float(hi[2] - Z_TOLERANCE))]


def _scene_items(rows: list[tuple]) -> list[InputItem]:
    """The blocks of :func:`_block_rows` as input-link items."""
    return [("block", [("id", bid), ("name", name), ("size", size), ("x", x), ("y", y),
                       ("z", z), *rel, *faces])
            for bid, name, size, x, y, z, rel, faces in rows]


def _plans(found: list[OutputValue]) -> list[PlanSequence]:
    return [PlanSequence(int(s["target"]), s["pair"], int(s["t-o"]), s["order"])
            for s in map(sequence_fields, found)]


#: Targets per run when the config says none: all in ours; in the kernel a few, as it slows
#: down with many live plans in one run (see the module's docstring).
_DEFAULT_GROUP = {"sann": len(NAMES), "soar_sml": 3}


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
        self.group = self.config.targets_per_run or _DEFAULT_GROUP[self.config.engine]

    def plan(self, feats: np.ndarray, targets: Iterable[int] | None = None
             ) -> dict[int, list[PlanSequence]]:
        rows = _block_rows(feats, self.config.clearance, self.config.margin)
        ids = [r[0] for r in rows]
        if len(set(ids)) != len(ids):
            raise ValueError("block ids in a scene must be unique")
        wanted = ids if targets is None else [int(t) for t in targets]
        missing = sorted(set(wanted) - set(ids))
        if missing:
            raise ValueError(f"targets {missing} are not blocks of the scene")
        cfg = self.config
        found: list[PlanSequence] = []
        top: list[InputItem] = [("cap", cfg.cap), ("horizon", cfg.horizon)]
        groups = [[("target", t) for t in wanted[g:g + self.group]]
                  for g in range(0, len(wanted), self.group)]
        if isinstance(self._backend, SmlBackend):
            # The scene stays on the input-link while groups of targets are planned.
            scene = self._backend.put(top + _scene_items(rows))
            for group in groups:
                found += _plans(self._backend.run(group))
            self._backend.remove(scene)
        else:
            for group in groups:
                found += _plans(self._backend.run(top + group + _scene_items(rows)))
        result: dict[int, list[PlanSequence]] = {t: [] for t in wanted}
        for seq in found:
            result[seq.target].append(seq)
        return {t: sorted(v, key=lambda s: (s.pair, s.t_o, s.order)) for t, v in result.items()}

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
    cap: int = DEFAULT_CAP,
    horizon: int = DEFAULT_HORIZON,
) -> dict[int, list[PlanSequence]]:
    """Plan one scene: ``{target id: sequences}``.

    ``scene`` is a Scene (planned on its true features, no noise) or an (n, 13) array of
    Table-1 feature rows. ``targets``: block ids, default every block.
    """
    feats = features(scene) if isinstance(scene, Scene) else np.asarray(scene)
    with Planner(PlannerConfig(engine=engine, rules=rules, cap=cap, horizon=horizon)) as p:
        return p.plan(feats, targets)


def t_o_lists(plans: dict[int, list[PlanSequence]]) -> dict[int, list[int]]:
    """``{target: [T_o of each sequence]}``, the input of :func:`sann.fusion.logical_item`."""
    return {t: [s.t_o for s in seqs] for t, seqs in plans.items()}
