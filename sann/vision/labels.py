"""Ground truth of a pile: visible fraction per cup, which cup lies on/over which, graspability.

Geometry first, from poses only (so it runs on estimated poses too): each cup is cast with
vertical rays on an xy grid (embree), giving per grid cell the top and the underside of the
cup there.  Cup a lies *over* cup b where a vertical line meets both and a's underside is above
b's top, over a minimum area; it lies *on* b when, in addition, the vertical gap is within
the contact tolerance.  Vertical lines make this robust for cups side by side: two cups that
merely touch sideways share no vertical line.

Graspability: the gripper comes straight down.  Its approach corridor around cup i is the
vertical prism over i's footprint grown by ``corridor_margin_mm``; i is *free* when no other
cup has a part inside the corridor above i's top there (i's top taken as the highest point of
i within the margin, so a neighbour beside i, lower than i's nearby top, does not count).  A
cup is graspable when it is free, reachable (in the box, below the workspace's height limit)
and visible (its visible fraction at least ``min_visible_fraction``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from embreex import rtcore_scene
from embreex.mesh_construction import TriangleMesh
from scipy import ndimage

from sann.vision.camera import Camera, transform_points
from sann.vision.cup import cup_mesh
from sann.vision.piles import Box, Pile, cup_in_box
from sann.vision.render import RenderResult, render, render_cup

RAY_START_MM = 2000.0  # rays start this far above / below the world origin


@dataclass(frozen=True)
class LabelParams:
    """Every threshold of the labels, in one place (mm unless stated)."""

    grid_mm: float = 2.0                # xy spacing of the vertical rays
    over_tolerance_mm: float = 3.0      # a's underside may dip this much below b's top
    min_overlap_mm2: float = 40.0       # "over" needs this much shared footprint
    contact_mm: float = 5.0             # "on" = over with a vertical gap at most this
    corridor_margin_mm: float = 5.0     # gripper fingers around the cup's footprint
    min_visible_fraction: float = 0.5   # visible enough to be seen and grasped
    max_height_mm: float = 350.0        # the workspace's height limit above the box floor

    def __post_init__(self) -> None:
        if self.grid_mm <= 0 or self.min_overlap_mm2 < 0 or self.corridor_margin_mm < 0:
            raise ValueError(f"invalid label parameters: {self}")
        if not 0.0 <= self.min_visible_fraction <= 1.0:
            raise ValueError("min_visible_fraction must lie in [0, 1]")

    @property
    def min_cells(self) -> int:
        return max(1, int(np.ceil(self.min_overlap_mm2 / self.grid_mm**2)))


@dataclass(frozen=True)
class HeightMaps:
    """Per cup and grid cell: top and underside z (mm), NaN where the vertical line misses."""

    top: np.ndarray      # (N, H, W)
    bottom: np.ndarray   # (N, H, W)
    origin: np.ndarray   # world xy of cell (0, 0)'s centre
    cell: float

    @property
    def hit(self) -> np.ndarray:
        return ~np.isnan(self.top)


@dataclass(frozen=True)
class CupRelations:
    """``over[a, b]``: cup a lies over cup b; ``on[a, b]``: ... and rests on it (touching);
    ``gap[a, b]``: smallest vertical gap (mm) where a is over b, +inf where it is not."""

    over: np.ndarray
    on: np.ndarray
    gap: np.ndarray

    def pairs(self, relation: str = "on") -> list[tuple[int, int]]:
        """(upper, lower) index pairs of a relation, "on" or "over"."""
        if relation not in ("on", "over"):
            raise ValueError(f"relation must be 'on' or 'over', got {relation!r}")
        return [tuple(map(int, p)) for p in np.argwhere(getattr(self, relation))]


@dataclass(frozen=True)
class GraspLabels:
    """Per cup: graspable = free and reachable and visible; the parts kept for inspection."""

    graspable: np.ndarray
    free: np.ndarray
    reachable: np.ndarray
    visible: np.ndarray
    visible_fraction: np.ndarray
    blockers: tuple[tuple[int, ...], ...]   # the cups inside each cup's corridor, above it


def _poses(poses: Pile | np.ndarray) -> np.ndarray:
    p = np.asarray(getattr(poses, "poses", poses), dtype=float)
    if p.ndim != 3 or p.shape[1:] != (4, 4):
        raise ValueError(f"poses must have shape (N, 4, 4), got {p.shape}")
    return p


def height_maps(poses: Pile | np.ndarray, cell: float = 2.0, pad: float = 10.0) -> HeightMaps:
    """Cast vertical rays down and up through every cup, alone, on a common xy grid."""
    poses = _poses(poses)
    mesh = cup_mesh()
    verts = [transform_points(p, np.asarray(mesh.vertices)) for p in poses]
    if not verts:
        return HeightMaps(np.zeros((0, 1, 1)), np.zeros((0, 1, 1)), np.zeros(2), cell)
    allv = np.vstack(verts)
    origin = allv[:, :2].min(axis=0) - pad
    shape = np.ceil((allv[:, :2].max(axis=0) + pad - origin) / cell).astype(int)[::-1]
    top = np.full((len(poses), *shape), np.nan)
    bottom = np.full_like(top, np.nan)
    faces = np.asarray(mesh.faces, dtype=np.int32)
    for i, v in enumerate(verts):
        lo = np.floor((v[:, :2].min(axis=0) - origin) / cell).astype(int)
        hi = np.ceil((v[:, :2].max(axis=0) - origin) / cell).astype(int) + 1
        yy, xx = np.mgrid[lo[1]:hi[1], lo[0]:hi[0]]
        xy = origin + np.stack([xx.ravel(), yy.ravel()], axis=1) * cell
        scene = rtcore_scene.EmbreeScene()
        TriangleMesh(scene=scene, vertices=v.astype(np.float32), indices=faces)
        for sign, out in ((1.0, top), (-1.0, bottom)):
            org = np.column_stack([xy, np.full(len(xy), sign * RAY_START_MM)]).astype(np.float32)
            d = np.tile(np.float32([0.0, 0.0, -sign]), (len(xy), 1))
            res = scene.run(org, d, output=1)
            z = np.where(res["primID"] >= 0, sign * (RAY_START_MM - res["tfar"]), np.nan)
            out[i, lo[1]:hi[1], lo[0]:hi[0]] = z.reshape(yy.shape)
    return HeightMaps(top, bottom, origin, cell)


def _above_counts(bottom: np.ndarray, top: np.ndarray, tol: float) -> tuple[int, float]:
    """Cells where both are defined and ``bottom >= top - tol``, and the smallest such gap."""
    with np.errstate(invalid="ignore"):
        above = bottom >= top - tol
    n = int(np.count_nonzero(above))
    return n, float(np.min(bottom[above] - top[above])) if n else np.inf


def cup_relations(poses: Pile | np.ndarray, params: LabelParams | None = None,
                  maps: HeightMaps | None = None) -> CupRelations:
    """Which cup lies over / on which, from poses only (true or estimated)."""
    params = params or LabelParams()
    maps = maps or height_maps(poses, params.grid_mm)
    n = len(maps.top)
    over = np.zeros((n, n), dtype=bool)
    gap = np.full((n, n), np.inf)
    for a in range(n):
        for b in range(n):
            if a == b:
                continue
            count, g = _above_counts(maps.bottom[a], maps.top[b], params.over_tolerance_mm)
            if count >= params.min_cells:
                over[a, b], gap[a, b] = True, g
    # Overlapping (estimated) cups can look over each other both ways: keep the larger share.
    both = over & over.T
    for a, b in np.argwhere(np.triu(both)):
        keep_ab = _share(maps, a, b, params) >= _share(maps, b, a, params)
        over[b, a], over[a, b] = not keep_ab, keep_ab
    gap[~over] = np.inf
    return CupRelations(over=over, on=over & (gap <= params.contact_mm), gap=gap)


def _share(maps: HeightMaps, a: int, b: int, params: LabelParams) -> int:
    with np.errstate(invalid="ignore"):
        return int(np.count_nonzero(maps.bottom[a] >= maps.top[b] - params.over_tolerance_mm))


def corridor_blockers(maps: HeightMaps, params: LabelParams) -> list[tuple[int, ...]]:
    """For each cup, the other cups with a part in its approach corridor above its top."""
    radius = int(round(params.corridor_margin_mm / maps.cell))
    yy, xx = np.mgrid[-radius:radius + 1, -radius:radius + 1]
    disk = xx**2 + yy**2 <= radius**2
    blockers = []
    for i in range(len(maps.top)):
        top = np.where(np.isnan(maps.top[i]), -np.inf, maps.top[i])
        grown = ndimage.grey_dilation(top, footprint=disk, mode="constant", cval=-np.inf)
        grown[np.isinf(grown)] = np.nan
        blockers.append(tuple(
            j for j in range(len(maps.top))
            if j != i and _above_counts(maps.bottom[j], grown, params.over_tolerance_mm)[0]
            >= params.min_cells))
    return blockers


def visible_fractions(poses: Pile | np.ndarray, camera: Camera,
                      rendered: RenderResult | None = None, box: Box | None = None,
                      ) -> np.ndarray:
    """Per cup: pixels seen in the scene / pixels it would cover alone in the image.

    ``rendered`` is the scene's render (made here when not given, with ``box`` or the pile's
    box); a cup entirely outside the image gets 0.
    """
    p = _poses(poses)
    scene = rendered if rendered is not None else render(
        poses if isinstance(poses, Pile) else p, camera, box=box)
    seen = np.bincount(scene.instance[scene.instance >= 0].ravel(), minlength=len(p))
    alone = np.array([render_cup(q, camera, frame="world").mask.sum() for q in p])
    return np.divide(seen[:len(p)], alone, out=np.zeros(len(p)), where=alone > 0)


def reachable(poses: Pile | np.ndarray, box: Box | None, params: LabelParams) -> np.ndarray:
    """In the box (when there is one) and with its top within the workspace's height."""
    p = _poses(poses)
    tops = np.array([transform_points(q, np.asarray(cup_mesh(24).vertices))[:, 2].max()
                     for q in p]).reshape(-1)
    inside = np.array([box is None or cup_in_box(q, box) for q in p], dtype=bool)
    return inside & (tops <= params.max_height_mm)


