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
"""

from __future__ import annotations

import numpy as np

from ..errors import GeometryError
from ..surface import shadow_layers_on_surface
from ..tolerance import Tolerance
from ..topology import Caster, row_groups, unique_integers
from .casters import CasterSet
from .darkness import Lighting
from .model import SceneLight, Shape, shadow_shape
from .receivers import Receiver, repeated_faces


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
) -> tuple[np.ndarray, np.ndarray]:
    """The faces of ``geometry`` that no planar receiver covers, as one
    (vertices, faces) surface in world coordinates (open shapes' faces twice,
    once each way round; a face repeated within a shape once), in the shapes'
    order. ``stacked``: the shapes' :class:`~.casters.CasterSet`, when the
    caller has it; all shapes are handled in one numpy pass."""
    if stacked is None:
        stacked = CasterSet(geometry)
    if not len(stacked.faces):
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
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
    used = unique_integers(faces.reshape(-1))
    renumber = np.zeros(len(stacked.vertices), dtype=np.int64)
    renumber[used] = np.arange(len(used))
    return stacked.vertices[used], renumber[faces]


def surface_shadow(
    surface: tuple[np.ndarray, np.ndarray],
    casters: list[Caster],
    opacity: np.ndarray,
    scene_light: SceneLight,
    tolerance: Tolerance,
    lift: float,
    notes: list[str],
    light_name: str,
    lighting: Lighting | None = None,
) -> list[tuple[float, Shape]]:
    """The shadow of ``casters`` (in world coordinates; ``opacity`` (k,) the
    casting opacity of each, above 0) on ``surface`` as shapes (role
    ``"shadow"``), one per opacity, most opaque first, as the planar
    receivers' (:func:`~shadowgeo.shadow_layers_on_surface`: the layers do
    not overlap, each as dark as its opacity); none when no shadow falls on
    it; as dark as ``lighting`` says for X3D's default material (the surface
    spans shapes of many looks), else the light's ``shadow_intensity``."""
    vertices, faces = surface
    with_faces = [k for k, caster in enumerate(casters) if caster.n_faces]
    if not len(faces) or not with_faces:
        return []
    levels = sorted({float(opacity[k]) for k in with_faces}, reverse=True)
    groups = [[casters[k] for k in with_faces if opacity[k] == level] for level in levels]
    try:
        layers = shadow_layers_on_surface(
            groups, scene_light.light, (vertices, faces), offset=lift, tolerance=tolerance
        )
    except GeometryError as error:
        notes.append(f"shadows: no shadows on the surfaces for light {light_name}: {error}")
        return []
    where = f"shadow of light {light_name} on the scene's surfaces"
    shapes = []
    for level, layer in zip(levels, layers, strict=True):
        if not len(layer.faces):
            continue
        darkness = None
        if lighting is not None:
            darkness = lighting.darkness(scene_light, layer.vertices, layer.faces)
        source = where if level >= 1 else f"{where}, of casters of opacity {level:g}"
        shape = shadow_shape(layer.vertices, layer.faces, scene_light, source, level, darkness)
        shapes.append((level, shape))
    return shapes
