"""USD asset containment: every file a USD scene names stays in its folder.

usd-core opens whatever a layer names as it composes a stage, so the check
comes first: :func:`check_assets` reads each layer alone with ``Sdf`` (no
composition, nothing else opened), collects every asset path it holds, and
refuses the file when one is absolute, has a URI scheme or a variable
expression, or resolves (symbolic links followed) outside the scene's folder.
Only then may the caller open the ``Usd.Stage``.

Asset paths of every kind are checked:

- sublayers;
- references and payloads, on prims and inside variants;
- value clips (the ``clips`` metadata): ``assetPaths``, ``manifestAssetPath``
  and ``templateAssetPath``, a file-name pattern whose ``#`` stand for digits;
- every other asset value: asset-valued attributes (textures), their time
  samples, and asset values in metadata dictionaries (``customData``,
  ``assetInfo``, ...).

Sublayers, references, payloads, clips and manifests are layers usd-core
opens: each must be a file, and is walked in turn; the files a clip template
matches are walked too. Other assets (textures) are only checked, not opened.
"""

from __future__ import annotations

import glob
import re
from collections.abc import Iterator
from pathlib import Path

from ..errors import SceneError
from . import refuse_outside
from .usd_layout import opened, pxr

# Kinds of asset path that name a layer usd-core opens.
LAYER_KINDS = {"sublayer", "reference", "payload", "value clip", "value clip manifest"}
_ASSET_TYPES = {"asset", "asset[]"}


def check_assets(path: Path) -> None:
    """Refuse ``path`` unless every asset path in it, and in every layer it
    pulls in, stays inside its folder.

    Raises
    ------
    SceneError
        Naming ``path``, the kind of asset path, the asset path itself and,
        for a layer ``path`` pulls in, that layer: a path that is absolute,
        remote, a variable expression or outside the folder; a layer that is
        missing or not USD.
    """
    Sdf = pxr()[1]
    root = path.resolve()
    folder = root.parent
    pending, seen = [root], set()
    while pending:
        current = pending.pop()
        if current in seen:
            continue
        seen.add(current)
        # Anonymous: read afresh, never a stale copy from the layer registry.
        layer = opened(Sdf.Layer.OpenAsAnonymous, current, "not a USD file")
        inside = "" if current == root else f" in {current.relative_to(folder)}"
        try:
            assets = list(layer_assets(layer))
        except SceneError as error:
            raise SceneError(error.message, path=str(path), node=f"{error.node}{inside}") from None
        for kind, asset in assets:
            if not asset:
                continue  # an internal reference or payload
            where = f"{kind} {asset!r}{inside}"
            target = _checked_target(kind, asset, current.parent, folder, path, where)
            if kind == "value clip template":
                pending.extend(_template_files(target, folder, path, where))
            elif kind in LAYER_KINDS:
                if not target.is_file():
                    raise SceneError("missing layer", path=str(path), node=where)
                pending.append(target)


def _checked_target(kind, asset: str, base: Path, folder: Path, path: Path, where: str) -> Path:
    """Where ``asset`` (anchored at ``base``) leads, after refusing it unless
    it is a plain relative path inside ``folder``."""
    if asset.startswith("`"):
        # Expressions evaluate to paths only usd-core sees: refuse them unread.
        raise SceneError("refused: a variable expression", path=str(path), node=where)
    if kind == "value clip template" and "#" in asset.replace("\\", "/").rpartition("/")[0]:
        raise SceneError("refused: '#' outside the file name", path=str(path), node=where)
    target = (base / asset).resolve()
    refuse_outside(asset, target, folder, path=path, where=where)
    return target


def _template_files(pattern: Path, folder: Path, path: Path, where: str) -> list[Path]:
    """The existing files a clip template (``#`` for digits) may name, each
    checked to stay in ``folder`` (one may be a symbolic link)."""
    name = "*".join(glob.escape(part) for part in re.split("#+", pattern.name))
    files = []
    for match in sorted(pattern.parent.glob(name)):
        target = match.resolve()
        if not target.is_relative_to(folder):
            raise SceneError(
                f"refused: {match.name} leaves the file's folder", path=str(path), node=where
            )
        files.append(target)
    return files


def layer_assets(layer) -> Iterator[tuple[str, str]]:
    """Every ``(kind, asset path)`` an ``Sdf.Layer`` holds, as authored."""
    Sdf = pxr()[1]
    for sublayer in layer.subLayerPaths:
        yield "sublayer", sublayer
    specs = []
    layer.Traverse(Sdf.Path.absoluteRootPath, specs.append)
    for spec_path in specs:
        spec = layer.GetObjectAtPath(spec_path)
        if spec is not None:
            yield from _spec_assets(spec, spec_path)


def _spec_assets(spec, spec_path) -> Iterator[tuple[str, str]]:
    """The asset paths in one spec's fields (its metadata and values)."""
    is_attribute = spec_path.IsPropertyPath() and spec.GetInfo("typeName") in _ASSET_TYPES
    for key in spec.ListInfoKeys():
        if key in ("subLayers", "subLayerOffsets"):
            continue  # walked through layer.subLayerPaths
        if key in ("default", "timeSamples") and spec_path.IsPropertyPath() and not is_attribute:
            continue  # a value of a type that holds no asset (points, ...)
        try:
            value = spec.GetInfo(key)
        except TypeError:
            # A field Python cannot see might hold an asset path: fail closed.
            raise SceneError(
                f"refused: cannot inspect {key!r} for asset paths", node=f"<{spec_path}>"
            ) from None
        if key in ("references", "payload"):
            kind = "reference" if key == "references" else "payload"
            for item in _list_op_items(value):
                yield kind, item.assetPath
        elif key == "clips" and isinstance(value, dict):
            yield from _clip_assets(value)
        else:
            for asset in _asset_values(value):
                yield "asset", asset


def _list_op_items(list_op) -> list:
    """The items a list op adds, in any of its forms (deleted ones open nothing)."""
    return [
        *list_op.explicitItems,
        *list_op.addedItems,
        *list_op.prependedItems,
        *list_op.appendedItems,
        *list_op.orderedItems,
    ]


def _clip_assets(clips: dict) -> Iterator[tuple[str, str]]:
    """Asset paths of the value-clip sets in a prim's ``clips`` metadata."""
    for clip_set in clips.values():
        if not isinstance(clip_set, dict):
            continue
        for key, value in clip_set.items():
            if key == "assetPaths":
                kind = "value clip"
            elif key == "manifestAssetPath":
                kind = "value clip manifest"
            elif key == "templateAssetPath":
                yield "value clip template", str(value)
                continue
            else:
                kind = "asset"
            for asset in _asset_values(value):
                yield kind, asset


def _asset_values(value) -> Iterator[str]:
    """The asset paths in a field value: an asset, an asset array, or any
    dictionary or list holding them (time samples, custom data)."""
    Sdf = pxr()[1]
    if isinstance(value, Sdf.AssetPath):
        yield value.authoredPath or value.path
    elif isinstance(value, Sdf.AssetPathArray):
        for item in value:
            yield item.authoredPath or item.path
    elif isinstance(value, dict):
        for item in value.values():
            yield from _asset_values(item)
    elif isinstance(value, (list, tuple)):
        for item in value:
            yield from _asset_values(item)
