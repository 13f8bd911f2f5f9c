"""EXTERNPROTO: the ProtoDeclare an ExternProtoDeclare names, in a local file.

Each ``url`` is tried in order, as X3D browsers do; the first that gives a
prototype is used. ``"file.x3dv#Name"`` names the PROTO ``Name`` of that file;
without a fragment, the file's first PROTO (VRML 97, 4.9.3); ``"#Name"`` alone,
a PROTO of the file that declares the EXTERNPROTO. A file is found under Inline's rules
(:func:`.inline.resolve_url`): taken from the declaring file's folder,
nothing remote (a ``urn:`` neither), nothing outside the scene's folder; it is
parsed once per scene read, whatever its encoding. A file whose prototype of
that name is itself an EXTERNPROTO is followed on, at most
:data:`~shadowgeo.limits.MAX_INLINE_DEPTH` files deep; a chain that comes back
to a file and name it has passed is a SceneError.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ... import limits
from ...errors import SceneError
from .fields import Element, local_name, parse
from .inline import InlineReader, resolve_url, x3d_tree

__all__ = ["Found", "find"]


@dataclass(frozen=True)
class Found:
    """A ProtoDeclare read from another file."""

    declaration: Element
    root: Element  # the root of the file's tree
    path: Path


def find(
    reader: InlineReader,
    extern: Element,
    file: Path,
    passed: tuple[tuple[Path, str | None], ...] = (),
) -> Found | str:
    """The ProtoDeclare ``extern`` (declared in ``file``) names, or why none
    is used: each url with why it was not.

    Raises
    ------
    SceneError
        The chain of EXTERNPROTOs comes back on itself, or is too long.
    """
    try:
        urls = [url.strip() for url in parse(extern.get("url", ""), "MFString") if url.strip()]
    except ValueError as problem:
        return f"url {problem}"
    reasons = []
    for url in urls:
        found = _from_url(reader, extern, file, url, passed)
        if isinstance(found, Found):
            return found
        reasons.append(found)
    return "; ".join(reasons) or "no url"


def _from_url(
    reader: InlineReader,
    extern: Element,
    file: Path,
    url: str,
    passed: tuple[tuple[Path, str | None], ...],
) -> Found | str:
    """The ProtoDeclare one url of ``extern`` leads to (through further
    EXTERNPROTOs), or why it leads to none."""
    location, _, fragment = url.partition("#")
    name = fragment or None
    target = file if not location else resolve_url(reader, file.parent, location, url)
    if isinstance(target, str):
        return target
    tree = x3d_tree(reader, target)
    if isinstance(tree, str):
        return f"'{url}' {tree}"
    root = tree.getroot()
    declaration = _declared(root, "ProtoDeclare", name)
    if declaration is not None:
        return Found(declaration, root, target)
    onward = None if name is None else _declared(root, "ExternProtoDeclare", name)
    if onward is None or onward is extern:
        named = "" if name is None else f" '{name}'"
        return f"'{url}': {target.name} declares no PROTO{named}"
    if (target, name) in passed:
        raise _error(extern, file, f"EXTERNPROTO cycle: '{url}' leads back to itself")
    if len(passed) >= limits.MAX_INLINE_DEPTH:
        depth = limits.MAX_INLINE_DEPTH
        raise _error(extern, file, f"EXTERNPROTOs lead on through more than {depth} files")
    found = find(reader, onward, target, (*passed, (target, name)))
    return found if isinstance(found, Found) else f"'{url}': {found}"


def _declared(root: Element, tag: str, name: str | None) -> Element | None:
    """The file's first declaration ``tag`` of prototype ``name`` (of any name
    for None), outside any prototype's body (a PROTO declared in a body is
    local to it)."""
    for scene in (child for child in root if local_name(child) == "Scene"):
        for element in scene:
            if local_name(element) == tag and name in (None, element.get("name")):
                return element
    return None


def _error(extern: Element, file: Path, message: str) -> SceneError:
    node = f"ExternProtoDeclare name='{extern.get('name', '')}'"
    return SceneError(message, path=str(file), line=extern.sourceline, node=node)
