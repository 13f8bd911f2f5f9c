"""OBJ, STL, PLY and OFF input through trimesh (read only).

trimesh decodes the triangles and, for formats that have one, the node
graph. These formats carry no units: a scene reads as Y-up with
``meters_per_unit=1``, which is what they mean in practice. The glTF reader
(:mod:`.gltf_read`) also decodes its triangles here, with
:func:`load_scene` and :func:`trimesh_material`.
"""

from __future__ import annotations

import io
import os
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ..errors import GeometryError, SceneError
from ..limits import check_coordinates
from ..scene import Material, Scene, Shape

if TYPE_CHECKING:
    import trimesh

__all__ = [
    "MALFORMED",
    "checked_shape",
    "load_scene",
    "mesh_shape",
    "read",
    "triangle_meshes",
    "trimesh_material",
]

MALFORMED = (TypeError, ValueError, KeyError, IndexError, AttributeError)


def load_scene(path: Path, data: bytes | None = None) -> trimesh.Scene:
    """trimesh's scene of ``path``, or of ``data`` in its place (external
    resources then resolve from the file's folder); SceneError naming the
    file when trimesh cannot read it. Nothing remote is ever fetched."""
    import trimesh  # here: 1.4 s to import, and plain glTF and X3D do without it

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


def trimesh_material(geometry: Any) -> tuple[Material, bool]:
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


def triangle_meshes(
    loaded: trimesh.Scene, path: Path, warnings: list[str], frames: Iterable[str]
) -> Iterator[tuple[str, np.ndarray, Any, trimesh.Trimesh]]:
    """``(frame, transform, geometry name, Trimesh)`` of each of ``frames``
    (frames of ``loaded``'s graph that hold geometry), skipping points and
    lines with a warning."""
    import trimesh

    for frame in frames:
        try:
            transform, geometry_name = loaded.graph[frame]
        except AssertionError:  # trimesh asserts that a node matrix is rigid up to scale
            raise SceneError(
                f"node {frame!r}: its matrix is not a rotation, scale and translation",
                path=str(path),
            ) from None
        geometry = loaded.geometry[geometry_name]
        if not isinstance(geometry, trimesh.Trimesh):
            warnings.append(f"{path.name}: skipped {frame!r}: {type(geometry).__name__}")
            continue
        yield frame, transform, geometry_name, geometry


def mesh_shape(
    geometry: trimesh.Trimesh, transform: ArrayLike, name: str | None, path: Path, **fields: Any
) -> Shape:
    """The :class:`Shape` of a ``trimesh.Trimesh`` placed by ``transform``
    (4, 4), named ``name`` in the file ``path``; its material and solidity
    come from trimesh unless ``fields`` (other Shape arguments) give them."""
    material, solid = trimesh_material(geometry)
    # trimesh's own arrays, not copies (the trimesh scene is dropped after reading)
    points = np.asarray(geometry.vertices, dtype=np.float64).reshape(-1, 3)
    faces = np.asarray(geometry.faces, dtype=np.int64).reshape(-1, 3)
    return checked_shape(
        points, faces, transform, name, path, **{"material": material, "solid": solid, **fields}
    )


def checked_shape(
    points: np.ndarray,
    faces: np.ndarray,
    transform: ArrayLike,
    name: str | None,
    path: Path,
    *,
    in_range: bool = False,
    **fields: Any,
) -> Shape:
    """The :class:`Shape` of float64 ``points`` (n, 3) and int64 ``faces``
    (m, 3) read from node ``name`` of the file ``path``, placed by
    ``transform`` (4, 4), with ``fields`` (other Shape arguments);
    ``in_range``: the points are already known finite and within range.

    A face that refers to a vertex the mesh does not have (trimesh keeps the
    file's indices as they are), or a vertex that is not finite or beyond
    ``limits.LARGEST_COORDINATE``, is a SceneError naming the node."""
    node = f"node {name!r}" if name else None
    if not in_range:
        try:
            check_coordinates(points, "the mesh's")
        except GeometryError as error:
            raise SceneError(str(error), path=str(path), node=node) from None
    if len(faces) and (faces.min() < 0 or faces.max() >= len(points)):
        bad = int(faces.max()) if faces.max() >= len(points) else int(faces.min())
        raise SceneError(
            f"a face refers to vertex {bad} of {len(points)}", path=str(path), node=node
        )
    return Shape(
        points,
        faces,
        np.array(transform, dtype=np.float64),
        name=name,
        source=f"{path.name}, node {name!r}" if name else path.name,
        **fields,
    )


def read(path: str | os.PathLike[str], **options: Any) -> Scene:
    """Read an OBJ, STL, PLY or OFF file into a :class:`Scene`.

    Parameters
    ----------
    path : str or Path
        ``.obj``, ``.stl``, ``.ply`` or ``.off``.

    Returns
    -------
    Scene
        One shape per mesh instance (OBJ object, ...), with its world
        transform, colour and name (the geometry's, or the file's stem when
        there is one geometry). Points and lines are skipped with a warning.

    Raises
    ------
    SceneError
        Missing, unreadable or corrupt file, or a file without triangles.
    """
    path = Path(path)
    if options:
        raise SceneError(f"mesh reader takes no options, got {sorted(options)}", path=str(path))
    if not path.is_file():
        raise SceneError("no such file", path=str(path))
    loaded = load_scene(path)
    scene = Scene(path=str(path))
    frames = sorted(loaded.graph.nodes_geometry)
    try:
        for _, transform, geometry_name, geometry in triangle_meshes(
            loaded, path, scene.warnings, frames
        ):
            name = geometry_name if len(loaded.geometry) > 1 else path.stem
            scene.shapes.append(mesh_shape(geometry, transform, name, path))
    except MALFORMED as error:
        if isinstance(error, SceneError):
            raise
        kind = path.suffix.lower().lstrip(".").upper()
        raise SceneError(f"malformed {kind}: {error}", path=str(path)) from error
    if not any(shape.n_faces for shape in scene.shapes):
        raise SceneError("no triangles in the file", path=str(path))
    return scene
