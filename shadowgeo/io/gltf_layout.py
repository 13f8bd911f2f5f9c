"""What the glTF reader and writer share: the GLB container, the JSON
document, the ``KHR_lights_punctual`` lights and the ``extras["shadowgeo"]``
layout, each written and read back here, side by side.

``extras["shadowgeo"]``
-----------------------
What glTF has no field for goes in a node's ``extras["shadowgeo"]``:

- shape nodes: ``role`` (``"geometry"``, ``"shadow"``, ``"volume"``,
  ``"ground"``), ``group
  (the light group) and, when not the defaults, ``castsShadow`` and
  ``receivesShadow``;
- light nodes: ``on``, ``intensity`` (unclamped), ``shadows`` (whether the
  browser draws its shadows: false once shadowgeo baked them),
  ``shadowIntensity``, ``ambientIntensity``, ``attenuation``, ``beamWidth``
  and ``global``, X3D's light fields; ``shadowsBaked`` when shadowgeo baked
  its shadows and turned its runtime shadows off;
- group and root nodes the writer adds: ``role`` ``"group"`` / ``"root"``.
"""

from __future__ import annotations

import json
import math
import struct
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import SceneError
from ..lights import DirectionalLight, Light, PointLight, SpotLight
from ..scene import SceneLight, Shape
from . import float_triple, look_rotation, optional_module

__all__ = [
    "BIN_CHUNK",
    "GLB_MAGIC",
    "JSON_CHUNK",
    "LIGHTS",
    "SCHEMA",
    "check_types",
    "external_uris",
    "glb_chunks",
    "glb_container",
    "json_document",
    "light_entry",
    "orjson",
    "quaternion_xyzw",
    "scene_light",
    "shadowgeo_extras",
    "shape_extras",
    "shape_fields",
    "unit_float",
]

GLB_MAGIC, JSON_CHUNK, BIN_CHUNK = b"glTF", 0x4E4F534A, 0x004E4942
LIGHTS = "KHR_lights_punctual"


# -- the container ------------------------------------------------------------------------


def glb_container(text: bytes, binary: bytes | memoryview) -> bytes:
    """A GLB file of a JSON chunk ``text`` and, when not empty, a BIN chunk
    ``binary``, each padded to 4 bytes as the spec requires (spaces, zeros).
    The pieces are joined once: a big buffer is copied once, not per piece."""
    text_pad = -len(text) % 4
    pieces: list[bytes | memoryview] = [
        struct.pack("<II", len(text) + text_pad, JSON_CHUNK),
        text,
        b" " * text_pad,
    ]
    if len(binary):
        binary_pad = -len(binary) % 4
        pieces += [struct.pack("<II", len(binary) + binary_pad, BIN_CHUNK), binary]
        pieces.append(b"\0" * binary_pad)
    length = 12 + sum(len(piece) for piece in pieces)
    return b"".join([struct.pack("<4sII", GLB_MAGIC, 2, length), *pieces])


def glb_chunks(data: bytes, path: Path) -> tuple[bytes, bytes | memoryview]:
    """The JSON chunk and the BIN chunk (``b""`` when there is none) of the
    GLB file ``data``, each checked to lie inside the file. The BIN chunk is
    a view into ``data``, not a copy."""
    if len(data) < 20:
        raise SceneError("truncated GLB header", path=str(path))
    length, kind = struct.unpack_from("<II", data, 12)
    if kind != JSON_CHUNK or 20 + length > len(data):
        raise SceneError("GLB's first chunk is not a complete JSON chunk", path=str(path))
    rest = memoryview(data)[20 + length :]
    binary: bytes | memoryview = b""
    if len(rest) >= 8:
        bin_length, bin_kind = struct.unpack_from("<II", rest, 0)
        if bin_kind == BIN_CHUNK:
            binary = rest[8 : 8 + bin_length]
    return data[20 : 20 + length], binary


def json_document(path: Path) -> tuple[dict[str, Any], bytes | memoryview | None]:
    """The JSON document of a ``.gltf`` or ``.glb`` file, checked to be a JSON
    object, and a GLB's binary chunk (None for ``.gltf``)."""
    try:
        data = path.read_bytes()
    except OSError as error:
        raise SceneError(f"cannot read: {error.strerror}", path=str(path)) from error
    binary = None
    if data[:4] == GLB_MAGIC:
        data, binary = glb_chunks(data, path)
    try:
        document = _loads(data)
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise SceneError(f"not glTF: invalid JSON ({error})", path=str(path)) from None
    except RecursionError:
        raise SceneError("not glTF: JSON nested too deeply", path=str(path)) from None
    if not isinstance(document, dict):
        raise SceneError("not glTF: no 'asset' object", path=str(path))
    return document, binary


