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

from dataclasses import dataclass

import numpy as np
import trimesh

from sann.vision.camera import make_pose

MM = 1e-3  # MuJoCo works in SI units
ORIENTATIONS = ("upright", "side", "upside_down")


@dataclass(frozen=True)
class Box:
    """An open cardboard box (mm): inner floor ``length`` (x) by ``width`` (y)."""

    length: float = 300.0
    width: float = 250.0
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
