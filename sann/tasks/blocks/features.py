"""The sensor of the blocks world: noisy observed centres and the Table-1 features.

Features (Table 1 of the paper, in this column order): X, Y, Z (observed centre), Distance
(from the observed centre to the robot base, clipped to 130), Size, Color, Target (the block's
own id), Left, Right, Front, Back, Up, Down: the id of the neighbour on that side, 0 for
none/table. They are computed from centres observed with Gaussian sensor noise; a block ``c``
is the neighbour of ``b`` on a side when the gap between the facing faces is below
``neighbour_gap`` (a slightly negative observed gap counts: noise) and the two blocks overlap by
more than ``overlap_eps`` in both other axes; of several, the nearest face wins (then the lower
id). Left is -x, Right +x, Front -y (towards the robot), Back +y, Up +z, Down -z. Because only
one neighbour per side is listed, a 10-block carrying two 5-blocks lists one of them as Up: the
features are, like the paper's, a lossy description, and the labels are not.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .world import DISTANCE_CLIP, ROBOT_BASE, BlockWorldParams, Scene, as_rng, graspable

# (axis, sign) of each side: the neighbour on side "right" has the larger x, etc.
_SIDE_AXES = ((0, -1), (0, 1), (1, -1), (1, 1), (2, 1), (2, -1))


def observe(scene: Scene, rng: np.random.Generator | int | None,
            params: BlockWorldParams | None = None) -> np.ndarray:
    """Observed centres: the true centres plus Gaussian noise (sd ``params.sensor_noise``)."""
    params = params or BlockWorldParams()
    gen = as_rng(rng)
    return scene.centre + gen.normal(0.0, params.sensor_noise, size=scene.centre.shape)


def neighbours(scene: Scene, centre: np.ndarray, params: BlockWorldParams | None = None
               ) -> np.ndarray:
    """(n, 6) neighbour ids on the sides Left, Right, Front, Back, Up, Down (0 = none/table)."""
    params = params or BlockWorldParams()
    half = scene.size[:, None] / 2.0
    lo, hi = centre - half, centre + half
    ov = np.minimum(hi[:, None, :], hi[None, :, :]) - np.maximum(lo[:, None, :], lo[None, :, :])
    out = np.zeros((scene.n, 6), dtype=np.int64)
    for k, (axis, sign) in enumerate(_SIDE_AXES):
        if sign > 0:
            gap = lo[None, :, axis] - hi[:, None, axis]
            ahead = centre[None, :, axis] > centre[:, None, axis]
        else:
            gap = lo[:, None, axis] - hi[None, :, axis]
            ahead = centre[None, :, axis] < centre[:, None, axis]
        others = [a for a in range(3) if a != axis]
        ok = ahead & (np.abs(gap) < params.neighbour_gap)
        for a in others:
            ok &= ov[:, :, a] > params.overlap_eps
        np.fill_diagonal(ok, False)
        # nearest face first, then the lower id (slots are in id order)
        score = np.where(ok, np.abs(gap), np.inf)
        best = np.argmin(score, axis=1)
        has = np.isfinite(score[np.arange(scene.n), best])
        out[has, k] = scene.ids[best[has]]
    return out


def features(scene: Scene, centre: np.ndarray | None = None,
             params: BlockWorldParams | None = None) -> np.ndarray:
    """(n, 13) float array of the Table-1 features (``FEATURE_NAMES`` order), by slot.

    ``centre`` is the observed centres (from :func:`observe`); None means the true ones.
    """
    params = params or BlockWorldParams()
    c = scene.centre if centre is None else np.asarray(centre, dtype=np.float64)
    base = np.array(ROBOT_BASE)
    dist = np.minimum(np.linalg.norm(c - base, axis=1), DISTANCE_CLIP)
    cols = [c[:, 0], c[:, 1], c[:, 2], dist, scene.size, scene.color, scene.ids]
    return np.column_stack(cols + [neighbours(scene, c, params)]).astype(np.float64)


@dataclass(frozen=True)
class ObservedScene:
    """A scene with what the sensor reports: the Table-1 feature rows and the true labels."""

    scene: Scene
    features: np.ndarray  # (n, 13) float64
    labels: np.ndarray  # (n,) bool, ground truth


def observe_scene(scene: Scene, rng: np.random.Generator | int | None,
                  params: BlockWorldParams | None = None) -> ObservedScene:
    """Noisy features plus true labels of one scene."""
    params = params or BlockWorldParams()
    obs = observe(scene, rng, params)
    return ObservedScene(scene, features(scene, obs, params), graspable(scene, params))
