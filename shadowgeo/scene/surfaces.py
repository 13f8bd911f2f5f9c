"""Shadows on every surface of a scene, for :func:`~shadowgeo.add_shadows`.

The planar receivers (:mod:`.receivers`: grounds, floors, walls, slab tops)
keep the fast planar path. Every other face of the scene's geometry (terrain,
steps, the sides of a box, a sphere, the casters themselves) receives through
:func:`shadowgeo.shadow_on_surface`, all shapes of the scene at once: one
surface made of those faces, every shape that casts a caster. Casters of
less than full opacity (:mod:`.opacity`) cast lighter layers, each less the
shadows of the more opaque ones, as on the planar receivers. A face of a planar receiver
is left out of that surface, so no face is shadowed twice.

A solid shape (X3D ``solid="true"``, the default) receives on the front of its
faces only; an open one (``solid="false"``) on both sides, as X3D browsers draw
it: its faces go in once each way round.

On a smoothly shaded shape (:attr:`Shape.crease_angle`: Sphere, Cone, Cylinder,
a creased IndexedFaceSet) the shadow is drawn where the viewer's shading lights
the surface, not where the facets face the light (:mod:`.terminator`): cut at
the smooth terminator, and carried onto the faces just past the faceted one
that the shading still lights, where every other shape casts on them but the
shape itself does not (as its smooth surface would not). So a cast shadow that
reaches the terminator ends in a smooth curve, not in facet-wide stair steps.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..errors import GeometryError
from ..lights import Light, is_positional
from ..surface import shadow_layers_on_surface
from ..tolerance import Tolerance
from ..topology import Caster, row_groups, unique_integers
from .casters import CasterSet
from .darkness import Lighting
from .model import SceneLight, Shape, lights, shadow_shape
from .receivers import Receiver, repeated_faces
from .terminator import clip_to_lit, corner_normals, lit_values

__all__ = [
    "ReceivingSurface",
    "receiving_faces",
    "surface_covered",
    "surface_darkness",
    "surface_shadow",
]


class ReceivingSurface(NamedTuple):
    """The faces that receive besides the planar receivers, in world coordinates.

    vertices : (n, 3) float64
    faces : (m, 3) int64
    owner : (m,) int64
        The shape (index in the geometry list) of each face.
    normals : (m, 3, 3) float64
        The normals the viewer shades each face's corners with
        (:func:`~.terminator.corner_normals`).
    scopes : tuple of frozenset of int
        Each shape's :attr:`~.model.Shape.scopes` (indexed as ``owner``).
    """

    vertices: np.ndarray
    faces: np.ndarray
    owner: np.ndarray
    normals: np.ndarray
    scopes: tuple[frozenset[int], ...] = ()

    def lit_by(self, scene_light: SceneLight) -> ReceivingSurface:
        """The faces ``scene_light`` lights: those of shapes in its scope (all
        for a light with none; the vertices are kept as they are)."""
        if scene_light.scope is None:
            return self
        inside = np.array([lights(scene_light, scopes) for scopes in self.scopes], dtype=bool)
        keep = inside[self.owner] if len(self.owner) else np.zeros(0, dtype=bool)
        return self.only(keep)

    def only(self, keep: np.ndarray) -> ReceivingSurface:
        """The faces where ``keep`` (m,) bool is set (the vertices kept as they are)."""
        return self._replace(
            faces=self.faces[keep], owner=self.owner[keep], normals=self.normals[keep]
        )


def _receiver_centroids(found: list[Receiver]) -> np.ndarray:
    patches = [receiver.triangles for receiver in found if receiver.triangles is not None]
    if not patches:
        return np.zeros((0, 3))
    centroids: np.ndarray = np.concatenate(patches).mean(axis=1)
    return centroids


def _rows_in(rows: np.ndarray, table: np.ndarray) -> np.ndarray:
    """(n,) bool: is each row of ``rows`` a row of ``table`` (both int64, one
    numpy pass instead of a Python set look-up per face)."""
    both = np.concatenate([table, rows])
    inverse = row_groups(both - both.min(axis=0))[1]
    found: np.ndarray = np.isin(inverse[len(table) :], inverse[: len(table)])
    return found


def receiving_faces(
    geometry: list[Shape],
    found: list[Receiver],
    tolerance: Tolerance,
    stacked: CasterSet | None = None,
) -> ReceivingSurface:
    """The faces of ``geometry`` that no planar receiver covers, as one
    surface in world coordinates (open shapes' faces twice, once each way
    round; a face repeated within a shape once), in the shapes' order, with
    each face's shape and shading normals. ``stacked``: the shapes'
    :class:`~.casters.CasterSet`, when the caller has it; all shapes are
    handled in one numpy pass."""
    if stacked is None:
        stacked = CasterSet(geometry)
    if not len(stacked.faces):
        none = np.zeros((0, 3), dtype=np.int64)
        return ReceivingSurface(
            np.zeros((0, 3)), none, none[:, 0], np.zeros((0, 3, 3)), _scopes(geometry)
        )
    owner = stacked.face_owner
    # a face repeated (by coordinates) receives one shadow, not one per copy
    first = np.sort(repeated_faces(stacked.vertices, stacked.faces, owner)[0])
    keys = np.round(_receiver_centroids(found) / tolerance.length).astype(np.int64)
    if len(keys):
        centroids = stacked.vertices[stacked.faces[first]].mean(axis=1)
        rounded = np.round(centroids / tolerance.length).astype(np.int64)
        first = first[~_rows_in(rounded, keys)]
    open_shape = np.array([not shape.solid for shape in geometry], dtype=bool)
    twice = first[open_shape[owner[first]]]
    faces = np.concatenate([stacked.faces[first], stacked.faces[twice][:, ::-1]])
    # in the shapes' order: each shape's faces, then its faces turned round
    order = np.lexsort(
        (
            np.concatenate([first, twice]),
            np.repeat([0, 1], [len(first), len(twice)]),
            owner[np.concatenate([first, twice])],
        )
    )
    faces = faces[order]
    owners = owner[np.concatenate([first, twice])[order]]
    turned = np.repeat([0, 1], [len(first), len(twice)])[order]
    used = unique_integers(faces.reshape(-1))
    renumber = np.zeros(len(stacked.vertices), dtype=np.int64)
    renumber[used] = np.arange(len(used))
    vertices, faces = stacked.vertices[used], renumber[faces]
    crease = np.array([shape.crease_angle for shape in geometry], dtype=np.float64)[owners]
    # each side of an open shape smoothed on its own: a creaseAngle of 3.1416
    # ("smooth everything") must not average a face with the turned copies
    normals = corner_normals(vertices, faces, 2 * owners + turned, crease)
    return ReceivingSurface(vertices, faces, owners, normals, _scopes(geometry))


def _scopes(geometry: list[Shape]) -> tuple[frozenset[int], ...]:
    return tuple(shape.scopes for shape in geometry)


def surface_shadow(
    surface: ReceivingSurface,
    casters: list[Caster],
    opacity: np.ndarray,
    caster_shapes: np.ndarray,
    scene_light: SceneLight,
    tolerance: Tolerance,
    lift: float,
    light_name: str,
    lighting: Lighting | None = None,
) -> tuple[list[tuple[float, Shape]], list[str]]:
    """The shadow of ``casters`` (in world coordinates; ``opacity`` (k,) the
    casting opacity of each, above 0; ``caster_shapes`` (k,) the index of
    each one's shape) on ``surface`` as shapes (role ``"shadow"``), one per
    opacity, most opaque first, as the planar receivers'
    (:func:`~shadowgeo.shadow_layers_on_surface`: the layers do not overlap,
    each as dark as its opacity), drawn where the shading lights the surface
    (module notes); none when no shadow falls on it. As dark as ``lighting``
    says for X3D's default material (the surface spans shapes of many
    looks), else the light's ``shadow_intensity``. With a note when the
    shadow could not be made."""
    light = scene_light.light
    keep = [k for k, caster in enumerate(casters) if caster.n_faces]
    if not len(surface.faces) or not keep:
        return [], []
    levels, groups, shapes_of = _by_opacity(casters, opacity, caster_shapes, keep)
    corners = surface.vertices[surface.faces]
    values = lit_values(corners, surface.normals, light)
    try:
        layers = shadow_layers_on_surface(
            groups, light, (surface.vertices, surface.faces), offset=lift, tolerance=tolerance
        )
    except GeometryError as error:
        return [], [f"shadows: no shadows on the surfaces for light {light_name}: {error}"]
    pieces = [
        [clip_to_lit(layer.vertices, layer.faces, layer.face_index, corners, values)]
        for layer in layers
    ]
    shadowed = np.concatenate([layer.face_index for layer in layers])
    past = _past_terminator(surface, values, shadowed, light)
    if len(past):
        turned = _turned_pieces(surface, past, groups, shapes_of, light, lift, tolerance, values)
        for layer_pieces, part in zip(pieces, turned or [], strict=False):
            layer_pieces.append(part)  # (none when the turned faces keep their own terminator)
    where = f"shadow of light {light_name} on the scene's surfaces"
    shapes = []
    for level, layer_pieces in zip(levels, pieces, strict=True):
        source = where if level >= 1 else f"{where}, of casters of opacity {level:g}"
        shape = _pieces_shape(surface, layer_pieces, scene_light, source, level, lighting)
        if shape is not None:
            shapes.append((level, shape))
    return shapes, []


def _by_opacity(
    casters: list[Caster], opacity: np.ndarray, caster_shapes: np.ndarray, keep: list[int]
) -> tuple[list[float], list[list[Caster]], np.ndarray]:
    """The casters ``keep`` grouped by opacity, most opaque first: the
    levels, the groups, and each caster's shape in the groups' order."""
    levels = sorted({float(opacity[k]) for k in keep}, reverse=True)
    order = [k for level in levels for k in keep if opacity[k] == level]  # group by group
    groups = [[casters[k] for k in keep if opacity[k] == level] for level in levels]
    return levels, groups, np.asarray(caster_shapes)[order]


_Piece = tuple[np.ndarray, np.ndarray, np.ndarray]  # (vertices, faces, face of each face)


def _turned_pieces(
    surface: ReceivingSurface,
    past: np.ndarray,
    groups: list[list[Caster]],
    shapes_of: np.ndarray,
    light: Light,
    lift: float,
    tolerance: Tolerance,
    values: np.ndarray,
) -> list[_Piece] | None:
    """Each layer's shadow on the faces ``past`` the terminator (turned round,
    each face fronts the light; lifted back out along its own normal), clipped
    to where the shading lights them; None when it cannot be made (these
    faces keep the shading's own terminator)."""
    turned = surface.faces[past][:, ::-1]
    used, inverse = unique_integers(turned.reshape(-1), return_inverse=True)
    position = {int(shape): k for k, shape in enumerate(shapes_of)}
    own = np.array([position.get(int(shape), -1) for shape in surface.owner[past]])
    try:
        parts = shadow_layers_on_surface(
            groups,
            light,
            (surface.vertices[used], inverse.reshape(-1, 3)),
            offset=-lift,
            tolerance=tolerance,
            not_shadowed_by=own,
        )
    except GeometryError:
        return None
    corners = surface.vertices[surface.faces]
    return [
        clip_to_lit(
            part.vertices, part.faces, past[part.face_index], corners[:, ::-1], values[:, ::-1]
        )
        for part in parts
    ]


def _pieces_shape(
    surface: ReceivingSurface,
    pieces: list[_Piece],
    scene_light: SceneLight,
    source: str,
    level: float,
    lighting: Lighting | None,
) -> Shape | None:
    """One layer's ``pieces`` as one shadow shape; None when they are empty."""
    vertices, triangles = _joined([(points, faces) for points, faces, _ in pieces])
    if not len(triangles):
        return None
    darkness = None
    if lighting is not None:
        index = np.concatenate([index for *_, index in pieces])
        darkness = surface_darkness(surface, lighting, scene_light, vertices, triangles, index)
    return shadow_shape(vertices, triangles, scene_light, source, level, darkness)


def surface_darkness(
    surface: ReceivingSurface,
    lighting: Lighting,
    scene_light: SceneLight,
    vertices: np.ndarray,
    triangles: np.ndarray,
    face_index: np.ndarray,
) -> float:
    """How dark ``lighting`` draws the shadow of ``scene_light`` made of
    ``triangles`` on the faces ``face_index`` (t,) of ``surface``: each
    triangle lit by the lights whose scope holds its shape."""
    owners = surface.owner[face_index]
    table = np.empty(len(surface.scopes), dtype=object)  # frozensets, not sequences
    table[:] = surface.scopes
    scopes = list(table[owners]) if len(table) else None
    return lighting.darkness(scene_light, vertices, triangles, scopes=scopes)


def surface_covered(
    surface: ReceivingSurface,
    scene_light: SceneLight,
    opacity: float,
    lift: float,
    light_name: str,
    lighting: Lighting | None = None,
) -> list[tuple[float, Shape]]:
    """The shadow of a closed caster round the light (of casting ``opacity``)
    on ``surface``: every face, where the shading lights it, lifted ``lift``
    along its normal; as dark as :func:`surface_shadow`'s. The light lights
    nothing outside the caster, and the surface's lit faces outside it are
    all there is to darken (the caster's own faces turn away from the light
    inside it)."""
    light = scene_light.light
    if not len(surface.faces):
        return []
    corners = surface.vertices[surface.faces]
    values = lit_values(corners, surface.normals, light)
    lit = np.flatnonzero(values.max(axis=1) > 0)
    if not len(lit):
        return []
    normals = np.cross(corners[lit, 1] - corners[lit, 0], corners[lit, 2] - corners[lit, 0])
    lengths = np.linalg.norm(normals, axis=1, keepdims=True)
    lifted = corners[lit] + lift * (normals / np.where(lengths > 0, lengths, 1.0))[:, None]
    triangles = np.arange(3 * len(lit)).reshape(-1, 3)
    vertices, faces, index = clip_to_lit(lifted.reshape(-1, 3), triangles, lit, corners, values)
    if not len(faces):
        return []
    darkness = None
    if lighting is not None:
        darkness = surface_darkness(surface, lighting, scene_light, vertices, faces, index)
    where = f"shadow of light {light_name} on the scene's surfaces, from a caster round it"
    return [(opacity, shadow_shape(vertices, faces, scene_light, where, opacity, darkness))]


def _past_terminator(
    surface: ReceivingSurface,
    values: np.ndarray,
    shadowed: np.ndarray,
    light: Light,
) -> np.ndarray:
    """The faces turned away from the light that the shading still lights
    (some corner with ``values > 0``) and that touch a face with a cast
    shadow (``shadowed``: face of each shadow triangle)."""
    none = np.zeros(0, dtype=np.int64)
    if not len(shadowed):
        return none
    corners = surface.vertices[surface.faces]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    if is_positional(light):
        turned = np.einsum("ij,ij->i", normals, light.position - corners[:, 0]) <= 0
    else:
        turned = normals @ light.direction >= 0
    candidates = np.flatnonzero(turned & (values.max(axis=1) > 0))
    if not len(candidates):
        return none
    touched = np.zeros(len(surface.vertices), dtype=bool)
    touched[surface.faces[unique_integers(shadowed)].reshape(-1)] = True
    near: np.ndarray = candidates[touched[surface.faces[candidates]].any(axis=1)]
    return near


def _joined(parts: list[tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """Meshes (vertices, faces) as one."""
    starts = np.cumsum([0] + [len(points) for points, _ in parts[:-1]])
    vertices = np.concatenate([points for points, _ in parts])
    faces = np.concatenate(
        [triangles + start for (_, triangles), start in zip(parts, starts, strict=True)]
    )
    return vertices, faces.astype(np.int64)
