"""Sun studies of a scene: its floor, its casters, its hours of sunlight baked in.

:func:`shadowgeo.sun_study` works on a caster, a plane and a region given by
hand. Here they come from a scene, as ``shadowgeo convert`` finds its
receivers: the floor is the largest flat surface found that faces up and lies
under the scene (a ground slab, a courtyard's paving; :func:`receivers.select`,
then :func:`receivers.is_floor`, or covering half the scene's plan whatever
lies under it: a basement), or a named shape, or a given plane, or else
the ground plane under the scene's lowest point. The region studied is the
floor's outline (its largest part; holes in it are studied too), or for an
unbounded plane the scene's plan (its bounding box on the plane). Every other
face of the scene casts; the floor's own faces, lying in the plane, do not.
Translucent casters count by their opacity, as the converter's rule
(:mod:`shadowgeo.scene.opacity`: ``1 - Material.transparency`` in sixteenths,
none for ``casts_shadow`` False): a point hidden at a sample gets ``1 - a`` of
its sun, ``a`` the largest opacity of the casters hiding it
(:func:`shadowgeo.sun_study`'s ``opacity``).

:func:`sunlight_shapes` turns a day's study into shapes, one per duration of
sunlight, coloured from dark purple (no sun) to yellow (sun all day), lifted off
the floor as baked shadows are: a map of sunlight hours a viewer can open.
"""

from __future__ import annotations

import dataclasses
import datetime as _dt
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
import shapely
from numpy.typing import ArrayLike
from shapely.geometry.polygon import orient

from .. import plane2d as poly
from ..errors import SceneError
from ..plane import Plane
from ..sunstudy import SunStudy, sun_study, sun_study_by_day, sun_summaries_by_day
from ..tolerance import Tolerance
from ..topology import Caster
from .casters import CasterSet, distinct
from .model import Material, Scene, Shape, located, unique_name
from .opacity import opacities
from .receivers import FLOOR_COSINE, FLOOR_COVER, Receiver, ground, is_floor
from .receivers import select as select_receivers

__all__ = [
    "GROUND_COVER_HEIGHT",
    "SceneStudy",
    "ground_cover",
    "hours_faces",
    "level_meshes",
    "level_regions",
    "ramp_colour",
    "roof_triangles",
    "scene_study",
    "shadows_at",
    "study_scene",
    "sunlight_shapes",
]

# FLOOR_COSINE as an angle from the vertical, for messages.
FLOOR_SLOPE_DEGREES = float(np.degrees(np.arccos(FLOOR_COSINE)))
# Metres: a city object rising less than this (a kerb, a bank, a low wall
# along a road) is ground cover in a sun study of city data, not a caster:
# LoD1 roads and land use carry such steps, and a caster at ground level
# would shade the ground plane under it all day.
GROUND_COVER_HEIGHT = 1.0
_CITY_GROUND = "the ground of the city's flat objects"

# Lift of the sunlight map off its floor, relative to the scene's size (as
# shadows are lifted: shadowgeo.scene.shadows).
_LIFT = 1e-3
# The map's colours, from no sun to sun all day: matplotlib's viridis at five
# stops (dark purple, blue, teal, green, yellow), evenly spaced, between
# which the colour is interpolated: each step of sunlight reads as a step of
# colour, as a heat map's reader expects.
_RAMP = np.array(
    [
        [0.267, 0.005, 0.329],
        [0.229, 0.322, 0.546],
        [0.128, 0.567, 0.551],
        [0.369, 0.789, 0.383],
        [0.993, 0.906, 0.144],
    ]
)


def ramp_colour(share: float) -> tuple[float, float, float]:
    """The map's colour for ``share`` (0: no sun, 1: sun all day)."""
    position = float(np.clip(share, 0.0, 1.0)) * (len(_RAMP) - 1)
    low = min(int(position), len(_RAMP) - 2)
    red, green, blue = (
        float(c) for c in _RAMP[low] + (_RAMP[low + 1] - _RAMP[low]) * (position - low)
    )
    return red, green, blue


