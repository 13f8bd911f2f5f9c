"""The scene model every reader fills and every writer reads.

Data flows one way: read -> :class:`Scene` -> shadow geometry -> :class:`Scene`
-> write. Geometry is float64 triangles in each shape's local frame with a 4x4
world transform; lights are stored in world coordinates.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike

from ..boxes import bounding_box
from ..errors import SceneError
from ..lights import (
    AreaLight,
    DirectionalLight,
    DiskLight,
    PointLight,
    RectLight,
    SpotLight,
    centre_light,
)

__all__ = [
    "Color",
    "MARK",
    "Material",
    "OVERVIEW_FROM",
    "Placement",
    "Scene",
    "SceneLight",
    "Semantics",
    "Shape",
    "Site",
    "Viewpoint",
    "axis_angle",
    "located",
    "lights",
    "overview",
    "rotate",
    "safe_name",
    "shadow_shape",
    "transformed",
    "unique_name",
]

Color = tuple[float, float, float]

# The X3D ``class`` of the groups holding the shapes shadowgeo adds; each added
# Shape's class is ``MARK + "-" + role``, so a reader gives it back its role.
MARK = "shadowgeo-shadows"
_IDENTITY = np.eye(4)


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
    ambient_intensity: float = 0.2


@dataclass
class SceneLight:
    """A light of the scene: its geometry (world coordinates) and how it looks.

    ``shadows`` and ``shadow_intensity`` are X3D 4's fields (``shadows``: the
    browser draws the light's shadows at run time); ``name`` is the DEF name
    (or the glTF/USD node name) where there is one. ``baked``: shadowgeo
    baked this light's shadows into the scene as shapes and turned its
    runtime shadows off: every writer writes X3D's ``shadows`` as
    ``shadows and not baked`` (:attr:`runtime_shadows`), with a mark its
    reader gives back as ``baked``, so ``shadows`` stays the author's.
    ``node``: the X3D reader's XPath of the light's element in
    ``Scene.document`` (None for a light of an Inline or a prototype), so
    the writer of that document marks the element a baked light came from.

    ``scope``: for a light that lights only part of the scene (X3D's
    ``global="false"``: the descendants of its parent grouping node), the
    id of that grouping node's instance, found in :attr:`Shape.scopes` of
    the shapes it lights (:func:`lights`); None: it lights every shape. The
    X3D reader sets it (a light reached twice through USE is two lights, each
    with its own scope; one at the top of the scene's own file lights
    everything); glTF's KHR_lights_punctual and USD's UsdLux have no scope,
    so their lights light every shape. ``global_`` stays the author's field,
    written back as it was read. ``scope_group``: where that grouping node
    lies in ``Scene.document`` (None for one of an Inline or a prototype), so
    a shape shadowgeo adds for this light (the ground it draws) can be written
    inside the scope, lit by the light in every browser.

    ``area``: a light with a shape (UsdLux ``RectLight``, ``DiskLight``).
    ``light`` is then the spot light at its centre that stands for it
    (:func:`~shadowgeo.lights.centre_light`): the hard-shadow paths and the
    X3D and glTF writers, which hold no such light, use it; the soft-shadow
    baking and the USD writer use ``area`` (:attr:`emitter`).
    ``SceneLight(RectLight(...))`` sets both.
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
    baked: bool = False
    node: str | None = None
    scope: int | None = None
    scope_group: Placement | None = None
    area: AreaLight | None = None

    def __post_init__(self) -> None:
        light: object = self.light
        if isinstance(light, RectLight | DiskLight):  # given as the light itself
            self.area = light
            self.light = centre_light(light)

    @property
    def emitter(self) -> PointLight | DirectionalLight | SpotLight | AreaLight:
        """The light with its size: :attr:`area` when there is one, else
        :attr:`light` (whose ``source_radius`` or ``angle`` is its size)."""
        return self.area if self.area is not None else self.light

    @property
    def runtime_shadows(self) -> bool:
        """Whether a browser draws this light's shadows: X3D's ``shadows`` as
        written, false once they are baked (see :attr:`baked`)."""
        return self.shadows and not self.baked


@dataclass(frozen=True)
class Placement:
    """An element of an X3D ``Scene.document`` a shape can be written in:
    ``node``, its XPath, and ``matrix`` (4, 4), the world transform of its
    children's coordinates (column vectors)."""

    node: str
    matrix: np.ndarray


