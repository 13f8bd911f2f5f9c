"""glTF 2.0 input (``.glb``, ``.gltf``): triangles decoded by numpy or by
trimesh, the rest from the JSON.

A plain file (triangle primitives, float positions, a tree of nodes: what
shadowgeo and many exporters write) is decoded by :mod:`.gltf_native`,
views of its buffers; anything else (Draco, sparse or quantized accessors,
strips, lines, vertex colours) by trimesh (:mod:`.trimesh_formats`), as
before. Either way this module reads the JSON itself for what trimesh drops
or changes: the nodes' own names (trimesh renames duplicates), materials as
float factors (trimesh keeps 8-bit colours), ``KHR_lights_punctual`` lights
and the ``extras["shadowgeo"]`` that :mod:`.gltf_write` writes (roles, light
groups, X3D light fields; the layout is in :mod:`.gltf_layout`).

Safety: a glTF's buffers and images may only be data URIs or relative paths
that stay in the file's folder; anything else (``http:``, ``/etc/...``,
``../``) is refused before either decoder sees the file, and nothing remote
is ever fetched. Textures play no part in shadows and are not decoded; a
missing image is a warning, a missing buffer an error.

glTF is Y-up in metres, so a glTF scene reads as ``up_axis="Y"``,
``meters_per_unit=1``.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any
from urllib.parse import unquote

import numpy as np

from .. import limits
from ..errors import SceneError
from ..scene import Material, Scene, Shape
from ..scene.model import Viewpoint, axis_angle
from . import file_problem, float_triple, refuse_outside
from .gltf_layout import (
    LIGHTS,
    check_types,
    external_uris,
    glb_container,
    json_document,
    scene_light,
    shadowgeo_extras,
    shape_fields,
)
from .gltf_native import PlainMeshes, plain_meshes, trs_matrix
from .trimesh_formats import MALFORMED, checked_shape, load_scene, mesh_shape, triangle_meshes

__all__ = ["read"]


def _gltf_document(path: Path) -> tuple[dict[str, Any], bytes | memoryview | None]:
    """The JSON document of a .gltf or .glb file, checked to be glTF 2.x with
    node references that exist and geometry trimesh decodes correctly, and a
    GLB's binary chunk (None for .gltf)."""
    document, binary = json_document(path)
    if not isinstance(document.get("asset"), dict):
        raise SceneError("not glTF: no 'asset' object", path=str(path))
    version = str(document["asset"].get("version", ""))
    if not version.startswith("2."):
        raise SceneError(f"glTF version {version!r} is not supported (2.x)", path=str(path))
    check_types(document, path)
    _check_references(document, path)
    _check_compression(document, path)
    return document, binary


def _check_compression(document: dict[str, Any], path: Path) -> None:
    """Refuse geometry trimesh would decode wrongly without an error: compressed
    primitives (it reads placeholder zeros and only logs that) and normalized
    integer positions (it ignores ``normalized``)."""
    _check_normalized_positions(document, path)
    used = set(document.get("extensionsUsed") or []) | set(document.get("extensionsRequired") or [])
    if "EXT_meshopt_compression" in used:
        raise SceneError("EXT_meshopt_compression is not supported", path=str(path))
    if "KHR_draco_mesh_compression" in used:
        try:
            import DracoPy  # noqa: F401  (trimesh decodes Draco through it)
        except ImportError:
            raise SceneError(
                'KHR_draco_mesh_compression needs DracoPy: pip install "shadowgeo[draco]"',
                path=str(path),
            ) from None


def _check_normalized_positions(document: dict[str, Any], path: Path) -> None:
    """Refuse a POSITION accessor marked ``normalized`` (KHR_mesh_quantization)."""
    accessors = document.get("accessors") or []
    for mesh_index, mesh in enumerate(document.get("meshes") or []):
        for primitive in (mesh.get("primitives") or []) if isinstance(mesh, dict) else []:
            position = (primitive.get("attributes") or {}).get("POSITION")
            if not (isinstance(position, int) and 0 <= position < len(accessors)):
                continue
            accessor = accessors[position]
            if isinstance(accessor, dict) and accessor.get("normalized"):
                # KHR_mesh_quantization; trimesh would keep the raw integers.
                raise SceneError(
                    "normalized integer positions are not supported",
                    path=str(path),
                    node=f"meshes[{mesh_index}] POSITION accessor {position}",
                )