@dataclasses.dataclass(frozen=True)
class SceneStudy:
    """What a scene's sun study is made of.

    Attributes
    ----------
    caster : Caster
        Every face of the scene's geometry that casts (``Shape.casts_shadow``)
        but those lying in ``plane`` facing up.
    plane : Plane
        The floor's plane, its normal up.
    region : (n, 3) float64
        The polygon studied, on ``plane``.
    floor : str
        What the floor is, for messages (``"the floor 'ground'"``, ``"the
        ground plane"``, ``"the plane given"``).
    up : str
        The scene's up axis, ``"Y"`` or ``"Z"``.
    scale : float
        The scene's size (for the lift of :func:`sunlight_shapes`).
    notes : list of str
        What was chosen and why.
    opacity : (m,) float64 or None
        Each of ``caster``'s faces' casting opacity
        (:func:`shadowgeo.scene.opacity.casting_opacity` of its shape), for
        :func:`shadowgeo.sun_study`; None when every one is opaque.
    """

    caster: Caster
    plane: Plane
    region: np.ndarray
    floor: str
    up: str
    scale: float
    notes: list[str]
    opacity: np.ndarray | None = None


def scene_study(
    scene: Scene,
    *,
    receivers: Sequence[str] | None = None,
    plane: Plane | None = None,
    region: ArrayLike | None = None,
) -> SceneStudy:
    """The caster, floor and region of ``scene``'s sun study (see the module
    notes). ``receivers``: DEF names, the first of them that is a floor (its
    largest patch facing up) is studied; ``plane``: study that plane instead,
    over the scene's plan; ``region``: (n, 2) corners in plan (the two
    horizontal axes, x and z for a Y-up scene, x and y for Z up), the part of
    the floor's plane studied (straight down onto it; it may reach past the
    floor's edges, where the plane is studied as well).

    Raises
    ------
    SceneError
        When the scene has no geometry, a named shape has no patch facing
        up, or the plane is vertical.
    """
    shapes = [s for s in scene.shapes if s.role == "geometry" and s.n_faces]
    geometry = distinct(shapes)
    if not geometry:
        raise SceneError("the scene has no geometry: nothing casts a shadow to study")
    axis = scene.up_index
    up_name = "YZ"[axis - 1]
    stacked = CasterSet(geometry)
    bounds = stacked.bounds
    tolerance = Tolerance.for_points(bounds)
    plane, cover, notes = _city_ground(scene, geometry, plane, (receivers, region))
    floor, floor_notes = _floor(scene, geometry, stacked, receivers, plane, tolerance)
    notes.extend(floor_notes)
    facing = floor.plane
    if facing.normal[axis] < 0:
        facing = facing.flipped()
    if region is not None:
        polygon = _plan_polygon(facing, region, axis)
        what = f"the floor '{floor.name}'" if floor.triangles is not None else "the plane"
        notes.append(f"sun study: over {what}, within the region given")
    elif floor.triangles is not None:
        polygon, outline_notes = _outline(facing, floor.triangles, floor.name)
        notes.extend(outline_notes)
        what = f"the floor '{floor.name}'"
        notes.append(f"sun study: over {what}, within its outline")
    else:
        polygon = _plan(facing, bounds)
        what = "the plane given" if plane is not None else "the ground plane"
        what = _CITY_GROUND if cover.any() else what
        notes.append(f"sun study: over {what}, within the scene's plan (its bounding box)")
    opacity = opacities(geometry)
    faces = stacked.off_plane(facing, tolerance) & stacked.faces_of((opacity > 0) & ~cover)
    if not faces.any():
        raise SceneError(
            "nothing in the scene casts a shadow on the floor studied (it has the sun "
            "whenever the sun is up)"
        )
    caster = stacked.mesh(faces)
    cast = stacked.faces_of(opacity)[faces]
    translucent = cast if (cast < 1).any() else None
    notes.extend(_translucent_note(opacity[stacked.owners(faces)]))
    return SceneStudy(caster, facing, polygon, what, up_name, tolerance.scale, notes, translucent)


def _translucent_note(casting: np.ndarray) -> list[str]:
    """A note naming how many of the casters (their opacities ``casting``)
    are translucent, when any is."""
    translucent = casting[casting < 1]
    if not len(translucent):
        return []
    values = ", ".join(f"{value:g}" for value in np.unique(translucent))
    return [
        f"sun study: {len(translucent)} translucent caster(s) let part of the sun through "
        f"(opacity {values}: 1 - their material's transparency)"
    ]


