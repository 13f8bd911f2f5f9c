"""What an X3D subtree expands to, estimated before it is walked: the budgets
of :mod:`shadowgeo.limits` checked before the work that would exceed them.

Through DEF/USE a few hundred bytes stand for billions of nodes. Before the
reader walks a document (or a prototype's copy), :func:`expansion` counts
what it stands for, each DEF'd node once (linear time in the document):

- ``nodes``: every element of every copy (:data:`~shadowgeo.limits.MAX_NODES`);
- ``visits``: the grouping nodes and Shapes the traversal walks one by one,
  every copy counted (:data:`~shadowgeo.limits.MAX_VISITS`): what walking
  costs, about 10 microseconds each, even when they hold nothing;
- ``triangles``: the geometry's triangles, from the lengths of its index and
  point fields and its dimensions, without reading a number of them (what
  the scene will take in memory: :data:`~shadowgeo.limits.BYTES_PER_TRIANGLE`
  each, within :data:`~shadowgeo.limits.MEMORY_BUDGET`).

The estimate of a mesh is an upper bound on what it builds (a face of ``k``
indices makes ``k - 2`` triangles); a curved primitive counts
:data:`CURVED_TRIANGLES`, the fewest its tessellation makes (the exact
count is checked shape by shape as the reader tessellates).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from lxml import etree

from ...limits import MAX_EXTRUSION_POINTS
from .fields import Context, Element, local_name

__all__ = [
    "CAP",
    "CURVED_TRIANGLES",
    "Estimates",
    "Expansion",
    "expansion",
    "flat_expansion",
    "past_budget",
    "tokens",
]

# A Sphere, Cone or Cylinder makes from a few dozen to a few thousand
# triangles, by its size against the scene's chord (a Sphere 528 alone, 2,808
# beside a box ten times smaller); the estimate counts the fewest any
# tessellation makes (8 segments round: a Sphere 48, a Cone's or Cylinder's
# cap 8), so a scene that fits is never refused for its primitives: the
# reader counts their exact triangles shape by shape as it tessellates them
# and stops at the budget (identical primitives share one tessellation).
CURVED_TRIANGLES = {"Sphere": 48, "Cone": 8, "Cylinder": 8}
# Beyond this a count stops growing: the budgets are far below it.
CAP = 1 << 62
_CHUNK = 1 << 20  # characters of a long field scanned at a time
_VISITED = {"Shape", "Transform", "Group", "StaticGroup", "Collision", "Anchor", "Billboard"}
_VISITED |= {"CADAssembly", "CADLayer", "CADPart", "CADFace", "Layer", "LayerSet"}
_VISITED |= {"MatrixTransform", "Switch", "LOD"}
_MAKE_TRIANGLES = {"Box", "Sphere", "Cone", "Cylinder", "IndexedFaceSet", "IndexedTriangleSet"}
_MAKE_TRIANGLES |= {"IndexedQuadSet", "IndexedTriangleFanSet", "IndexedTriangleStripSet"}
_MAKE_TRIANGLES |= {"TriangleSet", "QuadSet", "TriangleFanSet", "TriangleStripSet"}
_MAKE_TRIANGLES |= {"ElevationGrid", "Extrusion"}
# A prototype's body is built only in its copies, each counted as it is made.
_DECLARATIONS = {"ProtoDeclare", "ExternProtoDeclare"}


@dataclass(frozen=True)
class Expansion:
    """What a subtree stands for once every USE is expanded."""

    nodes: int = 0
    visits: int = 0
    triangles: int = 0

    def __add__(self, other: Expansion) -> Expansion:
        return Expansion(
            min(self.nodes + other.nodes, CAP),
            min(self.visits + other.visits, CAP),
            min(self.triangles + other.triangles, CAP),
        )

    def times(self, count: int) -> Expansion:
        return Expansion(
            min(self.nodes * count, CAP),
            min(self.visits * count, CAP),
            min(self.triangles * count, CAP),
        )


@dataclass
class Estimates:
    """The expansions found so far, each element's once, and for each measure
    (``"nodes"``, ``"visits"``, ``"triangles"``) the first element found whose
    own expansion passes ``budget``'s: the node an error names, the innermost
    one too big."""

    budget: Expansion
    sizes: dict[Element, Expansion] = field(default_factory=dict)
    first_over: dict[str, Element] = field(default_factory=dict)


def expansion(context: Context, element: Element, estimates: Estimates) -> Expansion:
    """What ``element`` (a USE: the DEF it names) stands for, counted in
    linear time; a cycle counts nothing here and is reported by the traversal.

    Examples
    --------
    >>> from lxml import etree
    >>> from shadowgeo.io.x3d.fields import Context
    >>> root = etree.fromstring(
    ...     '<Scene><Transform DEF="a"><Shape><Box/></Shape></Transform>'
    ...     '<Group><Transform USE="a"/><Transform USE="a"/></Group></Scene>'
    ... )
    >>> context = Context("t.x3d", (4, 0))
    >>> context.defs = {"a": [root[0]]}
    >>> expansion(context, root, Estimates(Expansion(10**6, 10**6, 10**6)))
    Expansion(nodes=11, visits=7, triangles=36)
    """
    target = context.definition(element) if element.get("USE") else element
    if target is None:
        return Expansion(nodes=1)
    known = estimates.sizes.get(target)
    if known is not None:
        return known
    estimates.sizes[target] = Expansion()  # (a cycle back to here counts nothing)
    tag = local_name(target)
    own = Expansion(nodes=1, visits=int(tag in _VISITED), triangles=_triangles(context, target))
    for child in target:
        if local_name(child) in _DECLARATIONS:  # built only in copies, counted as made
            own = own + Expansion(nodes=int(_ELEMENTS_IN(child)))
        elif local_name(child):
            own = own + expansion(context, child, estimates)
    estimates.sizes[target] = own
    for measure in ("nodes", "visits", "triangles"):
        if getattr(own, measure) > getattr(estimates.budget, measure):
            estimates.first_over.setdefault(measure, target)
    return own


def flat_expansion(context: Context, element: Element) -> Expansion:
    """:func:`expansion` of a subtree with no USE in it, counted by libxml2
    but for the geometry's own fields: a prototype's copy counted ten
    thousand times costs no Python call per node."""
    # With no declaration in or above it (a prototype's copy, most
    # documents), lxml's own tag filter finds the nodes, in C; XPath's tests of
    # local-name() and of every node's ancestors cost 0.1 s a 30,000-node copy.
    if _DECLARATION_NEAR(element):
        geometry: list[Element] = _GEOMETRY_IN(element)
        visits = int(_VISITED_IN(element))
    else:
        geometry = list(element.iter(*_ANY_GEOMETRY))
        visits = sum(1 for _ in element.iter(*_ANY_VISITED))
    triangles = sum(_triangles(context, node) for node in geometry)
    return Expansion(nodes=int(_ELEMENTS_IN(element)), visits=visits, triangles=min(triangles, CAP))


def past_budget(element: Element, tags: set[str], budget: int) -> Element | None:
    """The node past ``budget`` among those with a tag in ``tags`` written in
    ``element``'s subtree outside prototype declarations (each one the
    reader meets is read at least once), or None: a scene of more such nodes
    than its budget is refused before the walk, not after reading that many.

    >>> from lxml import etree
    >>> root = etree.fromstring("<Scene><PointLight/><Group><PointLight/></Group></Scene>")
    >>> past_budget(root, {"PointLight"}, 1).getparent().tag
    'Group'
    >>> past_budget(root, {"PointLight"}, 2) is None
    True
    """
    wanted = tuple(f"{{*}}{tag}" for tag in sorted(tags))
    if sum(1 for _ in element.iter(*wanted)) <= budget:  # (lxml's filter, in C)
        return None
    outside: list[Element] = etree.XPath(
        f"descendant-or-self::*[{_any_of(tags)}][{_OUTSIDE_DECLARATIONS}]"
    )(element)
    return outside[budget] if len(outside) > budget else None


def _any_of(tags: set[str]) -> str:
    return " or ".join(f"local-name()='{tag}'" for tag in sorted(tags))


_ELEMENTS_IN = etree.XPath("count(descendant-or-self::*)")
_OUTSIDE_DECLARATIONS = f"not(ancestor::*[{_any_of(_DECLARATIONS)}])"
_VISITED_IN = etree.XPath(
    f"count(descendant-or-self::*[{_any_of(_VISITED)}][{_OUTSIDE_DECLARATIONS}])"
)
_GEOMETRY_IN = etree.XPath(
    f"descendant-or-self::*[{_any_of(_MAKE_TRIANGLES)}][{_OUTSIDE_DECLARATIONS}]"
)
_DECLARATION_NEAR = etree.XPath(
    f"boolean(descendant-or-self::*[{_any_of(_DECLARATIONS)}]"
    f" | ancestor::*[{_any_of(_DECLARATIONS)}])"
)
# the same tags in any namespace (or none), as local-name() reads them
_ANY_VISITED = tuple(f"{{*}}{tag}" for tag in sorted(_VISITED))
_ANY_GEOMETRY = tuple(f"{{*}}{tag}" for tag in sorted(_MAKE_TRIANGLES))


# Triangles a geometry node makes: a fixed count, or index (or point) tokens per triangle.
_FIXED = {"Box": 12, **CURVED_TRIANGLES}
_INDEX_TOKENS = {"IndexedTriangleSet": 3, "IndexedQuadSet": 2}
_INDEX_TOKENS |= {"IndexedTriangleFanSet": 1, "IndexedTriangleStripSet": 1}
_POINTS = {"TriangleSet": 3, "QuadSet": 2, "TriangleFanSet": 1, "TriangleStripSet": 1}


def _triangles(context: Context, element: Element) -> int:
    """Triangles one geometry node makes at most (0 for any other node)."""
    tag = local_name(element)
    if tag in _FIXED:
        return _FIXED[tag]
    if tag == "IndexedFaceSet":
        return _polygon_triangles(element.get("coordIndex") or "")
    if tag in _INDEX_TOKENS:
        return tokens(element.get("index") or "") // _INDEX_TOKENS[tag]
    if tag in _POINTS:
        return _points(context, element) // _POINTS[tag]
    if tag == "ElevationGrid":
        columns, rows = _integer(element, "xDimension"), _integer(element, "zDimension")
        return 2 * max(columns - 1, 0) * max(rows - 1, 0)
    if tag == "Extrusion":
        return _extrusion_triangles(element)
    return 0


def _extrusion_triangles(element: Element) -> int:
    """An Extrusion's side and two caps; 0 past its own vertex budget (it is
    then skipped unbuilt, with a note)."""
    spine = tokens(element.get("spine") or "0 0 0 0 1 0") // 3
    section = tokens(element.get("crossSection") or "1 1 1 -1 -1 -1 -1 1 1 1") // 2
    if spine * section > MAX_EXTRUSION_POINTS:
        return 0
    return 2 * spine * section + 2 * section


def _polygon_triangles(text: str) -> int:
    """Triangles of an IndexedFaceSet's ``coordIndex``: a face of ``k``
    indices and its ``-1`` make ``k - 2``."""
    ended = text.count("-1")
    rest = text.rstrip(", \t\r\n")
    last = 2 if rest and not rest.endswith("-1") else 0  # the last face needs no -1
    return max(tokens(text) - 3 * ended - last, 0)


def _points(context: Context, geometry: Element) -> int:
    """Points of a geometry node's Coordinate child (or the DEF it USEs)."""
    for child in geometry:
        if local_name(child) in ("Coordinate", "CoordinateDouble"):
            node = context.definition(child) if child.get("USE") else child
            return 0 if node is None else tokens(node.get("point") or "") // 3
    return 0


def _integer(element: Element, name: str) -> int:
    try:
        return max(int((element.get(name) or "0").strip()), 0)
    except ValueError:
        return 0


def tokens(text: str) -> int:
    """Number of whitespace- or comma-separated tokens in ``text``, counted a
    megabyte at a time (a 45 MB index field is not split into a list).

    >>> tokens(" 0 1,2  -1,, 3 ")
    5
    """
    count, after_separator = 0, True
    for start in range(0, len(text), _CHUNK):
        chunk = np.frombuffer(text[start : start + _CHUNK].encode("latin-1", "replace"), np.uint8)
        separator = (chunk <= 32) | (chunk == 44)
        before = np.concatenate(([after_separator], separator[:-1]))
        count += int(np.count_nonzero(~separator & before))
        after_separator = bool(separator[-1])
    return count
