"""X3D writer, every encoding of the same tree: XML (``.x3d``; ``.x3dz``, the
same gzip-compressed), JSON (``.x3dj``, ``.json``, by :mod:`.json`),
ClassicVRML (``.x3dv``; ``.x3dvz``, ``.x3dv.gz``: gzip) or a translation to
VRML 97 (``.wrl``; ``.wrz``, ``.wrl.gz``), both by :mod:`.classic_write`.

Two cases:

* The scene came from X3D (``scene.document`` is the reader's lxml tree): the
  output is that document, unchanged, with one ``<Group DEF="shadows_<light>">``
  per group of added shapes (role ``"shadow"``, ``"volume"`` or ``"ground"``) appended to
  ``<Scene>``. Scripts, routes, viewpoints, metadata, comments and the
  ``version`` attribute stay as they were (but see *What is never copied*);
  the added nodes (Group, Shape,
  Appearance, Material, IndexedTriangleSet, Coordinate) exist in every X3D
  version from 3.0, so the version stays valid. The added groups have
  ``class="shadowgeo-shadows"``: such a group whose shapes the scene no
  longer holds (``add_shadows`` replaced them: a converted file converted
  again) is dropped rather than stacked under a second set. A document with
  no viewpoint node gets one, first in ``<Scene>`` (the one browsers bind),
  framing the scene and its shadows (:func:`~shadowgeo.scene.model.overview`,
  its orientation in the document's angle unit), with a note; it has
  ``class="shadowgeo-overview"`` and is framed anew when converted again.
  Relative urls (Inline, textures, EXTERNPROTO, Script, ...) are rewritten
  for the output's folder (:mod:`.urls`).
  A light whose shadows are baked (``SceneLight.baked``) gets
  ``shadows="false"``, the class token ``shadowgeo-shadows-baked`` (read
  back as ``baked``) and a comment before it saying why; a light that is no
  longer baked loses both. Lights of Inlines and prototypes are not
  rewritten.
* Otherwise (glTF, USD, mesh input, or a scene built in code): a fresh X3D 4.0
  document with the scene's viewpoints (else one that shows the scene and
  its shadows from above at an angle: :func:`~shadowgeo.scene.model.overview`),
  ``<NavigationInfo headlight="false"/>`` when the scene has no headlight
  and a light that is on, the lights (marked as above when baked), one
  ``Transform`` (translation, rotation, scale, scaleOrientation: any affine
  transform exactly) around each shape that is not in world coordinates, and
  the added shapes in their groups.

Added shapes are ``IndexedTriangleSet`` in world coordinates with
``solid="false"``; coordinates are written with Python's shortest round-trip
float format, so reading back gives the same float64 values.

What is never copied
--------------------
The reader follows no external reference, and the output must not make a
later reader follow one either; nor may it carry a number X3D cannot hold.
From the input document the writer leaves out, each with a note in
``scene.warnings`` (printed by ``shadowgeo convert``):

* a DOCTYPE other than the standard Web3D one (``<!DOCTYPE X3D PUBLIC
  "ISO//Web3D//DTD X3D 3.x or 4.x//EN" "http(s)://www.web3d.org/specifications/
  x3d-3.x or 4.x.dtd">``, which is written anew from the versions it names, never
  copied): a SYSTEM id pointing at a local file, another PUBLIC id, an
  internal subset;
* processing instructions (``<?xml-stylesheet href=...?>``);
* elements outside the X3D namespace (``xi:include`` and any other XInclude
  or foreign element), with their content;
* an attribute whose values are all numbers and one is not finite
  (``position="0 inf 0"``, ``1e999``): the node then takes the field's
  default, as the reader did.

Shapes and lights the writer makes itself are finite: a non-finite number
there raises :class:`~shadowgeo.SceneError`.
"""

from __future__ import annotations

import copy
import functools
import gzip
import math
import os
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import cast

import numpy as np
from lxml import etree
from numpy.typing import ArrayLike

from ...errors import SceneError
from ...lights import DirectionalLight, SpotLight
from ...limits import MATRIX_ROUNDING, PRODUCT_ROUNDING
from ...scene import Scene, SceneLight, Shape
from ...scene.model import MARK, Viewpoint, overview, unique_name
from .. import up_and_units
from ..atomic import atomic_path
from . import classic_write as x3d_classic_write
from . import json as x3d_json
from .fields import Element, Tree, numbers_or_none
from .lights import BAKED
from .numbers import LONG_VALUE, Splicer, integers_text, long_number_bytes, points_text
from .tables import field_type
from .urls import rewrite_urls

__all__ = [
    "ADDED_ROLES",
    "CLASSIC_SUFFIXES",
    "LIGHT_TAGS",
    "OVERVIEW_CLASS",
    "VRML97_SUFFIXES",
    "write",
]

ADDED_ROLES = ("shadow", "volume", "ground")
LIGHT_TAGS = ("PointLight", "SpotLight", "DirectionalLight")
# What the comment before a light whose shadows are baked says.
_BAKED_COMMENT = (
    " shadowgeo: the shadows of this light are baked into the scene as shapes; its runtime "
    'shadows are off (shadows="false") so that a browser does not darken them twice '
)
# Written in the ClassicVRML encoding (the same tree, another syntax).
CLASSIC_SUFFIXES = (".x3dv", ".x3dvz", ".x3dv.gz")
VRML97_SUFFIXES = (".wrl", ".wrz", ".wrl.gz")
# X3D's SFFloat has no infinity: an unlimited light radius is written as this.
_UNLIMITED_RADIUS = 1e30


