"""glTF triangles decoded with numpy alone, for the plain files most tools
write: the fast path of :mod:`.gltf_read`.

trimesh builds a ``Trimesh`` object, a scene-graph edge and a cached
transform for every glTF node: 10,000 small meshes took about a second to
decode that way, where the accessors themselves are views of one buffer.
:func:`plain_meshes` decodes a document here when everything it needs is
plain: every primitive of a mesh triangles (``mode`` 4) with float
``POSITION`` (finite, within ``limits.LARGEST_COORDINATE``), optional
unsigned ``indices``, no ``COLOR_0`` (trimesh turns
vertex colours into a material) and no extensions (Draco); every
accessor in bounds of its buffer view and buffer; the default scene a tree
of nodes. Anything else returns None and trimesh decodes the file as before,
with its own errors: this path never refuses a file the other would read.

Only the meshes that nodes of the default scene use are decoded: a broken
mesh no node shows (an accessor past its buffer, a line strip) is no error
here, where trimesh, which decodes every mesh, refuses the whole file.

World transforms are the products of the nodes' local matrices, exactly as
the file gives them (trimesh also drops near-identity factors and nudges
near-rigid products to rigid ones, by 1e-8 at most).
"""

from __future__ import annotations

import base64
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import unquote

import numpy as np

from ..limits import LARGEST_COORDINATE

__all__ = ["PlainMeshes", "plain_meshes", "quaternion_matrix", "trs_matrix"]

# glTF componentType -> numpy dtype (little-endian), for the types read here.
_FLOAT = 5126
_COMPONENTS: dict[int, np.dtype[Any]] = {
    5121: np.dtype("<u1"),  # UNSIGNED_BYTE, UNSIGNED_SHORT, UNSIGNED_INT: indices
    5123: np.dtype("<u2"),
    5125: np.dtype("<u4"),
    _FLOAT: np.dtype("<f4"),
}
_TRIANGLES = 4


@dataclass
class PlainMeshes:
    """What :func:`plain_meshes` decodes: ``worlds`` maps every node of the
    default scene to its (4, 4) world transform; ``meshes`` maps each mesh
    index used by those nodes to its primitives' ``(vertices, faces,
    primitive)`` (float64 (n, 3), int64 (m, 3), the primitive's JSON object),
    one shape each, as trimesh reads them."""

    worlds: dict[int, np.ndarray]
    meshes: dict[int, list[tuple[np.ndarray, np.ndarray, dict[str, Any]]]]


def plain_meshes(
    document: dict[str, Any], binary: bytes | memoryview | None, path: Path
) -> PlainMeshes | None:
    """The default scene's world transforms and mesh triangles of a plain
    glTF ``document`` (with a GLB's ``binary`` chunk), or None when the file
    is not plain (see the module's text) and trimesh must decode it."""
    worlds = _worlds(document)
    if worlds is None:
        return None
    nodes = document.get("nodes", [])
    used = sorted({nodes[index]["mesh"] for index in worlds if "mesh" in nodes[index]})
    decoder = _Decoder(document, binary, path)
    meshes = {}
    for index in used:
        decoded = decoder.mesh(index)
        if decoded is None:
            return None
        meshes[index] = decoded
    return PlainMeshes(worlds, meshes)


def _is_index(value: Any, count: int) -> bool:
    return type(value) is int and 0 <= value < count


def _worlds(document: dict[str, Any]) -> dict[int, np.ndarray] | None:
    """World transform of each node of the default scene, or None unless the
    scene is a tree of nodes with plain local transforms."""
    nodes = document.get("nodes", [])
    roots = _roots(document)
    if not isinstance(nodes, list) or roots is None:
        return None
    worlds: dict[int, np.ndarray] = {}
    pending: list[tuple[Any, np.ndarray | None]] = [(index, None) for index in reversed(roots)]
    while pending:
        index, parent = pending.pop()
        if not _is_index(index, len(nodes)) or index in worlds:
            return None  # a dangling index, or a node reached twice: not a tree
        node = nodes[index]
        local = _local(node) if isinstance(node, dict) else None
        if local is None:
            return None
        worlds[index] = local if parent is None else parent @ local
        children = node.get("children", [])
        if not isinstance(children, list):
            return None
        pending.extend((child, worlds[index]) for child in reversed(children))
    return worlds


def _roots(document: dict[str, Any]) -> list[Any] | None:
    """The root nodes' indices (unchecked) of the default scene, or None."""
    scenes = document.get("scenes")
    if not isinstance(scenes, list) or not scenes:
        return None
    default = document.get("scene", 0)
    if not _is_index(default, len(scenes)) or not isinstance(scenes[default], dict):
        return None
    roots = scenes[default].get("nodes", [])
    return roots if isinstance(roots, list) else None


def _entry(document: dict[str, Any], key: str, index: Any) -> dict[str, Any] | None:
    """``document[key][index]`` when ``document[key]`` is an array, ``index`` one
    of its indices and the entry an object; None otherwise."""
    entries = document.get(key)
    if not isinstance(entries, list) or not _is_index(index, len(entries)):
        return None
    entry = entries[index]
    return entry if isinstance(entry, dict) else None


