"""glTF 2.0 writer (``.glb`` binary, ``.gltf`` JSON with an embedded buffer).

What is written
---------------
- One node per shape, named after it, holding the shape's transform as a
  column-major ``matrix`` and a mesh of one triangle primitive. A transform
  that is not translation x rotation x scale (a shear, which X3D's
  ``scaleOrientation`` can make and glTF forbids) is baked into the vertices
  instead, and the node gets none.
- Materials: ``pbrMetallicRoughness`` with ``baseColorFactor`` = diffuse
  colour and alpha = 1 - transparency, ``alphaMode`` ``BLEND`` when
  transparent, ``doubleSided`` when the shape is not solid, emissive colour.
- Shadows and shadow volumes (shapes with role ``"shadow"`` / ``"volume"``) as
  their own meshes under one node per light group, named after the group.
- Lights through ``KHR_lights_punctual``, each on its own node
  (:func:`.gltf_layout.light_entry`).
- glTF is Y-up in metres: a scene that is Z-up, or not in metres, goes under
  one root node that rotates and scales it there.
- A perspective camera for each of the scene's viewpoints (an X3D
  Viewpoint, a glTF camera read), else one that frames the scene and its
  shadows (:func:`~shadowgeo.scene.model.overview`): each on a node of the
  default scene, in glTF's Y-up metres, the first being the one viewers
  open at. ``yfov`` is the viewpoint's field of view (X3D's smaller angle:
  the vertical one in a landscape window); ``aspectRatio`` is left to the
  viewer and ``zfar`` out (an infinite projection).
- What glTF has no field for (roles, groups, X3D's ``shadows``,
  ``shadowIntensity``, ``on``, attenuation, ambient intensity) goes in the
  node's ``extras["shadowgeo"]`` (:mod:`.gltf_layout`), which
  :mod:`.gltf_read` reads back.

Precision
---------
glTF stores positions as float32. Node transforms are JSON numbers (float64),
so a shape keeps its own frame and only its *local* coordinates are rounded:
a round trip is exact to about ``6e-8`` times the shape's local extent, not
to float64.
"""

from __future__ import annotations

import base64
import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import SceneError
from ..limits import TRS_RELATIVE as _TRS_RELATIVE
from ..scene import Scene, SceneLight, Shape
from ..scene.model import overview, rotate
from . import check_face_indices, up_and_units
from .atomic import atomic_path
from .gltf_layout import (
    LIGHTS,
    glb_container,
    light_entry,
    quaternion_xyzw,
    shape_extras,
    unit_float,
)

__all__ = ["build", "is_trs", "write"]

_ARRAY_BUFFER = 34962
_ELEMENT_ARRAY_BUFFER = 34963
_FLOAT = 5126
_UNSIGNED_INT = 5125


def is_trs(matrix: np.ndarray) -> bool:
    """True when a (4, 4) affine matrix is translation x rotation x scale
    (its linear part has orthogonal columns), as glTF requires of ``matrix``.

    (In plain floats: one call per shape node, and numpy's per-call cost on a
    3 x 3 was seconds in a scene of 50,000 shapes.)"""
    rows = matrix.tolist()
    if not all(math.isfinite(value) for row in rows for value in row):
        return False
    last_row = zip(rows[3], _LAST_ROW, strict=True)
    if not all(abs(value - unit) <= _TRS_RELATIVE for value, unit in last_row):
        return False
    return _orthogonal_columns([[rows[0][j], rows[1][j], rows[2][j]] for j in range(3)])


def _orthogonal_columns(columns: list[list[float]]) -> bool:
    """Whether three columns, none zero, are orthogonal to within
    :data:`~shadowgeo.limits.TRS_RELATIVE` of the largest product."""
    gram = [[u[0] * v[0] + u[1] * v[1] + u[2] * v[2] for v in columns] for u in columns]
    size = max(max(abs(value) for row in gram for value in row), _TINY)
    off_diagonal = max(abs(gram[i][j]) for i in range(3) for j in range(3) if i != j)
    return bool(off_diagonal <= _TRS_RELATIVE * size and min(gram[i][i] for i in range(3)) > 0)


_TINY = float(np.finfo(float).tiny)
_LAST_ROW = (0.0, 0.0, 0.0, 1.0)
_IDENTITY = np.eye(4)