def write(scene: Scene, path: str | os.PathLike[str]) -> None:
    """Write ``scene`` as X3D to ``path``: XML, gzip when it ends in ``.x3dz``,
    the JSON encoding when in ``.x3dj`` or ``.json``.

    Parameters
    ----------
    scene : Scene
        Not modified (the document is copied before shapes are added),
        except that what is left out of the document is noted in
        ``scene.warnings`` (see *What is never copied*).
    path : str or Path
        Written atomically: a failure leaves no partial file.

    Raises
    ------
    SceneError
        The scene's document has no ``<Scene>`` element; a shape or light to
        write has a non-finite number; for JSON, a field value that is not of
        its field's type (JSON types every value).
    """
    path = Path(path)
    doctype = None
    # the shapes' numbers, and the long ones the reader held, kept out of the
    # tree (see .numbers)
    splicer = Splicer(scene.numbers if scene.document is not None else None)
    if scene.document is not None:
        tree = _with_added(scene, splicer)
        source = Path(scene.path).name if scene.path else "input"
        doctype = _clean(tree, scene.warnings, source, splicer)
        _standard_transforms(tree, scene.warnings, source)
        if scene.path:
            scene.warnings.extend(rewrite_urls(tree, Path(scene.path), path))
    else:
        tree = _fresh(scene, splicer)
    name = path.name.lower()
    if x3d_json.is_x3d_json(path):
        splicer.fill(tree)
        parts = [x3d_json.dumps(tree)]
    elif name.endswith(CLASSIC_SUFFIXES + VRML97_SUFFIXES):
        splicer.fill(tree)
        vrml97 = name.endswith(VRML97_SUFFIXES)
        try:
            parts = [x3d_classic_write.classic_text(tree, vrml97=vrml97).encode("utf-8")]
        except SceneError as problem:  # a document VRML 97 cannot say
            raise SceneError(problem.message, path=str(path)) from None
    elif not name.endswith((".x3dz", ".gz")):
        # XML streamed into the file: a big document is never held as bytes
        with atomic_path(path) as temporary, open(temporary, "wb") as handle:
            handle.write(_DECLARATION)
            spliced = splicer.writer(handle)
            tree.write(spliced, xml_declaration=False, encoding="UTF-8", doctype=doctype)
            spliced.close()
            handle.write(b"\n")
        return
    else:
        text = etree.tostring(tree, xml_declaration=False, encoding="UTF-8", doctype=doctype)
        parts = [_DECLARATION, splicer.splice(text)]
    # written part by part: a big document is not copied to join or end it
    if not parts[-1].endswith(b"\n"):
        parts.append(b"\n")
    if name.endswith((".x3dz", ".x3dvz", ".wrz", ".gz")):
        parts = [gzip.compress(b"".join(parts), mtime=0)]
    with atomic_path(path) as temporary, open(temporary, "wb") as handle:
        for part in parts:
            handle.write(part)


_DECLARATION = b'<?xml version="1.0" encoding="UTF-8"?>\n'


def _with_added(scene: Scene, splicer: Splicer | None = None) -> Tree:
    tree = copy.deepcopy(scene.document)
    if not isinstance(tree, etree._ElementTree):
        tree = etree.ElementTree(tree)
    root = tree.getroot()
    namespace = root.tag[: root.tag.index("}") + 1] if root.tag.startswith("{") else ""
    body = root.find(f"{namespace}Scene")
    if body is None:
        raise SceneError("the X3D document has no <Scene> element", path=scene.path)
    added = [s for s in scene.shapes if s.role in ADDED_ROLES]
    lights = _document_lights(tree, scene)  # found before the marked groups go
    homes = _homes(tree, added)  # (likewise: the paths are of the document as read)
    _remove_marked(tree)  # the scene's added shapes replace them
    authored = _bound_viewpoint(tree)  # (before the names are taken: ours gets its own back)
    _mark_lights(lights, _legacy_version(root.get("version")))
    used = set(tree.xpath("//@DEF"))
    if added and root.get("profile") == "Core":
        _require_components(root, namespace)
    x3d4 = _version(root.get("version")) >= 4.0
    _place_added(body, added, homes, used, namespace, splicer, x3d4)
    if authored is None:
        if root.get("profile") == "Core":
            _require_components(root, namespace, {"Navigation": 1})
        _add_overview(body, scene, used, namespace)
    return tree


def _mark_lights(lights: list[tuple[Element, SceneLight]], legacy: bool) -> None:
    """The document's lights told what shadows they cast at run time."""
    for element, scene_light in lights:
        _runtime_shadows(element, scene_light)
        if legacy and not scene_light.global_ and element.get("global") is None:
            # X_ITE takes a DirectionalLight of X3D 3.0 and VRML 97 with no
            # ``global`` as global; the standard's default (false) said aloud
            # keeps it to its group there too, as shadowgeo baked it
            element.set("global", "false")


