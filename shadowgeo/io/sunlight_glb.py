"""Hours of sunlight per face as a binary glTF (``.glb``): a mesh a 3-D viewer
or a game engine colours and queries.

The writer takes plain arrays (vertices, triangles, hours per triangle, a
group per triangle and the groups' names), so anything that finds hours per
face (the ground's levels of a sun study, sunlight on walls and roofs) feeds
it. Each group is a node with one mesh. Triangles share no vertex, so a
face's value is its three vertices' value, written twice:

- ``COLOR_0`` (float RGB): :func:`shadowgeo.scene.sunlight.ramp_colour` of
  ``hours / most_hours``, dark purple (none) to yellow (sun at every sample);
  faces whose hours are unknown (``NaN``: not studied) are grey;
- ``_SUNLIGHT_HOURS`` (float SCALAR): the hours, ``-1`` where unknown (a
  glTF accessor holds no NaN). The leading underscore is glTF 2.0's mark for
  an application's own attribute (section 3.7.2.1).

Coordinates: the input is Z up (city data) or Y up; glTF is Y up, so a Z-up
``(x, y, z)`` is written ``(x, z, -y)``. Positions are float32 about the
data's centre, and the centre goes, in float64, in each node's
``translation``: RD New's 400,000 m would lose their centimetres in float32.
The material is unlit (``KHR_materials_unlit``): the colours read as the
legend says, whatever the viewer's lights. Written atomically.
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..errors import SceneError
from ..scene.sunlight import ramp_colour
from .atomic import atomic_path
from .gltf_layout import glb_container

__all__ = ["HOURS_ATTRIBUTE", "UNKNOWN_HOURS", "write_hours_glb"]

HOURS_ATTRIBUTE = "_SUNLIGHT_HOURS"
UNKNOWN_HOURS = -1.0
_UNKNOWN_COLOUR = (0.6, 0.6, 0.6)
_UNLIT = "KHR_materials_unlit"
_FLOAT, _ARRAY_BUFFER = 5126, 34962


def write_hours_glb(
    path: str | os.PathLike[str],
    vertices: ArrayLike,
    faces: ArrayLike,
    hours: ArrayLike,
    *,
    most_hours: float,
    groups: ArrayLike | None = None,
    names: Sequence[str] = ("sunlight",),
    up: str = "Z",
) -> None:
    """Write triangles with hours of sunlight per face to a ``.glb``.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (m, 3) int
        Triangles, indices into ``vertices``.
    hours : (m,) float
        Hours of sunlight of each face; NaN where not known.
    most_hours : float
        The hours of sun at every sample: the colour ramp's yellow end.
    groups : (m,) int, optional
        Each face's group, an index into ``names`` (default: all in group 0).
    names : sequence of str
        The groups' node names (a building's id, ``"ground"``).
    up : {"Z", "Y"}
        The input's up axis.

    Raises
    ------
    SceneError
        Arrays that do not fit together (naming ``path``), or a file that
        cannot be written.
    """
    points, triangles, values, owners = _checked(path, vertices, faces, hours, groups, names)
    centre = 0.5 * (points.min(axis=0) + points.max(axis=0)) if len(points) else np.zeros(3)
    turned = _y_up(points - centre, up)
    colours = np.array(
        [
            _UNKNOWN_COLOUR if np.isnan(value) else ramp_colour(value / most_hours)
            for value in values
        ]
        if most_hours > 0
        else [ramp_colour(1.0)] * len(values),
        dtype=np.float32,
    ).reshape(-1, 3)
    document, binary = _document(turned, triangles, values, colours, owners, names)
    offset = _y_up(centre[None], up)[0]
    for node in document["nodes"]:
        node["translation"] = [float(value) for value in offset]
    text = json.dumps(document, separators=(",", ":")).encode()
    target = Path(path)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(target) as temporary:
            temporary.write_bytes(glb_container(text, binary))
    except OSError as error:
        raise SceneError(f"cannot write: {error.strerror or error}", path=str(path)) from None


def _checked(
    path: str | os.PathLike[str],
    vertices: ArrayLike,
    faces: ArrayLike,
    hours: ArrayLike,
    groups: ArrayLike | None,
    names: Sequence[str],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The arrays as float64 / int64, checked to fit together."""
    points = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    triangles = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    values = np.asarray(hours, dtype=np.float64).reshape(-1)
    owners = np.zeros(len(triangles), np.int64) if groups is None else np.asarray(groups, np.int64)
    problem = None
    if len(values) != len(triangles) or owners.shape != (len(triangles),):
        problem = f"{len(triangles)} faces but {len(values)} hours and {owners.size} groups"
    elif len(triangles) and (triangles.min() < 0 or triangles.max() >= len(points)):
        problem = f"a face's index is outside the {len(points)} vertices"
    elif len(owners) and (owners.min() < 0 or owners.max() >= len(names)):
        problem = f"a face's group is outside the {len(names)} names"
    elif not np.all(np.isfinite(points)):
        problem = "vertices are not all finite"
    elif np.any(np.isinf(values)):
        problem = "hours are infinite"
    if problem is not None:
        raise SceneError(f"cannot write hours per face: {problem}", path=str(path))
    return points, triangles, values, owners