def _root_matrix(scene: Scene) -> np.ndarray | None:
    """Column-vector matrix taking the scene to glTF's Y-up metres, or None."""
    up, meters_per_unit = up_and_units(scene)
    if up == "Y" and meters_per_unit == 1.0:
        return None
    matrix = np.eye(4)
    if up == "Z":
        # Z-up to Y-up: (x, y, z) -> (x, z, -y).
        matrix[:3, :3] = [[1, 0, 0], [0, 0, 1], [0, -1, 0]]
    matrix[:3, :3] *= meters_per_unit
    return matrix


class _Builder:
    """Accumulates the glTF JSON and its one binary buffer."""

    def __init__(self) -> None:
        self.gltf: dict[str, Any] = {
            "asset": {"version": "2.0", "generator": "shadowgeo"},
            "scene": 0,
            "scenes": [{"nodes": []}],
            "nodes": [],
        }
        self.binary = bytearray()
        self.materials: dict[tuple[Any, ...], int] = {}
        self.packed: dict[tuple[Any, ...], tuple[Any, ...]] = {}

    def _view(self, data: np.ndarray, target: int) -> int:
        """A buffer view of the contiguous array ``data`` (copied once, into
        the buffer, from its memory)."""
        self.binary.extend(b"\0" * (-len(self.binary) % 4))
        views = self.gltf.setdefault("bufferViews", [])
        views.append(
            {
                "buffer": 0,
                "byteOffset": len(self.binary),
                "byteLength": data.nbytes,
                "target": target,
            }
        )
        self.binary += data.data.cast("B")
        return len(views) - 1

    def _accessor(self, **accessor: Any) -> int:
        accessors = self.gltf.setdefault("accessors", [])
        accessors.append(accessor)
        return len(accessors) - 1

    def node(self, node: dict[str, Any]) -> int:
        self.gltf["nodes"].append(node)
        return len(self.gltf["nodes"]) - 1

    def material(self, shape: Shape) -> int:
        look = shape.material
        alpha = unit_float(1.0 - float(look.transparency))
        roughness = unit_float(1.0 - look.shininess)
        key = (
            tuple(look.diffuse_color),
            tuple(look.emissive_color),
            alpha,
            roughness,
            shape.solid,
            look.name,
        )
        if key not in self.materials:
            material = {
                "pbrMetallicRoughness": {
                    "baseColorFactor": [*(unit_float(c) for c in look.diffuse_color), alpha],
                    "metallicFactor": 0.0,
                    "roughnessFactor": roughness,
                },
                "doubleSided": not shape.solid,
            }
            if any(look.emissive_color):
                material["emissiveFactor"] = [unit_float(c) for c in look.emissive_color]
            if alpha < 1.0:
                material["alphaMode"] = "BLEND"
            if look.name:
                material["name"] = look.name
            materials = self.gltf.setdefault("materials", [])
            materials.append(material)
            self.materials[key] = len(materials) - 1
        return self.materials[key]

    def light(self, light: SceneLight) -> dict[str, Any]:
        """Add the light's KHR_lights_punctual entry; return the node placing it."""
        lights = self.gltf.setdefault("extensions", {}).setdefault(LIGHTS, {"lights": []})
        entry, node = light_entry(light, len(lights["lights"]))
        lights["lights"].append(entry)
        self.gltf.setdefault("extensionsUsed", [])
        if LIGHTS not in self.gltf["extensionsUsed"]:
            self.gltf["extensionsUsed"].append(LIGHTS)
        return node

    def mesh(self, shape: Shape, vertices: np.ndarray) -> int | None:
        """A one-primitive mesh for ``vertices`` (n, 3) and the shape's faces;
        None when there is nothing to draw (glTF forbids empty accessors)."""
        check_face_indices(shape)
        if len(shape.faces) == 0:
            return None
        # shapes that share their arrays (DEF/USE, prototype copies, equal
        # primitives) are packed once; the arrays are held, so ids stay theirs
        if vertices is not shape.vertices:  # (world vertices: this shape's own)
            positions, indices, low, high = _packed(shape, vertices)
        else:
            key = (_memory(vertices), _memory(shape.faces))
            if key not in self.packed:
                self.packed[key] = (vertices, shape.faces, *_packed(shape, vertices))
            positions, indices, low, high = self.packed[key][2:]
        position = self._accessor(
            bufferView=self._view(positions, _ARRAY_BUFFER),
            componentType=_FLOAT,
            count=len(positions),
            type="VEC3",
            min=list(low),
            max=list(high),
        )
        index = self._accessor(
            bufferView=self._view(indices, _ELEMENT_ARRAY_BUFFER),
            componentType=_UNSIGNED_INT,
            count=int(indices.size),
            type="SCALAR",
        )
        meshes = self.gltf.setdefault("meshes", [])
        primitive = {"attributes": {"POSITION": position}, "indices": index, "mode": 4}
        primitive["material"] = self.material(shape)
        meshes.append({"primitives": [primitive], **({"name": shape.name} if shape.name else {})})
        return len(meshes) - 1


