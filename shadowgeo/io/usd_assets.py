"""USD asset containment: every file a USD scene names stays in its folder.

usd-core opens whatever a layer names as it composes a stage, so the check
comes first: :func:`check_assets` reads each layer alone with ``Sdf`` (no
composition, nothing else opened), collects every asset path it holds, and
refuses the file when one is absolute, has a URI scheme or a variable
expression, or resolves (symbolic links followed) outside the scene's folder,
and refuses layers that define ``expressionVariables``.
Only then may the caller open the ``Usd.Stage``.

Asset paths of every kind are checked:

- sublayers;
- references and payloads, on prims and inside variants;
- value clips (the ``clips`` metadata): ``assetPaths``, ``manifestAssetPath``
  and ``templateAssetPath``, a file-name pattern whose ``#`` stand for digits;
- every other asset value, as ``UsdUtils.ModifyAssetPaths`` lists them:
  asset-valued attributes (textures) and their time samples, and asset values
  in metadata (``customData``, ``assetInfo``, ...).

Sublayers, references, payloads, clips and manifests are layers usd-core
opens: each must be a file, and is walked in turn; the files a clip template
matches are walked too. Other assets (textures) are never opened, by usd-core
or by shadowgeo: one outside the folder (DCC tools often write absolute
texture paths) is named in a note and the scene is still read.
"""

from __future__ import annotations

import glob
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from ..errors import SceneError
from . import outside_reason, refuse_outside
from .usd_layout import opened, pxr
from .usd_text import parse_within_budget

__all__ = ["LAYER_KINDS", "check_assets", "layer_assets"]

# Kinds of asset path that name a layer usd-core opens.
LAYER_KINDS = {"sublayer", "reference", "payload", "value clip", "value clip manifest"}


def check_assets(path: Path, notes: list[str] | None = None) -> None:
    """Refuse ``path`` unless every layer-type asset path in it, and in every
    layer it pulls in, stays inside its folder; other asset paths (textures)
    that leave it are appended to ``notes``.

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
        parse_within_budget(current)  # read first by a child held to a budget
        # Anonymous: read afresh, never a stale copy from the layer registry.
        layer = opened(Sdf.Layer.OpenAsAnonymous, current, "not a USD file")
        inside = "" if current == root else f" in {current.relative_to(folder)}"
        if getattr(layer, "expressionVariables", None):
            # They would let an expression evaluate, in the composed stage, to
            # a path this check never saw.
            raise SceneError(
                "refused: expressionVariables (variable expressions) are not supported",
                path=str(path),
                node=f"layer metadata{inside}",
            )
        for kind, asset in layer_assets(layer):
            if not asset:
                continue  # an internal reference or payload
            where = f"{kind} {asset!r}{inside}"
            if kind == "asset":
                _note_outside(asset, current.parent, folder, path, where, notes)
                continue
            target = _checked_target(kind, asset, current.parent, folder, path, where)
            if kind == "value clip template":
                pending.extend(_template_files(target, folder, path, where))
            elif kind in LAYER_KINDS:
                if not target.is_file():
                    raise SceneError("missing layer", path=str(path), node=where)
                pending.append(target)


def _checked_target(
    kind: str, asset: str, base: Path, folder: Path, path: Path, where: str
) -> Path:
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


def _note_outside(
    asset: str, base: Path, folder: Path, path: Path, where: str, notes: list[str] | None
) -> None:
    """A note, not a refusal, for an asset that is never opened (a texture)."""
    reason: str | None
    if asset.startswith("`"):
        reason = "a variable expression"
    else:
        reason = outside_reason(asset, (base / asset).resolve(), folder)
    if reason is not None and notes is not None:
        notes.append(f"{path.name}: {where}: not read ({reason})")


def _template_files(pattern: Path, folder: Path, path: Path, where: str) -> list[Path]:
    """The existing files a clip template (``#`` for digits) may name, each
    checked to stay in ``folder`` (one may be a symbolic link)."""
    name = "*".join(glob.escape(part) for part in re.split("#+", pattern.name))
    files = []
    for match in sorted(pattern.parent.glob(name)):
        target = match.resolve()
        if not target.is_file():
            continue
        if not target.is_relative_to(folder):
            raise SceneError(
                f"refused: {match.name} leaves the file's folder", path=str(path), node=where
            )
        files.append(target)
    return files


def layer_assets(layer: Any) -> list[tuple[str, str]]:
    """Every ``(kind, asset path)`` an ``Sdf.Layer`` holds, as authored.

    The layer must be a throwaway copy (opened anonymously): its ``clips``
    metadata is cleared once read, so that ``UsdUtils`` (which lists every
    other asset path, in C++) does not look for a clip template's files.
    """
    from pxr import UsdUtils

    found = [("sublayer", sublayer) for sublayer in layer.subLayerPaths]
    prims = list(layer.rootPrims)
    while prims:
        prim = prims.pop()
        if prim is None:  # a variant without its prim spec: a corrupt crate
            continue
        found.extend(_arcs_and_clips(prim))
        prims.extend(prim.nameChildren)
        for variant_set in prim.variantSets.values():
            prims.extend(variant.primSpec for variant in variant_set.variants.values())
    labelled = {asset for _, asset in found}
    others: list[str] = []

    def note(asset: str) -> str:
        others.append(asset)
        return asset

    UsdUtils.ModifyAssetPaths(layer, note)
    found.extend(("asset", asset) for asset in others if asset not in labelled)
    return found


def _arcs_and_clips(spec: Any) -> Iterator[tuple[str, str]]:
    """A prim's or variant's references, payloads and value clips, labelled;
    its ``clips`` are cleared once read (see :func:`layer_assets`)."""
    for key, kind in (("references", "reference"), ("payload", "payload")):
        if spec.HasInfo(key):
            for item in _list_op_items(spec.GetInfo(key)):
                yield kind, item.assetPath
    if spec.HasInfo("clips"):
        clips = spec.GetInfo("clips")
        spec.ClearInfo("clips")
        if isinstance(clips, dict):
            yield from _clip_assets(clips)


def _list_op_items(list_op: Any) -> list[Any]:
    """The items a list op adds, in any of its forms (deleted ones open nothing)."""
    return [
        *list_op.explicitItems,
        *list_op.addedItems,
        *list_op.prependedItems,
        *list_op.appendedItems,
        *list_op.orderedItems,
    ]


def _clip_assets(clips: dict[str, Any]) -> Iterator[tuple[str, str]]:
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


def _asset_values(value: Any) -> Iterator[str]:
    """The asset paths in a field value: an asset, an asset array, or any
    dictionary or list holding them (time samples, custom data)."""
    Sdf = pxr()[1]
    if isinstance(value, Sdf.AssetPath):
        yield _authored(value)
    elif isinstance(value, Sdf.AssetPathArray):
        for item in value:
            yield _authored(item)
    elif isinstance(value, dict):
        for item in value.values():
            yield from _asset_values(item)
    elif isinstance(value, (list, tuple)):
        for item in value:
            yield from _asset_values(item)


def _authored(asset: Any) -> str:
    """An ``Sdf.AssetPath`` as written in the file (before any expression is
    evaluated; usd-core before 25 keeps only ``path``)."""
    authored: str = getattr(asset, "authoredPath", None) or asset.path
    return authored
