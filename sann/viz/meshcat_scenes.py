"""3D views of the tasks with meshcat: block scenes, plans played as animations, cup piles.

Every builder returns a `sann.viz.embed.Scene`: in the built book it shows as a static,
offline viewer; in JupyterLab as a live meshcat viewer. Lengths are converted to metres,
meshcat's unit, so its grid, lights and mouse controls behave: block scenes use one table unit
= 1 cm (the 130-unit table is 1.3 m wide), cup piles are given in mm.
"""

from __future__ import annotations

import io
from collections.abc import Iterable, Sequence
from functools import lru_cache

import meshcat.geometry as g
import meshcat.transformations as tf
import numpy as np
from meshcat.animation import Animation

from sann.tasks import blocks as bw
from sann.viz.embed import Scene

MM = 1e-3  # cup piles: mm -> m
UNIT = 1e-2  # block world: one table unit -> m
#: Block colours 1..4 of Table 1 (red, yellow, blue, green) as 0-255 RGB.
BLOCK_RGB = {1: (214, 64, 64), 2: (240, 196, 48), 3: (64, 112, 214), 4: (64, 170, 92)}
TABLE_COLOUR = 0xB8A58C
ROBOT_COLOUR = 0x404650
HALO_COLOUR = 0x111111
FPS = 30
STEP_FRAMES = 30  # one removal per second
CUP_TRUE_COLOUR = 0xECE8DE
CUP_ESTIMATED_COLOUR = 0xF08C00
CARDBOARD_COLOUR = 0xC49E6C


def rgb_int(rgb: Sequence[float]) -> int:
    """0-255 RGB triple -> the 0xRRGGBB integer meshcat materials take."""
    r, gr, b = (int(round(float(c))) for c in rgb)
    for c in (r, gr, b):
        if not 0 <= c <= 255:
            raise ValueError(f"colour components must lie in 0..255, got {tuple(rgb)}")
    return (r << 16) | (gr << 8) | b


#: Everything a builder draws hangs under this path, so the view can be centred on it.
WORLD = "world"


def set_camera(scene: Scene, target: Sequence[float], offset: Sequence[float]) -> None:
    """Look at ``target`` from ``target + offset`` (world, z up, metres); orbiting stays on.

    meshcat's orbit controls always turn about the viewer's origin (three.js looks at a
    world-space target), so instead of moving the camera the drawing under ``/meshcat/world``
    is shifted to put ``target`` at the origin. The camera's ``position`` is set on
    ``/Cameras/default/rotated/<object>`` in three.js's y-up frame: world (x, y, z) is
    three.js (x, z, -y).
    """
    x, y, z = (float(v) for v in offset)
    if x == y == z == 0.0:
        raise ValueError("the camera offset must be non-zero (a zero offset locks orbiting)")
    scene.vis[WORLD].set_transform(tf.translation_matrix([-float(v) for v in target]))
    scene.vis["/Cameras/default/rotated/<object>"].set_property("position", [x, z, -y])


def style(scene: Scene, grid: bool = True) -> None:
    """Book look: a light background, no axis triad, the ground grid optional."""
    scene.vis["/Background"].set_property("top_color", [0.97, 0.97, 0.98])
    scene.vis["/Background"].set_property("bottom_color", [0.80, 0.84, 0.90])
    scene.vis["/Axes"].set_property("visible", False)
    scene.vis["/Grid"].set_property("visible", grid)


def _poses(poses: np.ndarray | Sequence[np.ndarray], name: str) -> np.ndarray:
    array = np.asarray(poses, dtype=float)
    if array.ndim != 3 or array.shape[1:] != (4, 4):
        raise ValueError(f"{name} must be an array of 4x4 poses (N, 4, 4), got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} contains non-finite values")
    return array


def _metres(pose_mm: np.ndarray) -> np.ndarray:
    pose = np.array(pose_mm, dtype=float)
    pose[:3, 3] *= MM
    return pose


def _mesh_geometry(mesh: object) -> g.TriangularMeshGeometry:
    vertices = np.asarray(getattr(mesh, "vertices", None), dtype=float)
    faces = np.asarray(getattr(mesh, "faces", None))
    if vertices.ndim != 2 or vertices.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3:
        raise ValueError("mesh must have (V, 3) vertices and (F, 3) faces, like a trimesh")
    return g.TriangularMeshGeometry(vertices * MM, faces)


def _draw_box(scene: Scene, box: object) -> None:
    """The open cardboard box of a pile (anything with ``slabs()`` -> (centre, half) mm)."""
    material = g.MeshLambertMaterial(color=CARDBOARD_COLOUR, opacity=0.35)
    for i, (centre, half) in enumerate(box.slabs()):  # type: ignore[attr-defined]
        node = scene.vis[WORLD][f"box/slab{i}"]
        node.set_object(g.Box(list(2 * np.asarray(half) * MM)), material)
        node.set_transform(tf.translation_matrix(list(np.asarray(centre) * MM)))


