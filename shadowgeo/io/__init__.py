"""Readers and writers, one module (or small family of modules) per format.
They know the scene model, not the shadow algorithms.

:func:`load` and :func:`save` pick the module from the file's extension:

=========  ===================================  ========================  =========================
format     extensions                           read                      write
=========  ===================================  ========================  =========================
X3D XML    ``.x3d``, ``.x3dz``, ``.x3d.gz``     :mod:`.x3d.read`          :mod:`.x3d.write`
X3D JSON   ``.x3dj``, ``.json``                 :mod:`.x3d.json`          :mod:`.x3d.json`
Classic    ``.x3dv``, ``.x3dvz``, ``.x3dv.gz``  :mod:`.x3d.classic_read`  :mod:`.x3d.classic_write`
VRML 97    ``.wrl``, ``.wrz``, ``.wrl.gz``      (as ClassicVRML)          (as ClassicVRML)
glTF 2.0   ``.glb``, ``.gltf``                  :mod:`.gltf_read`         :mod:`.gltf_write`
USD        ``.usda``, ``.usdc``, ``.usd``       :mod:`.usd_read`          :mod:`.usd_write`
OBJ, STL,  ``.obj``, ``.stl``, ``.ply``,        :mod:`.trimesh_formats`   --
PLY, OFF   ``.off``
CityJSON   ``.city.json``, ``.json``,           :mod:`.cityjson`          --
           ``.city.jsonl`` (CityJSONSeq)
footprints ``.geojson``, ``.json``, ``.gpkg``,  :mod:`.footprints`        --
           ``.shp``
=========  ===================================  ========================  =========================

A ``.json`` file is X3D JSON unless its top-level ``type`` says CityJSON or
GeoJSON (``FeatureCollection``, ``Feature``): :func:`json_format`. The city
readers share :mod:`.city_crs` (coordinate reference systems, the scene's
site) and :mod:`.city_surfaces` (a city object's polygons as one shape).

Every X3D encoding becomes the same XML element tree, read and written by the
:mod:`.x3d` package (its docstring names the parts): :mod:`.x3d.parse` parses
XML, hands JSON to :mod:`.x3d.json` and ClassicVRML and VRML 97 text
(``#X3D``, ``#VRML V2.0``) to :mod:`.x3d.classic_read`; :mod:`.x3d.read`
reads that tree whatever the encoding, and :mod:`.x3d.write` writes it back in
the encoding the output's extension names.

What a format's reader and writer share lives beside them, named for the
format: :mod:`.gltf_layout` (the GLB container, ``KHR_lights_punctual`` and
``extras["shadowgeo"]``), :mod:`.usd_layout` (usd-core, the ``shadowgeo:``
attributes) and :mod:`.usd_assets` (every asset path checked before usd-core
opens a stage).

Each reader provides ``read(path, **options) -> Scene`` and each writer
``write(scene, path, **options) -> None``; writers go through
:func:`shadowgeo.io.atomic.atomic_path`, so a failure leaves no partial file.
Helpers more than one format needs live here: :func:`up_and_units`,
:func:`check_face_indices` and :func:`look_rotation` for writers,
:func:`outside_reason` and :func:`refuse_outside` for readers that follow
references to other files.
"""

from __future__ import annotations

import importlib
import inspect
import json
import math
import os
import stat
from collections.abc import Iterable
from pathlib import Path
from types import ModuleType
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike

from .. import limits
from ..errors import SceneError
from ..scene import Scene, Shape

__all__ = [
    "READERS",
    "WRITERS",
    "check_face_indices",
    "check_folder",
    "check_writable",
    "file_problem",
    "float_triple",
    "json_format",
    "load",
    "look_rotation",
    "optional_module",
    "outside_reason",
    "reader_name",
    "refuse_outside",
    "save",
    "up_and_units",
]