def _check_references(document: dict[str, Any], path: Path) -> None:
    """Node references to meshes and nodes must exist (trimesh skips a missing
    mesh silently, which would lose geometry without a word)."""
    nodes = document.get("nodes") or []
    n_meshes = len(document.get("meshes") or [])
    for index, node in enumerate(nodes):
        where = f"nodes[{index}]" + (f" {node.get('name')!r}" if isinstance(node, dict) else "")
        if not isinstance(node, dict):
            raise SceneError("malformed glTF: a node is not an object", path=str(path), node=where)
        mesh = node.get("mesh")
        if mesh is not None and not (isinstance(mesh, int) and 0 <= mesh < n_meshes):
            message = f"mesh {mesh!r} does not exist ({n_meshes} meshes)"
            raise SceneError(message, path=str(path), node=where)
        for child in node.get("children") or []:
            if not (isinstance(child, int) and 0 <= child < len(nodes)):
                message = f"child {child!r} does not exist ({len(nodes)} nodes)"
                raise SceneError(message, path=str(path), node=where)


def _check_triangles(document: dict[str, Any], path: Path, limit: int | None) -> None:
    """Refuse, naming the node, a file whose triangles (each mesh's index or
    position count over 3, counted for each node that uses it: at most what
    decoding makes) pass the memory budget, before a buffer is decoded."""
    accessors = document.get("accessors") or []
    meshes = document.get("meshes") or []

    def count(index: Any) -> int:
        accessor = (
            accessors[index] if isinstance(index, int) and 0 <= index < len(accessors) else {}
        )
        value = accessor.get("count", 0) if isinstance(accessor, dict) else 0
        return value if isinstance(value, int) and value > 0 else 0

    def mesh_triangles(mesh: Any) -> int:
        primitives = mesh.get("primitives") if isinstance(mesh, dict) else None
        total = 0
        for primitive in primitives if isinstance(primitives, list) else []:
            if not isinstance(primitive, dict) or primitive.get("mode", 4) not in (4, 5, 6):
                continue  # points and lines make none
            attributes = primitive.get("attributes")
            position = attributes.get("POSITION") if isinstance(attributes, dict) else None
            per_triangle = 3 if primitive.get("mode", 4) == 4 else 1  # strips and fans: 1
            total += count(primitive.get("indices", position)) // per_triangle
        return total

    per_mesh = [mesh_triangles(mesh) for mesh in meshes]
    triangles = 0
    for index, node in enumerate(document.get("nodes") or []):
        mesh = node.get("mesh") if isinstance(node, dict) else None
        if isinstance(mesh, int) and 0 <= mesh < len(per_mesh):
            triangles += per_mesh[mesh]
            name = f"nodes[{index}]" + (f" {node.get('name')!r}" if node.get("name") else "")
            limits.check_expansion(triangles, str(path), name, None, limit, through="nodes")


def _check_uris(document: dict[str, Any], path: Path) -> list[str]:
    """Refuse resources that are remote or outside the file's folder, and
    missing buffers; return warnings for missing images (textures, which
    shadowgeo does not use)."""
    folder = path.resolve().parent
    warnings = []
    for where, uri in external_uris(document):
        target = (folder / unquote(uri)).resolve()
        refuse_outside(uri, target, folder, path=path, where=where)
        if file_problem(target) is None:
            continue
        if where.startswith("buffers"):
            raise SceneError("missing external file", path=str(path), node=where)
        warnings.append(f"{path.name}: {where}: missing texture image, ignored")
    return warnings


def _for_trimesh(
    document: dict[str, Any], binary: bytes | memoryview | None
) -> tuple[bytes, dict[str, int]]:
    """The file trimesh reads, and its frame name -> glTF node index.

    Nodes and meshes are renamed ``node<i>`` and ``mesh<i>``: trimesh renames
    duplicate names (and fails on duplicates holding ``{``), so the real names
    come from ``document`` instead. Resource URIs are percent-decoded.
    """
    renamed = dict(document)
    renamed["nodes"] = [
        {**node, "name": f"node{index}"} for index, node in enumerate(document.get("nodes") or [])
    ]
    if document.get("meshes"):
        renamed["meshes"] = [
            {**mesh, "name": f"mesh{index}"} if isinstance(mesh, dict) else mesh
            for index, mesh in enumerate(document["meshes"])
        ]
    # URIs are percent-encoded (RFC 3986) and trimesh does not decode them;
    # _check_uris has already kept them inside the file's folder.
    if document.get("buffers"):
        renamed["buffers"] = [
            {**item, "uri": unquote(item["uri"])}
            if isinstance(item, dict) and not str(item.get("uri", "data:")).startswith("data:")
            else item
            for item in document["buffers"]
        ]
    # Textures play no part in shadows: trimesh need not decode (or miss) them.
    for kind in ("images", "textures", "samplers"):
        renamed.pop(kind, None)
    if document.get("materials"):
        renamed["materials"] = [_untextured(material) for material in document["materials"]]
    text = json.dumps(renamed).encode()
    frames = {f"node{index}": index for index in range(len(renamed["nodes"]))}
    return (text if binary is None else glb_container(text, binary)), frames