def cups_scene(
    poses: np.ndarray | Sequence[np.ndarray],
    mesh: object,
    estimated: np.ndarray | Sequence[np.ndarray] | None = None,
    box: object | None = None,
    title: str = "Cup pile",
    height: int = 420,
    mode: str = "auto",
) -> Scene:
    """A pile of cups at their true poses, optionally with estimated poses overlaid.

    ``poses`` and ``estimated`` are cup-to-world 4x4 poses in mm (world z up), ``mesh`` the
    cup (``sann.vision.cup.cup_mesh()``), ``box`` the pile's box (``Pile.box``). True cups are
    solid, estimated ones orange wireframes: where an estimate is right, the two coincide.
    """
    true_poses = _poses(poses, "poses")
    scene = Scene(title=title, height=height, mode=mode)
    style(scene, grid=box is None)
    world = scene.vis[WORLD]
    geometry = _mesh_geometry(mesh)
    solid = g.MeshLambertMaterial(color=CUP_TRUE_COLOUR)
    for i, pose in enumerate(true_poses):
        world[f"cups/true/cup{i}"].set_object(geometry, solid)
        world[f"cups/true/cup{i}"].set_transform(_metres(pose))
    if estimated is not None:
        est = np.zeros((0, 4, 4)) if len(estimated) == 0 else _poses(estimated, "estimated")
        wire = g.MeshBasicMaterial(color=CUP_ESTIMATED_COLOUR, wireframe=True)
        for i, pose in enumerate(est):
            world[f"cups/estimated/cup{i}"].set_object(geometry, wire)
            world[f"cups/estimated/cup{i}"].set_transform(_metres(pose))
    if box is not None:
        _draw_box(scene, box)
    centre = true_poses[:, :3, 3].mean(axis=0) * MM if len(true_poses) else np.zeros(3)
    set_camera(scene, centre, [0.12, -0.3, 0.35])
    return scene


# --------------------------------------------------------------------------- block world


@lru_cache(maxsize=128)
def _letter_png(name: str, colour: int) -> bytes:
    """A face texture: the block's letter on its colour (so every face names the block)."""
    from PIL import Image, ImageDraw, ImageFont

    rgb = ((colour >> 16) & 255, (colour >> 8) & 255, colour & 255)
    image = Image.new("RGB", (64, 64), rgb)
    ink = (255, 255, 255) if sum(rgb) < 400 else (30, 30, 30)
    ImageDraw.Draw(image).text((32, 33), name, font=ImageFont.load_default(size=44), fill=ink,
                               anchor="mm")
    out = io.BytesIO()
    image.save(out, format="PNG", optimize=True)
    return out.getvalue()


def _block_material(name: str, colour_id: int) -> g.MeshLambertMaterial:
    if colour_id not in BLOCK_RGB:
        raise ValueError(f"block colour must be one of {sorted(BLOCK_RGB)}, got {colour_id}")
    texture = g.ImageTexture(g.PngImage(_letter_png(name, rgb_int(BLOCK_RGB[colour_id]))))
    return g.MeshLambertMaterial(color=0xFFFFFF, map=texture)


def _block_pose(centre: Sequence[float]) -> np.ndarray:
    return tf.translation_matrix([float(v) * UNIT for v in centre])


def _check_scene(scene: object) -> bw.Scene:
    if not isinstance(scene, bw.Scene):
        raise TypeError(f"expected a sann.tasks.blocks.Scene, got {type(scene).__name__}")
    return scene


def _frame_camera(view: Scene, scene: bw.Scene, extra: np.ndarray | None = None) -> None:
    """Aim at the blocks' bounding box (and ``extra`` points, in table units) from the
    robot's side of the table, above it."""
    if scene.n:
        lo, hi = scene.lo().min(axis=0), scene.hi().max(axis=0)
    else:
        lo, hi = np.zeros(3), np.array([bw.TABLE_SIZE, bw.TABLE_SIZE, 0.0])
    if extra is not None and len(extra):
        lo, hi = np.minimum(lo, extra.min(axis=0)), np.maximum(hi, extra.max(axis=0))
    centre = (lo + hi) / 2 * UNIT
    radius = max(float(np.max(hi - lo)) * UNIT, 0.35)
    set_camera(view, centre, [0.1 * radius, -0.7 * radius, 0.5 * radius])