def graspability(poses: Pile | np.ndarray, visible_fraction: np.ndarray, box: Box | None = None,
                 params: LabelParams | None = None, maps: HeightMaps | None = None,
                 ) -> GraspLabels:
    """Ground-truth graspability of each cup (see the module docstring for the definition)."""
    params = params or LabelParams()
    p = _poses(poses)
    box = getattr(poses, "box", box)
    fraction = np.asarray(visible_fraction, dtype=float).reshape(-1)
    if len(fraction) != len(p):
        raise ValueError(f"{len(fraction)} visible fractions for {len(p)} cups")
    maps = maps or height_maps(p, params.grid_mm)
    blockers = corridor_blockers(maps, params)
    free = np.array([not b for b in blockers], dtype=bool)
    reach = reachable(p, box, params)
    visible = fraction >= params.min_visible_fraction
    return GraspLabels(graspable=free & reach & visible, free=free, reachable=reach,
                       visible=visible, visible_fraction=fraction, blockers=tuple(blockers))


@dataclass(frozen=True)
class PileLabels:
    grasp: GraspLabels
    relations: CupRelations


def label_pile(pile: Pile, camera: Camera, rendered: RenderResult | None = None,
               params: LabelParams | None = None) -> PileLabels:
    """Everything the experiments need to know about a pile, from its true poses."""
    params = params or LabelParams()
    maps = height_maps(pile.poses, params.grid_mm)
    fraction = visible_fractions(pile, camera, rendered)
    return PileLabels(grasp=graspability(pile, fraction, params=params, maps=maps),
                      relations=cup_relations(pile.poses, params, maps))