def _place_added(
    body: Element,
    added: list[Shape],
    homes: dict[int, tuple[Element, np.ndarray]],
    used: set[str],
    namespace: str,
    splicer: Splicer | None,
    x3d4: bool,
) -> None:
    """The added shapes into the document: in the group they were read from
    (their home), the others in new groups at the top of ``body``."""
    at_top = [shape for shape in added if id(shape) not in homes]
    groups = _add_groups(body, at_top, used, namespace, splicer, x3d4)
    if groups:
        _indent(body, groups)
    for shape in added:
        if id(shape) in homes:
            _add_home(shape, *homes[id(shape)], used, namespace, splicer, x3d4)


def _version(version: str | None) -> float:
    """An X3D document's ``version`` as a number (3.0 when absent or unreadable)."""
    try:
        return float(version or "3.0")
    except ValueError:
        return 3.0


def _legacy_version(version: str | None) -> bool:
    """Whether an X3D document of ``version`` is one X_ITE reads with its
    legacy defaults (3.0 and older: a DirectionalLight is global)."""
    return _version(version) <= 3.0


def _bound_viewpoint(tree: Tree) -> Element | None:
    """The document's first viewpoint node (any kind, a prototype's too), or
    None; one shadowgeo added earlier is dropped, to be framed anew."""
    for element in tree.xpath(_VIEWPOINTS):
        if element.get("class") == OVERVIEW_CLASS:
            _drop(element)
        else:
            return element
    return None


_VIEWPOINTS = (
    "//*[local-name()='Viewpoint' or local-name()='OrthoViewpoint' or local-name()='GeoViewpoint']"
)
OVERVIEW_CLASS = "shadowgeo-overview"
_DEFAULT_FIELD_OF_VIEW = 0.7854  # X3D's, a little over pi/4


def _add_overview(body: Element, scene: Scene, used: set[str], namespace: str) -> None:
    """Put a Viewpoint framing the scene and its shadows first in ``body`` (the
    one a browser binds), its orientation in the document's angle unit, with a
    note. Its field of view is X3D's default, pi/4, left unwritten: written in
    degrees it would break the schema's bound (< 3.1416) that ignores units."""
    view = overview(scene, field_of_view=_DEFAULT_FIELD_OF_VIEW)
    factor = _angle_factor(body.getparent(), namespace)
    view = replace(view, orientation=(*view.orientation[:3], view.orientation[3] / factor))
    element = _viewpoint_element(view, used, namespace)
    del element.attrib["fieldOfView"]
    element.set("class", OVERVIEW_CLASS)
    lead = body.text if body.text and "\n" in body.text and not body.text.strip() else "\n"
    if len(body):
        element.tail = lead
    else:
        element.tail = body.text or "\n"
        body.text = lead + "  "
    body.insert(0, element)
    source = Path(scene.path).name if scene.path else "input"
    scene.warnings.append(
        f"{source}: no Viewpoint; added '{element.get('DEF')}', showing the scene and its "
        "shadows from 35 degrees above"
    )


def _angle_factor(root: Element, namespace: str) -> float:
    """Radians per angle unit of the document (``<unit category="angle">``), 1 if none."""
    for unit in root.iterfind(f"{namespace}head/{namespace}unit"):
        if unit.get("category") == "angle":
            try:
                factor = float(unit.get("conversionFactor", ""))
            except ValueError:
                continue
            if math.isfinite(factor) and factor > 0:
                return factor
    return 1.0


# The standard DOCTYPE of X3D 3.0 to 4.1; only this is written, and anew.
_STANDARD_DOCTYPE = re.compile(
    r"ISO//Web3D//DTD X3D (?P<version>[34]\.[0-9])//EN\n"
    r"https?://www\.web3d\.org/specifications/x3d-(?P=version)\.dtd"
)
# Attributes that hold names or text, never numbers, whatever they spell.
_TEXT_ATTRIBUTES = {"DEF", "USE", "class", "id", "style", "name", "description", "containerField"}


def _clean(tree: Tree, notes: list[str], source: str, splicer: Splicer) -> str | None:
    """Strip from ``tree`` (a copy) what must never be copied (see the module
    notes), noting each; returns the DOCTYPE to write (None: none). Long
    number attributes go to ``splicer``: the file then gets their bytes as
    they are, where lxml would first copy and escape them into its own
    buffers (values of number characters alone, which XML escapes nowhere,
    so the file is the same)."""
    doctype = _clean_doctype(tree.docinfo, notes, source)
    root = tree.getroot()
    _drop_instructions(tree, notes, source)
    _drop_foreign(tree, notes, source)
    # In document order. (Not an XPath ``contains()`` per letter: it copies
    # every attribute value once per call, 60 MB each for a big mesh.)
    declared = _declared_types(root)
    for element in root.iter(etree.Element):
        _clean_numbers(element, notes, source, splicer, declared)
    return doctype


def _clean_doctype(info: etree.DocInfo, notes: list[str], source: str) -> str | None:
    """The standard X3D DOCTYPE to write anew (None: none), any other noted;
    the document's own cleared."""
    if not info.doctype:
        return None
    doctype = None
    ids = f"{info.public_id or ''}\n{info.system_url or ''}"
    subset = info.internalDTD
    empty = subset is None or not (list(subset.iterelements()) or list(subset.entities()))
    standard = _STANDARD_DOCTYPE.fullmatch(ids)
    if standard and empty:
        version = standard.group("version")
        doctype = (
            f'<!DOCTYPE X3D PUBLIC "ISO//Web3D//DTD X3D {version}//EN" '
            f'"https://www.web3d.org/specifications/x3d-{version}.dtd">'
        )
    else:
        shown = info.doctype if len(info.doctype) <= 80 else info.doctype[:77] + "..."
        notes.append(f"{source}: {shown} not written (only the standard X3D DOCTYPE is)")
    info.clear()
    return doctype


