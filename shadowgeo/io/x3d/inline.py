"""X3D Inline: local X3D (any encoding) or glTF files only, inside the scene's folder.

Each ``url`` is tried in order, as X3D browsers do; the first that reads is
used. Remote URLs (any ``scheme:``) are never fetched; a relative path is
taken from the inlining file's folder and is never read when it leaves the
top scene's folder (or the ``root`` folder :func:`.read.read` is given).
X3D is read with the same rules as the scene (its own DEF names); glTF and
GLB with the glTF reader (:mod:`.gltf_read`), lights left out (with a
warning); a glTF whose buffers or images lie outside the folder is
not read. When no url gives a file that reads (missing, remote, outside the
folder, unreadable, not X3D or glTF), the Inline is skipped with a warning
naming the file, line and every url with why it was not used. An Inline that
includes itself, directly or not, is a SceneError (as are the reader's limits
on nesting and expansion). A url is taken from the folder of the file the
Inline was written in (a prototype's file, for one in an EXTERNPROTO's body).
:func:`resolve_url` and :func:`x3d_tree` find and read EXTERNPROTO files too
(:mod:`.extern`), under the same rules.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any, Protocol
from urllib.parse import unquote

import numpy as np

from ... import limits
from ...errors import GeometryError, SceneError
from ...scene import Scene
from .. import file_problem, outside_reason
from ..gltf_layout import external_uris, json_document
from . import parse as x3d_parse
from .fields import Context, Element, Tree, local_name
from .geometry import Instance, Mesh

__all__ = [
    "GLTF_SUFFIXES",
    "InlineReader",
    "MAX_INLINE_DEPTH",
    "MAX_INLINE_INSTANCES",
    "URL_SCHEME",
    "X3D_SUFFIXES",
    "load_inline",
    "resolve_url",
    "x3d_tree",
]

# A scheme of two letters or more: a Windows drive ("C:/...") is not one.
URL_SCHEME = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]+:")
X3D_SUFFIXES = {".x3d", ".x3dz", ".x3dv", ".x3dvz", ".wrl", ".wrz"}
X3D_SUFFIXES |= {".x3d.gz", ".x3dv.gz", ".wrl.gz"}
X3D_SUFFIXES |= set(x3d_parse.ENCODINGS)
GLTF_SUFFIXES = {".gltf", ".glb"}
MAX_INLINE_DEPTH = limits.MAX_INLINE_DEPTH  # see shadowgeo.limits
MAX_INLINE_INSTANCES = limits.MAX_INLINE_INSTANCES


class InlineReader(Protocol):
    """What reading an Inline needs of the X3D reader (:mod:`.read`'s)."""

    root_folder: Path
    warnings: list[str]
    instances: list[Instance]
    inline_stack: list[Path]
    inline_files: dict[Path, Any]  # each Inline file read once: tree, Scene or why not
    inlines_read: int  # X3D Inline instances read so far (MAX_INLINE_INSTANCES)
    within: tuple[int, ...]  # the grouping node instances being read (see Instance)

    def document(self, tree: Tree, path: Path, matrix: np.ndarray, *, name: str | None) -> None: ...


def resolve_url(
    reader: InlineReader, folder: Path, url: str, shown: str | None = None
) -> Path | str:
    """The local file ``url`` names, taken from ``folder`` (that of the file
    that names it), or a string saying why there is none, quoting ``shown``
    (default ``url``); nothing outside the scene's folder is looked at."""
    shown = url if shown is None else shown
    if URL_SCHEME.match(url):
        return f"'{shown}' is remote (never fetched)"
    candidate = (folder / url).resolve()
    reason = outside_reason(url, candidate, reader.root_folder)
    if reason == "it leaves the file's folder":
        return f"'{shown}' leaves the scene's folder {reader.root_folder} (never read)"
    if reason is not None:
        return f"'{shown}' is {reason} (never read)"
    problem = file_problem(candidate)
    if problem is not None:
        return f"'{shown}' {problem}"
    return candidate


def load_inline(
    reader: InlineReader, context: Context, element: Element, matrix: np.ndarray, name: str | None
) -> None:
    if not context.field(element, "load"):
        return
    urls = [url.strip() for url in context.field(element, "url") if url.strip()]
    reasons = []
    folder = Path(context.file_of(element)).resolve().parent
    for url in urls:
        found = resolve_url(reader, folder, url)
        if isinstance(found, str):
            reasons.append(found)
            continue
        suffix = _suffix(found)
        if suffix in X3D_SUFFIXES:
            problem = _x3d(reader, context, element, found, matrix, name)
        elif suffix in GLTF_SUFFIXES:
            problem = _gltf(reader, context, element, found, matrix, name)
        else:
            problem = "is not X3D, VRML 97 or glTF"
        if problem is None:
            return
        reasons.append(f"'{url}' {problem}")
    context.warn(element, "Inline skipped: " + ("; ".join(reasons) or "no url"))


def _is_vrml1(path: Path) -> bool:
    try:
        return x3d_parse.read_bytes(path).startswith(b"#VRML V1.")
    except SceneError:
        return False  # _x3d says why it cannot be read


def _suffix(path: Path) -> str:
    return "".join(path.suffixes[-2:] if path.suffix == ".gz" else [path.suffix]).lower()


def x3d_tree(reader: InlineReader, path: Path) -> Tree | str:
    """The X3D document at ``path`` (any encoding), parsed once per scene
    read, or why it cannot be read (an Inline's file, an EXTERNPROTO's)."""
    if _suffix(path) not in X3D_SUFFIXES:
        return "is not X3D or VRML 97"
    if path not in reader.inline_files:
        reader.inline_files[path] = _parsed(reader, path)
    found: Tree | str = reader.inline_files[path]
    return found


def _parsed(reader: InlineReader, path: Path) -> Tree | str:
    if _is_vrml1(path):
        return "is VRML 1.0 (not supported)"
    try:
        tree = x3d_parse.parse(path, reader.warnings)
    except SceneError as error:
        return f"cannot be read: {error}"
    if not any(local_name(child) == "Scene" for child in tree.getroot()):
        return "cannot be read: it has no <Scene> element"
    return tree


def _x3d(
    reader: InlineReader,
    context: Context,
    element: Element,
    path: Path,
    matrix: np.ndarray,
    name: str | None,
) -> str | None:
    """Read an inlined X3D file into ``reader``; None, or why it cannot be read."""
    if path in reader.inline_stack:
        raise context.error(element, f"Inline cycle: {path.name} includes itself")
    if len(reader.inline_stack) > MAX_INLINE_DEPTH:
        raise context.error(element, f"Inlines nested more than {MAX_INLINE_DEPTH} deep")
    tree = x3d_tree(reader, path)
    if isinstance(tree, str):
        return tree
    # each copy is a document walked anew: counted before the walk, so a
    # fan-out of small files stops here, not after minutes
    reader.inlines_read += 1
    if reader.inlines_read > MAX_INLINE_INSTANCES:
        raise context.error(
            element,
            f"more than {MAX_INLINE_INSTANCES:,} Inline instances to read, every copy "
            "counted (shadowgeo.limits.MAX_INLINE_INSTANCES)",
        )
    reader.document(tree, path, matrix, name=name)
    return None


def _read_gltf(reader: InlineReader, context: Context, element: Element, path: Path) -> Scene | str:
    """The glTF file read as a Scene, or why it is not read."""
    try:
        document, _ = json_document(path)
    except SceneError as error:
        return f"cannot be read: {error}"
    for _, uri in external_uris(document):
        target = (path.parent / unquote(uri)).resolve()
        if outside_reason(uri, target, reader.root_folder) is not None:
            return f"refers to '{uri}', outside the scene's folder (never read)"
    # the glTF reader's own checks (compression, quantized positions, ...) and materials
    try:
        from .. import gltf_read  # (trimesh: imported for a glTF Inline only)

        loaded = gltf_read.read(path)
    except (SceneError, GeometryError) as error:
        return f"cannot be read: {error}"
    reader.warnings.extend(loaded.warnings)
    if loaded.lights:
        context.warn(element, f"{len(loaded.lights)} light(s) of '{path.name}' not read")
    return loaded


def _gltf(
    reader: InlineReader,
    context: Context,
    element: Element,
    path: Path,
    matrix: np.ndarray,
    name: str | None,
) -> str | None:
    """Add an inlined glTF's shapes to ``reader``; None, or why it cannot be read."""
    if path not in reader.inline_files:
        reader.inline_files[path] = _read_gltf(reader, context, element, path)
    loaded = reader.inline_files[path]
    if isinstance(loaded, str):
        return loaded
    for shape in loaded.shapes:
        if shape.n_faces == 0:
            continue
        reader.instances.append(
            Instance(
                Mesh(shape.vertices, shape.faces, shape.solid),
                matrix @ shape.transform,
                shape.material,
                shape.name or name,
                shape.source or path.name,
                casts_shadow=shape.casts_shadow,
                within=reader.within,
            )
        )
    return None
