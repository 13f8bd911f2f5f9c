"""X3D Inline: local X3D or glTF files only, inside the scene's folder.

Each ``url`` is tried in order. Remote URLs (any ``scheme:``) are never
fetched; a relative path is taken from the inlining file's folder and must
stay inside the top scene's folder (else SceneError); the first that exists is
read. X3D is read with the same rules as the scene (its own DEF names); glTF
and GLB with the glTF reader (:mod:`.meshes`), lights left out (with a
warning). An Inline that includes itself, directly or not, is a SceneError.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

from .. import limits
from . import meshes, x3d_parse
from .x3d_fields import Context
from .x3d_geometry import Instance, Mesh

# A scheme of two letters or more: a Windows drive ("C:/...") is not one.
URL_SCHEME = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]+:")
X3D_SUFFIXES = {".x3d", ".x3dz"}
GLTF_SUFFIXES = {".gltf", ".glb"}
MAX_INLINE_DEPTH = limits.MAX_INLINE_DEPTH  # see shadowgeo.limits


def resolve_url(reader, context: Context, element, url: str) -> Path | str:
    """The local file ``url`` names, or a string saying why there is none."""
    if URL_SCHEME.match(url):
        return f"'{url}' is remote (never fetched)"
    folder = Path(context.path).resolve().parent
    candidate = (folder / url).resolve()
    if not candidate.is_relative_to(reader.root_folder):
        raise context.error(
            element, f"Inline url '{url}' leaves the scene's folder {reader.root_folder}; refused"
        )
    if not candidate.is_file():
        return f"'{url}' not found"
    return candidate


def load_inline(reader, context: Context, element, matrix: np.ndarray, name) -> None:
    if not context.field(element, "load"):
        return
    urls = [url.strip() for url in context.field(element, "url") if url.strip()]
    reasons = []
    for url in urls:
        found = resolve_url(reader, context, element, url)
        if isinstance(found, str):
            reasons.append(found)
            continue
        suffix = found.suffix.lower()
        if suffix in X3D_SUFFIXES:
            _x3d(reader, context, element, found, matrix, name)
            return
        if suffix in GLTF_SUFFIXES:
            _gltf(reader, context, element, found, matrix, name)
            return
        reasons.append(f"'{url}' is not X3D XML or glTF")
    context.warn(element, "Inline skipped: " + ("; ".join(reasons) or "no url"))


def _x3d(reader, context: Context, element, path: Path, matrix: np.ndarray, name) -> None:
    if path in reader.inline_stack:
        raise context.error(element, f"Inline cycle: {path.name} includes itself")
    if len(reader.inline_stack) > MAX_INLINE_DEPTH:
        raise context.error(element, f"Inlines nested more than {MAX_INLINE_DEPTH} deep")
    if path not in reader.inline_files:
        reader.inline_files[path] = x3d_parse.parse(path)
    reader.document(reader.inline_files[path], path, matrix, name=name)


def _gltf_uris(path: Path) -> list[str]:
    """The external ``uri`` of a glTF's buffers and images (JSON or GLB)."""
    data = path.read_bytes()
    if data[:4] == b"glTF":
        length = int.from_bytes(data[12:16], "little")
        data = data[20 : 20 + length]
    try:
        document = json.loads(data)
    except ValueError:
        return []  # the glTF reader will say what is wrong with it
    items = [*document.get("buffers", []), *document.get("images", [])]
    uris = [item.get("uri") for item in items if isinstance(item, dict)]
    return [uri for uri in uris if isinstance(uri, str) and not uri.startswith("data:")]


def _read_gltf(reader, context: Context, element, path: Path):
    for uri in _gltf_uris(path):
        target = (path.parent / uri).resolve()
        if URL_SCHEME.match(uri) or not target.is_relative_to(reader.root_folder):
            raise context.error(
                element,
                f"glTF '{path.name}' refers to '{uri}', outside the scene's folder; refused",
            )
    # the glTF reader's own checks (compression, quantized positions, ...) and materials
    loaded = meshes.read(path)
    reader.warnings.extend(loaded.warnings)
    if loaded.lights:
        context.warn(element, f"{len(loaded.lights)} light(s) of '{path.name}' not read")
    return loaded


def _gltf(reader, context: Context, element, path: Path, matrix: np.ndarray, name) -> None:
    if path not in reader.inline_files:
        reader.inline_files[path] = _read_gltf(reader, context, element, path)
    for shape in reader.inline_files[path].shapes:
        if shape.n_faces == 0:
            continue
        reader.instances.append(
            Instance(
                Mesh(shape.vertices, shape.faces, shape.solid),
                matrix @ shape.transform,
                shape.material,
                shape.name or name,
                shape.source or path.name,
            )
        )