def _drop_instructions(tree: Tree, notes: list[str], source: str) -> None:
    """Remove every processing instruction, in and around the root, noting each."""
    root = tree.getroot()
    # Found by XPath, in C: a Python loop over the nodes of a document of
    # 10,000 shapes took a tenth of a second each time.
    around = [*root.itersiblings(preceding=True), *root.itersiblings()]
    for instruction in [
        *(node for node in around if isinstance(node, etree._ProcessingInstruction)),
        *root.xpath(".//processing-instruction()"),
    ]:
        line = f" line {instruction.sourceline}" if instruction.sourceline else ""
        notes.append(
            f"{source}{line}: processing instruction <?{instruction.target} ...?> not written"
        )
    etree.strip_elements(tree, etree.PI, with_tail=False)


def _drop_foreign(tree: Tree, notes: list[str], source: str) -> None:
    """Remove elements of other namespaces (the outermost of each, noted)."""
    root = tree.getroot()
    namespace = etree.QName(root).namespace
    foreign = root.xpath(".//*[namespace-uri() != $namespace]", namespace=namespace or "")
    dropped = set(foreign)
    for element in foreign:
        if any(ancestor in dropped for ancestor in element.iterancestors()):
            continue
        notes.append(
            f"{source} line {element.sourceline}: <{element.prefix or ''}"
            f"{':' if element.prefix else ''}{etree.QName(element).localname}> is not X3D "
            "(never followed); not written"
        )
        _drop(element)
    etree.cleanup_namespaces(tree)


def _clean_numbers(
    element: Element, notes: list[str], source: str, splicer: Splicer, declared: _Declared
) -> None:
    """Remove an element's non-finite number attributes (noted); long number
    values go to ``splicer``. ``declared``: the prototypes' field types."""
    tag = etree.QName(element).localname
    for name, value in element.items():
        if name not in _TEXT_ATTRIBUTES and _non_finite(value, _kind(tag, name, element, declared)):
            shown = value if len(value) <= 40 else value[:37] + "..."
            notes.append(
                f"{source} line {element.sourceline}, {tag}: "
                f"{name}='{shown}' is not finite; not written (the field's default applies)"
            )
            del element.attrib[name]
        elif len(value) >= LONG_VALUE and (data := long_number_bytes(value)) is not None:
            splicer.set(element, name, data)


def _standard_transforms(tree: Tree, notes: list[str], source: str) -> None:
    """Write each MatrixTransform (a Castle Game Engine and VRML 97 browser
    extension, not X3D: X_ITE and the X3D schema know no such node) as the
    Transform of the same matrix (:func:`_transform_fields`: any affine matrix
    exactly), noting it. One whose matrix is not affine or not finite, or
    that a ROUTE or IS reaches (its ``matrix`` may change), stays as it is."""
    found = tree.xpath("//*[local-name() = 'MatrixTransform']")
    if not found:
        return
    routed = {
        name
        for route in tree.xpath("//*[local-name() = 'ROUTE']")
        for name in (route.get("fromNode"), route.get("toNode"))
        if name
    }
    written = [
        str(element.sourceline or "?")
        for element in found
        if element.get("DEF") not in routed
        and element.find("{*}IS") is None
        and _as_transform(element)
    ]
    if written:
        lines = ", ".join(written[:10]) + (f" and {len(written) - 10} more" * (len(written) > 10))
        notes.append(
            f"{source} line{'s' * (len(written) > 1)} {lines}: MatrixTransform (a Castle "
            "Game Engine node, not X3D) written as the Transform of the same matrix, which "
            "every X3D browser draws"
        )


def _as_transform(element: Element) -> bool:
    """Turn a MatrixTransform into the Transform of its matrix, if it is affine
    and finite; whether it was."""
    values = numbers_or_none(element.get("matrix") or "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1")
    if values is None or len(values) != 16 or not np.all(np.isfinite(values)):
        return False
    matrix = values.reshape(4, 4).T  # X3D's SFMatrix4f: rows, translation in the last
    if not np.array_equal(matrix[3], [0.0, 0.0, 0.0, 1.0]):
        return False
    try:
        fields = _transform_fields(matrix)
    except SceneError:
        return False
    element.tag = element.tag.replace("MatrixTransform", "Transform")
    element.attrib.pop("matrix", None)
    for name, value in fields.items():
        element.set(name, value)
    return True


# An exponent of three digits or more (searched with its letter first: a
# literal start makes the search skip from letter to letter), and 200 digits
# in a row: without one or the other no float64 word overflows.
_BIG_EXPONENTS = (re.compile(r"e\+?0*[1-9]\d\d"), re.compile(r"E\+?0*[1-9]\d\d"))
_DIGITS_TO_ZERO = bytes.maketrans(b"0123456789", b"0" * 10)


def _drop(node: Element) -> None:
    """Remove ``node`` from its tree, keeping the text after it."""
    parent = node.getparent()
    previous = node.getprevious()
    before = previous.tail if previous is not None else parent.text
    # indentation before the node gives way to the text after it
    after = node.tail if before is None or not before.strip() else before + (node.tail or "")
    if previous is not None:
        previous.tail = after
    else:
        parent.text = after
    parent.remove(node)


