"""Mesh-format input through trimesh: ``.glb``, ``.gltf``, ``.obj``, ``.stl``,
``.ply``, ``.off``.

trimesh decodes the triangles and the node graph. For glTF this module also
reads the JSON itself, for what trimesh drops or changes: the nodes' own
names (trimesh renames duplicates), materials as float factors (trimesh keeps
8-bit colours), ``KHR_lights_punctual`` lights and the ``extras["shadowgeo"]``
that :mod:`.gltf` writes (roles, light groups, X3D light fields).

Safety: a glTF's buffers and images may only be data URIs or relative paths
that stay in the file's folder; anything else (``http:``, ``/etc/...``,
``../``) is refused before trimesh sees the file, and trimesh never fetches
remote resources. Textures play no part in shadows and are not decoded; a
missing image is a warning, a missing buffer an error.

glTF is Y-up in metres, so a glTF scene reads as ``up_axis="Y"``,
``meters_per_unit=1``. Other mesh formats carry no units: they read as Y-up
with ``meters_per_unit=1`` too, which is what they mean in practice.
"""

from __future__ import annotations

import io
import json
import math
import struct
from pathlib import Path
from urllib.parse import unquote

import numpy as np
import trimesh

from ..errors import SceneError
from ..lights import DirectionalLight, PointLight, SpotLight
from ..scene import Material, Scene, SceneLight, Shape
from . import refuse_outside
from .gltf import BIN_CHUNK, GLB_MAGIC, JSON_CHUNK, glb_container

_LIGHTS = "KHR_lights_punctual"


def _gltf_document(path: Path) -> tuple[dict, bytes | None]:
    """The JSON part of a .gltf or .glb file, checked to be a JSON object, and
    a GLB's binary chunk (None for .gltf)."""
    try:
        data = path.read_bytes()
    except OSError as error:
        raise SceneError(f"cannot read: {error.strerror}", path=str(path)) from error
    binary = None
    if data[:4] == GLB_MAGIC:
        if len(data) < 20:
            raise SceneError("truncated GLB header", path=str(path))
        length, kind = struct.unpack_from("<II", data, 12)
        if kind != JSON_CHUNK or 20 + length > len(data):
            raise SceneError("GLB's first chunk is not a complete JSON chunk", path=str(path))
        rest = data[20 + length :]
        binary = b""
        if len(rest) >= 8:
            bin_length, bin_kind = struct.unpack_from("<II", rest, 0)
            if bin_kind == BIN_CHUNK:
                binary = rest[8 : 8 + bin_length]
        data = data[20 : 20 + length]
    try:
        document = json.loads(data)
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise SceneError(f"not glTF: invalid JSON ({error})", path=str(path)) from None
    except RecursionError:
        raise SceneError("not glTF: JSON nested too deeply", path=str(path)) from None
    if not isinstance(document, dict) or not isinstance(document.get("asset"), dict):
        raise SceneError("not glTF: no 'asset' object", path=str(path))
    version = str(document["asset"].get("version", ""))
    if not version.startswith("2."):
        raise SceneError(f"glTF version {version!r} is not supported (2.x)", path=str(path))
    _check_references(document, path)
    _check_compression(document, path)
    return document, binary


def _check_compression(document: dict, path: Path) -> None:
    """Refuse geometry trimesh would decode wrongly without an error: compressed
    primitives (it reads placeholder zeros and only logs that) and normalized
    integer positions (it ignores ``normalized``)."""
    used = set(document.get("extensionsUsed") or []) | set(document.get("extensionsRequired") or [])
    accessors = document.get("accessors") or []
    for mesh_index, mesh in enumerate(document.get("meshes") or []):
        for primitive in (mesh.get("primitives") or []) if isinstance(mesh, dict) else []:
            position = (primitive.get("attributes") or {}).get("POSITION")
            if isinstance(position, int) and 0 <= position < len(accessors):
                accessor = accessors[position]
                if isinstance(accessor, dict) and accessor.get("normalized"):
                    # KHR_mesh_quantization; trimesh would keep the raw integers.
                    raise SceneError(
                        "normalized integer positions are not supported",
                        path=str(path),
                        node=f"meshes[{mesh_index}] POSITION accessor {position}",
                    )
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


def _check_references(document: dict, path: Path) -> None:
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


def _check_uris(document: dict, path: Path) -> list[str]:
    """Refuse resources that are remote or outside the file's folder, and
    missing buffers; return warnings for missing images (textures, which
    shadowgeo does not use)."""
    folder = path.resolve().parent
    warnings = []
    for kind in ("buffers", "images"):
        for index, resource in enumerate(document.get(kind) or []):
            uri = resource.get("uri") if isinstance(resource, dict) else None
            if not isinstance(uri, str) or uri.startswith("data:"):
                continue
            where = f"{kind}[{index}] uri {uri!r}"
            target = (folder / unquote(uri)).resolve()
            refuse_outside(uri, target, folder, path=path, where=where)
            if target.is_file():
                continue
            if kind == "buffers":
                raise SceneError("missing external file", path=str(path), node=where)
            warnings.append(f"{path.name}: {where}: missing texture image, ignored")
    return warnings