def _untextured(material: Any) -> Any:
    """A glTF material without its texture references (and extensions, which
    may hold more)."""
    if not isinstance(material, dict):
        return material
    plain = {
        key: value
        for key, value in material.items()
        if key not in ("normalTexture", "occlusionTexture", "emissiveTexture", "extensions")
    }
    if isinstance(plain.get("pbrMetallicRoughness"), dict):
        plain["pbrMetallicRoughness"] = {
            key: value
            for key, value in plain["pbrMetallicRoughness"].items()
            if key not in ("baseColorTexture", "metallicRoughnessTexture")
        }
    return plain


def _unit(value: Any, default: float) -> float:
    """A glTF factor clipped to its range [0, 1]; ``default`` when not finite
    (JSON's 1e400 reads as inf): writers store colours as float32."""
    number = float(value)
    return min(max(number, 0.0), 1.0) if math.isfinite(number) else default


def _material_from_gltf(entry: dict[str, Any]) -> tuple[Material, bool]:
    """(Material, solid) from a glTF material object."""
    pbr = entry.get("pbrMetallicRoughness") or {}
    red, green, blue, alpha = (list(pbr.get("baseColorFactor", [1, 1, 1, 1])) + [1.0] * 4)[:4]
    alpha = _unit(alpha, 1.0) if entry.get("alphaMode", "OPAQUE") == "BLEND" else 1.0
    emissive = (list(entry.get("emissiveFactor") or [0, 0, 0]) + [0.0] * 3)[:3]
    material = Material(
        diffuse_color=float_triple(_unit(c, 1.0) for c in (red, green, blue)),
        emissive_color=float_triple(_unit(c, 0.0) for c in emissive),
        shininess=1.0 - _unit(pbr.get("roughnessFactor", 1.0), 1.0),
        transparency=1.0 - alpha,
        name=entry.get("name"),
    )
    return material, not entry.get("doubleSided", False)


def read(
    path: str | os.PathLike[str], *, max_triangles: int | None = None, **options: Any
) -> Scene:
    """Read a glTF 2.0 file into a :class:`Scene`.

    Parameters
    ----------
    path : str or Path
        ``.glb`` or ``.gltf``.
    max_triangles : int, optional
        The triangle (memory) budget, default
        :data:`~shadowgeo.limits.MAX_TRIANGLES`: a file whose meshes, counted
        once for each node that uses them, pass it is refused before a
        buffer is decoded.

    Returns
    -------
    Scene
        One shape per mesh instance (glTF node), with its world transform,
        material, name and, for glTF written by shadowgeo, its role and light
        group; the ``KHR_lights_punctual`` lights; the perspective cameras,
        as Viewpoints (a glTF camera, like X3D's, looks along its -Z with +Y
        up). Points and lines are skipped with a warning.

    Raises
    ------
    SceneError
        Missing, unreadable or corrupt file; a resource outside its folder.
    """
    path = Path(path)
    if options:
        raise SceneError(f"glTF reader takes no options, got {sorted(options)}", path=str(path))
    if not path.is_file():
        raise SceneError("no such file", path=str(path))
    document, binary = _gltf_document(path)
    warnings = _check_uris(document, path)
    _check_triangles(document, path, max_triangles)
    scene = Scene(path=str(path), warnings=warnings)
    nodes = document.get("nodes") or []
    plain = plain_meshes(document, binary, path)
    try:
        world: Callable[[int], np.ndarray | None]
        if plain is not None:
            keys = _read_plain_shapes(scene, plain, path, nodes, document)
            world = plain.worlds.get
        else:
            keys, world = _read_shapes(scene, path, nodes, document, binary)
        _read_empty_shapes(scene, world, nodes, keys)
        _read_lights(scene, world, nodes, document)
        _read_cameras(scene, document, None if plain is None else plain.worlds)
    except MALFORMED as error:
        if isinstance(error, SceneError):
            raise
        kind = path.suffix.lower().lstrip(".").upper()
        raise SceneError(f"malformed {kind}: {error}", path=str(path)) from error
    # A glTF may hold only lights: no triangles is no error here.
    return scene


