"""The scene model every reader fills and every writer reads.

Data flows one way: read -> :class:`Scene` -> shadow geometry -> :class:`Scene`
-> write. Geometry is float64 triangles in each shape's local frame with a 4x4
world transform; lights are stored in world coordinates.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..lights import DirectionalLight, PointLight, SpotLight

Color = tuple[float, float, float]

# The X3D ``class`` of the groups holding the shapes shadowgeo adds; each added
# Shape's class is ``MARK + "-" + role``, so a reader gives it back its role.
MARK = "shadowgeo-shadows"


def safe_name(text: str) -> str:
    """``text`` made a valid X3D DEF name (an XML NCName): other characters
    become ``_`` and a leading digit, ``-`` or ``.`` gets a ``_`` before it.

    >>> safe_name("1st lamp:a")
    '_1st_lamp_a'
    """
    name = re.sub(r"[^A-Za-z0-9_.\-]", "_", text) or "_"
    return name if re.match(r"[A-Za-z_]", name) else "_" + name


def unique_name(text: str, used: set[str]) -> str:
    """``safe_name(text)``, numbered ``_2``, ``_3``, ... until it is not in
    ``used``; the name is added to ``used``.

    >>> unique_name("lamp", {"lamp"})
    'lamp_2'
    """
    base = name = safe_name(text)
    count = 1
    while name in used:
        count += 1
        name = f"{base}_{count}"
    used.add(name)
    return name


@dataclass
class Material:
    """A shape's look: what the writers need to reproduce it."""

    diffuse_color: Color = (0.8, 0.8, 0.8)
    emissive_color: Color = (0.0, 0.0, 0.0)
    specular_color: Color = (0.0, 0.0, 0.0)
    shininess: float = 0.2
    transparency: float = 0.0
    name: str | None = None


@dataclass
class SceneLight:
    """A light of the scene: its geometry (world coordinates) and how it looks.

    ``shadows`` and ``shadow_intensity`` are X3D 4's fields; ``name`` is the
    DEF name (or the glTF/USD node name) where there is one.
    """

    light: PointLight | DirectionalLight | SpotLight
    name: str | None = None
    color: Color = (1.0, 1.0, 1.0)
    intensity: float = 1.0
    ambient_intensity: float = 0.0
    attenuation: tuple[float, float, float] = (1.0, 0.0, 0.0)
    beam_width: float = math.pi / 4
    on: bool = True
    global_: bool = True
    shadows: bool = False
    shadow_intensity: float = 1.0


@dataclass
class Shape:
    """A triangle mesh with its world transform, material and role.

    Parameters
    ----------
    vertices : (n, 3) float64
        In the shape's local frame.
    faces : (m, 3) int64
        Counter-clockwise seen from the outside (readers fix ``ccw="false"``).
    transform : (4, 4) float64
        Local to world, for column vectors.
    role : str
        ``"geometry"`` for the scene's own shapes, ``"shadow"`` for planar
        shadows and ``"volume"`` for shadow volumes added by shadowgeo.
    group : str, optional
        For added shadows: the name of the group (one per light) they go in.
    source : str, optional
        Where the shape came from, for messages: ``"scene.x3d line 42, Shape DEF='roof'"``.
    """

    vertices: np.ndarray
    faces: np.ndarray
    transform: np.ndarray = field(default_factory=lambda: np.eye(4))
    material: Material = field(default_factory=Material)
    name: str | None = None
    solid: bool = True
    role: str = "geometry"
    group: str | None = None
    source: str | None = None
    casts_shadow: bool = True
    receives_shadow: bool = False

    def __post_init__(self) -> None:
        self.vertices = np.asarray(self.vertices, dtype=np.float64).reshape(-1, 3)
        self.faces = np.asarray(self.faces, dtype=np.int64).reshape(-1, 3)
        self.transform = np.asarray(self.transform, dtype=np.float64).reshape(4, 4)

    @property
    def world_vertices(self) -> np.ndarray:
        """(n, 3) vertices in world coordinates."""
        homogeneous: np.ndarray = self.vertices @ self.transform[:3, :3].T + self.transform[:3, 3]
        return homogeneous

    @property
    def n_faces(self) -> int:
        return len(self.faces)


@dataclass
class Scene:
    """Shapes, lights and what the reader noticed.

    ``document`` keeps the reader's own representation (for X3D, the parsed XML
    tree) so a writer of the same format can keep everything shadowgeo does not
    model (scripts, routes, viewpoints, metadata, comments).
    """

    shapes: list[Shape] = field(default_factory=list)
    lights: list[SceneLight] = field(default_factory=list)
    path: str | None = None
    up_axis: str = "Y"
    meters_per_unit: float = 1.0
    warnings: list[str] = field(default_factory=list)
    document: Any = None

    def shapes_with_role(self, role: str) -> list[Shape]:
        return [shape for shape in self.shapes if shape.role == role]

    @property
    def bounds(self) -> np.ndarray:
        """(2, 3) world bounding box of the scene's own geometry."""
        points = [s.world_vertices for s in self.shapes if s.role == "geometry" and len(s.faces)]
        if not points:
            return np.zeros((2, 3))
        stacked = np.concatenate(points)
        return np.array([stacked.min(axis=0), stacked.max(axis=0)])