def _kind(tag: str, name: str, element: Element, declared: _Declared) -> str:
    """What attribute ``name`` of an element ``tag`` holds, as far as the
    schema (or a ``<field>``'s ``type``, or a ``<fieldValue>``'s field's in
    ``declared``) says: ``"numbers"``, ``"other"`` (strings, booleans,
    nodes), or ``"unknown"``."""
    if tag == "field" and name == "value":
        kind = element.get("type")
    elif tag == "fieldValue" and name == "value":
        instance = element.getparent()  # its ProtoInstance, named as its prototype
        prototype = None if instance is None else instance.get("name")
        kind = declared.get((prototype, element.get("name")))
    else:
        kind = field_type(tag, name)
    if kind is None:
        return "unknown"
    return "other" if kind.endswith(("String", "Bool", "Node")) else "numbers"


# (prototype name, field name) -> the field's declared type
_Declared = dict[tuple[str | None, str | None], str]


def _declared_types(root: Element) -> _Declared:
    """The type of every field a ProtoDeclare or ExternProtoDeclare of the
    document declares (the first declaration of a name wins): what a
    ProtoInstance's ``<fieldValue>`` of that name holds."""
    declared: _Declared = {}
    for declare in root.iter(etree.Element):
        if etree.QName(declare).localname not in ("ProtoDeclare", "ExternProtoDeclare"):
            continue
        for field in declare.iter(etree.Element):
            kind = field.get("type")
            if etree.QName(field).localname == "field" and kind is not None:
                declared.setdefault((declare.get("name"), field.get("name")), kind)
    return declared


def _non_finite(value: str, kind: str = "unknown") -> bool:
    """Whether ``value`` holds a number that is not finite: any word of it in
    a field of numbers (``kind`` from :func:`_kind`; the reader refuses the
    whole value for its default, even beside a word that is no number), only
    when all its words are numbers in a field the schema does not know, and
    never in one of strings."""
    if kind == "other":
        return False
    # A word reads as inf or nan only if it spells one (an n) or overflows
    # (an e with a big exponent, or a long run of digits). Anything else is
    # finite however long the text: 60 MB of coordinates are not parsed again.
    if "n" not in value and "N" not in value:
        if not any(pattern.search(value) for pattern in _BIG_EXPONENTS) and not _long_run(value):
            return False
    numbers = numbers_or_none(value)
    if numbers is not None:
        return not bool(np.isfinite(numbers).all())
    return kind == "numbers" and any(
        _not_finite_word(word) for word in value.replace(",", " ").split()
    )


def _not_finite_word(word: str) -> bool:
    """Whether ``word`` reads as a number that is not finite (inf, nan, or
    one past float64's range)."""
    try:
        return not math.isfinite(float(word))
    except ValueError:
        return False


def _long_run(value: str) -> bool:
    """Whether ``value`` has 200 digits in a row; a megabyte at a time, so
    that a big mesh's text is not copied whole (twice) to find out."""
    run = b"0" * 200
    for begin in range(0, len(value), _SCANNED):
        piece = value[max(begin - len(run), 0) : begin + _SCANNED]
        if run in piece.encode("utf-8").translate(_DIGITS_TO_ZERO):
            return True
    return False


_SCANNED = 1 << 20


# What the added nodes need beyond the Core profile (Interchange and up have it).
_COMPONENTS = {"Grouping": 1, "Rendering": 3, "Shape": 1}


def _require_components(
    root: Element, namespace: str, components: dict[str, int] | None = None
) -> None:
    """Declare ``components`` (name: level; by default what the added shapes
    use) in a ``profile="Core"`` document's ``<head>`` (components come first
    in it)."""
    head = root.find(f"{namespace}head")
    if head is None:
        head = etree.Element(f"{namespace}head")
        root.insert(0, head)
    declared = {
        c.get("name"): int(c.get("level", "1") or 1) for c in head.findall(f"{namespace}component")
    }
    position = len(head.findall(f"{namespace}component"))
    for name, level in (components or _COMPONENTS).items():
        if declared.get(name, 0) < level:
            component = etree.Element(f"{namespace}component", name=name, level=str(level))
            head.insert(position, component)
            position += 1


def _document_lights(tree: Tree, scene: Scene) -> list[tuple[Element, SceneLight]]:
    """The elements of ``tree`` (a copy of ``scene.document``) the scene's
    lights were read from, with those lights; a light of an Inline or a
    prototype has none. Every light element loses the marks of an earlier
    run (the ``class`` token, the comment before it): the scene's lights say
    which are baked now."""
    for element in tree.iter():
        if not isinstance(element.tag, str) or element.tag.rsplit("}", 1)[-1] not in LIGHT_TAGS:
            continue
        marks = (element.get("class") or "").split()
        if BAKED in marks:
            marks.remove(BAKED)
            if marks:
                element.set("class", " ".join(marks))
            else:
                del element.attrib["class"]
        previous = element.getprevious()
        if isinstance(previous, etree._Comment) and (previous.text or "").startswith(
            " shadowgeo: "
        ):
            _drop(previous)
    found: dict[Element, SceneLight] = {}
    for scene_light in scene.lights:
        if scene_light.node is None:
            continue
        elements = tree.xpath(scene_light.node)
        if isinstance(elements, list) and len(elements) == 1:  # a USEd light: its first
            found.setdefault(cast(Element, elements[0]), scene_light)
    return list(found.items())