def _city_ground(
    scene: Scene,
    geometry: list[Shape],
    plane: Plane | None,
    chosen: tuple[Any, ...],
) -> tuple[Plane | None, np.ndarray, list[str]]:
    """City data's ground: the plane of its ground cover (:func:`ground_cover`,
    at :func:`_cover_plane`) and which shapes are cover, with a note. Only
    for a scene with a site whose user chose no ``plane`` and nothing of
    ``chosen`` (receivers, region); else ``plane`` as given and no cover, as
    when the shapes are all cover or none is."""
    none = np.zeros(len(geometry), dtype=bool)
    if scene.site is None or plane is not None or any(item is not None for item in chosen):
        return plane, none, []
    axis = scene.up_index
    cover = ground_cover(geometry, axis, scene.meters_per_unit)
    if not cover.any() or cover.all():
        return None, none, []
    plane = _cover_plane(geometry, cover, axis)
    note = (
        f"sun study: {int(cover.sum())} flat city object(s) (roads, land, water: no "
        f"face steeper than {FLOOR_SLOPE_DEGREES:.0f} degrees, or lower than "
        f"{GROUND_COVER_HEIGHT:g} m) are the ground, at "
        f"{'xyz'[axis]} = {-plane.offset:.6g} (their area's median height); "
        f"the {int((~cover).sum())} other(s) cast"
    )
    return plane, cover, [note]


def ground_cover(geometry: list[Shape], axis: int, meters_per_unit: float) -> np.ndarray:
    """Per shape, whether it is ground cover, which receives sunlight and
    does not block it (city data's roads, land use, water): every face
    within ``FLOOR_COSINE`` of the up axis (no wall), or the whole shape
    lower than ``GROUND_COVER_HEIGHT`` (a kerb, a bank)."""
    flat = np.zeros(len(geometry), dtype=bool)
    low = GROUND_COVER_HEIGHT / meters_per_unit
    for index, shape in enumerate(geometry):
        corners = shape.world_vertices[shape.faces]
        if not len(corners):
            continue
        normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        lengths = np.linalg.norm(normals, axis=1)
        steep = np.abs(normals[:, axis]) < FLOOR_COSINE * lengths
        height = float(np.ptp(corners[:, :, axis]))
        flat[index] = height < low or not bool(steep[lengths > 0].any())
    return flat


def _cover_plane(geometry: list[Shape], cover: np.ndarray, axis: int) -> Plane:
    """The plane, facing up, at the area-weighted median height of the
    ground cover's faces: where most of the ground is."""
    heights, areas = [], []
    for shape in (shape for shape, flat in zip(geometry, cover, strict=True) if flat):
        corners = shape.world_vertices[shape.faces]
        normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        heights.append(corners[:, :, axis].mean(axis=1))
        areas.append(np.linalg.norm(normals, axis=1) / 2)
    height, area = np.concatenate(heights), np.concatenate(areas)
    order = np.argsort(height, kind="stable")
    middle = np.searchsorted(np.cumsum(area[order]), 0.5 * area.sum())
    normal = np.zeros(3)
    normal[axis] = 1.0
    return Plane(normal, -float(height[order][min(int(middle), len(order) - 1)]))


def _floor(
    scene: Scene,
    geometry: list[Shape],
    stacked: CasterSet,
    receivers: Sequence[str] | None,
    plane: Plane | None,
    tolerance: Tolerance,
) -> tuple[Receiver, list[str]]:
    """The receiver studied: the plane given, the first named patch or found
    floor facing up, else the ground plane under the scene (with its note)."""
    axis = scene.up_index
    if plane is not None:
        if abs(float(plane.normal[axis])) <= tolerance.angle:
            raise SceneError(
                f"the plane {plane.normal.tolist()} is vertical: a sun study needs a plane "
                "the sun shines down on"
            )
        return Receiver(plane, "plane"), []
    own = dataclasses.replace(scene, shapes=geometry)
    # (the search's notes speak of shadows' receivers; the study notes its floor)
    found, _ = select_receivers(own, geometry, receivers, None, tolerance, stacked, False)
    bounds = stacked.bounds
    lowest = stacked.vertices[int(np.argmin(stacked.vertices[:, axis]))]
    across = [k for k in range(3) if k != axis]
    plan = float(np.prod(bounds[1, across] - bounds[0, across]))
    floors = []
    for receiver in found:
        up = float(receiver.plane.normal[axis])
        facing_up = (abs(up) if receiver.two_sided else up) >= FLOOR_COSINE
        if facing_up and (
            receivers is not None
            or is_floor(receiver, bounds, lowest, axis)
            or receiver.area * abs(up) >= FLOOR_COVER * plan  # over a deep basement
        ):
            floors.append(receiver)
    if floors:
        # the first named, else the largest found (the scene's order among equals)
        floor = floors[0] if receivers is not None else max(floors, key=lambda r: r.area)
        return floor, []
    if receivers is not None:
        raise SceneError(
            f"no patch of {', '.join(receivers)} faces up (within 30 degrees): a sun study "
            "needs a floor (--plane a,b,c,d studies a plane)"
        )
    ground_plane, note = ground(scene, geometry, bounds)
    return ground_plane, [note]


