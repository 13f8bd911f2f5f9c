"""Scripts that build geometry: the one note a scene gets about them.

shadowgeo does not run Scripts (the scene is read as it is at load time). A
Script *builds geometry* when what it sends reaches geometry: a ROUTE from it
to a geometry node, a Shape, a node geometry is made of (Coordinate, Normal,
Color, ...) or a grouping node's children, or a node field of a Script with
``directOutput`` holding such a node (which the script may change directly).
Such a Script, or any Script of a scene in which no geometry was read, gets
one note naming its file, line and DEF, in place of the usual "skipped" note
for Scripts.

DEF names are looked up where X3D scopes them: the document, or the ProtoBody
that holds the ROUTE and the Script.
"""

from __future__ import annotations

from .fields import Element, local_name
from .geometry import COORDINATES, GEOMETRY

__all__ = ["CHILDREN", "SHAPED", "script_note"]

# Nodes a Script changes the geometry of by writing any of their fields (text,
# lines and points cast no shadow anyway).
SHAPED = GEOMETRY | COORDINATES | {"Shape"}
SHAPED |= {"Normal", "Color", "ColorRGBA", "TextureCoordinate", "HAnimHumanoid"}
# Fields of a grouping node whose writing adds or removes geometry.
CHILDREN = {"children", "addChildren", "removeChildren", "set_children", "children_changed"}


def script_note(root: Element, path: str, has_geometry: bool) -> str | None:
    """The note on the document's Scripts (see the module notes), or None.

    Parameters
    ----------
    root : the document's root element
    path : the document's file, as messages name it
    has_geometry : whether any geometry was read from the scene
    """
    scripts = [element for element in root.iter("{*}Script") if element.get("USE") is None]
    if not scripts:
        return None
    names = _definitions(root)
    builder = next((script for script in scripts if _builds(script, names)), None)
    if builder is not None:
        return (
            f"{_where(builder, path)}: geometry is built by this Script, which shadowgeo does "
            "not run; what it builds casts no shadow"
        )
    if not has_geometry:
        return (
            f"{_where(scripts[0], path)}: no geometry was read, and this Script may build it "
            "when run, which shadowgeo does not do"
        )
    return None


def _where(script: Element, path: str) -> str:
    """The Script as every note names a node: file, line, type and DEF."""
    named = f" DEF='{script.get('DEF')}'" if script.get("DEF") else ""
    return f"{path} line {script.sourceline}, Script{named}"


def _scope(element: Element) -> Element | None:
    """The ProtoBody whose names ``element`` sees, or None for the document's."""
    return next((a for a in element.iterancestors() if local_name(a) == "ProtoBody"), None)


def _definitions(root: Element) -> dict[tuple[Element | None, str], Element]:
    """(scope, DEF name) -> the node (the first of that name)."""
    names: dict[tuple[Element | None, str], Element] = {}
    for element in root.iter():
        if isinstance(element.tag, str) and element.get("DEF") is not None:
            names.setdefault((_scope(element), element.get("DEF")), element)
    return names


def _builds(script: Element, names: dict[tuple[Element | None, str], Element]) -> bool:
    return _writes_directly(script, names) or _routes_to_geometry(script, names)


def _writes_directly(script: Element, names: dict[tuple[Element | None, str], Element]) -> bool:
    """A ``directOutput`` Script holding a shaped node in one of its fields."""
    if script.get("directOutput", "").strip().lower() != "true":
        return False
    scope = _scope(script)
    for field in (child for child in script if local_name(child) == "field"):
        for node in (child for child in field if local_name(child)):
            target = names.get((scope, node.get("USE")), node) if node.get("USE") else node
            if local_name(target) in SHAPED:
                return True
    return False


def _routes_to_geometry(script: Element, names: dict[tuple[Element | None, str], Element]) -> bool:
    """A Script with a ROUTE (in its scope) to a shaped node or to children."""
    name = script.get("DEF")
    if name is None:
        return False
    scope = _scope(script)
    scope_root = script.getroottree().getroot() if scope is None else scope
    return any(
        route.get("fromNode") == name and _scope(route) is scope and _feeds(route, scope, names)
        for route in scope_root.iter("{*}ROUTE")
    )


def _feeds(
    route: Element, scope: Element | None, names: dict[tuple[Element | None, str], Element]
) -> bool:
    """Whether ``route`` goes to a shaped node, or to a node's children."""
    target = names.get((scope, route.get("toNode", "")))
    if target is None:
        return False
    tag = local_name(target)
    return tag in SHAPED or (tag != "Script" and route.get("toField") in CHILDREN)