# Five times faster than json on a document of 10,000 nodes: the `speed` extra.
orjson = optional_module("orjson")


def _loads(data: bytes) -> Any:
    """``json.loads(data)``, by orjson when it is installed and takes the
    text: the same objects for strict JSON (save an integer beyond 64 bits,
    which orjson reads as a float; none is valid where shadowgeo reads).
    Whatever orjson refuses (NaN, UTF-16, bad UTF-8, a byte-order mark, deep
    nesting) goes to json, which accepts or refuses it as before."""
    if orjson is not None:
        try:
            return orjson.loads(data)
        except orjson.JSONDecodeError:
            pass
    return json.loads(data)


def external_uris(document: dict[str, Any]) -> list[tuple[str, str]]:
    """``(where, uri)`` of each buffer and image that names a file (not a
    ``data:`` URI), ``where`` as in ``"buffers[0] uri 'a.bin'"``."""
    found = []
    for kind in ("buffers", "images"):
        for index, resource in enumerate(document.get(kind) or []):
            uri = resource.get("uri") if isinstance(resource, dict) else None
            if isinstance(uri, str) and not uri.startswith("data:"):
                found.append((f"{kind}[{index}] uri {uri!r}", uri))
    return found


# -- JSON types ---------------------------------------------------------------------------

# The parts of a glTF document shadowgeo reads, by type: ``str``, ``int``,
# ``bool``, ``float`` (any finite JSON number), ``[spec]`` (an array of spec,
# ``(length, spec)`` for a fixed length), ``{key: spec}`` (an object; ``"*"``
# for every member). Other members are not checked.
_NUMBER, _INDICES = float, [int]
_SHADOWGEO = {
    "role": str,
    "group": str,
    "castsShadow": bool,
    "receivesShadow": bool,
    "on": bool,
    "intensity": _NUMBER,
    "shadows": bool,
    "shadowsBaked": bool,
    "shadowIntensity": _NUMBER,
    "ambientIntensity": _NUMBER,
    "attenuation": (3, _NUMBER),
    "beamWidth": _NUMBER,
    "global": bool,
}
_LIGHT = {
    "type": str,
    "name": str,
    "color": (3, _NUMBER),
    "intensity": _NUMBER,
    "range": _NUMBER,
    "spot": {"innerConeAngle": _NUMBER, "outerConeAngle": _NUMBER},
}
_MATERIAL = {
    "name": str,
    "pbrMetallicRoughness": {
        "baseColorFactor": (4, _NUMBER),
        "roughnessFactor": _NUMBER,
        "metallicFactor": _NUMBER,
    },
    "emissiveFactor": (3, _NUMBER),
    "alphaMode": str,
    "doubleSided": bool,
}
_PRIMITIVE = {"attributes": {"*": int}, "indices": int, "material": int, "mode": int}
_NODE = {
    "name": str,
    "mesh": int,
    "children": _INDICES,
    "matrix": (16, _NUMBER),
    "translation": (3, _NUMBER),
    "rotation": (4, _NUMBER),
    "scale": (3, _NUMBER),
    "extensions": {LIGHTS: {"light": int}},
}
SCHEMA: dict[str, Any] = {
    "asset": {"version": str},
    "scene": int,
    "scenes": [{"nodes": _INDICES}],
    "nodes": [_NODE],
    "meshes": [{"name": str, "primitives": [_PRIMITIVE]}],
    "materials": [_MATERIAL],
    "accessors": [{"bufferView": int, "count": int, "normalized": bool}],
    "bufferViews": [{"buffer": int}],
    "buffers": [{"uri": str, "byteLength": int}],
    "images": [{"uri": str}],
    "textures": [dict],
    "samplers": [dict],
    "extensionsUsed": [str],
    "extensionsRequired": [str],
    "extensions": {LIGHTS: {"lights": [_LIGHT]}},
}
_NAMES = {str: "a string", int: "an integer", bool: "true or false", float: "a finite number"}


def check_types(document: dict[str, Any], path: Path) -> None:
    """Refuse a document whose members shadowgeo reads (:data:`SCHEMA`, and
    a node's ``extras["shadowgeo"]`` when it is an object) have the wrong JSON
    type, with a SceneError naming the JSON pointer (``/nodes/3/name``)."""
    _check(document, SCHEMA, "", path)
    for index, node in enumerate(document.get("nodes") or []):
        _check(shadowgeo_extras(node), _SHADOWGEO, f"/nodes/{index}/extras/shadowgeo", path)