READERS = {
    ".x3d": "x3d.read",
    ".x3dz": "x3d.read",
    ".x3dj": "x3d.read",
    ".json": "x3d.read",
    ".x3d.gz": "x3d.read",
    **dict.fromkeys([".x3dv", ".x3dvz", ".x3dv.gz", ".wrl", ".wrz", ".wrl.gz"], "x3d.read"),
    ".glb": "gltf_read",
    ".gltf": "gltf_read",
    ".obj": "trimesh_formats",
    ".stl": "trimesh_formats",
    ".ply": "trimesh_formats",
    ".off": "trimesh_formats",
    ".usda": "usd_read",
    ".usdc": "usd_read",
    ".usd": "usd_read",
    ".city.json": "cityjson",
    ".city.jsonl": "cityjson",
    ".jsonl": "cityjson",
    ".geojson": "footprints",
    ".gpkg": "footprints",
    ".shp": "footprints",
}
# Extensions of two parts that name a format (the last part alone names another).
_COMPOUND = (".city.json", ".city.jsonl")
# The top-level "type" of a .json document that is not X3D JSON -> its reader.
_JSON_TYPES = {"CityJSON": "cityjson", "FeatureCollection": "footprints", "Feature": "footprints"}

WRITERS = {
    ".x3d": "x3d.write",
    ".x3dz": "x3d.write",
    ".x3dj": "x3d.write",
    ".json": "x3d.write",
    **dict.fromkeys([".x3dv", ".x3dvz", ".x3dv.gz", ".wrl", ".wrz", ".wrl.gz"], "x3d.write"),
    ".glb": "gltf_write",
    ".gltf": "gltf_write",
    ".usda": "usd_write",
    ".usdc": "usd_write",
    ".usd": "usd_write",
}


def optional_module(name: str) -> Any:
    """The module ``name``, or None when it is not installed (an extra's)."""
    try:
        return importlib.import_module(name)
    except ImportError:  # pragma: no cover - the fallbacks are tested by monkeypatching
        return None


def float_triple(values: Iterable[Any]) -> tuple[float, float, float]:
    """``tuple(float(v) for v in values)``, typed as the three it holds (an
    ``(x, y, z)`` or an ``(r, g, b)``)."""
    return cast("tuple[float, float, float]", tuple(float(v) for v in values))


def _suffix(path: str | os.PathLike[str]) -> str:
    """The extension, with the one before it for gzip (``.x3dv.gz``)."""
    path = Path(path)
    name = path.name.lower()
    for compound in _COMPOUND:
        if name.endswith(compound):
            return compound
    if path.suffix.lower() == ".gz":
        return "".join(path.suffixes[-2:]).lower()
    return path.suffix.lower()


def _module(table: dict[str, str], path: str | os.PathLike[str], verb: str) -> ModuleType:
    suffix = _suffix(path)
    if suffix not in table:
        known = ", ".join(sorted(table))
        raise SceneError(
            f"cannot {verb} '{suffix or 'no extension'}' files (known: {known})", path=str(path)
        )
    return importlib.import_module(f"{__name__}.{table[suffix]}")


def json_format(path: str | os.PathLike[str]) -> str:
    """The reader module of a ``.json`` file: ``"cityjson"`` or
    ``"footprints"`` when its top-level ``type`` is ``CityJSON`` or a GeoJSON
    ``FeatureCollection`` / ``Feature``, else ``"x3d.read"`` (X3D JSON, whose
    reader says what is wrong with a file that is neither). Only a file that
    holds one of those words is parsed to tell."""
    from .x3d.parse import read_bytes

    try:
        data = read_bytes(Path(path))
    except SceneError:
        return READERS[".json"]
    if not any(f'"{kind}"'.encode() in data for kind in _JSON_TYPES):
        return READERS[".json"]
    try:
        document = json.loads(data)
    except (ValueError, RecursionError):
        return READERS[".json"]
    kind = document.get("type") if isinstance(document, dict) else None
    return _JSON_TYPES.get(kind, READERS[".json"]) if isinstance(kind, str) else READERS[".json"]