def _y_up(points: np.ndarray, up: str) -> np.ndarray:
    """Points of a ``up``-axis scene in glTF's Y-up frame."""
    if up == "Y":
        return points
    return np.column_stack([points[:, 0], points[:, 2], -points[:, 1]])


def _document(
    points: np.ndarray,
    triangles: np.ndarray,
    values: np.ndarray,
    colours: np.ndarray,
    owners: np.ndarray,
    names: Sequence[str],
) -> tuple[dict[str, Any], bytes]:
    """The glTF JSON and its binary buffer: a node and mesh per group with
    faces, each face's three corners its own."""
    accessors: list[dict[str, Any]] = []
    views: list[dict[str, Any]] = []
    chunks: list[bytes] = []
    meshes, nodes = [], []

    def add(data: np.ndarray, kind: str, bounds: bool = False) -> int:
        raw = np.ascontiguousarray(data, dtype=np.float32).tobytes()
        start = sum(len(chunk) for chunk in chunks)
        views.append(
            {"buffer": 0, "byteOffset": start, "byteLength": len(raw), "target": _ARRAY_BUFFER}
        )
        chunks.append(raw)
        accessor: dict[str, Any] = {
            "bufferView": len(views) - 1,
            "componentType": _FLOAT,
            "count": len(data),
            "type": kind,
        }
        if bounds:  # glTF requires POSITION's box
            flat = np.asarray(data, dtype=np.float32)
            accessor["min"] = [float(v) for v in flat.min(axis=0)]
            accessor["max"] = [float(v) for v in flat.max(axis=0)]
        accessors.append(accessor)
        return len(accessors) - 1

    for group, name in enumerate(names):
        chosen = np.flatnonzero(owners == group)
        if not len(chosen):
            continue
        corners = points[triangles[chosen]].reshape(-1, 3)
        attributes = {
            "POSITION": add(corners, "VEC3", bounds=True),
            "COLOR_0": add(np.repeat(colours[chosen], 3, axis=0), "VEC3"),
            HOURS_ATTRIBUTE: add(
                np.repeat(np.nan_to_num(values[chosen], nan=UNKNOWN_HOURS), 3), "SCALAR"
            ),
        }
        meshes.append({"name": name, "primitives": [{"attributes": attributes, "material": 0}]})
        nodes.append({"name": name, "mesh": len(meshes) - 1})
    binary = b"".join(chunks)
    document: dict[str, Any] = {
        "asset": {"version": "2.0", "generator": "shadowgeo sunlight hours"},
        "extensionsUsed": [_UNLIT],
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": [
            {
                "name": "sunlight hours",
                "pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 1.0},
                "doubleSided": True,
                "extensions": {_UNLIT: {}},
            }
        ],
        "accessors": accessors,
        "bufferViews": views,
    }
    if binary:
        document["buffers"] = [{"byteLength": len(binary)}]
    return document, binary