def _check(value: Any, spec: Any, pointer: Any, path: Path) -> None:
    """Check ``value`` against ``spec`` (see :data:`SCHEMA`) at ``pointer``:
    a string, or ``(parent pointer, key)`` spelled out only for a message
    (a document of 10,000 nodes has some 200,000 members to check)."""
    if isinstance(spec, dict):
        _check_object(value, spec, pointer, path)
    elif isinstance(spec, (list, tuple)):
        _check_array(value, spec, pointer, path)
    elif spec is dict:
        if not isinstance(value, dict):
            _refuse(pointer, "an object", value, path)
    elif spec is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            _refuse(pointer, _NAMES[float], value, path)
        if not math.isfinite(value):
            _refuse(pointer, _NAMES[float], value, path)
    elif isinstance(value, bool) != (spec is bool) or not isinstance(value, spec):
        _refuse(pointer, _NAMES[spec], value, path)


def _check_object(value: Any, spec: dict[str, Any], pointer: Any, path: Path) -> None:
    """An object's members against ``spec`` (``"*"``: every member)."""
    if not isinstance(value, dict):
        _refuse(pointer, "an object", value, path)
    if "*" in spec:
        for key, member in value.items():
            _check(member, spec["*"], (pointer, key), path)
    for key, sub in spec.items():
        if key != "*" and key in value:
            member = value[key]
            # the common leaves checked here, without a call each (10,000
            # nodes, meshes and accessors have some 100,000 of them)
            if sub is int and type(member) is int or sub is str and type(member) is str:
                continue
            _check(member, sub, (pointer, key), path)


def _check_array(value: Any, spec: list[Any] | tuple[Any, ...], pointer: Any, path: Path) -> None:
    """An array's items against ``[item spec]`` or ``(length, item spec)``."""
    length, sub = spec if isinstance(spec, tuple) else (None, spec[0])
    if not isinstance(value, list):
        _refuse(pointer, "an array", value, path)
    if length is not None and len(value) != length:
        _refuse(pointer, f"an array of {length}", value, path)
    if sub is int and all(type(item) is int for item in value):
        return  # the common case of index arrays, in one pass
    if sub is float and all(type(item) is float for item in value):
        if all(map(math.isfinite, value)):
            return  # translations, matrices, accessor bounds: in two passes
    for index, item in enumerate(value):
        _check(item, sub, (pointer, index), path)


def _spelled(pointer: Any) -> str:
    """A JSON pointer from ``_check``'s ``(parent, key)`` chain."""
    keys = []
    while isinstance(pointer, tuple):
        pointer, key = pointer
        keys.append(str(key))
    return str(pointer) + "".join(f"/{key}" for key in reversed(keys))


def _refuse(pointer: Any, wanted: str, value: Any, path: Path) -> None:
    pointer = _spelled(pointer)
    shown = repr(value) if len(repr(value)) <= 40 else repr(value)[:37] + "..."
    raise SceneError(f"malformed glTF: {pointer or '/'} is {shown}, not {wanted}", path=str(path))


# -- extras["shadowgeo"] ------------------------------------------------------------------


def shadowgeo_extras(node: Any) -> dict[str, Any]:
    """``node["extras"]["shadowgeo"]`` where both are objects, else ``{}``."""
    extras = node.get("extras") if isinstance(node, dict) else None
    found = extras.get("shadowgeo") if isinstance(extras, dict) else None
    return found if isinstance(found, dict) else {}


def shape_extras(shape: Shape) -> dict[str, Any]:
    """A shape node's ``extras`` (see the module's docstring)."""
    extras: dict[str, Any] = {"role": shape.role}
    if shape.group:
        extras["group"] = shape.group
    if not shape.casts_shadow or shape.receives_shadow:
        extras["castsShadow"] = bool(shape.casts_shadow)
        extras["receivesShadow"] = bool(shape.receives_shadow)
    return {"shadowgeo": extras}


def shape_fields(extras: dict[str, Any]) -> dict[str, Any]:
    """The :class:`Shape` keyword arguments a shape node's
    ``extras["shadowgeo"]`` holds, with their defaults."""
    return {
        "role": extras.get("role", "geometry"),
        "group": extras.get("group"),
        "casts_shadow": bool(extras.get("castsShadow", True)),
        "receives_shadow": bool(extras.get("receivesShadow", False)),
    }


# -- lights -------------------------------------------------------------------------------