def _runtime_shadows(element: Element, scene_light: SceneLight) -> None:
    """Write the light's ``shadows`` field where it changed, and mark a light
    whose shadows are baked (its runtime shadows turned off): a ``class``
    token the reader gives back as ``baked``, and a comment saying so."""
    written = (element.get("shadows") or "false").strip().lower() == "true"
    if written != scene_light.runtime_shadows:
        element.set("shadows", _bool(scene_light.runtime_shadows))
    if not scene_light.baked:
        return
    element.set("class", " ".join([*(element.get("class") or "").split(), BAKED]))
    comment = etree.Comment(_BAKED_COMMENT)
    comment.tail = element.getprevious().tail if element.getprevious() is not None else None
    element.addprevious(comment)
    if comment.tail is None:  # the first child: indent as the parent's text does
        comment.tail = element.getparent().text


def _remove_marked(tree: Tree) -> None:
    """Drop the groups an earlier run added, keeping the whitespace around
    them: the reader gave their shapes back as role "shadow"/"volume", so the
    scene's added shapes are what is written (the same ones, or new ones
    add_shadows made)."""
    marked = f"contains(concat(' ', normalize-space(@class), ' '), ' {MARK} ')"
    for group in tree.xpath(f"//*[{marked}]"):
        parent = group.getparent()
        previous = group.getprevious()
        if previous is not None:
            previous.tail = group.tail
        else:
            parent.text = group.tail
        parent.remove(group)


def _add_groups(
    parent: Element,
    shapes: list[Shape],
    used: set[str],
    namespace: str = "",
    splicer: Splicer | None = None,
    x3d4: bool = True,
) -> list[Element]:
    """Append one Group per ``shape.group`` holding those shapes; returns them.
    In an X3D 4 document (``x3d4``) each says ``castShadow="false"``: a
    browser drawing runtime shadows (``--keep-runtime-shadows``) must not
    cast the baked shadows' own overlays, nor the added ground."""
    groups: dict[str, etree._Element] = {}
    for shape in shapes:
        key = shape.group or f"shadows_{shape.role}"
        if key not in groups:
            groups[key] = etree.SubElement(
                parent, f"{namespace}Group", DEF=unique_name(key, used), attrib={"class": MARK}
            )
        element = _shape_element(shape, used, namespace, world=True, splicer=splicer)
        element.set("class", f"{MARK}-{shape.role}")  # read back as this role
        if x3d4:
            element.set("castShadow", "false")
        groups[key].append(element)
    return list(groups.values())


def _homes(tree: Tree, added: list[Shape]) -> dict[int, tuple[Element, np.ndarray]]:
    """The added shapes with a :attr:`~shadowgeo.scene.model.Shape.placement`
    found in ``tree`` (by id): the element and the inverse of its matrix
    (world to its local coordinates). One whose element is gone, or whose
    matrix has no inverse, is written at the top."""
    found = {}
    for shape in added:
        if shape.placement is None:
            continue
        elements = tree.xpath(shape.placement.node)
        if not isinstance(elements, list) or len(elements) != 1:
            continue
        with np.errstate(all="ignore"):
            try:
                inverse = np.linalg.inv(shape.placement.matrix)
            except np.linalg.LinAlgError:
                continue
        if np.all(np.isfinite(inverse)):
            found[id(shape)] = (cast(Element, elements[0]), inverse)
    return found


def _add_home(
    shape: Shape,
    parent: Element,
    inverse: np.ndarray,
    used: set[str],
    namespace: str,
    splicer: Splicer | None,
    x3d4: bool,
) -> None:
    """Append ``shape`` in its own marked Group to ``parent`` (its placement),
    its coordinates made local to it, indented as ``parent``'s children."""
    local = replace(shape, transform=inverse @ shape.transform)
    _indent(parent, _add_groups(parent, [local], used, namespace, splicer, x3d4))


def _indent(body: Element, groups: list[Element]) -> None:
    """Indent the added groups like the other children of ``body`` (``<Scene>``,
    or the group a shape is placed in), and leave the whitespace of everything
    else as it was."""
    children = list(body)
    first = children.index(groups[0])
    previous = children[first - 1] if first else None
    spacing = _spacing(body, previous.tail if previous is not None else body.text)
    if previous is not None:
        previous.tail = "\n" + spacing.indent
    else:
        body.text = "\n" + spacing.indent
    for group in groups:
        etree.indent(group, space=spacing.step or "  ", level=spacing.level)
        group.tail = "\n" + spacing.indent
    groups[-1].tail = spacing.closing


@dataclass(frozen=True)
class _Spacing:
    """The whitespace of a parent's children: ``indent`` before each child,
    ``closing`` before the parent's end tag, ``step`` per level (empty when
    unclear) and the children's ``level``."""

    indent: str
    closing: str
    step: str
    level: int


def _spacing(body: Element, before: str | None) -> _Spacing:
    """How ``body``'s children are indented, from its text and the whitespace
    ``before`` the first added group."""
    closing = before if before and "\n" in before and not before.strip() else "\n"
    lead = body.text or ""
    indent = lead.rsplit("\n", 1)[1] if "\n" in lead and not lead.strip() else ""
    outer = closing.rsplit("\n", 1)[1]  # the indentation of </Scene>
    step = indent[len(outer) :] if indent.startswith(outer) and len(indent) > len(outer) else ""
    level = len(indent) // len(step) if step and len(indent) % len(step) == 0 else 1
    return _Spacing(indent, closing, step, level)


