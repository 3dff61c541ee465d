"""Piles of cups in a cardboard box, made by dropping the cups one by one in MuJoCo.

World frame: mm, z up, the origin at the centre of the top face of the box's floor.  The box
is open at the top: a floor of ``length`` x ``width`` (inner, along x and y) and walls of
``wall_height`` and ``thickness``; it stands on a table (the plane z = -thickness).

Physics: each cup collides as the convex hull of its mesh (the cup is a truncated cone with a
rim, so the hull is nearly the cup itself and is never smaller: no visual interpenetration
hides behind it); it is rendered with the true mesh.  Cups not yet dropped are parked away
from the box, weightless and without contacts, so one compiled model serves the whole pile.
A cup is dropped from just above the pile with a random pose (upright, lying on its side or
upside down, tilted a little, any yaw), and the simulation runs until every cup is at rest
before the next drop.  A cup that ends outside the box is taken out and dropped anew.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import trimesh

from sann.vision.camera import invert_pose, make_pose, rotation_to, transform_points
from sann.vision.cup import cup_mesh, signed_distance

MM = 1e-3  # MuJoCo works in SI units
ORIENTATIONS = ("upright", "side", "upside_down")


@dataclass(frozen=True)
class Box:
    """An open cardboard box (mm): inner floor ``length`` (x) by ``width`` (y)."""

    length: float = 350.0
    width: float = 280.0
    wall_height: float = 150.0
    thickness: float = 5.0

    def __post_init__(self) -> None:
        if min(self.length, self.width, self.wall_height, self.thickness) <= 0:
            raise ValueError(f"box dimensions must be positive: {self}")

    def slabs(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """(centre, half extents) of the floor and the four walls, in mm."""
        hx, hy, h, t = self.length / 2, self.width / 2, self.wall_height, self.thickness
        return [
            (np.array([0.0, 0.0, -t / 2]), np.array([hx + t, hy + t, t / 2])),
            (np.array([hx + t / 2, 0.0, h / 2]), np.array([t / 2, hy + t, h / 2])),
            (np.array([-hx - t / 2, 0.0, h / 2]), np.array([t / 2, hy + t, h / 2])),
            (np.array([0.0, hy + t / 2, h / 2]), np.array([hx, t / 2, h / 2])),
            (np.array([0.0, -hy - t / 2, h / 2]), np.array([hx, t / 2, h / 2])),
        ]

    def contains(self, points: np.ndarray, tol: float = 1.0) -> np.ndarray:
        """Per point: inside the box's inner volume (open top: no upper limit), within tol."""
        p = np.asarray(points)
        return ((np.abs(p[..., 0]) <= self.length / 2 + tol)
                & (np.abs(p[..., 1]) <= self.width / 2 + tol) & (p[..., 2] >= -tol))


TABLE_HALF_SIZE = 800.0


