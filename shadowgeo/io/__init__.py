"""Readers and writers, one module per format. They know the scene model,
not the shadow algorithms.

:func:`load` and :func:`save` pick the module from the file's extension:

================================  ==========================  ==================
extension                         read                        write
================================  ==========================  ==================
``.x3d``, ``.x3dz``               :mod:`.x3d_read`            :mod:`.x3d_write`
``.glb``, ``.gltf``               :mod:`.meshes` (trimesh)    :mod:`.gltf`
``.usda``, ``.usdc``, ``.usd``    :mod:`.usd`                 :mod:`.usd`
``.obj``, ``.stl``, ``.ply``,     :mod:`.meshes` (trimesh)    --
``.off``
================================  ==========================  ==================

Each module provides ``read(path, **options) -> Scene`` and/or
``write(scene, path, **options) -> None``; writers go through
:func:`shadowgeo.io.atomic.atomic_path`, so a failure leaves no partial file.
Checks more than one format needs live here: :func:`up_and_units` and
:func:`check_face_indices` for writers, :func:`refuse_outside` for readers
that follow references to other files.
"""

from __future__ import annotations

import importlib
import math
import os
from pathlib import Path
from types import ModuleType
from typing import Any

from ..errors import SceneError
from ..scene import Scene, Shape

READERS = {
    ".x3d": "x3d_read",
    ".x3dz": "x3d_read",
    ".glb": "meshes",
    ".gltf": "meshes",
    ".obj": "meshes",
    ".stl": "meshes",
    ".ply": "meshes",
    ".off": "meshes",
    ".usda": "usd",
    ".usdc": "usd",
    ".usd": "usd",
}

WRITERS = {
    ".x3d": "x3d_write",
    ".x3dz": "x3d_write",
    ".glb": "gltf",
    ".gltf": "gltf",
    ".usda": "usd",
    ".usdc": "usd",
    ".usd": "usd",
}


def _suffix(path: str | os.PathLike[str]) -> str:
    return Path(path).suffix.lower()


def _module(table: dict[str, str], path: str | os.PathLike[str], verb: str) -> ModuleType:
    suffix = _suffix(path)
    if suffix not in table:
        known = ", ".join(sorted(table))
        raise SceneError(
            f"cannot {verb} '{suffix or 'no extension'}' files (known: {known})", path=str(path)
        )
    return importlib.import_module(f"{__name__}.{table[suffix]}")


def up_and_units(scene: Scene) -> tuple[str, float]:
    """The scene's up axis (``"Y"`` or ``"Z"``) and metres per unit, checked
    for the writers; SceneError for any other axis or a scale not > 0."""
    up = (scene.up_axis or "Y").upper()
    if up not in ("Y", "Z"):
        raise SceneError(f"up axis must be 'Y' or 'Z', got {scene.up_axis!r}", path=scene.path)
    meters = float(scene.meters_per_unit)
    if not (math.isfinite(meters) and meters > 0):
        raise SceneError(f"metersPerUnit must be > 0, got {scene.meters_per_unit!r}")
    return up, meters


def check_face_indices(shape: Shape) -> None:
    """SceneError naming the first face index that is not one of the shape's
    vertices (negative or too large), for the writers."""
    outside = (shape.faces < 0) | (shape.faces >= len(shape.vertices))
    if outside.any():
        raise SceneError(
            f"faces index vertex {int(shape.faces[outside][0])} of {len(shape.vertices)}",
            node=f"shape {shape.name!r}",
        )


def refuse_outside(
    reference: str, target: Path, folder: Path, *, path: str | os.PathLike[str], where: str
) -> None:
    """Raise a SceneError unless ``reference`` (a URI or asset path a file
    names) is relative and ``target`` (what it resolves to) is inside
    ``folder``: readers open nothing remote, absolute or in a parent folder."""
    if ":" in reference.split("/")[0] or reference.startswith(("/", "\\")):
        raise SceneError("refused: not a relative path", path=str(path), node=where)
    if not target.is_relative_to(folder):
        raise SceneError("refused: it leaves the file's folder", path=str(path), node=where)


def load(path: str | os.PathLike[str], **options: Any) -> Scene:
    """Read a scene from ``path``; the format comes from the extension.

    Raises
    ------
    SceneError
        The file is missing, unreadable or malformed; the message names the
        file and, where known, the line and node.
    """
    path = Path(path)
    module = _module(READERS, path, "read")
    if not path.is_file():
        raise SceneError("no such file", path=str(path))
    scene: Scene = module.read(path, **options)
    return scene


def check_writable(path: str | os.PathLike[str]) -> None:
    """SceneError, naming the known extensions, unless :func:`save` can write
    a file named ``path``: for callers that check before long work."""
    _module(WRITERS, path, "write")


def save(scene: Scene, path: str | os.PathLike[str], **options: Any) -> None:
    """Write ``scene`` to ``path`` atomically; the format comes from the extension."""
    module = _module(WRITERS, path, "write")
    module.write(scene, Path(path), **options)