def reader_name(path: str | os.PathLike[str]) -> str:
    """The module of this package that :func:`load` reads ``path`` with
    (``"x3d.read"``, ``"cityjson"``, ...): by extension, and for ``.json``
    by :func:`json_format`; SceneError for an extension no reader takes."""
    _module(READERS, path, "read")
    suffix = _suffix(path)
    return json_format(path) if suffix == ".json" else READERS[suffix]


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
    faces = shape.faces
    if faces.size == 0 or (faces.min() >= 0 and faces.max() < len(shape.vertices)):
        return  # two reductions; the mask below only for the message
    outside = (faces < 0) | (faces >= len(shape.vertices))
    if outside.any():
        raise SceneError(
            f"faces index vertex {int(shape.faces[outside][0])} of {len(shape.vertices)}",
            node=f"shape {shape.name!r}",
        )


def outside_reason(reference: str, target: Path, folder: Path) -> str | None:
    """Why a reader may not open ``reference`` (a URI or asset path a file
    names), which resolves to ``target``: ``"not a relative path"`` (remote,
    absolute, a drive), ``"it leaves the file's folder"`` (``target`` is not
    inside ``folder``), or None when it may."""
    if ":" in reference.split("/")[0] or reference.startswith(("/", "\\")):
        return "not a relative path"
    if not target.is_relative_to(folder):
        return "it leaves the file's folder"
    return None


def file_problem(target: Path) -> str | None:
    """None when ``target`` is a regular file, else why not: ``"not found"``,
    ``"not a file"``, or the system's reason it cannot even be looked up (a
    name too long, a NUL character), so that a url read from a file leads
    to a note or a SceneError, never a traceback (``Path.is_file`` raises on
    those before Python 3.14)."""
    try:
        mode = target.stat().st_mode
    except (FileNotFoundError, NotADirectoryError):
        return "not found"
    except OSError as error:
        return f"cannot be looked up: {error.strerror or error}"
    except ValueError:  # an embedded NUL character
        return "cannot be looked up: a NUL character"
    return None if stat.S_ISREG(mode) else "not a file"


def refuse_outside(
    reference: str, target: Path, folder: Path, *, path: str | os.PathLike[str], where: str
) -> None:
    """Raise a SceneError naming ``path`` and ``where`` unless ``reference``
    is relative and ``target`` (what it resolves to) is inside ``folder``
    (:func:`outside_reason`): readers open nothing remote, absolute or in a
    parent folder."""
    reason = outside_reason(reference, target, folder)
    if reason is not None:
        raise SceneError(f"refused: {reason}", path=str(path), node=where)


def look_rotation(direction: ArrayLike) -> np.ndarray:
    """(3, 3) rotation turning -Z onto ``direction`` (the convention of glTF
    and USD lights), by the shortest arc.

    Examples
    --------
    >>> look_rotation([1.0, 0.0, 0.0]) @ [0.0, 0.0, -1.0]
    array([1., 0., 0.])
    """
    target = np.asarray(direction, dtype=np.float64)
    target = target / np.linalg.norm(target)
    source = np.array([0.0, 0.0, -1.0])
    cosine = float(source @ target)
    axis = np.cross(source, target)
    if cosine < -1.0 + limits.PRODUCT_ROUNDING:
        # Pointing along +Z: half a turn about X.
        return np.diag([1.0, -1.0, -1.0])
    # Rodrigues' formula for the rotation by the angle between source and target.
    cross = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    rotation: np.ndarray = np.eye(3) + cross + cross @ cross / (1.0 + cosine)
    return rotation