def background_mesh(box: Box | None, table: bool = True,
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices (mm, world), faces and per-face RGB albedo of the box and the table."""
    from sann.vision.render import CARDBOARD_RGB, TABLE_RGB

    parts, colours = [], []
    if box is not None:
        for centre, half in box.slabs():
            parts.append(trimesh.creation.box(extents=2 * half,
                                              transform=make_pose(np.eye(3), centre)))
            colours.append(CARDBOARD_RGB)
    if table:
        z = -(box.thickness if box is not None else 0.0) - 0.5
        s = TABLE_HALF_SIZE
        parts.append(trimesh.Trimesh(vertices=[[-s, -s, z], [s, -s, z], [s, s, z], [-s, s, z]],
                                     faces=[[0, 1, 2], [0, 2, 3]], process=False))
        colours.append(TABLE_RGB)
    if not parts:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int32), np.zeros((0, 3))
    offsets = np.cumsum([0] + [len(p.vertices) for p in parts[:-1]])
    vertices = np.vstack([p.vertices for p in parts])
    faces = np.vstack([p.faces + o for p, o in zip(parts, offsets, strict=True)])
    albedo = np.vstack([np.tile(c, (len(p.faces), 1)) for p, c in zip(parts, colours,
                                                                      strict=True)])
    return vertices, faces.astype(np.int32), albedo


@dataclass(frozen=True)
class DropParams:
    """How cups are dropped and when the pile counts as settled (SI units where MuJoCo's)."""

    p_upright: float = 0.3
    p_side: float = 0.45
    p_upside_down: float = 0.25
    tilt_deg: float = 12.0          # random tilt away from the nominal orientation
    clearance_mm: float = 15.0      # drop height above the top of the pile
    cup_mass_kg: float = 0.015      # a paper cup with its lid
    friction: float = 0.6
    timestep: float = 0.002
    settle_speed: float = 0.004     # m/s, every cup slower than this ...
    settle_spin: float = 0.08       # rad/s, ... and turning slower than this
    settle_checks: int = 3          # ... at this many consecutive checks
    check_every: int = 10           # steps between checks
    max_drop_time: float = 2.0      # s of simulated time per drop before giving up waiting
    max_attempts: int = 4           # drops per cup before the pile is declared full
    hull_segments: int = 24         # the collision hull's resolution

    def kind_probabilities(self) -> np.ndarray:
        p = np.array([self.p_upright, self.p_side, self.p_upside_down], dtype=float)
        if np.any(p < 0) or p.sum() <= 0:
            raise ValueError(f"orientation probabilities must be >= 0 and not all 0: {p}")
        return p / p.sum()


@dataclass(frozen=True, eq=False)
class Pile:
    """A settled pile: cup-to-world poses (N, 4, 4) in mm, the box, and how it was made."""

    poses: np.ndarray
    box: Box
    seed: int
    kinds: tuple[str, ...] = ()       # nominal orientation of each cup when it was dropped
    sim_time: float = 0.0             # simulated seconds
    redrops: int = 0                  # drops that ended outside the box and were repeated
    requested: int = 0                # cups asked for (a full box may hold fewer)

    @property
    def n_cups(self) -> int:
        return len(self.poses)

    @property
    def axes(self) -> np.ndarray:
        """Each cup's axis (bottom to lid) in the world frame, (N, 3)."""
        return self.poses[:, :3, 2]

    @property
    def centres(self) -> np.ndarray:
        return self.poses[:, :3, 3]

    def to_dict(self) -> dict:
        """JSON-ready description (poses as nested lists), for caching datasets."""
        return {"poses": self.poses.tolist(), "box": asdict(self.box), "seed": self.seed,
                "kinds": list(self.kinds), "sim_time": self.sim_time, "redrops": self.redrops,
                "requested": self.requested}

    @classmethod
    def from_dict(cls, data: dict) -> Pile:
        """Inverse of ``to_dict``."""
        poses = np.asarray(data["poses"], dtype=float).reshape(-1, 4, 4)
        return cls(poses=poses, box=Box(**data["box"]), seed=int(data["seed"]),
                   kinds=tuple(data.get("kinds", ())), sim_time=float(data.get("sim_time", 0)),
                   redrops=int(data.get("redrops", 0)),
                   requested=int(data.get("requested", len(poses))))


def _xml(n_cups: int, box: Box, params: DropParams) -> str:
    hull = cup_mesh(params.hull_segments).vertices * MM
    vert = " ".join(f"{v:.6f}" for v in hull.ravel())
    walls = "\n".join(
        f'<geom type="box" pos="{" ".join(map(str, c * MM))}" size="{" ".join(map(str, h * MM))}"'
        ' rgba="0.8 0.6 0.4 1"/>' for c, h in box.slabs())
    park = "\n".join(
        f'<body name="cup{i}" pos="{2 + 0.2 * i} 2 1"><freejoint/>'
        f'<geom type="mesh" mesh="cup" mass="{params.cup_mass_kg}"/></body>'
        for i in range(n_cups))
    return f"""<mujoco>
  <option timestep="{params.timestep}" integrator="implicitfast" cone="elliptic"/>
  <default><geom friction="{params.friction} 0.005 0.0001" solref="0.005 1" condim="4"/>
  </default>
  <asset><mesh name="cup" vertex="{vert}"/></asset>
  <worldbody>
    <geom type="plane" size="1 1 0.01" pos="0 0 {-box.thickness * MM}"/>
    {walls}
    {park}
  </worldbody>
</mujoco>"""


class _Sim:
    """The MuJoCo model of one pile: the box, and n cups parked until dropped."""

    def __init__(self, n_cups: int, box: Box, params: DropParams) -> None:
        import mujoco

        self.mj = mujoco
        self.params = params
        self.model = mujoco.MjModel.from_xml_string(_xml(n_cups, box, params))
        self.data = mujoco.MjData(self.model)
        self.bodies = [self.model.body(f"cup{i}").id for i in range(n_cups)]
        self.geoms = [self.model.body_geomadr[b] for b in self.bodies]
        self.qpos = [self.model.jnt_qposadr[self.model.body_jntadr[b]] for b in self.bodies]
        self.dofs = [self.model.jnt_dofadr[self.model.body_jntadr[b]] for b in self.bodies]
        self.active: list[int] = []
        for i in range(n_cups):
            self._park(i)
        mujoco.mj_forward(self.model, self.data)

    def _park(self, i: int) -> None:
        """Cup i weightless, without contacts, far from the box."""
        self.model.body_gravcomp[self.bodies[i]] = 1.0
        self.model.geom_contype[self.geoms[i]] = 0
        self.model.geom_conaffinity[self.geoms[i]] = 0
        q = self.qpos[i]
        self.data.qpos[q:q + 7] = [2.0 + 0.2 * i, 2.0, 1.0, 1, 0, 0, 0]
        self.data.qvel[self.dofs[i]:self.dofs[i] + 6] = 0.0

    def drop(self, i: int, pose_mm: np.ndarray) -> None:
        """Put cup i at a pose (mm) at rest, with gravity and contacts."""
        self.model.body_gravcomp[self.bodies[i]] = 0.0
        self.model.geom_contype[self.geoms[i]] = 1
        self.model.geom_conaffinity[self.geoms[i]] = 1
        quat = np.zeros(4)
        self.mj.mju_mat2Quat(quat, pose_mm[:3, :3].ravel())
        q = self.qpos[i]
        self.data.qpos[q:q + 7] = np.concatenate([pose_mm[:3, 3] * MM, quat])
        self.data.qvel[self.dofs[i]:self.dofs[i] + 6] = 0.0
        self.active.append(i)

    def remove(self, i: int) -> None:
        self.active.remove(i)
        self._park(i)

    def settle(self) -> float:
        """Step until every active cup is at rest (or the time cap); simulated seconds."""
        p = self.params
        steps = 0
        calm = 0
        max_steps = int(p.max_drop_time / p.timestep)
        dofs = np.array([[d + k for k in range(6)] for d in (self.dofs[i] for i in self.active)])
        while steps < max_steps and calm < p.settle_checks:
            for _ in range(p.check_every):
                self.mj.mj_step(self.model, self.data)
            steps += p.check_every
            v = self.data.qvel[dofs]
            lin = np.linalg.norm(v[:, :3], axis=1).max()
            ang = np.linalg.norm(v[:, 3:], axis=1).max()
            calm = calm + 1 if lin < p.settle_speed and ang < p.settle_spin else 0
        return steps * p.timestep

    def pose(self, i: int) -> np.ndarray:
        b = self.bodies[i]
        return make_pose(self.data.xmat[b].reshape(3, 3), self.data.xpos[b] / MM)


def _hull_vertices(params: DropParams) -> np.ndarray:
    return np.asarray(cup_mesh(params.hull_segments).vertices)


def _drop_pose(rng: np.random.Generator, box: Box, top_z: float, params: DropParams,
               ) -> tuple[np.ndarray, str]:
    """A random pose above the pile whose cup lies within the box's walls (xy)."""
    kind = ORIENTATIONS[rng.choice(3, p=params.kind_probabilities())]
    nominal = {"upright": [0, 0, 1], "side": None, "upside_down": [0, 0, -1]}[kind]
    if nominal is None:
        a = rng.uniform(0, 2 * np.pi)
        nominal = [np.cos(a), np.sin(a), 0.0]
    tilt = np.radians(params.tilt_deg) * np.sqrt(rng.uniform())
    direction = rng.uniform(0, 2 * np.pi)
    axis = rotation_to(nominal) @ np.array(
        [np.sin(tilt) * np.cos(direction), np.sin(tilt) * np.sin(direction), np.cos(tilt)])
    rot = rotation_to(axis, yaw=rng.uniform(0, 2 * np.pi))
    v = _hull_vertices(params) @ rot.T
    lo, hi = v.min(axis=0), v.max(axis=0)
    margin = 2.0
    xy = [rng.uniform(-half - lo[k] + margin, half - hi[k] - margin)
          for k, half in ((0, box.length / 2), (1, box.width / 2))]
    z = max(top_z, 0.0) + params.clearance_mm - lo[2]
    return make_pose(rot, np.array([xy[0], xy[1], z])), kind


def cup_in_box(pose: np.ndarray, box: Box, tol: float = 3.0, segments: int = 24) -> bool:
    """Whether a cup rests in the box: its centre above the inner floor, and every part of it
    lower than the walls' top inside the walls (above the walls a cup may lean over the rim,
    as cups at the top of a full box do)."""
    v = transform_points(pose, np.asarray(cup_mesh(segments).vertices))
    low = v[:, 2] <= box.wall_height
    return bool(box.contains(pose[:3, 3], tol) and box.contains(v[low], tol).all())


def _cup_inside(pose: np.ndarray, box: Box, params: DropParams) -> bool:
    return cup_in_box(pose, box, segments=params.hull_segments)


def _top_of(sim: _Sim, params: DropParams) -> float:
    verts = _hull_vertices(params)
    return max((transform_points(sim.pose(i), verts)[:, 2].max() for i in sim.active),
               default=0.0)


def make_pile(n_cups: int, seed: int, box: Box | None = None,
              params: DropParams | None = None) -> Pile:
    """Drop ``n_cups`` cups one by one into the box; deterministic for a seed.

    Each cup is dropped once the previous ones are at rest.  A cup that comes to rest outside
    the box is removed and dropped again with a fresh random pose; after
    ``params.max_attempts`` failures for one cup the box is considered full and the pile is
    returned with fewer cups (``Pile.requested`` keeps the number asked for).
    """
    if not isinstance(n_cups, int | np.integer) or not 1 <= n_cups <= 20:
        raise ValueError(f"n_cups must be an integer in 1..20, got {n_cups!r}")
    box = box or Box()
    params = params or DropParams()
    rng = np.random.default_rng(seed)
    sim = _Sim(n_cups, box, params)
    kinds: list[str] = []
    sim_time, redrops = 0.0, 0
    for i in range(n_cups):
        for attempt in range(params.max_attempts):
            pose, kind = _drop_pose(rng, box, _top_of(sim, params), params)
            sim.drop(i, pose)
            sim_time += sim.settle()
            if all(_cup_inside(sim.pose(j), box, params) for j in sim.active):
                kinds.append(kind)
                break
            redrops += 1
            _remove_escaped(sim, box, params, kinds, i)
            if attempt == params.max_attempts - 1:
                return _pile(sim, box, seed, kinds, sim_time, redrops, n_cups)
    return _pile(sim, box, seed, kinds, sim_time, redrops, n_cups)


def _remove_escaped(sim: _Sim, box: Box, params: DropParams, kinds: list[str], new: int,
                    ) -> None:
    """Take every cup that left the box out of the simulation (the new one is never kept)."""
    for j in list(sim.active):
        if j == new or not _cup_inside(sim.pose(j), box, params):
            sim.remove(j)
            if j != new:
                kinds[j] = ""


def _pile(sim: _Sim, box: Box, seed: int, kinds: list[str], sim_time: float, redrops: int,
          requested: int) -> Pile:
    order = sorted(sim.active)
    return Pile(poses=np.array([sim.pose(i) for i in order]).reshape(-1, 4, 4), box=box,
                seed=seed, kinds=tuple(kinds[i] for i in order), sim_time=sim_time,
                redrops=redrops, requested=requested)


def interpenetration(poses: np.ndarray, samples: int = 48) -> float:
    """Deepest penetration (mm, 0 when none) of any cup's surface into another cup.

    The surface of each cup is sampled by the vertices and face centres of its mesh and tested
    against every other cup's exact solid (``signed_distance``).
    """
    poses = np.asarray(poses, dtype=float).reshape(-1, 4, 4)
    mesh = cup_mesh(samples)
    surface = np.vstack([mesh.vertices, mesh.triangles_center])
    deepest = 0.0
    for i, pi in enumerate(poses):
        world = transform_points(pi, surface)
        for j, pj in enumerate(poses):
            if i == j or np.linalg.norm(pi[:3, 3] - pj[:3, 3]) > 2 * 80.0:
                continue  # the cup fits in a sphere of radius 71 mm around its centre
            local = transform_points(invert_pose(pj), world)
            deepest = max(deepest, float(-signed_distance(local).min()))
    return deepest


def resimulate(pile: Pile, seconds: float = 0.3, params: DropParams | None = None) -> np.ndarray:
    """Poses (N, 4, 4) after placing the pile's cups at rest and letting physics run on.

    A settled pile barely moves; used to check that the piles are at rest.
    """
    params = params or DropParams()
    sim = _Sim(pile.n_cups, pile.box, params)
    for i, pose in enumerate(pile.poses):
        sim.drop(i, pose)
    for _ in range(int(round(seconds / params.timestep))):
        sim.mj.mj_step(sim.model, sim.data)
    return np.array([sim.pose(i) for i in range(pile.n_cups)]).reshape(-1, 4, 4)