def _memory(array: np.ndarray) -> tuple[Any, ...]:
    """Where ``array``'s numbers are: two views of the same memory (a shape
    used again, Shape's own ``asarray`` of an array) have the same."""
    return (array.__array_interface__["data"][0], array.shape, array.strides)


def _packed(
    shape: Shape, vertices: np.ndarray
) -> tuple[np.ndarray, np.ndarray, list[float], list[float]]:
    """glTF's float32 positions and uint32 indices of ``vertices`` and the
    shape's faces (only the vertices the faces use), with the positions' bounds."""
    # Only the vertices the faces use: glTF's validator flags unused ones
    # (a mask, not np.unique: linear, and no copy when all are used).
    in_use = np.zeros(len(vertices), dtype=bool)
    in_use[shape.faces.ravel()] = True
    if not in_use.all():
        used = np.flatnonzero(in_use)
        remap = np.zeros(len(vertices), dtype=np.int64)
        remap[used] = np.arange(len(used))
        vertices, faces = vertices[used], remap[shape.faces]
    else:
        faces = shape.faces
    # a float64 past float32's range becomes inf: said below, not warned
    with np.errstate(over="ignore"):
        positions = np.ascontiguousarray(vertices, dtype="<f4")
    indices = np.ascontiguousarray(faces, dtype="<u4")
    # column by column (a strided axis-0 reduction is several times
    # slower); NaN or inf anywhere shows in the bounds
    low = [float(positions[:, k].min()) for k in range(3)]
    high = [float(positions[:, k].max()) for k in range(3)]
    if not all(math.isfinite(value) for value in low + high):
        # name where the shape was read: the cause is there, not in the output
        where = f"shape {shape.name!r}" if shape.name else "a shape"
        where += f" ({shape.source})" if shape.source else ""
        if not np.isfinite(vertices).all():
            raise SceneError("non-finite vertex", node=where)
        raise SceneError(
            "a vertex past float32's range (about 3.4e38), which glTF positions hold",
            node=where,
        )
    return positions, indices, low, high


def _shape_node(builder: _Builder, shape: Shape) -> dict[str, Any]:
    node: dict[str, Any] = {}
    if shape.name:
        node["name"] = shape.name
    transform = shape.transform
    vertices = shape.vertices
    if not np.array_equal(transform, _IDENTITY):
        if is_trs(transform):  # (finite too)
            node["matrix"] = transform.T.reshape(-1).tolist()
        else:
            vertices = shape.world_vertices
    mesh = builder.mesh(shape, vertices)
    if mesh is not None:
        node["mesh"] = mesh
    node["extras"] = shape_extras(shape)
    return node


def build(scene: Scene) -> tuple[dict[str, Any], bytes]:
    """The glTF JSON document and its binary buffer for ``scene``.

    Returns
    -------
    gltf : dict
        The JSON document, without ``buffers`` (the caller adds the one buffer
        in the form its container needs).
    binary : bytes
        The buffer: positions (float32) and indices (uint32), 4-byte aligned.
    """
    builder = _Builder()
    top: list[int] = []
    groups: dict[str, int] = {}
    for shape in scene.shapes:
        index = builder.node(_shape_node(builder, shape))
        if shape.role == "geometry" and not shape.group:
            top.append(index)
            continue
        group = shape.group or f"shadowgeo {shape.role}s"
        if group not in groups:
            groups[group] = builder.node(
                {"name": group, "children": [], "extras": {"shadowgeo": {"role": "group"}}}
            )
            top.append(groups[group])
        builder.gltf["nodes"][groups[group]]["children"].append(index)
    for light in scene.lights:
        top.append(builder.node(builder.light(light)))
    root = _root_matrix(scene)
    cameras = [builder.node(node) for node in _camera_nodes(builder, scene, root)]
    if root is not None and top:
        top = [
            builder.node(
                {
                    "name": "shadowgeo root",
                    "matrix": [float(v) for v in root.T.reshape(-1)],
                    "children": top,
                    "extras": {"shadowgeo": {"role": "root"}},
                }
            )
        ]
    builder.gltf["scenes"][0]["nodes"] = top + cameras
    builder.binary.extend(b"\0" * (-len(builder.binary) % 4))
    return builder.gltf, bytes(builder.binary)