@dataclass(frozen=True)
class Semantics:
    """What each face of a shape is, in a city model's terms (CityGML's
    semantic surfaces: ``RoofSurface``, ``WallSurface``, ``GroundSurface``, ...).

    Parameters
    ----------
    kinds : tuple of str
        The names the faces use, each once.
    face_kind : (m,) int64
        Per face of the shape, an index into ``kinds``, or -1 for a face the
        file gives no kind.
    polygon : (m,) int64, optional
        Per face, the polygon of its city object it was cut from, the
        object's polygons numbered in the file's order (what a writer of
        values per polygon, :mod:`shadowgeo.io.cityjson_write`, matches them
        by); None when not known.

    Examples
    --------
    >>> labels = Semantics(("RoofSurface", "WallSurface"), [0, 1, 1, -1])
    >>> labels.counts()
    {'RoofSurface': 1, 'WallSurface': 2}
    >>> labels.faces("WallSurface").tolist()
    [1, 2]
    """

    kinds: tuple[str, ...]
    face_kind: np.ndarray
    polygon: np.ndarray | None = None

    def __post_init__(self) -> None:
        index = np.asarray(self.face_kind, dtype=np.int64).reshape(-1)
        if index.size and (index.min() < -1 or index.max() >= len(self.kinds)):
            raise ValueError(f"face kinds must be -1 or below {len(self.kinds)}")
        object.__setattr__(self, "face_kind", index)
        if self.polygon is not None:
            polygon = np.asarray(self.polygon, dtype=np.int64).reshape(-1)
            if polygon.shape != index.shape:
                raise ValueError(f"{len(polygon)} polygon numbers for {len(index)} faces")
            object.__setattr__(self, "polygon", polygon)

    def faces(self, kind: str) -> np.ndarray:
        """(k,) int64 the faces of ``kind`` (none for a kind it does not have)."""
        if kind not in self.kinds:
            return np.zeros(0, dtype=np.int64)
        return np.flatnonzero(self.face_kind == self.kinds.index(kind))

    def counts(self) -> dict[str, int]:
        """Faces of each kind, in the order of :attr:`kinds`."""
        tally = np.bincount(self.face_kind[self.face_kind >= 0], minlength=len(self.kinds))
        return {kind: int(count) for kind, count in zip(self.kinds, tally, strict=True)}


@dataclass(frozen=True)
class Site:
    """Where on Earth a scene read from geographic data stands.

    Parameters
    ----------
    crs : str
        The scene's own coordinate reference system (WKT2): what its
        coordinates are in, metres along x (east) and y (north), z up.
    source_crs : str
        The file's CRS as the file gave it (``"EPSG:7415"``, a URL, WKT): the
        one an output goes back to. Equal to ``crs`` when the file's CRS was
        projected and kept; for geographic input (longitude, latitude) the
        scene is in a transverse Mercator centred on the data instead.
    latitude, longitude : float
        Degrees (north and east positive) of the centre of the data's
        bounding box, what a sun study needs.
    north : (3,) tuple of float
        The horizontal unit vector pointing to true north there, in scene
        coordinates (grid north and true north differ by the meridian
        convergence of the projection).
    """

    crs: str
    source_crs: str
    latitude: float
    longitude: float
    north: tuple[float, float, float] = (0.0, 1.0, 0.0)