def _size(value: Any) -> int | None:
    """``value`` if it is a non-negative JSON integer, else None."""
    return value if type(value) is int and value >= 0 else None


def _numbers(value: Any, count: int) -> list[float] | None:
    """``value`` as ``count`` finite floats, or None."""
    if not isinstance(value, list) or len(value) != count:
        return None
    if not all(type(v) in (int, float) and math.isfinite(v) for v in value):
        return None
    return [float(v) for v in value]


def _local(node: dict[str, Any]) -> np.ndarray | None:
    """A node's local 4x4 transform: its column-major ``matrix`` (affine), or
    translation * rotation (x, y, z, w quaternion) * scale; None when it is
    anything else."""
    if "matrix" in node:
        if any(key in node for key in ("translation", "rotation", "scale")):
            return None
        values = _numbers(node["matrix"], 16)
        if values is None:
            return None
        matrix = np.array(values).reshape(4, 4).T
        return matrix if matrix[3].tolist() == [0.0, 0.0, 0.0, 1.0] else None
    translation = _numbers(node.get("translation", [0, 0, 0]), 3)
    rotation = _numbers(node.get("rotation", [0, 0, 0, 1]), 4)
    scale = _numbers(node.get("scale", [1, 1, 1]), 3)
    if translation is None or rotation is None or scale is None:
        return None
    return trs_matrix(translation, rotation, scale)


def trs_matrix(translation: list[float], rotation: list[float], scale: list[float]) -> np.ndarray:
    """The 4x4 translation * rotation (x, y, z, w quaternion) * scale of a
    glTF node (the identity parts skipped: they change no number)."""
    local = np.eye(4)
    if rotation != [0.0, 0.0, 0.0, 1.0]:
        local[:3, :3] = quaternion_matrix(rotation)
    if scale != [1.0, 1.0, 1.0]:
        local[:3, :3] *= scale
    local[:3, 3] = translation
    return local


def quaternion_matrix(xyzw: list[float]) -> np.ndarray:
    """(3, 3) rotation of the quaternion ``xyzw`` (glTF's order), normalised
    first (the identity for a zero quaternion): products of the scaled
    components, as trimesh's ``quaternion_matrix`` forms them, so that a
    quarter turn written as (0.7071..., 0, 0, 0.7071...) gives exact zeros
    and ones where ``1 - 2 x x`` would leave 2e-16."""
    q = np.array([xyzw[3], xyzw[0], xyzw[1], xyzw[2]], dtype=np.float64)
    norm = float(q @ q)
    if norm < np.finfo(np.float64).eps * 4.0:
        return np.eye(3)
    q *= math.sqrt(2.0 / norm)
    q = np.outer(q, q)
    return np.array(
        [
            [1.0 - q[2, 2] - q[3, 3], q[1, 2] - q[3, 0], q[1, 3] + q[2, 0]],
            [q[1, 2] + q[3, 0], 1.0 - q[1, 1] - q[3, 3], q[2, 3] - q[1, 0]],
            [q[1, 3] - q[2, 0], q[2, 3] + q[1, 0], 1.0 - q[1, 1] - q[2, 2]],
        ]
    )


_WIDTHS = {"SCALAR": 1, "VEC3": 3}


@dataclass(frozen=True)
class _Layout:
    """Where an accessor's ``count`` items of ``width`` components lie: buffer
    ``buffer`` (an unchecked index), its view at ``start`` of ``length`` bytes,
    the items from ``offset`` in it, ``stride`` bytes apart."""

    buffer: Any
    dtype: np.dtype[Any]
    width: int
    count: int
    offset: int
    start: int
    length: int
    stride: int

    @property
    def element(self) -> int:
        """Bytes of one item."""
        return int(self.dtype.itemsize) * self.width