def blocks_scene(
    scene: bw.Scene,
    highlight: Iterable[str | int] = (),
    title: str = "Block scene",
    height: int = 420,
    mode: str = "auto",
    frame: bool = True,
) -> Scene:
    """The table, the robot's base and every block as a cube lettered with its name.

    ``highlight`` names (or ids) of blocks to outline, e.g. the target of a plan; ``frame``
    aims the camera at the blocks (off when the caller frames the view). Blocks sit at
    their true centres; ``/meshcat/world/blocks/<name>`` is each block's path.
    """
    scene = _check_scene(scene)
    view = Scene(title=title, height=height, mode=mode)
    style(view, grid=False)
    side = bw.TABLE_SIZE * UNIT
    world = view.vis[WORLD]
    world["table"].set_object(g.Box([side, side, 0.02]), g.MeshLambertMaterial(
        color=TABLE_COLOUR))
    world["table"].set_transform(tf.translation_matrix([side / 2, side / 2, -0.01]))
    base = tf.translation_matrix([v * UNIT for v in bw.ROBOT_BASE])
    robot = g.Cylinder(height=0.04, radius=0.06)  # three.js cylinders stand along y
    world["robot"].set_object(robot, g.MeshLambertMaterial(color=ROBOT_COLOUR))
    world["robot"].set_transform(base)
    marked = {scene.slot(b) for b in highlight}
    for slot, name in enumerate(scene.names):
        size = float(scene.size[slot]) * UNIT
        node = world[f"blocks/{name}"]
        node.set_object(g.Box([size] * 3), _block_material(name, int(scene.color[slot])))
        node.set_transform(_block_pose(scene.centre[slot]))
        if slot in marked:
            node["halo"].set_object(_cube_edges(size * 1.2))
    if frame:
        _frame_camera(view, scene)
    return view


def _cube_edges(side: float) -> g.LineSegments:
    """The 12 edges of a cube centred on the origin, as line segments (an outline)."""
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * side / 2
    pairs = [(a, b) for a in range(8) for b in range(a + 1, 8)
             if np.count_nonzero(corners[a] != corners[b]) == 1]
    points = np.array([corners[i] for pair in pairs for i in pair], dtype=np.float32)
    return g.LineSegments(g.PointsGeometry(points.T), g.LineBasicMaterial(color=HALO_COLOUR))


def _sequence_slots(scene: bw.Scene, sequence: Sequence[str | int]) -> list[int]:
    if len(sequence) == 0:
        raise ValueError("a plan needs at least one block")
    slots = []
    for block in sequence:
        try:
            slots.append(scene.slot(block))
        except (KeyError, ValueError) as err:
            raise ValueError(f"the plan names block {block!r}, which is not in the scene "
                             f"(blocks: {' '.join(scene.names)})") from err
    if len(set(slots)) != len(slots):
        raise ValueError(f"the plan removes a block twice: {list(sequence)}")
    return slots


def parking_spot(k: int) -> np.ndarray:
    """Where the k-th removed block is put down: rows of ten in front of the table (units)."""
    row, col = divmod(k, 10)
    return np.array([10.0 + 12.0 * col, -12.0 - 12.0 * row, 0.0])


def plan_animation(
    scene: bw.Scene,
    sequence: Sequence[str | int],
    title: str = "Plan",
    height: int = 420,
    mode: str = "auto",
    loop: bool = True,
) -> Scene:
    """Play a plan: the blocks of ``sequence`` are lifted off one per second, in order.

    ``sequence`` is a logical sequence from the planner (names or ids), the target last; the
    target is outlined. Removed blocks are set down in rows in front of the table, so the
    final frame shows what the gripper had to clear. Press "Open Controls" in the viewer to
    pause, reset or scrub the animation.
    """
    scene = _check_scene(scene)
    slots = _sequence_slots(scene, sequence)
    view = blocks_scene(scene, highlight=[scene.names[slots[-1]]], title=title, height=height,
                        mode=mode, frame=False)
    _frame_camera(view, scene, np.array([parking_spot(k) for k in range(len(slots))]))
    animation = Animation(default_framerate=FPS)
    lift = float(scene.hi()[:, 2].max()) + 15.0
    for k, slot in enumerate(slots):
        home = scene.centre[slot]
        half = float(scene.size[slot]) / 2
        park = parking_spot(k) + np.array([0.0, 0.0, half])
        up_home, up_park = home.copy(), park.copy()
        up_home[2] = up_park[2] = lift
        start = k * STEP_FRAMES
        keys = [(0, home), (start, home), (start + 8, up_home), (start + 20, up_park),
                (start + 26, park), (len(slots) * STEP_FRAMES + STEP_FRAMES, park)]
        seen: set[int] = set()
        for frame, position in keys:
            if frame in seen:
                continue
            seen.add(frame)
            with animation.at_frame(view.vis, frame) as at:
                at[f"{WORLD}/blocks/{scene.names[slot]}"].set_transform(_block_pose(position))
    view.vis.set_animation(animation, play=True, repetitions=1000 if loop else 1)
    return view