def _camera_nodes(builder: _Builder, scene: Scene, root: np.ndarray | None) -> list[dict[str, Any]]:
    """A camera node for each of the scene's viewpoints, else for its
    overview, in glTF's frame (``root`` takes the scene there; its scale is
    taken out of the camera's rotation)."""
    root = np.eye(4) if root is None else root
    turn = root[:3, :3] / np.cbrt(np.linalg.det(root[:3, :3]))
    size = float(np.linalg.norm(np.subtract(*scene.bounds))) * np.cbrt(np.linalg.det(root[:3, :3]))
    cameras = builder.gltf.setdefault("cameras", [])
    nodes = []
    for view in scene.viewpoints or [overview(scene)]:
        rotation = np.column_stack([rotate(view.orientation, axis) for axis in np.eye(3)])
        position = root[:3, :3] @ np.asarray(view.position) + root[:3, 3]
        if not (np.all(np.isfinite(position)) and 0 < view.field_of_view < math.pi):
            raise SceneError(
                f"cannot write viewpoint {view.name or view.description!r}: not finite"
            )
        perspective = {"yfov": float(view.field_of_view), "znear": _near(size)}
        camera: dict[str, Any] = {"type": "perspective", "perspective": perspective}
        if view.description:
            camera["name"] = view.description
        cameras.append(camera)
        node: dict[str, Any] = {
            "camera": len(cameras) - 1,
            "translation": [float(v) for v in position],
            "rotation": quaternion_xyzw(turn @ rotation),
        }
        if view.name:
            node["name"] = view.name
        nodes.append(node)
    return nodes


def _near(size: float) -> float:
    """``znear`` for a scene ``size`` metres across: a thousandth of it, so
    that depth keeps its precision (1 cm for no size)."""
    return size / 1000 if math.isfinite(size) and size > 0 else 0.01


def _glb(gltf: dict[str, Any], binary: bytes) -> bytes:
    if binary:
        gltf["buffers"] = [{"byteLength": len(binary)}]
    return glb_container(json.dumps(gltf, separators=(",", ":"), allow_nan=False).encode(), binary)


def _embedded(gltf: dict[str, Any], binary: bytes) -> bytes:
    if binary:
        uri = "data:application/octet-stream;base64," + base64.b64encode(binary).decode()
        gltf["buffers"] = [{"byteLength": len(binary), "uri": uri}]
    return json.dumps(gltf, indent=1, allow_nan=False).encode()


def write(scene: Scene, path: str | os.PathLike[str], **options: Any) -> None:
    """Write ``scene`` as glTF 2.0: ``.glb`` binary or ``.gltf`` JSON with the
    buffer embedded as a data URI (one file, so the write stays atomic).

    Parameters
    ----------
    scene : Scene
    path : str or Path
        Ends in ``.glb`` or ``.gltf``.

    Raises
    ------
    SceneError
        Options not understood, an up axis other than Y or Z, non-finite
        numbers, or faces indexing missing vertices.
    """
    path = Path(path)
    if options:
        raise SceneError(f"glTF writer takes no options, got {sorted(options)}", path=str(path))
    suffix = path.suffix.lower()
    if suffix not in (".glb", ".gltf"):
        raise SceneError(f"glTF files end in .glb or .gltf, not {suffix!r}", path=str(path))
    try:
        gltf, binary = build(scene)
        data = _glb(gltf, binary) if suffix == ".glb" else _embedded(gltf, binary)
    except SceneError as error:
        raise SceneError(error.message, path=str(path), node=error.node) from None
    except ValueError as error:
        raise SceneError(f"cannot write glTF: {error}", path=str(path)) from error
    with atomic_path(path) as temporary:
        temporary.write_bytes(data)