def _look(document: dict[str, Any], node: dict[str, Any]) -> dict[str, Any]:
    """``material`` and ``solid`` from the glTF material of a node whose mesh
    is one primitive with a material (exact float factors); else ``{}``, and
    trimesh's 8-bit colours serve."""
    primitives = (document.get("meshes") or [{}])[node["mesh"]] if "mesh" in node else {}
    primitives = primitives.get("primitives") or []
    if len(primitives) == 1 and "material" in primitives[0]:
        return _primitive_look(document, primitives[0])
    return {}


def _primitive_look(document: dict[str, Any], primitive: dict[str, Any]) -> dict[str, Any]:
    """``material`` and ``solid`` of a primitive: its glTF material (exact
    float factors), else what trimesh gives a mesh without one or colours."""
    if "material" not in primitive:
        return {"material": Material(), "solid": True}
    material, solid = _material_from_gltf(document["materials"][primitive["material"]])
    return {"material": material, "solid": solid}


def _node_index(graph: Any, frame: str, frames: dict[str, int]) -> int | None:
    """The glTF node of a frame (a primitive's frame hangs under its node's)."""
    while frame is not None and frame not in frames:
        frame = graph.transforms.parents.get(frame)
    return frames.get(frame)


def _read_shapes(
    scene: Scene,
    path: Path,
    nodes: list[dict[str, Any]],
    document: dict[str, Any],
    binary: bytes | memoryview | None,
) -> tuple[list[int], Callable[[int], np.ndarray | None]]:
    """Shapes decoded by trimesh, in node order; returns each shape's node
    index and the world transform of a node (None when not in the scene)."""
    data, frames = _for_trimesh(document, binary)
    loaded = load_scene(path, data)
    graph = loaded.graph
    indices = {frame: _node_index(graph, frame, frames) for frame in graph.nodes_geometry}
    # In the file's node order (trimesh's graph order is not).
    order = sorted(indices, key=lambda frame: (indices[frame] or 0, frame))
    keys: list[int] = []
    for frame, transform, _, geometry in triangle_meshes(loaded, path, scene.warnings, order):
        index = indices[frame]
        node = nodes[index] if index is not None else {}
        fields = {**_look(document, node), **shape_fields(shadowgeo_extras(node))}
        scene.shapes.append(mesh_shape(geometry, transform, node.get("name"), path, **fields))
        keys.append(index or 0)

    def world(index: int) -> np.ndarray | None:
        frame = f"node{index}"
        return np.asarray(graph.get(frame)[0]) if frame in graph.nodes else None

    return keys, world


def _read_plain_shapes(
    scene: Scene,
    plain: PlainMeshes,
    path: Path,
    nodes: list[dict[str, Any]],
    document: dict[str, Any],
) -> list[int]:
    """Shapes of a plain glTF (:mod:`.gltf_native`), one per primitive, in
    node order; returns each shape's node index. Nodes that share a mesh
    share its arrays. A mesh of several primitives keeps each one's material
    as exact floats (trimesh's reading gives them as 8-bit colours)."""
    keys = []
    for index in sorted(plain.worlds):
        node = nodes[index]
        if "mesh" not in node:
            continue
        extras, name = shape_fields(shadowgeo_extras(node)), node.get("name")
        for vertices, faces, primitive in plain.meshes[node["mesh"]]:
            fields = {**_primitive_look(document, primitive), **extras}
            scene.shapes.append(
                checked_shape(
                    vertices, faces, plain.worlds[index], name, path, in_range=True, **fields
                )
            )
            keys.append(index)
    return keys


def _read_empty_shapes(
    scene: Scene,
    world: Callable[[int], np.ndarray | None],
    nodes: list[dict[str, Any]],
    keys: list[int],
) -> None:
    """Shapes shadowgeo wrote without triangles are nodes without a mesh
    (glTF forbids empty accessors); put them back in node order."""
    for index, node in enumerate(nodes):
        extras = shadowgeo_extras(node)
        if "mesh" in node or extras.get("role") not in ("geometry", "shadow", "volume", "ground"):
            continue
        transform = world(index)
        if transform is None:
            continue
        scene.shapes.append(
            Shape(
                np.zeros((0, 3)),
                np.zeros((0, 3), dtype=np.int64),
                np.asarray(transform, dtype=np.float64),
                name=node.get("name"),
                **shape_fields(extras),
            )
        )
        keys.append(index)
    order = sorted(range(len(keys)), key=keys.__getitem__)
    scene.shapes = [scene.shapes[i] for i in order]