def _numbers(values: ArrayLike) -> str:
    values = np.asarray(values, dtype=np.float64).ravel()
    if not np.all(np.isfinite(values)):
        raise SceneError(f"cannot write a non-finite number in X3D: {values.tolist()[:8]}")
    return " ".join(map(repr, values.tolist()))


@functools.lru_cache(maxsize=1024)
def _material_attributes(
    key: tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...], float, float],
) -> tuple[tuple[str, str], ...]:
    """A Material's attributes from its diffuse, emissive and specular
    colours, shininess and transparency (``key``): made once for the many
    shapes that share a look."""
    diffuse, emissive, specular, shininess, transparency = key
    attributes = [("diffuseColor", _numbers(diffuse))]
    if any(emissive):
        attributes.append(("emissiveColor", _numbers(emissive)))
    if any(specular):
        attributes.append(("specularColor", _numbers(specular)))
        attributes.append(("shininess", repr(shininess)))
    attributes.append(("transparency", repr(transparency)))
    return tuple(attributes)


def _bool(value: bool) -> str:
    return "true" if value else "false"


def _shape_element(
    shape: Shape,
    used: set[str],
    namespace: str = "",
    *,
    world: bool,
    splicer: Splicer | None = None,
) -> Element:
    """A ``<Shape>``: vertices in world coordinates when ``world``, else local;
    its numbers in ``splicer`` when given, else in the tree."""
    element = etree.Element(f"{namespace}Shape")
    if shape.name:
        element.set("DEF", unique_name(shape.name, used))
    appearance = etree.SubElement(element, f"{namespace}Appearance")
    material = shape.material
    key = (
        tuple(map(float, material.diffuse_color)),
        tuple(map(float, material.emissive_color)),
        tuple(map(float, material.specular_color)),
        float(material.shininess),
        float(material.transparency),
    )
    etree.SubElement(appearance, f"{namespace}Material", dict(_material_attributes(key)))
    vertices = shape.world_vertices if world else shape.vertices
    geometry = etree.SubElement(element, f"{namespace}IndexedTriangleSet")
    coordinate = etree.SubElement(geometry, f"{namespace}Coordinate")
    index, points = integers_text(shape.faces), points_text(vertices)
    if splicer is None:
        geometry.set("index", index.decode("ascii"))
        coordinate.set("point", points.decode("ascii"))
    else:
        splicer.set(geometry, "index", index)
        splicer.set(coordinate, "point", points)
    geometry.set("solid", _bool(shape.solid))
    return element


# -- a fresh X3D 4.0 document ----------------------------------------------------------------


_IDENTITY = np.eye(4)


def _fresh(scene: Scene, splicer: Splicer | None = None) -> Tree:
    up, meters = up_and_units(scene)
    xsd = "http://www.w3.org/2001/XMLSchema-instance"
    root = etree.Element("X3D", profile="Immersive", version="4.0", nsmap={"xsd": xsd})
    root.set(
        f"{{{xsd}}}noNamespaceSchemaLocation", "https://www.web3d.org/specifications/x3d-4.0.xsd"
    )
    _fresh_head(etree.SubElement(root, "head"), scene, meters)
    body = etree.SubElement(root, "Scene")
    used: set[str] = set()
    if up == "Z":
        # X3D is Y-up: one rotation about x takes (x, y, z) to (x, z, -y).
        name = unique_name("shadowgeo_z_up", used)
        body = etree.SubElement(body, "Transform", DEF=name, rotation=f"1 0 0 {-math.pi / 2!r}")
    # The input's cameras, else one showing the scene and its shadows from
    # above at an angle (X3D's default camera stands at ground level, where a
    # ground and its shadows are edge-on).
    for viewpoint in scene.viewpoints or [overview(scene)]:
        body.append(_viewpoint_element(viewpoint, used))
    _fresh_lights(body, scene, used)
    _fresh_shapes(body, scene, used, splicer)
    _add_groups(body, [s for s in scene.shapes if s.role in ADDED_ROLES], used, "", splicer)
    etree.indent(root, space="  ")
    return etree.ElementTree(root)


def _fresh_head(head: Element, scene: Scene, meters: float) -> None:
    """The ``<head>`` of a new document, in the schema's order: unit, meta."""
    from ... import __version__

    if meters != 1.0:
        etree.SubElement(
            head, "unit", category="length", name="metres_per_unit", conversionFactor=repr(meters)
        )
    etree.SubElement(head, "meta", name="generator", content=f"shadowgeo {__version__}")
    if scene.path:
        etree.SubElement(head, "meta", name="source", content=Path(scene.path).name)


def _fresh_lights(body: Element, scene: Scene, used: set[str]) -> None:
    """The scene's lights (and the headlight off when they light it)."""
    if not scene.headlight and any(light.on for light in scene.lights):
        # lit by its own lights, as in the viewers of the format it came from
        etree.SubElement(body, "NavigationInfo", headlight="false")
    for light in scene.lights:
        if light.baked:
            body.append(etree.Comment(_BAKED_COMMENT))
        body.append(_light_element(light, used))


