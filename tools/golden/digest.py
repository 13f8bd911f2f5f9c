"""Results as what a golden record keeps: areas, counts and array hashes.

Each array is hashed as its dtype name, shape and bytes, after conversion
to float64 (coordinates, fractions) or int64 (indices, flags), in the order
the API returns it: two results are identical when every hash and the
area's ``repr`` match, so a change in the last bit, the order of a loop or
the sign of a zero shows.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass
class Digest:
    """What a case produced: ``record`` goes into the manifest; ``arrays``
    and ``files`` are the raw results, written only with ``--keep``."""

    record: dict[str, Any]
    arrays: dict[str, np.ndarray] = field(default_factory=dict)
    files: dict[str, bytes] = field(default_factory=dict)


def sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def canonical(values: Any, kind: str) -> np.ndarray:
    """``values`` as a C-ordered float64 (``kind`` "f") or int64 ("i") array."""
    return np.ascontiguousarray(np.asarray(values, dtype=np.float64 if kind == "f" else np.int64))


def array_hash(array: np.ndarray) -> str:
    header = f"{array.dtype.name}{list(array.shape)}".encode()
    return sha256(header + array.tobytes())


class Builder:
    """Collects named arrays and counts into a :class:`Digest`."""

    def __init__(self, kind: str) -> None:
        self.record: dict[str, Any] = {"kind": kind, "arrays": {}, "counts": {}}
        self.arrays: dict[str, np.ndarray] = {}

    def array(self, name: str, values: Any, kind: str) -> None:
        array = canonical(values, kind)
        self.arrays[name] = array
        self.record["arrays"][name] = array_hash(array)

    def count(self, name: str, value: int) -> None:
        self.record["counts"][name] = int(value)

    def area(self, value: float) -> None:
        self.record["area"] = repr(float(value))

    def polygons(self, prefix: str, parts: list[list[np.ndarray]]) -> None:
        """Parts of ``[outer, hole, ...]`` loops: the points of every loop in
        order, and their structure (number of parts, loops per part, points
        per loop)."""
        loops = [loop for part in parts for loop in part]
        points = np.concatenate([np.asarray(loop, dtype=float) for loop in loops]) if loops else []
        structure = [len(parts), *(len(part) for part in parts), *(len(loop) for loop in loops)]
        self.array(f"{prefix}points", np.reshape(points, (-1, 2)), "f")
        self.array(f"{prefix}structure", structure, "i")
        self.count(f"{prefix}parts", len(parts))
        self.count(f"{prefix}loops", len(loops))
        self.count(f"{prefix}points", len(self.arrays[f"{prefix}points"]))

    def mesh(self, prefix: str, vertices: Any, faces: Any) -> None:
        self.array(f"{prefix}vertices", np.reshape(vertices, (-1, 3)), "f")
        self.array(f"{prefix}faces", np.reshape(faces, (-1, 3)), "i")
        self.count(f"{prefix}vertices", len(self.arrays[f"{prefix}vertices"]))
        self.count(f"{prefix}faces", len(self.arrays[f"{prefix}faces"]))

    def done(self) -> Digest:
        return Digest(self.record, self.arrays)


def shadow(result: Any, prefix: str = "", builder: Builder | None = None) -> Digest:
    """A ``Shadow``: area, polygons and the triangulated mesh."""
    builder = builder or Builder("Shadow")
    if not prefix:
        builder.area(result.area)
    else:
        builder.record.setdefault("areas", {})[prefix.rstrip(".")] = repr(float(result.area))
    builder.polygons(f"{prefix}polygons.", result.polygons)
    builder.mesh(f"{prefix}mesh.", result.mesh.vertices, result.mesh.faces)
    return builder.done()


def shadows(results: list[Any]) -> Digest:
    """A list of ``Shadow`` (one per light): each under ``light<i>.``, and
    the sum of their areas as the case's area."""
    builder = Builder("list[Shadow]")
    builder.area(sum(float(result.area) for result in results))
    builder.count("shadows", len(results))
    for index, result in enumerate(results):
        shadow(result, f"light{index}.", builder)
    return builder.done()


def surface_shadow(result: Any) -> Digest:
    """A ``SurfaceShadow``: area, triangles, the face of each, every face's fraction."""
    builder = Builder("SurfaceShadow")
    builder.area(result.area)
    builder.mesh("", result.vertices, result.faces)
    builder.array("face_index", result.face_index, "i")
    builder.array("fraction", result.fraction, "f")
    return builder.done()


def volume(result: Any) -> Digest:
    """A shadow volume (``trimesh.Trimesh``): its vertices, faces and volume."""
    builder = Builder("shadow_volume")
    builder.mesh("", result.vertices, result.faces)
    builder.area(result.volume)  # the "area" of a volume case is its volume
    return builder.done()


def silhouette(result: Any) -> Digest:
    """A ``Silhouette``: front faces, edges, loops, border, non-manifold edges."""
    builder = Builder("Silhouette")
    builder.array("front", result.front, "i")
    builder.array("edges", np.reshape(result.edges, (-1, 2)), "i")
    loops = list(result.loops)
    flat = np.concatenate([np.asarray(loop) for loop in loops]) if loops else []
    builder.array("loops", flat, "i")
    builder.array("loop_lengths", [len(loop) for loop in loops], "i")
    builder.array("border", np.reshape(result.border, (-1, 2)), "i")
    builder.array("non_manifold", np.reshape(result.non_manifold, (-1, 2)), "i")
    builder.count("front", int(np.count_nonzero(result.front)))
    builder.count("loops", len(loops))
    builder.record["is_closed"] = bool(result.is_closed)
    return builder.done()


def sun_study(result: Any) -> Digest:
    """A ``SunStudy``: the times kept, each time's shadow and every level's region."""
    builder = Builder("SunStudy")
    builder.area(result.area)
    builder.record["times"] = [time.isoformat() for time in result.times]
    for index, polygons in enumerate(result.shadows):
        builder.polygons(f"shadow{index}.", polygons)
    for level in sorted(result.levels):
        builder.polygons(f"level{level}.", result.levels[level])
    builder.record["level_areas"] = {
        repr(hours): repr(area) for hours, area in sorted(result.level_areas().items())
    }
    return builder.done()


def error(exception: BaseException) -> Digest:
    """A case that raised: its type and message are its result."""
    return Digest({"kind": "error", "error": f"{type(exception).__name__}: {exception}"})