def _outline(plane: Plane, triangles: np.ndarray, name: str) -> tuple[np.ndarray, list[str]]:
    """The outer loop of the largest part of a patch's ``triangles`` (world
    corners), on ``plane``, as (n, 3) points; a note when it has more parts."""
    flat = plane.to_2d(triangles.reshape(-1, 3)).reshape(-1, 3, 2)
    center = 0.5 * (flat.reshape(-1, 2).min(axis=0) + flat.reshape(-1, 2).max(axis=0))
    extent = float(np.abs(flat.reshape(-1, 2) - center).max()) or 1.0
    scale = poly.local_scale(extent)
    parts = poly.components(poly.triangles_region((flat - center) * scale))
    if not parts:
        raise SceneError(f"the floor '{name}' has no area")
    sizes = [float(poly.signed_areas(part).sum()) for part in parts]
    largest = parts[int(np.argmax(sizes))]
    notes = [f"sun study: the floor '{name}' is in {len(parts)} parts; the largest is studied"]
    return plane.to_3d(largest[0] / scale + center), notes if len(parts) > 1 else []


def _plan_polygon(plane: Plane, region: ArrayLike, axis: int) -> np.ndarray:
    """(n, 2) plan corners (the axes other than ``axis``, in order) dropped
    along ``axis`` onto ``plane``, as (n, 3) points."""
    corners = np.asarray(region, dtype=np.float64)
    if corners.ndim != 2 or corners.shape[1] != 2 or len(corners) < 3:
        raise SceneError(f"region must be three or more plan corners (n, 2), got {corners.shape}")
    if not np.all(np.isfinite(corners)):
        raise SceneError("region has NaN or infinite corners")
    if shapely.Polygon(corners).area == 0:
        raise SceneError("the region has no area")
    across = [k for k in range(3) if k != axis]
    points = np.zeros((len(corners), 3))
    points[:, across] = corners
    normal = plane.normal
    points[:, axis] = -(plane.offset + corners @ normal[across]) / normal[axis]
    return points


def _plan(plane: Plane, bounds: np.ndarray) -> np.ndarray:
    """The scene's bounding box seen on ``plane``: the convex hull of its
    eight corners on it, counter-clockwise, as (n, 3) points."""
    corners = np.array(
        [[x, y, z] for x in bounds[:, 0] for y in bounds[:, 1] for z in bounds[:, 2]]
    )
    flat = plane.to_2d(corners)
    hull = shapely.MultiPoint(flat).convex_hull
    if not isinstance(hull, shapely.Polygon) or hull.area == 0:
        raise SceneError("the scene is flat in the plane studied: its plan has no area")
    loop = np.asarray(orient(hull, 1.0).exterior.coords)[:-1]
    return plane.to_3d(loop)