def _read_lights(
    scene: Scene,
    world: Callable[[int], np.ndarray | None],
    nodes: list[dict[str, Any]],
    document: dict[str, Any],
) -> None:
    entries = ((document.get("extensions") or {}).get(LIGHTS) or {}).get("lights") or []
    for index, node in enumerate(nodes):
        reference = (node.get("extensions") or {}).get(LIGHTS)
        if reference is None:
            continue
        transform = world(index)
        if transform is None:
            continue
        extras = shadowgeo_extras(node)
        limits.check_lights(len(scene.lights) + 1, str(scene.path))
        scene.lights.append(
            scene_light(
                entries[reference["light"]], np.asarray(transform), node.get("name"), extras
            )
        )


def _local(node: dict[str, Any]) -> np.ndarray:
    """A glTF node's 4x4 local transform: its column-major ``matrix``, or
    translation * rotation (x, y, z, w quaternion) * scale, taken as they
    come (for cameras, whatever the rest of the file holds)."""
    if "matrix" in node:
        return np.asarray(node["matrix"], dtype=np.float64).reshape(4, 4).T
    return trs_matrix(
        [float(v) for v in node.get("translation", (0, 0, 0))],
        [float(v) for v in node.get("rotation", (0, 0, 0, 1))],
        [float(v) for v in node.get("scale", (1, 1, 1))],
    )


def _camera_worlds(
    document: dict[str, Any], worlds: dict[int, np.ndarray] | None
) -> list[tuple[int, np.ndarray]]:
    """(node index, world transform) of every camera node of the default
    scene, in the file's node order (trimesh re-parents camera nodes); from
    ``worlds`` when the fast path has them."""
    nodes = document.get("nodes") or []
    if not any("camera" in node for node in nodes):
        return []  # no world transform to compute (10,000 nodes cost a second)
    if worlds is not None:
        return [(index, worlds[index]) for index in sorted(worlds) if "camera" in nodes[index]]
    scenes = document.get("scenes") or [{"nodes": list(range(len(nodes)))}]
    roots = scenes[int(document.get("scene", 0))].get("nodes") or []
    found: dict[int, np.ndarray] = {}
    pending = [(int(index), np.eye(4)) for index in roots]
    seen: set[int] = set()
    while pending:
        index, parent = pending.pop()
        if index in seen:
            continue  # a node graph with a cycle (glTF allows only trees)
        seen.add(index)
        world = parent @ _local(nodes[index])
        if "camera" in nodes[index]:
            found[index] = world
        pending.extend((int(child), world) for child in nodes[index].get("children") or [])
    return sorted(found.items(), key=lambda item: item[0])


def _read_cameras(
    scene: Scene, document: dict[str, Any], worlds: dict[int, np.ndarray] | None
) -> None:
    """Each perspective camera as a Viewpoint, in the file's node order."""
    cameras = document.get("cameras") or []
    nodes = document.get("nodes") or []
    for index, world in _camera_worlds(document, worlds):
        node = nodes[index]
        camera = cameras[node["camera"]]
        perspective = camera.get("perspective") if camera.get("type") == "perspective" else None
        if not isinstance(perspective, dict):
            scene.warnings.append(
                f"{scene.path}: camera {node['camera']} skipped: only perspective cameras are read"
            )
            continue
        vertical = float(perspective["yfov"])
        aspect = float(perspective.get("aspectRatio") or 1.0)
        # X3D's fieldOfView is the smaller of the two angles; glTF gives the vertical one.
        smaller = vertical if aspect >= 1 else 2 * math.atan(math.tan(vertical / 2) * aspect)
        if not (np.all(np.isfinite(world)) and 0 < smaller < math.pi):
            scene.warnings.append(f"{scene.path}: camera {node['camera']} skipped: not finite")
            continue
        name = node.get("name")
        description = camera.get("name")
        scene.viewpoints.append(
            Viewpoint(
                float_triple(world[:3, 3]),
                axis_angle(world[:3, :3]),
                smaller,
                description=description if isinstance(description, str) else "",
                name=name if isinstance(name, str) else None,
            )
        )
