"""The multi-block world of the paper's first experiment: geometry, scenes, generation, labels.

Geometry (the paper gives none; this is our reading, stated once here and quoted by the book):

- The table is ``TABLE_SIZE`` x ``TABLE_SIZE`` (130 x 130) units. ``x`` runs left to right,
  ``y`` from the front edge (``y = 0``, where the robot stands) to the back, ``z`` up from the
  table top (``z = 0``). The robot base is the middle of the front edge, ``(65, 0, 0)``.
- A block is an axis-aligned cube given by its centre ``(x, y, z)`` and edge ``size`` (5 or
  10), named A..Z (ids 1..26) and coloured 1..4 (red, yellow, blue, green). A scene draws a
  random subset of the 26 names; sizes and colours are drawn per scene (the paper picks cubes
  from a set of 26 but does not list their sizes and colours).
- No two blocks overlap (touching is allowed). A stacked block rests on exactly one supporting
  block, with its centre over the support's top face, so every stack is statically stable; a
  block may rest on a larger one (a 5 on a 10, anywhere on its top) or on one of its own size
  or smaller (then nearly centred, so a 10 on a 5 overhangs by about 2.5 on each side).

Modes:

- **C1 scattered**: every block on the table; about a third are placed touching (or nearly
  touching) a block already placed, so side blockage occurs.
- **C2 single column**: one stack of all the blocks. The top block is the only block that is
  graspable (nothing rests on it and nothing stands beside it), so a C2 scene has exactly one
  graspable block.
- **C3 complex**: several stacks of different heights whose bases stand side by side (mostly
  touching) in one or more clusters, so blocks are blocked from above and from the sides.

Ground truth (from the TRUE geometry): a top-down two-finger gripper can grasp a block now iff
nothing rests on it and its fingers fit on both sides along x or along y, i.e. the slabs of
width ``gripper_finger_width`` beside both faces of that pair (their extent along the face
shrunk by ``finger_margin`` at each edge: the finger pad) are free of other blocks over the
block's height range (the fingers close on the faces; a block hanging over a slab higher up,
e.g. the overhang of a 10-block on a neighbouring stack, is taken to be reached under).
The fingers need ``gripper_finger_width`` = 4 units, twice the sensor's ``neighbour_gap`` (2):
a side block 2 to 4 units away blocks the grasp but is absent from the block's own features,
so a per-block network cannot see it, while the rules, which see the whole scene's observed
geometry, can (see BlockWorldParams and the header of rules/blocks.soar).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

TABLE_SIZE = 130.0
ROBOT_BASE = (65.0, 0.0, 0.0)
DISTANCE_CLIP = 130.0
MAX_BLOCKS = 26
BLOCK_SIZES = (5, 10)
N_COLORS = 4
COLOR_NAMES = ("red", "yellow", "blue", "green")
MODES = ("C1", "C2", "C3")
NAMES = tuple(chr(ord("A") + i) for i in range(MAX_BLOCKS))
FEATURE_NAMES = (
    "X", "Y", "Z", "Distance", "Size", "Color", "Target",
    "Left", "Right", "Front", "Back", "Up", "Down",
)  # fmt: skip
SIDES = ("left", "right", "front", "back", "up", "down")
_EPS = 1e-6


@dataclass(frozen=True)
class BlockWorldParams:
    """Every tunable constant of the block world, in one place.

    The gripper needs more room than the sensor reports. ``gripper_finger_width`` (4) is the
    free width a finger needs beside a face (finger width plus margin, units of the table);
    ``neighbour_gap`` (2) is the gap below which the sensor lists a side neighbour in the
    Table-1 features. A block whose nearest side block stands 2 to 4 units away therefore has
    neighbour feature 0 on that side and yet cannot be grasped along that axis: its own 13
    features do not carry the blockage (they hold no other block's position), while the Soar
    rules, which see every block's observed box, derive it from the geometry (gap between faces
    below the clearance, overlapping along the face and in height; rules/blocks.soar). This is
    what lets the scene-level reasoning beat a per-block network (paper Fig. 9a, D1).

    ``finger_margin``: a finger's pad covers its face except this much at each side edge, so a
    block that overlaps the finger's slab by less than the margin (a corner grazing it) does not
    stop it.
    ``neighbour_gap``: a face closer than this to another block's face makes it a neighbour feature;
    half the finger width, so a Left..Back feature means "a finger does not fit here" (up to sensor
    noise) but feature 0 does not mean it fits. ``sensor_noise``: standard deviation of the Gaussian
    noise on each observed centre coordinate. ``overlap_eps``: two blocks must overlap by more than
    this in the other two axes to be neighbours (so noise does not make a block on the next level a
    side neighbour). ``touch_prob``: probability that a C1 block, or a C3 stack base, is placed
    against an earlier one. ``near_gap_prob``: probability that such a placement leaves a small gap
    (uniform in [0, 1.5 x finger width), so a third of them are the hidden blockages between
    ``neighbour_gap`` and the finger width, a third are free) instead of touching exactly.
    ``stack_jitter``: the largest offset of a block on a support of its own size or smaller.
    ``min_blocks``/``max_blocks``: the number of blocks of a dataset scene is uniform in this
    range.
    """

    gripper_finger_width: float = 4.0
    finger_margin: float = 1.0
    neighbour_gap: float = 2.0
    sensor_noise: float = 0.2
    overlap_eps: float = 1.0
    touch_prob: float = 0.35
    near_gap_prob: float = 0.7
    stack_jitter: float = 1.0
    min_blocks: int = 2
    max_blocks: int = MAX_BLOCKS

    def __post_init__(self) -> None:
        for name in ("gripper_finger_width", "finger_margin", "neighbour_gap", "sensor_noise",
                     "overlap_eps", "stack_jitter"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value >= 0):
                raise ValueError(f"BlockWorldParams.{name} must be a finite number >= 0, "
                                 f"got {value!r}")
        for name in ("touch_prob", "near_gap_prob"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and 0 <= value <= 1):
                raise ValueError(f"BlockWorldParams.{name} must be in [0, 1], got {value!r}")
        if self.stack_jitter > 2.5:
            raise ValueError("BlockWorldParams.stack_jitter must be <= 2.5 so stacks stay stable")
        _check_n_blocks(self.min_blocks, "BlockWorldParams.min_blocks")
        _check_n_blocks(self.max_blocks, "BlockWorldParams.max_blocks")
        if self.min_blocks > self.max_blocks:
            raise ValueError(f"BlockWorldParams.min_blocks ({self.min_blocks}) exceeds "
                             f"max_blocks ({self.max_blocks})")


def _check_n_blocks(n: object, what: str = "n_blocks") -> int:
    if isinstance(n, bool) or not isinstance(n, int | np.integer):
        raise ValueError(f"{what} must be an integer in 1..{MAX_BLOCKS}, got {n!r}")
    if not 1 <= int(n) <= MAX_BLOCKS:
        raise ValueError(f"{what} must be in 1..{MAX_BLOCKS} (blocks are named A..Z), got {n}")
    return int(n)


def check_mode(mode: object) -> str:
    """Return ``mode`` if it is one of C1, C2, C3; otherwise raise a clear ValueError."""
    if mode not in MODES:
        raise ValueError(f"mode must be one of {', '.join(MODES)}, got {mode!r}")
    return str(mode)


@dataclass(frozen=True)
class Scene:
    """A block scene with explicit geometry (enough to draw it in 3D).

    Arrays are indexed by block *slot* ``0..n-1`` (slots are in increasing id order).
    ``ids``: 1..26 (A=1); ``size``: edge length; ``color``: 1..4; ``centre``: (n, 3) true
    centres; ``support``: slot of the block this one rests on, -1 for the table.
    """

    mode: str
    ids: np.ndarray
    size: np.ndarray
    color: np.ndarray
    centre: np.ndarray
    support: np.ndarray

    @property
    def n(self) -> int:
        return len(self.ids)

    @property
    def names(self) -> list[str]:
        return [NAMES[i - 1] for i in self.ids]

    def lo(self) -> np.ndarray:
        """(n, 3) lower corners."""
        return self.centre - self.size[:, None] / 2.0

    def hi(self) -> np.ndarray:
        """(n, 3) upper corners."""
        return self.centre + self.size[:, None] / 2.0

    def slot(self, name_or_id: str | int) -> int:
        """The slot of a block given by name ('C') or id (3)."""
        bid = NAMES.index(name_or_id) + 1 if isinstance(name_or_id, str) else int(name_or_id)
        hits = np.flatnonzero(self.ids == bid)
        if len(hits) == 0:
            raise KeyError(f"block {name_or_id!r} is not in this scene")
        return int(hits[0])

    def to_dict(self) -> dict:
        """Plain-Python description (for JSON, drawing, the book)."""
        return {
            "mode": self.mode,
            "blocks": [
                {"id": int(i), "name": NAMES[i - 1], "size": int(s), "color": int(c),
                 "centre": [float(v) for v in p], "support": int(sup)}
                for i, s, c, p, sup in zip(self.ids, self.size, self.color, self.centre,
                                           self.support, strict=True)
            ],
        }


def scene_from_blocks(blocks: list[tuple], mode: str = "C3") -> Scene:
    """Build a Scene by hand: ``blocks`` are ``(name, size, (x, y, z), color)`` tuples.

    Used by tests and the book. ``support`` is inferred (the block whose top touches this
    block's bottom and overlaps it most). Overlapping blocks raise ValueError.
    """
    rows = sorted(blocks, key=lambda b: NAMES.index(b[0]))
    ids = np.array([NAMES.index(b[0]) + 1 for b in rows], dtype=np.int64)
    if len(set(ids.tolist())) != len(ids):
        raise ValueError("block names must be unique")
    size = np.array([b[1] for b in rows], dtype=np.float64)
    centre = np.array([b[2] for b in rows], dtype=np.float64).reshape(len(rows), 3)
    color = np.array([b[3] if len(b) > 3 else 1 for b in rows], dtype=np.int64)
    support = _infer_support(centre, size)
    scene = Scene(check_mode(mode), ids, size, color, centre, support)
    if _any_overlap(scene.lo(), scene.hi()):
        raise ValueError("blocks overlap")
    return scene


def _infer_support(centre: np.ndarray, size: np.ndarray) -> np.ndarray:
    lo, hi = centre - size[:, None] / 2, centre + size[:, None] / 2
    support = np.full(len(size), -1, dtype=np.int64)
    for i in range(len(size)):
        if lo[i, 2] <= _EPS:
            continue
        ov = _overlap_xy(lo[i], hi[i], lo, hi)
        touching = (np.abs(hi[:, 2] - lo[i, 2]) < _EPS) & (ov > _EPS)
        if touching.any():
            support[i] = int(np.argmax(np.where(touching, ov, -1.0)))
    return support


def _overlap_xy(lo_i: np.ndarray, hi_i: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Area-free overlap measure: the smaller of the x and y interval overlaps."""
    ox = np.minimum(hi_i[0], hi[:, 0]) - np.maximum(lo_i[0], lo[:, 0])
    oy = np.minimum(hi_i[1], hi[:, 1]) - np.maximum(lo_i[1], lo[:, 1])
    return np.minimum(ox, oy)


def _any_overlap(lo: np.ndarray, hi: np.ndarray) -> bool:
    ov = np.minimum(hi[:, None, :], hi[None, :, :]) - np.maximum(lo[:, None, :], lo[None, :, :])
    inter = (ov > _EPS).all(axis=2)
    np.fill_diagonal(inter, False)
    return bool(inter.any())


# --------------------------------------------------------------------------- generation


class _Builder:
    """Places blocks one at a time, refusing overlaps and positions off the table."""

    def __init__(self, rng: np.random.Generator, params: BlockWorldParams) -> None:
        self.rng = rng
        self.params = params
        self.lo: list[np.ndarray] = []
        self.hi: list[np.ndarray] = []
        self.centre: list[np.ndarray] = []
        self.size: list[float] = []
        self.support: list[int] = []

    def fits(self, centre: np.ndarray, size: float, support: int = -1,
             clearance: float = 0.0) -> bool:
        """On the table, overlapping nothing (nor coming within ``clearance`` of anything in
        x-y), and, when stacked, touching the top of its support only: no block bridges two."""
        lo, hi = centre - size / 2, centre + size / 2
        if lo[0] < -_EPS or lo[1] < -_EPS or hi[0] > TABLE_SIZE + _EPS or hi[1] > TABLE_SIZE + _EPS:
            return False
        if not self.lo:
            return True
        olo, ohi = np.array(self.lo), np.array(self.hi)
        ov = np.minimum(hi, ohi) - np.maximum(lo, olo)
        if (ov > _EPS).all(axis=1).any():
            return False
        if clearance > 0 and (ov[:, :2] > -clearance).all(axis=1).any():
            return False
        footprint = (ov[:, 0] > -_EPS) & (ov[:, 1] > -_EPS)
        if ((np.abs(olo[:, 2] - hi[2]) < _EPS) & footprint).any():
            return False  # it would tuck under a block placed earlier (a second support)
        under = (np.abs(ohi[:, 2] - lo[2]) < _EPS) & footprint
        if support >= 0:
            under[support] = False
        return not bool(under.any())

    def place(self, centre: np.ndarray, size: float, support: int) -> int:
        self.centre.append(centre)
        self.lo.append(centre - size / 2)
        self.hi.append(centre + size / 2)
        self.size.append(size)
        self.support.append(support)
        return len(self.size) - 1

    def random_on_table(self, size: float) -> np.ndarray:
        x, y = self.rng.uniform(size / 2, TABLE_SIZE - size / 2, size=2)
        return np.array([x, y, size / 2])

    def beside(self, j: int, size: float) -> np.ndarray:
        """A table position against block ``j``'s base: touching or a small gap."""
        p = self.params
        gap = 0.0
        if self.rng.random() < p.near_gap_prob:
            gap = self.rng.uniform(0.0, 1.5 * p.gripper_finger_width)
        axis, sign = int(self.rng.integers(2)), (-1.0, 1.0)[int(self.rng.integers(2))]
        cj, sj = self.centre[j], self.size[j]
        slack = max(0.0, (sj + size) / 2 - 2.0)  # keep >= 2 units of face contact
        c = np.array([0.0, 0.0, size / 2])
        c[axis] = cj[axis] + sign * ((sj + size) / 2 + gap)
        c[1 - axis] = cj[1 - axis] + self.rng.uniform(-slack, slack)
        return c

    def on_top(self, j: int, size: float) -> np.ndarray:
        """A position resting on block ``j``, centre over its top face (stable)."""
        sj = self.size[j]
        reach = (sj - size) / 2 if size < sj else self.params.stack_jitter
        off = self.rng.uniform(-reach, reach, size=2)
        cj = self.centre[j]
        return np.array([cj[0] + off[0], cj[1] + off[1], cj[2] + sj / 2 + size / 2])

    def place_scattered(self, size: float, touch_prob: float) -> int:
        """A table position: against an earlier table block (probability ``touch_prob``), or
        anywhere at least two finger widths from every block, so that blocks are near one
        another only where the generator means it."""
        for _attempt in range(400):
            clearance = 0.0
            if self.size and self.rng.random() < touch_prob:
                j = int(self.rng.integers(len(self.size)))
                if self.support[j] != -1:
                    continue
                c = self.beside(j, size)
            else:
                c = self.random_on_table(size)
                clearance = 2.0 * self.params.gripper_finger_width
            if self.fits(c, size, clearance=clearance):
                return self.place(c, size, -1)
        raise RuntimeError("could not place a block on the table (table too crowded)")


def _draw_blocks(n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    ids = np.sort(rng.choice(np.arange(1, MAX_BLOCKS + 1), size=n, replace=False))
    size = rng.choice(np.array(BLOCK_SIZES, dtype=np.float64), size=n)
    color = rng.integers(1, N_COLORS + 1, size=n)
    return ids, size, color


def _build_c1(size: np.ndarray, b: _Builder) -> tuple[_Builder, list[int]]:
    return b, [b.place_scattered(float(s), b.params.touch_prob) for s in size]


def _build_c2(size: np.ndarray, b: _Builder) -> tuple[_Builder, list[int]]:
    order = b.rng.permutation(len(size))
    for _attempt in range(200):
        col = _Builder(b.rng, b.params)
        below = -1
        for k in order:
            s = float(size[k])
            c = col.random_on_table(s) if below == -1 else col.on_top(below, s)
            if not col.fits(c, s, below):
                break
            below = col.place(c, s, below)
        else:
            slot_of = {int(k): slot for slot, k in enumerate(order)}
            return col, [slot_of[k] for k in range(len(size))]
    raise RuntimeError("could not build a single column on the table")


def _build_c3(size: np.ndarray, b: _Builder) -> tuple[_Builder, list[int]]:
    n = len(size)
    rng = b.rng
    k_lo, k_hi = (1, 1) if n == 1 else (max(2, n // 4), max(2, (n + 1) // 2))
    n_stacks = int(rng.integers(k_lo, k_hi + 1))
    heights = 1 + rng.multinomial(n - n_stacks, rng.dirichlet(np.ones(n_stacks)))
    order = rng.permutation(n)
    placed: dict[int, int] = {}
    cursor = 0
    tops: list[int] = []
    for h in heights:  # bases first, side by side
        k = int(order[cursor])
        s = float(size[k])
        touch = 0.85 if tops else 0.0
        placed[k] = _place_base(b, s, touch, tops)
        tops.append(placed[k])
        cursor += int(h)
    cursor = 0
    for stack, h in enumerate(heights):  # then each stack grows upwards
        for k in order[cursor + 1: cursor + int(h)]:
            placed[int(k)] = _place_on_stack(b, float(size[k]), stack, tops)
        cursor += int(h)
    return b, [placed[k] for k in range(n)]


def _place_base(b: _Builder, s: float, touch: float, bases: list[int]) -> int:
    for _attempt in range(400):
        clearance = 0.0
        if bases and b.rng.random() < touch:
            c = b.beside(bases[int(b.rng.integers(len(bases)))], s)
        else:
            c = b.random_on_table(s)
            clearance = 2.0 * b.params.gripper_finger_width
        if b.fits(c, s, clearance=clearance):
            return b.place(c, s, -1)
    raise RuntimeError("could not place a stack base on the table")


def _place_on_stack(b: _Builder, s: float, stack: int, tops: list[int]) -> int:
    """Put a block on top of ``stack``; if it collides there, on another stack or the table."""
    candidates = [stack] + [t for t in b.rng.permutation(len(tops)).tolist() if t != stack]
    for t in candidates:
        for _attempt in range(8):
            c = b.on_top(tops[t], s)
            if b.fits(c, s, tops[t]):
                slot = b.place(c, s, tops[t])
                tops[t] = slot
                return slot
    slot = b.place_scattered(s, 1.0)
    tops.append(slot)
    return slot


_BUILDERS = {"C1": _build_c1, "C2": _build_c2, "C3": _build_c3}


def as_rng(rng: np.random.Generator | int | None) -> np.random.Generator:
    """A Generator from a Generator, an int seed or None (seed 0: everything is seeded)."""
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None:
        return np.random.default_rng(0)
    if isinstance(rng, int | np.integer) and not isinstance(rng, bool):
        return np.random.default_rng(int(rng))
    raise ValueError(f"rng must be a numpy Generator or an int seed, got {rng!r}")


def generate_scene(
    mode: str,
    n_blocks: int,
    rng: np.random.Generator | int | None = None,
    params: BlockWorldParams | None = None,
) -> Scene:
    """Generate one scene of ``n_blocks`` (1..26) blocks in ``mode`` (C1, C2, C3), seeded."""
    mode = check_mode(mode)
    n = _check_n_blocks(n_blocks)
    params = params or BlockWorldParams()
    gen = as_rng(rng)
    ids, size, color = _draw_blocks(n, gen)
    builder, slot_of = _BUILDERS[mode](size, _Builder(gen, params))
    centre = np.array([builder.centre[slot_of[k]] for k in range(n)])
    inverse = {slot: k for k, slot in enumerate(slot_of)}
    support = np.array([inverse.get(builder.support[slot_of[k]], -1) for k in range(n)],
                       dtype=np.int64)
    return Scene(mode, ids, size, color, centre, support)


# --------------------------------------------------------------------------- labels


def rests_on_matrix(scene: Scene) -> np.ndarray:
    """``M[i, j]`` is True when block j rests on block i (touches its top, overlapping it)."""
    lo, hi = scene.lo(), scene.hi()
    touch = np.abs(lo[None, :, 2] - hi[:, None, 2]) < _EPS
    ox = np.minimum(hi[:, None, 0], hi[None, :, 0]) - np.maximum(lo[:, None, 0], lo[None, :, 0])
    oy = np.minimum(hi[:, None, 1], hi[None, :, 1]) - np.maximum(lo[:, None, 1], lo[None, :, 1])
    return touch & (ox > _EPS) & (oy > _EPS)


def _pair_free(scene: Scene, axis: int, width: float, margin: float = 0.0) -> np.ndarray:
    """For each block: both finger slabs along ``axis`` are free over its height range (the
    slab spans the face minus ``margin`` at each side edge)."""
    lo, hi = scene.lo(), scene.hi()
    other = 1 - axis
    free = np.ones(scene.n, dtype=bool)
    for side in (-1, 1):
        slab_lo, slab_hi = lo.copy(), hi.copy()
        slab_lo[:, other] += margin
        slab_hi[:, other] -= margin
        if side < 0:
            slab_lo[:, axis], slab_hi[:, axis] = lo[:, axis] - width, lo[:, axis]
        else:
            slab_lo[:, axis], slab_hi[:, axis] = hi[:, axis], hi[:, axis] + width
        o_a = (np.minimum(slab_hi[:, None, axis], hi[None, :, axis])
               - np.maximum(slab_lo[:, None, axis], lo[None, :, axis]))
        o_b = (np.minimum(slab_hi[:, None, other], hi[None, :, other])
               - np.maximum(slab_lo[:, None, other], lo[None, :, other]))
        o_z = np.minimum(slab_hi[:, None, 2], hi[None, :, 2]) - np.maximum(slab_lo[:, None, 2],
                                                                           lo[None, :, 2])
        hit = (o_a > _EPS) & (o_b > _EPS) & (o_z > _EPS)
        np.fill_diagonal(hit, False)
        free &= ~hit.any(axis=1)
    return free


def graspable(scene: Scene, params: BlockWorldParams | None = None) -> np.ndarray:
    """Ground-truth label per block (bool, by slot) from the true geometry (see module doc)."""
    params = params or BlockWorldParams()
    clear = ~rests_on_matrix(scene).any(axis=1)
    w, m = params.gripper_finger_width, params.finger_margin
    return clear & (_pair_free(scene, 0, w, m) | _pair_free(scene, 1, w, m))