def study_scene(
    scene: Scene,
    times: Sequence[_dt.datetime],
    *,
    latitude: float | None = None,
    longitude: float | None = None,
    step: _dt.timedelta | None = None,
    receivers: Sequence[str] | None = None,
    plane: Plane | None = None,
    region: ArrayLike | None = None,
    tz: _dt.tzinfo | None = None,
    scheduler: Any = None,
    progress: Callable[[int, int], None] | None = None,
    summaries: bool = False,
    sun_angle: float = 0.0,
    sun_samples: int | None = None,
) -> tuple[SceneStudy, Any]:
    """:func:`shadowgeo.sun_study_by_day` of a scene's casters over its floor
    (:func:`scene_study`): one study a calendar day (in ``tz``) of ``times``,
    serially or on Dask (``scheduler``, as there), as :class:`SunStudies`;
    with ``summaries``, :func:`shadowgeo.sun_summaries_by_day`'s
    ``{day: DaySummary}`` instead (no polygons kept: for many days).
    ``sun_angle`` and ``sun_samples``: the sun's disc, as
    :func:`shadowgeo.sun_study` takes it (0: a point sun). Translucent
    casters count by their opacity (:attr:`SceneStudy.opacity`).

    ``latitude`` and ``longitude`` default to the scene's :attr:`Scene.site`
    (city data whose file names its CRS), which also gives true north in the
    scene's frame (a projected CRS's grid north turns from it); a scene with
    no site needs them (SceneError)."""
    latitude, longitude, north = located(scene, latitude, longitude)
    inputs = scene_study(scene, receivers=receivers, plane=plane, region=region)
    by_day = sun_summaries_by_day if summaries else sun_study_by_day
    studies = by_day(
        inputs.caster,
        inputs.plane,
        inputs.region,
        times,
        latitude=latitude,
        longitude=longitude,
        step=step,
        up=inputs.up,
        north=north,
        tz=tz,
        scheduler=scheduler,
        progress=progress,
        sun_angle=sun_angle,
        sun_samples=sun_samples,
        opacity=inputs.opacity,
    )
    return inputs, studies


def level_meshes(
    study: SunStudy, scale: float
) -> list[tuple[float, float, np.ndarray, np.ndarray]]:
    """A day's levels as triangles, rising: ``(hours, share, vertices, faces)``
    each, ``share`` the level's sunlit samples over all (0 to 1, the colour
    ramp's position), the (n, 3) world vertices lifted ``1e-3`` of ``scale``
    off the plane, the (m, 3) int64 faces the level's exact polygons
    triangulated. Levels with no triangle are left out."""
    plane = study.plane
    lift = _LIFT * scale * plane.normal
    # every sample sunlit (every direction of each one's sun disc): the brightest
    most = max(study.full_level, 1)
    meshes = []
    for k, parts in sorted(study.levels.items()):
        if not parts:
            continue
        points = np.concatenate([loop for part in parts for loop in part])
        center = 0.5 * (points.min(axis=0) + points.max(axis=0))
        extent = float(np.abs(points - center).max()) or 1.0
        local_scale = poly.local_scale(extent)
        local = [[(loop - center) * local_scale for loop in part] for part in parts]
        flat, faces = poly.triangulate_parts(local)
        if not len(faces):
            continue
        vertices = plane.to_3d(flat / local_scale + center) + lift
        meshes.append((study.hours(k), k / most, vertices, faces.astype(np.int64)))
    return meshes


def sunlight_shapes(study: SunStudy, scale: float, name: str = "sunlight") -> list[Shape]:
    """A day's study as shapes: one per duration of sunlight with area, named
    ``{name}_{hours}h``, coloured by :func:`ramp_colour` from dark purple (none)
    to yellow (every sample),
    lifted ``1e-3`` of ``scale`` off the plane, emissive (unlit in a viewer),
    two-sided, casting nothing,
    role ``"shadow"`` (``shadowgeo convert`` replaces them as baked shadows).
    The triangles of each shape are the level's exact polygons
    (:func:`level_meshes`)."""
    shapes = []
    for hours, share, vertices, faces in level_meshes(study, scale):
        red, green, blue = ramp_colour(share)
        label = f"{hours:g}".replace(".", "_")
        shapes.append(
            Shape(
                vertices,
                faces,
                # emissive: the same colour in every viewer, whatever its lights
                material=Material(diffuse_color=(0.0, 0.0, 0.0), emissive_color=(red, green, blue)),
                name=f"{name}_{label}h",
                solid=False,
                role="shadow",
                group=name,
                source=f"sun study: {hours:g} h of sunlight",
                casts_shadow=False,
            )
        )
    return shapes