def _fresh_shapes(body: Element, scene: Scene, used: set[str], splicer: Splicer | None) -> None:
    """The scene's own shapes (not the added ones), each in a Transform unless at identity."""
    for shape in scene.shapes:
        if shape.role in ADDED_ROLES:
            continue
        node = _shape_element(shape, used, world=False, splicer=splicer)
        if not shape.casts_shadow:  # (X3D 4.0's field: this document's version)
            node.set("castShadow", "false")
        if not np.array_equal(shape.transform, _IDENTITY):
            transform = etree.SubElement(body, "Transform", _transform_fields(shape.transform))
            transform.append(node)
        else:
            body.append(node)


def _viewpoint_element(viewpoint: Viewpoint, used: set[str], namespace: str = "") -> Element:
    element = etree.Element(
        f"{namespace}Viewpoint",
        position=_numbers(viewpoint.position),
        orientation=_numbers(viewpoint.orientation),
        fieldOfView=repr(float(viewpoint.field_of_view)),
    )
    if viewpoint.description:
        element.set("description", viewpoint.description)
    if viewpoint.name:
        element.set("DEF", unique_name(viewpoint.name, used))
    return element


def _light_element(scene_light: SceneLight, used: set[str]) -> Element:
    light = scene_light.light
    if isinstance(light, DirectionalLight):
        element = etree.Element("DirectionalLight", direction=_numbers(light.direction))
    else:
        kind = "SpotLight" if isinstance(light, SpotLight) else "PointLight"
        element = etree.Element(kind, location=_numbers(light.position))
        if isinstance(light, SpotLight):
            element.set("direction", _numbers(light.direction))
            element.set("cutOffAngle", repr(float(light.cut_off_angle)))
            element.set("beamWidth", repr(float(min(scene_light.beam_width, math.pi / 2))))
        radius = light.radius if math.isfinite(light.radius) else _UNLIMITED_RADIUS
        element.set("radius", repr(float(radius)))
        element.set("attenuation", _numbers(scene_light.attenuation))
    if scene_light.name:
        element.set("DEF", unique_name(scene_light.name, used))
    element.set("color", _numbers(scene_light.color))
    element.set("intensity", repr(float(scene_light.intensity)))
    element.set("ambientIntensity", repr(float(scene_light.ambient_intensity)))
    element.set("on", _bool(scene_light.on))
    element.set("global", _bool(scene_light.global_))
    element.set("shadows", _bool(scene_light.runtime_shadows))
    element.set("shadowIntensity", repr(float(scene_light.shadow_intensity)))
    if scene_light.baked:
        element.set("class", BAKED)
    return element


def _transform_fields(matrix: np.ndarray) -> dict[str, str]:
    """X3D Transform fields that give exactly ``matrix`` (4, 4): the linear part
    ``A = R (SR S SR^-1)`` from the singular value decomposition
    ``A = U diag(s) V^T`` with ``R = U V^T``, ``SR = V``, scale ``s``."""
    if not np.allclose(matrix[3], [0, 0, 0, 1], rtol=0, atol=PRODUCT_ROUNDING):
        raise SceneError(f"cannot write a projective transform in X3D: {matrix.tolist()}")
    linear = matrix[:3, :3]
    u, s, vt = np.linalg.svd(linear)
    if np.linalg.det(u) < 0:
        u[:, 2] *= -1
        s[2] *= -1
    if np.linalg.det(vt) < 0:
        vt[2] *= -1
        s[2] *= -1
    fields = {"translation": _numbers(matrix[:3, 3])}
    rotation = u @ vt
    if not np.allclose(rotation, np.eye(3), rtol=0, atol=MATRIX_ROUNDING):
        fields["rotation"] = _numbers(_axis_angle(rotation))
    if not np.allclose(s, 1.0, rtol=0, atol=MATRIX_ROUNDING):
        fields["scale"] = _numbers(s)
        if not np.allclose(vt, np.eye(3), rtol=0, atol=MATRIX_ROUNDING):
            fields["scaleOrientation"] = _numbers(_axis_angle(vt.T))
    return fields


def _axis_angle(rotation: np.ndarray) -> np.ndarray:
    """(4,) axis x, y, z and angle of a 3x3 rotation matrix, via its unit
    quaternion (Shepperd's method: divide by the largest of its four terms)."""
    m = rotation
    trace = float(np.trace(m))
    largest = int(np.argmax([trace, m[0, 0], m[1, 1], m[2, 2]]))
    vector = np.zeros(3)
    if largest == 0:
        w = math.sqrt(max(1.0 + trace, 0.0)) / 2
        vector[:] = [m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]]
        vector /= 4 * w
    else:
        a = largest - 1
        b, c = (a + 1) % 3, (a + 2) % 3
        vector[a] = math.sqrt(max(1.0 + m[a, a] - m[b, b] - m[c, c], 0.0)) / 2
        vector[b] = (m[b, a] + m[a, b]) / (4 * vector[a])
        vector[c] = (m[c, a] + m[a, c]) / (4 * vector[a])
        w = (m[c, b] - m[b, c]) / (4 * vector[a])
    length = float(np.linalg.norm(vector))
    if length == 0.0:
        return np.array([0.0, 0.0, 1.0, 0.0])
    return np.append(vector / length, 2 * math.atan2(length, w))