def load(
    path: str | os.PathLike[str], *, max_triangles: int | None = None, **options: Any
) -> Scene:
    """Read a scene from ``path``; the format comes from the extension.

    ``max_triangles``: the largest scene accepted, counted after tessellation
    and instancing (default :data:`shadowgeo.limits.MAX_TRIANGLES`); raise it
    for a trusted file.

    Raises
    ------
    SceneError
        The file is missing, unreadable or malformed, or holds more triangles
        than ``max_triangles``; the message names the file and, where known,
        the line and node.
    """
    path = Path(path)
    _module(READERS, path, "read")  # an unknown extension first, then a missing file
    problem = file_problem(path)
    if problem is not None:
        raise SceneError("no such file" if problem == "not found" else problem, path=str(path))
    module = importlib.import_module(f"{__name__}.{reader_name(path)}")
    if "max_triangles" in inspect.signature(module.read).parameters:
        options["max_triangles"] = max_triangles  # it estimates them before building them
    scene: Scene = module.read(path, **options)
    limits.check_triangles(sum(shape.n_faces for shape in scene.shapes), str(path), max_triangles)
    return scene


def check_writable(path: str | os.PathLike[str]) -> None:
    """SceneError, naming the known extensions, unless :func:`save` can write
    a file named ``path``; SceneError naming the folder when the folder it
    would go in (or the nearest one above that exists) is not a folder or is
    not writable: for callers that check before long work. (Only a hint: the
    write itself still fails cleanly if the folder changes meanwhile.)"""
    _module(WRITERS, path, "write")
    check_folder(path)


def check_folder(path: str | os.PathLike[str]) -> None:
    """SceneError naming ``path`` when the folder it would go in (or the
    nearest one above that exists) is not a folder or is not writable: for a
    writer of any format, checked before long work (a hint, as
    :func:`check_writable`)."""
    folder = Path(path).parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    if not folder.is_dir():
        raise SceneError(f"cannot write: {folder} is not a folder", path=str(path))
    if not os.access(folder, os.W_OK | os.X_OK):
        raise SceneError(f"cannot write: the folder {folder} is not writable", path=str(path))


def save(scene: Scene, path: str | os.PathLike[str], **options: Any) -> None:
    """Write ``scene`` to ``path`` atomically; the format comes from the extension.

    A light's size (a sun's ``angle``, a sphere light's ``source_radius``, a
    rectangle or disc light's shape) goes only into USD, which has fields
    for it; X3D and glTF have none, and a note in ``scene.warnings`` names
    the lights whose size is left out. A rectangle or disc light goes into
    them as the spot light at its centre that stands for it
    (:attr:`SceneLight.light`: facing the same way, cut-off angle 90
    degrees, lighting the half-space the panel lights).

    An error of the file system (a full disk, a missing or read-only folder)
    is a :class:`SceneError` naming ``path``, its ``OSError`` as the cause;
    ``path`` is then left as it was."""
    module = _module(WRITERS, path, "write")
    try:
        module.write(scene, Path(path), **options)
    except OSError as error:
        raise SceneError(f"cannot write: {error.strerror or error}", path=str(path)) from error
    if WRITERS[_suffix(path)] != "usd_write":
        sized = [_size_text(i, light) for i, light in enumerate(scene.lights)]
        left = [text for text in sized if text]
        if left:
            shown = "; ".join(left[:10]) + (
                f"; and {len(left) - 10} more" if len(left) > 10 else ""
            )
            kind = "glTF" if WRITERS[_suffix(path)] == "gltf_write" else "X3D"
            scene.warnings.append(
                f"{Path(path).name}: {kind} has no field for a light's size, so these are not "
                f"written (their hard shadows cast from the light's centre): {shown}"
            )


def _size_text(index: int, scene_light: Any) -> str:
    """What size a light has, for :func:`save`'s note ("" for none)."""
    light, area = scene_light.light, scene_light.area
    name = scene_light.name or f"light {index}"
    if area is not None:
        shape = (
            f"a {area.width:.6g} x {area.height:.6g} rectangle"
            if hasattr(area, "width")
            else f"a disc of radius {area.radius:.6g}"
        )
        return f"{name}, {shape} (written as a spot light at its centre, cut-off 90 degrees)"
    if getattr(light, "angle", 0.0):
        return f"{name}, angle {math.degrees(light.angle):.3g} degrees"
    if getattr(light, "source_radius", 0.0):
        return f"{name}, source radius {light.source_radius:.6g}"
    return ""