def quaternion_xyzw(rotation: np.ndarray) -> list[float]:
    """Unit quaternion ``[x, y, z, w]`` of a (3, 3) rotation matrix."""
    m = np.asarray(rotation, dtype=np.float64)
    trace = np.trace(m)
    if trace > 0:
        s = 2.0 * math.sqrt(trace + 1.0)
        q = [(m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, s / 4]
    else:
        i = int(np.argmax(np.diag(m)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(max(1.0 + m[i, i] - m[j, j] - m[k, k], 0.0))
        q = [0.0, 0.0, 0.0, (m[k, j] - m[j, k]) / s]
        q[i] = s / 4
        q[j] = (m[j, i] + m[i, j]) / s
        q[k] = (m[k, i] + m[i, k]) / s
    q = np.array(q) / np.linalg.norm(q)
    return [float(v) for v in q]


def unit_float(value: float) -> float:
    """A colour or factor clamped to glTF's [0, 1]."""
    return min(max(float(value), 0.0), 1.0)


def light_entry(light: SceneLight, index: int) -> tuple[dict[str, Any], dict[str, Any]]:
    """The ``KHR_lights_punctual`` entry of ``light`` and the node that places
    it and refers to the entry by ``index``.

    The node's translation is the light's position and its rotation turns the
    node's -Z onto the light's direction. Point and spot lights get ``range``
    from a finite radius; a spot's ``outerConeAngle`` is its cut-off angle and
    ``innerConeAngle`` its beam width, kept just below the outer angle as glTF
    requires. The node's ``extras`` keep what glTF has no field for.
    """
    geometry = light.light
    entry: dict[str, Any] = {
        "color": [unit_float(c) for c in light.color],
        "intensity": max(float(light.intensity), 0.0) if light.on else 0.0,
    }
    node: dict[str, Any] = {}
    if isinstance(geometry, DirectionalLight):
        entry["type"] = "directional"
    else:
        entry["type"] = "spot" if isinstance(geometry, SpotLight) else "point"
        node["translation"] = [float(v) for v in geometry.position]
        if math.isfinite(geometry.radius):
            entry["range"] = float(geometry.radius)
    if isinstance(geometry, SpotLight):
        outer = float(geometry.cut_off_angle)
        inner = min(max(float(light.beam_width), 0.0), float(np.nextafter(outer, 0.0)))
        entry["spot"] = {"innerConeAngle": inner, "outerConeAngle": outer}
    if not isinstance(geometry, PointLight):
        node["rotation"] = quaternion_xyzw(look_rotation(geometry.direction))
    if light.name:
        entry["name"] = light.name
        node["name"] = light.name
    node["extensions"] = {LIGHTS: {"light": index}}
    node["extras"] = {
        "shadowgeo": {
            "on": bool(light.on),
            "intensity": float(light.intensity),
            "shadows": bool(light.runtime_shadows),
            "shadowIntensity": float(light.shadow_intensity),
            "ambientIntensity": float(light.ambient_intensity),
            "attenuation": [float(a) for a in light.attenuation],
            "beamWidth": float(light.beam_width),
            "global": bool(light.global_),
        }
    }
    if light.baked:
        node["extras"]["shadowgeo"]["shadowsBaked"] = True
    return entry, node


def scene_light(
    entry: dict[str, Any], world: np.ndarray, name: str | None, extras: dict[str, Any]
) -> SceneLight:
    """A SceneLight from a ``KHR_lights_punctual`` entry placed by ``world``
    (4, 4), the node's ``name`` and its ``extras["shadowgeo"]``."""
    kind = entry.get("type")
    position = world[:3, 3]
    direction = world[:3, :3] @ [0.0, 0.0, -1.0]
    radius = float(entry.get("range", math.inf))
    light: Light
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
        color=float_triple(entry.get("color", [1, 1, 1])[:3]),
        intensity=float(extras.get("intensity", entry.get("intensity", 1.0))),
        ambient_intensity=float(extras.get("ambientIntensity", 0.0)),
        attenuation=float_triple(extras.get("attenuation", (1.0, 0.0, 0.0))),
        beam_width=float(beam),
        on=bool(extras.get("on", True)),
        global_=bool(extras.get("global", True)),
        # a light shadowgeo baked had shadows before they were turned off
        shadows=bool(extras.get("shadows", False)) or bool(extras.get("shadowsBaked", False)),
        shadow_intensity=float(extras.get("shadowIntensity", 1.0)),
        baked=bool(extras.get("shadowsBaked", False)),
    )