def plan_region(plane: Plane, parts: Sequence[Sequence[np.ndarray]], up: str) -> Any:
    """Polygons on ``plane`` (``[outer, hole, ...]`` loops of (k, 2) plane
    coordinates, as a :class:`SunStudy` holds them) seen in plan: one shapely
    MultiPolygon in the two horizontal axes (x, y for ``up="Z"``; x, z for
    ``"Y"``), a part each. The parts are kept as the study cut them (a
    level's along tile edges), not merged: they tile the level exactly,
    where GEOS's union of thousands of them can refuse (a hole touching a
    shell) or round the vertices. Empty ``parts`` give an empty MultiPolygon."""
    axis = "XYZ".index(up)
    across = [k for k in range(3) if k != axis]
    pieces = [
        shapely.Polygon(
            plane.to_3d(part[0])[:, across], [plane.to_3d(hole)[:, across] for hole in part[1:]]
        )
        for part in parts
    ]
    return shapely.MultiPolygon(pieces)


def level_regions(study: SunStudy, up: str) -> list[tuple[float, Any]]:
    """A day's levels of sunlight in plan, rising: (hours, :func:`plan_region`)."""
    return [
        (study.hours(k), plan_region(study.plane, parts, up))
        for k, parts in sorted(study.levels.items())
        if parts
    ]


def shadows_at(
    inputs: SceneStudy,
    times: Sequence[_dt.datetime],
    *,
    latitude: float,
    longitude: float,
    north: ArrayLike | None = None,
) -> list[tuple[_dt.datetime, Any]]:
    """The exact shadow on ``inputs``' region at each of ``times`` with the
    sun up, in plan (:func:`plan_region`): the same shadows a sun study of
    those times casts (:func:`shadowgeo.sun_study`, one sample each)."""
    found = []
    for time in times:
        study = sun_study(
            inputs.caster,
            inputs.plane,
            inputs.region,
            [time],
            latitude=latitude,
            longitude=longitude,
            up=inputs.up,
            north=north,
        )
        if study.times:
            found.append((time, plan_region(inputs.plane, study.shadows[0], inputs.up)))
    return found


def roof_triangles(inputs: SceneStudy) -> list[Any]:
    """The casters' faces that face up (roofs, the tops of blocks), in plan
    (as :func:`plan_region`), one shapely triangle each: the buildings as a
    map draws them."""
    axis = "XYZ".index(inputs.up)
    across = [k for k in range(3) if k != axis]
    corners = inputs.caster.vertices[inputs.caster.faces]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    up = normals[:, axis] > FLOOR_COSINE * np.linalg.norm(normals, axis=1)
    return list(shapely.polygons(corners[up][:, :, across]))


def hours_faces(
    scene: Scene,
    study: SunStudy,
    scale: float,
    ground: str = "ground",
    shape_hours: Mapping[int, np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, list[str]]:
    """The day's ground levels (:func:`level_meshes`) and the scene's
    geometry as plain arrays for a writer of hours per face
    (:func:`shadowgeo.io.sunlight_glb.write_hours_glb`): (n, 3) world
    vertices, (m, 3) faces, (m,) hours, (m,) group of each face and the
    groups' names (``ground`` first, then each shape's name). The scene's
    own faces have NaN hours (not studied) unless ``shape_hours`` gives
    them: shape ``i`` of ``scene.shapes`` -> its faces' hours, (f,) float
    (NaN where not studied; walls and roofs from
    :func:`shadowgeo.scene.facade_hours.facade_hours`)."""
    vertices, faces, hours, groups = [], [], [], []
    names = [ground]
    base = 0
    given = shape_hours or {}

    def add(points: np.ndarray, triangles: np.ndarray, value: ArrayLike, group: int) -> None:
        nonlocal base
        vertices.append(points)
        faces.append(triangles + base)
        hours.append(np.broadcast_to(np.asarray(value, dtype=np.float64), len(triangles)))
        groups.append(np.full(len(triangles), group, dtype=np.int64))
        base += len(points)

    for value, _, points, triangles in level_meshes(study, scale):
        add(points, triangles, value, 0)
    used: set[str] = {ground}
    for index, shape in enumerate(scene.shapes):
        if shape.role == "geometry" and shape.n_faces:
            names.append(unique_name(shape.name or "shape", used))
            own = given.get(index, np.nan)
            add(shape.world_vertices, shape.faces.astype(np.int64), own, len(names) - 1)
    if not faces:
        return (
            np.zeros((0, 3)),
            np.zeros((0, 3), np.int64),
            np.zeros(0),
            np.zeros(0, np.int64),
            names,
        )
    return (
        np.concatenate(vertices),
        np.concatenate(faces),
        np.concatenate(hours),
        np.concatenate(groups),
        names,
    )