def located(
    scene: Scene, latitude: float | None, longitude: float | None
) -> tuple[float, float, tuple[float, float, float] | None]:
    """Where a sun study of ``scene`` stands: (latitude, longitude, true
    north in the scene's frame). The degrees given win; what is not given
    comes from :attr:`Scene.site`, which also gives north (None: the
    scene's grid north). SceneError naming the file when neither says."""
    site = scene.site
    if latitude is None or longitude is None:
        if site is None:
            raise SceneError(
                "the scene does not say where it is (no CRS in its file): give the "
                "latitude and longitude",
                path=scene.path,
            )
        latitude = site.latitude if latitude is None else latitude
        longitude = site.longitude if longitude is None else longitude
    return latitude, longitude, None if site is None else site.north


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
    crease_angle : float
        How a viewer shades it (radians, X3D's ``creaseAngle``): normals are
        smoothed across edges whose faces meet at less than this angle; 0
        (the default) shades every face flat. Shadows on the shape end where
        that shading does (:mod:`shadowgeo.scene.terminator`).
    scopes : frozenset of int
        The scopes (:attr:`SceneLight.scope`) of the non-global lights that
        light it: the grouping nodes holding such a light that it lies in.
    placement : Placement, optional
        For an added shape: the element of the scene's X3D document the X3D
        writer puts its group in (with its coordinates made local to it);
        None: at the top of ``<Scene>``.
    semantics : Semantics, optional
        What each face is in a city model (roof, wall, ground), from the city
        readers; None where the file says nothing of it.
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
    crease_angle: float = 0.0
    scopes: frozenset[int] = frozenset()
    placement: Placement | None = None
    semantics: Semantics | None = None

    def __post_init__(self) -> None:
        self.vertices = np.asarray(self.vertices, dtype=np.float64).reshape(-1, 3)
        self.faces = np.asarray(self.faces, dtype=np.int64).reshape(-1, 3)
        self.transform = np.asarray(self.transform, dtype=np.float64).reshape(4, 4)
        if self.semantics is not None and len(self.semantics.face_kind) != len(self.faces):
            raise ValueError(
                f"semantics name {len(self.semantics.face_kind)} faces, the shape has "
                f"{len(self.faces)}"
            )

    @property
    def world_vertices(self) -> np.ndarray:
        """(n, 3) vertices in world coordinates (inf where they overflow float64:
        the geometry's range check names them). Under the identity transform,
        a read-only view of :attr:`vertices` (``x * 1 + y * 0 + z * 0 + 0``
        is ``x``): a big shape is not copied."""
        if np.array_equal(self.transform, _IDENTITY):
            view = self.vertices.view()
            view.setflags(write=False)
            return view
        return transformed(self.vertices, self.transform)

    @property
    def n_faces(self) -> int:
        return len(self.faces)


def lights(scene_light: SceneLight, scopes: frozenset[int] | None) -> bool:
    """Whether ``scene_light`` lights a shape in ``scopes`` (its
    :attr:`Shape.scopes`; None for what no scope excludes, e.g. a plane the
    user gives): a light with no scope lights everything.

    >>> from shadowgeo import DirectionalLight
    >>> sun = SceneLight(DirectionalLight([0, -1, 0]), global_=False, scope=3)
    >>> lights(sun, frozenset({3})), lights(sun, frozenset()), lights(sun, None)
    (True, False, True)
    """
    return scene_light.scope is None or scopes is None or scene_light.scope in scopes


def transformed(points: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """(n, 3) ``points`` under the 4x4 affine ``matrix`` (column vectors; inf
    where they overflow float64: the geometry's range check names them)."""
    with np.errstate(over="ignore", invalid="ignore"):
        world: np.ndarray = points @ matrix[:3, :3].T + matrix[:3, 3]
    return world


def rotate(axis_angle: ArrayLike, vector: ArrayLike) -> np.ndarray:
    """``vector`` (3,) turned by the rotation ``(x, y, z, angle)`` (right-hand
    rule about the axis; a zero axis turns nothing), by Rodrigues' formula.

    >>> rotate((0, 1, 0, math.pi / 2), (0, 0, -1)).round(12).tolist()
    [-1.0, 0.0, -0.0]
    """
    rotation = np.asarray(axis_angle)
    axis = np.asarray(rotation[:3], dtype=np.float64)
    angle = float(rotation[3])
    turned = np.asarray(vector, dtype=np.float64)
    length = float(np.linalg.norm(axis))
    if length == 0.0:
        return turned.copy()
    axis = axis / length
    result: np.ndarray = (
        turned * math.cos(angle)
        + np.cross(axis, turned) * math.sin(angle)
        + axis * float(axis @ turned) * (1.0 - math.cos(angle))
    )
    return result


def axis_angle(matrix: ArrayLike) -> tuple[float, float, float, float]:
    """The rotation ``(x, y, z, angle)`` nearest to the 3x3 ``matrix`` (its
    polar factor: scale and shear dropped, a mirror undone), with a unit axis
    and ``0 <= angle <= pi``; ``(0, 0, 1, 0)`` for no rotation.

    >>> [round(v, 12) for v in axis_angle([[0, 0, 1], [0, 1, 0], [-1, 0, 0]])]
    [0.0, 1.0, 0.0, 1.570796326795]
    """
    left, _, right = np.linalg.svd(np.asarray(matrix, dtype=np.float64).reshape(3, 3))
    turn = left @ right
    if np.linalg.det(turn) < 0:
        left[:, -1] *= -1
        turn = left @ right
    # Shepperd's method: the quaternion from the largest of its four squares.
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = turn.tolist()
    trace = r00 + r11 + r22
    if trace >= max(r00, r11, r22):
        s = 2 * math.sqrt(max(1 + trace, 0.0))
        w, x, y, z = s / 4, (r21 - r12) / s, (r02 - r20) / s, (r10 - r01) / s
    elif r00 >= r11 and r00 >= r22:
        s = 2 * math.sqrt(max(1 + r00 - r11 - r22, 0.0))
        w, x, y, z = (r21 - r12) / s, s / 4, (r01 + r10) / s, (r02 + r20) / s
    elif r11 >= r22:
        s = 2 * math.sqrt(max(1 + r11 - r00 - r22, 0.0))
        w, x, y, z = (r02 - r20) / s, (r01 + r10) / s, s / 4, (r12 + r21) / s
    else:
        s = 2 * math.sqrt(max(1 + r22 - r00 - r11, 0.0))
        w, x, y, z = (r10 - r01) / s, (r02 + r20) / s, (r12 + r21) / s, s / 4
    if w < 0:
        w, x, y, z = -w, -x, -y, -z
    sine = math.sqrt(x * x + y * y + z * z)
    if sine == 0.0:
        return (0.0, 0.0, 1.0, 0.0)
    return (x / sine, y / sine, z / sine, 2 * math.atan2(sine, w))


@dataclass(frozen=True)
class Viewpoint:
    """A camera the scene's author placed (X3D's Viewpoint), in world coordinates.

    Parameters
    ----------
    position : (x, y, z)
    orientation : (x, y, z, angle)
        Axis and angle (radians) turning the default camera, which looks
        along -Z with +Y up, to this one.
    field_of_view : float
        Radians: the smaller of the picture's two view angles (X3D's
        ``fieldOfView``; its default is pi / 4).
    description : str
        The text a browser lists it by.
    name : str, optional
        The DEF name.

    Examples
    --------
    >>> view = Viewpoint((0, 5, 0), (1, 0, 0, -math.pi / 2))
    >>> (view.direction.round(12) + 0.0).tolist(), (view.up.round(12) + 0.0).tolist()
    ([0.0, -1.0, 0.0], [0.0, 0.0, -1.0])
    """

    position: tuple[float, float, float] = (0.0, 0.0, 10.0)
    orientation: tuple[float, float, float, float] = (0.0, 0.0, 1.0, 0.0)
    field_of_view: float = math.pi / 4
    description: str = ""
    name: str | None = None

    @property
    def direction(self) -> np.ndarray:
        """(3,) unit vector the camera looks along: -Z turned by ``orientation``."""
        return rotate(self.orientation, (0.0, 0.0, -1.0))

    @property
    def up(self) -> np.ndarray:
        """(3,) unit vector of the picture's up: +Y turned by ``orientation``."""
        return rotate(self.orientation, (0.0, 1.0, 0.0))


@dataclass
class Scene:
    """Shapes, lights, the author's cameras and what the reader noticed.

    ``viewpoints`` are in document order; the first is the one a browser
    shows first (X3D's bound Viewpoint).

    ``headlight``: the viewer carries a light (a white directional light of
    intensity 1 along the view). The X3D reader gives the ``headlight`` of
    the scene's first NavigationInfo (X3D's default, true, when it has
    none); a scene built in code or read from glTF, USD or a mesh has none,
    as those formats' viewers light it by its own lights, and the X3D writer
    then writes ``<NavigationInfo headlight="false"/>`` when it has a light
    that is on.

    ``document`` keeps the reader's own representation (for X3D, the parsed XML
    tree) so a writer of the same format can keep everything shadowgeo does not
    model (scripts, routes, viewpoints, metadata, comments). The X3D reader
    keeps the long number fields it reads (64 KB of text and more: a big
    mesh's points and indices) as bytes in ``numbers``, a placeholder in their
    place in ``document``; ``scene.numbers.filled_copy(scene.document)`` is
    the tree with them in place.

    ``site``: where the scene stands on Earth and in which coordinate
    reference system, for scenes read from geographic data (the city
    readers) whose file names its CRS; None otherwise (a sun study then needs
    the latitude and longitude from the caller).
    """

    shapes: list[Shape] = field(default_factory=list)
    lights: list[SceneLight] = field(default_factory=list)
    path: str | None = None
    up_axis: str = "Y"
    meters_per_unit: float = 1.0
    warnings: list[str] = field(default_factory=list)
    document: Any = None
    viewpoints: list[Viewpoint] = field(default_factory=list)
    numbers: Any = None
    headlight: bool = False
    site: Site | None = None

    def shapes_with_role(self, role: str) -> list[Shape]:
        return [shape for shape in self.shapes if shape.role == role]

    @property
    def up_index(self) -> int:
        """The index of the up axis in a point (1 for Y, 2 for Z)."""
        return 2 if (self.up_axis or "Y").upper() == "Z" else 1

    @property
    def bounds(self) -> np.ndarray:
        """(2, 3) world bounding box of the scene's own geometry."""
        geometry = [s for s in self.shapes if s.role == "geometry" and len(s.faces)]
        if not geometry:
            return np.zeros((2, 3))
        return _world_box(geometry)


def _world_box(shapes: list[Shape]) -> np.ndarray:
    """(2, 3) the bounding box of the shapes' world vertices (zeros for no
    shape): one box of all the stacked vertices, but a lone shape's own
    vertices are not copied to stack them."""
    if not shapes:
        return np.zeros((2, 3))
    points = [shape.world_vertices for shape in shapes]
    return bounding_box(points[0] if len(points) == 1 else np.concatenate(points))


# Where the overview camera looks from, seen from the scene's centre, Y up:
# from +z (in front, as X3D's default camera) a little to +x, 35 degrees up,
# on the side the default sun's shadows fall to (not hidden behind casters).
OVERVIEW_FROM = (1.0, 1.2, 1.4)


def overview(scene: Scene, field_of_view: float = math.pi / 4) -> Viewpoint:
    """A Viewpoint that shows the whole scene, its shadows included, from
    above at an angle (:data:`OVERVIEW_FROM`, turned for a Z-up scene): the
    bounding sphere of every shape fits in ``field_of_view``.

    Examples
    --------
    >>> cube = Shape([[-1, -1, -1], [1, 1, 1], [1, -1, 1]], [[0, 1, 2]])
    >>> view = overview(Scene([cube]))
    >>> [round(v, 4) for v in view.position]  # sqrt(3) / sin(pi / 8) along (1, 1.2, 1.4)
    [2.1577, 2.5893, 3.0208]
    >>> to_centre = -np.array(view.position) / np.linalg.norm(view.position)
    >>> round(float(view.direction @ to_centre), 12), round(float(view.up[1]), 4)  # cos 34.9 deg
    (1.0, 0.8202)
    """
    low, high = _world_box([shape for shape in scene.shapes if shape.n_faces])
    center = (low + high) / 2
    radius = max(float(np.linalg.norm(high - low)) / 2, 1e-6)
    x, y, z = OVERVIEW_FROM
    z_up = scene.up_index == 2
    away = np.array([x, -z, y] if z_up else [x, y, z])
    away /= np.linalg.norm(away)
    up = np.array([0.0, 0.0, 1.0] if z_up else [0.0, 1.0, 0.0])
    position = center + away * radius / math.sin(field_of_view / 2)
    # The camera's frame as columns: right, up, backwards (the -Z it looks along).
    right = np.cross(-away, up)
    right /= np.linalg.norm(right)
    frame = np.column_stack([right, np.cross(away, right), away])
    return Viewpoint(
        cast("tuple[float, float, float]", tuple(float(v) for v in position)),
        axis_angle(frame),
        field_of_view,
        "shadowgeo: the scene and its shadows",
        "shadowgeo_overview",
    )


def shadow_shape(
    vertices: ArrayLike,
    faces: ArrayLike,
    scene_light: SceneLight,
    source: str,
    opacity: float = 1.0,
    darkness: float | None = None,
) -> Shape:
    """A baked shadow as a shape: black, two-sided, casting nothing (role
    ``"shadow"``), its darkness (one less its transparency) ``darkness`` times
    ``opacity``: ``darkness`` the light's shadow as the browser would draw it
    (:func:`~shadowgeo.scene.darkness.shadow_darkness`; default the light's
    ``shadow_intensity``), ``opacity`` (0 to 1) that of the casters (a shadow of
    half-transparent casters is half as dark)."""
    dark = scene_light.shadow_intensity if darkness is None else darkness
    transparency = 1.0 - float(np.clip(dark, 0.0, 1.0)) * opacity
    return Shape(
        np.asarray(vertices, dtype=np.float64),
        np.asarray(faces, dtype=np.int64),
        material=Material(diffuse_color=(0.0, 0.0, 0.0), transparency=transparency),
        solid=False,
        role="shadow",
        source=source,
        casts_shadow=False,
    )