def _for_trimesh(document: dict, binary: bytes | None) -> tuple[bytes, dict[str, int]]:
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


def _untextured(material):
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


def _shadowgeo_extras(node) -> dict:
    """``node["extras"]["shadowgeo"]`` where both are objects, else ``{}``."""
    extras = node.get("extras") if isinstance(node, dict) else None
    found = extras.get("shadowgeo") if isinstance(extras, dict) else None
    return found if isinstance(found, dict) else {}


def _material_from_gltf(entry: dict) -> tuple[Material, bool]:
    """(Material, solid) from a glTF material object."""
    pbr = entry.get("pbrMetallicRoughness") or {}
    red, green, blue, alpha = (list(pbr.get("baseColorFactor", [1, 1, 1, 1])) + [1.0] * 4)[:4]
    alpha = float(alpha) if entry.get("alphaMode", "OPAQUE") == "BLEND" else 1.0
    material = Material(
        diffuse_color=(float(red), float(green), float(blue)),
        emissive_color=tuple(float(c) for c in (entry.get("emissiveFactor") or [0, 0, 0])[:3]),
        shininess=1.0 - float(pbr.get("roughnessFactor", 1.0)),
        transparency=1.0 - alpha,
        name=entry.get("name"),
    )
    return material, not entry.get("doubleSided", False)


def _material_from_trimesh(geometry) -> tuple[Material, bool]:
    """(Material, solid) from a trimesh visual (8-bit colours)."""
    visual = getattr(geometry, "visual", None)
    material = getattr(visual, "material", None)
    color = None
    solid = True
    if material is not None:
        color = getattr(material, "baseColorFactor", None)
        if color is None:
            color = getattr(material, "main_color", None)
        solid = not getattr(material, "doubleSided", False)
    elif visual is not None and getattr(visual, "kind", None) in ("face", "vertex"):
        color = visual.main_color
    if color is None:
        return Material(), solid
    rgba = np.asarray(color, dtype=np.float64).reshape(-1)[:4] / 255.0
    alpha = rgba[3] if len(rgba) == 4 else 1.0
    name = getattr(material, "name", None)
    return Material(diffuse_color=tuple(rgba[:3]), transparency=1.0 - alpha, name=name), solid


def _light(entry: dict, world: np.ndarray, name: str | None, extras: dict) -> SceneLight:
    """A SceneLight from a KHR_lights_punctual entry placed by ``world`` (4, 4)."""
    kind = entry.get("type")
    position = world[:3, 3]
    direction = world[:3, :3] @ [0.0, 0.0, -1.0]
    radius = float(entry.get("range", math.inf))
    if kind == "directional":
        light = DirectionalLight(direction)
    elif kind == "point":
        light = PointLight(position, radius)
    elif kind == "spot":
        cone = entry.get("spot") or {}
        light = SpotLight(
            position, direction, float(cone.get("outerConeAngle", math.pi / 4)), radius
        )
    else:
        raise ValueError(f"unknown light type {kind!r}")
    beam = extras.get("beamWidth")
    if beam is None:
        beam = (entry.get("spot") or {}).get("innerConeAngle", 0.0)  # the spec's default
    return SceneLight(
        light,
        name=name if name is not None else entry.get("name"),
        color=tuple(float(c) for c in entry.get("color", [1, 1, 1])[:3]),
        intensity=float(extras.get("intensity", entry.get("intensity", 1.0))),
        ambient_intensity=float(extras.get("ambientIntensity", 0.0)),
        attenuation=tuple(float(a) for a in extras.get("attenuation", (1.0, 0.0, 0.0))),
        beam_width=float(beam),
        on=bool(extras.get("on", True)),
        global_=bool(extras.get("global", True)),
        shadows=bool(extras.get("shadows", False)),
        shadow_intensity=float(extras.get("shadowIntensity", 1.0)),
    )


def _load(path: Path, data: bytes | None = None) -> trimesh.Scene:
    """trimesh's scene of ``path``, or of ``data`` in its place (external
    resources then resolve from the file's folder)."""
    try:
        if data is None:
            loaded = trimesh.load_scene(path, allow_remote=False)
        else:
            loaded = trimesh.load_scene(
                io.BytesIO(data),
                file_type=path.suffix.lower().lstrip("."),
                resolver=trimesh.resolvers.FilePathResolver(str(path)),
                allow_remote=False,
            )
    except SceneError:
        raise
    except Exception as error:  # trimesh raises many kinds on corrupt files
        kind = path.suffix.lower().lstrip(".").upper()
        message = f"{type(error).__name__}: {error}" if str(error) else type(error).__name__
        raise SceneError(f"cannot read as {kind}: {message}", path=str(path)) from error
    return loaded