class _Decoder:
    """Meshes, accessors and buffers of one glTF ``document`` (a GLB's
    ``binary`` chunk; ``path``, the file, for buffers beside it), each
    buffer read once."""

    def __init__(
        self, document: dict[str, Any], binary: bytes | memoryview | None, path: Path
    ) -> None:
        self.document, self.binary, self.path = document, binary, path
        self.buffers: dict[int, bytes | memoryview] = {}
        self.vertices: dict[int, np.ndarray] = {}  # POSITION accessor -> float64 vertices

    def mesh(self, index: int) -> list[tuple[np.ndarray, np.ndarray, dict[str, Any]]] | None:
        """``(vertices, faces, primitive)`` of each primitive of a mesh whose
        primitives are all plain triangles, or None."""
        meshes = self.document.get("meshes")
        if not isinstance(meshes, list) or not _is_index(index, len(meshes)):
            return None
        primitives = meshes[index].get("primitives") if isinstance(meshes[index], dict) else None
        if not isinstance(primitives, list) or not primitives:
            return None
        decoded = []
        for primitive in primitives:
            part = self.primitive(primitive)
            if part is None:
                return None
            decoded.append(part)
        return decoded

    def primitive(self, primitive: Any) -> tuple[np.ndarray, np.ndarray, dict[str, Any]] | None:
        """``(vertices, faces, primitive)`` of a plain triangle primitive, or
        None. Primitives that share a POSITION accessor share its array."""
        if not isinstance(primitive, dict) or "extensions" in primitive:
            return None
        attributes = primitive.get("attributes")
        if primitive.get("mode", _TRIANGLES) != _TRIANGLES or not isinstance(attributes, dict):
            return None
        if "COLOR_0" in attributes:
            return None
        vertices = self.positions(attributes.get("POSITION"))
        if vertices is None:
            return None
        if "indices" in primitive:
            flat = self.accessor(primitive["indices"], "SCALAR")
            if flat is None or flat.dtype.kind != "u" or len(flat) % 3:
                return None
            faces = flat.reshape(-1).astype(np.int64).reshape(-1, 3)
        else:
            if len(vertices) % 3:
                return None
            faces = np.arange(len(vertices), dtype=np.int64).reshape(-1, 3)
        return vertices, faces, primitive

    def positions(self, index: Any) -> np.ndarray | None:
        """The float64 (n, 3) vertices of POSITION accessor ``index`` (float,
        not empty, finite and within ``limits.LARGEST_COORDINATE``: trimesh's
        reading refuses others naming the node), decoded once; None
        otherwise."""
        if type(index) is int and index in self.vertices:
            return self.vertices[index]
        points = self.accessor(index, "VEC3")
        if points is None or points.dtype != np.float32 or len(points) == 0:
            return None
        with np.errstate(invalid="ignore"):  # a signalling NaN, refused just below
            vertices = points.astype(np.float64)
        if not (vertices.max() <= LARGEST_COORDINATE and vertices.min() >= -LARGEST_COORDINATE):
            return None  # NaN fails both comparisons
        self.vertices[index] = vertices
        return vertices

    def accessor(self, index: Any, kind: str) -> np.ndarray | None:
        """The (count, width) array of accessor ``index`` (a view of its buffer,
        strided or not), or None unless it is of ``kind`` and lies in bounds."""
        accessor = _entry(self.document, "accessors", index)
        if accessor is None or accessor.get("type") != kind:
            return None
        if "sparse" in accessor or accessor.get("normalized", False) is not False:
            return None
        layout = self.layout(accessor, kind)
        if layout is None:
            return None
        data = self.buffer(layout.buffer)
        if data is None or layout.start + layout.length > len(data):
            return None
        if (
            layout.count
            and layout.offset + layout.stride * (layout.count - 1) + layout.element > layout.length
        ):
            return None
        return np.ndarray(
            (layout.count, layout.width),
            dtype=layout.dtype,
            buffer=data,
            offset=layout.start + layout.offset,
            strides=(layout.stride, layout.dtype.itemsize),
        )

    def layout(self, accessor: dict[str, Any], kind: str) -> _Layout | None:
        """Where a plain accessor's items lie in its buffer view, or None unless
        every size is a non-negative integer and the stride fits the items."""
        component = accessor.get("componentType")
        dtype = _COMPONENTS.get(component) if type(component) is int else None
        count, offset = _size(accessor.get("count")), _size(accessor.get("byteOffset", 0))
        view = _entry(self.document, "bufferViews", accessor.get("bufferView"))
        if dtype is None or count is None or offset is None or view is None:
            return None
        width = _WIDTHS[kind]
        element = dtype.itemsize * width
        start, length = _size(view.get("byteOffset", 0)), _size(view.get("byteLength"))
        stride = _size(view.get("byteStride", element))
        if start is None or length is None or stride is None:
            return None
        if stride < element or offset % dtype.itemsize or stride % dtype.itemsize:
            return None
        return _Layout(view.get("buffer"), dtype, width, count, offset, start, length, stride)

    def buffer(self, index: Any) -> bytes | memoryview | None:
        """The bytes of buffer ``index``: the GLB chunk, a base64 data URI or a
        file beside the glTF (already checked to stay in its folder), at least
        its declared ``byteLength`` long; None otherwise."""
        entries = self.document.get("buffers")
        if not isinstance(entries, list) or not _is_index(index, len(entries)):
            return None
        if index in self.buffers:
            return self.buffers[index]
        entry = entries[index]
        length = entry.get("byteLength") if isinstance(entry, dict) else None
        if type(length) is not int or length < 0:
            return None
        data = self.source(entry.get("uri"), index)
        if data is None or len(data) < length:
            return None
        data = memoryview(data)[:length]
        self.buffers[index] = data
        return data

    def source(self, uri: Any, index: int) -> bytes | memoryview | None:
        """A buffer's whole bytes: the GLB chunk (no uri), a base64 data URI or
        a file beside the glTF; None when it cannot be had."""
        if uri is None:
            return self.binary if index == 0 else None
        if not isinstance(uri, str):
            return None
        if uri.startswith("data:"):
            head, comma, text = uri.partition(",")
            if not comma or not head.endswith(";base64"):
                return None
            try:
                return base64.b64decode(text, validate=True)
            except ValueError:
                return None
        try:
            return (self.path.resolve().parent / unquote(uri)).read_bytes()
        except OSError:
            return None