def read(path, **options) -> Scene:
    """Read a mesh file into a :class:`Scene`.

    Parameters
    ----------
    path : str or Path
        ``.glb``, ``.gltf``, ``.obj``, ``.stl``, ``.ply`` or ``.off``.

    Returns
    -------
    Scene
        One shape per mesh instance (glTF node, OBJ object, ...), with its
        world transform, material, name and, for glTF written by shadowgeo,
        its role and light group; glTF lights. Points and lines are skipped
        with a warning.

    Raises
    ------
    SceneError
        Missing, unreadable or corrupt file; a glTF resource outside its folder.
    """
    path = Path(path)
    if options:
        raise SceneError(f"mesh reader takes no options, got {sorted(options)}", path=str(path))
    if not path.is_file():
        raise SceneError("no such file", path=str(path))
    is_gltf = path.suffix.lower() in (".glb", ".gltf")
    document, frames, data, warnings = {}, {}, None, []
    if is_gltf:
        document, binary = _gltf_document(path)
        warnings = _check_uris(document, path)
        data, frames = _for_trimesh(document, binary)
    loaded = _load(path, data)
    scene = Scene(path=str(path), warnings=warnings)
    nodes = document.get("nodes") or []
    try:
        _read_shapes(scene, loaded, path, frames, nodes, document)
        if is_gltf:
            _read_lights(scene, loaded.graph, frames, nodes, document)
    except (TypeError, ValueError, KeyError, IndexError, AttributeError) as error:
        if isinstance(error, SceneError):
            raise
        kind = path.suffix.lower().lstrip(".").upper()
        raise SceneError(f"malformed {kind}: {error}", path=str(path)) from error
    if not is_gltf and not any(shape.n_faces for shape in scene.shapes):
        # A glTF may hold only lights; a plain mesh file without triangles is broken.
        raise SceneError("no triangles in the file", path=str(path))
    return scene


def _node_index(graph, frame: str, frames: dict[str, int]) -> int | None:
    """The glTF node of a frame (a primitive's frame hangs under its node's)."""
    while frame is not None and frame not in frames:
        frame = graph.transforms.parents.get(frame)
    return frames.get(frame)


def _read_shapes(scene, loaded, path, frames, nodes, document) -> None:
    graph = loaded.graph
    indices = {frame: _node_index(graph, frame, frames) for frame in graph.nodes_geometry}
    # In the file's node order (trimesh's graph order is not).
    order = sorted(indices, key=lambda frame: (indices[frame] or 0, frame))
    keys: list[int] = []
    for frame in order:
        transform, geometry_name = graph[frame]
        geometry = loaded.geometry[geometry_name]
        if not isinstance(geometry, trimesh.Trimesh):
            scene.warnings.append(f"{path.name}: skipped {frame!r}: {type(geometry).__name__}")
            continue
        index = indices[frame]
        node = nodes[index] if index is not None else {}
        extras = _shadowgeo_extras(node)
        material, solid = _material_from_trimesh(geometry)
        primitives = (document.get("meshes") or [{}])[node["mesh"]] if "mesh" in node else {}
        primitives = primitives.get("primitives") or []
        if len(primitives) == 1 and "material" in primitives[0]:
            material, solid = _material_from_gltf(document["materials"][primitives[0]["material"]])
        if document:
            name = node.get("name")
        else:
            name = geometry_name if len(loaded.geometry) > 1 else path.stem
        scene.shapes.append(
            Shape(
                np.array(geometry.vertices, dtype=np.float64),
                np.array(geometry.faces, dtype=np.int64),
                np.array(transform, dtype=np.float64),
                material=material,
                name=name,
                solid=solid,
                role=extras.get("role", "geometry"),
                group=extras.get("group"),
                source=f"{path.name}, node {name!r}" if name else path.name,
                casts_shadow=bool(extras.get("castsShadow", True)),
                receives_shadow=bool(extras.get("receivesShadow", False)),
            )
        )
        keys.append(index or 0)
    _read_empty_shapes(scene, graph, frames, nodes, keys)


def _read_empty_shapes(scene, graph, frames, nodes, keys) -> None:
    """Shapes shadowgeo wrote without triangles are nodes without a mesh
    (glTF forbids empty accessors); put them back in node order."""
    for frame, index in frames.items():
        extras = _shadowgeo_extras(nodes[index])
        if "mesh" in nodes[index] or extras.get("role") not in ("geometry", "shadow", "volume"):
            continue
        if frame not in graph.nodes:
            continue
        scene.shapes.append(
            Shape(
                np.zeros((0, 3)),
                np.zeros((0, 3), dtype=np.int64),
                np.asarray(graph.get(frame)[0], dtype=np.float64),
                name=nodes[index].get("name"),
                role=extras["role"],
                group=extras.get("group"),
            )
        )
        keys.append(index)
    order = sorted(range(len(keys)), key=keys.__getitem__)
    scene.shapes = [scene.shapes[i] for i in order]


def _read_lights(scene, graph, frames, nodes, document) -> None:
    entries = ((document.get("extensions") or {}).get(_LIGHTS) or {}).get("lights") or []
    for frame, index in frames.items():
        node = nodes[index]
        reference = (node.get("extensions") or {}).get(_LIGHTS)
        if reference is None or frame not in graph.nodes:
            continue
        world, _ = graph.get(frame)
        extras = _shadowgeo_extras(node)
        scene.lights.append(
            _light(entries[reference["light"]], np.asarray(world), node.get("name"), extras)
        )
