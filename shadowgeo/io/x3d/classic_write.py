"""Write an X3D XML tree in the ClassicVRML encoding (``.x3dv``).

The tree is what :mod:`.write` would write as XML (the input document
with the shadow groups added, or a fresh one); this module only changes its
syntax, so every node, DEF/USE name, field value, PROTO, ROUTE, Script,
IMPORT/EXPORT, head entry and comment is kept. Field types come from the
schema table (:mod:`.tables`), a prototype's declaration, or a
``<field type>``: SFString values are quoted, MF values bracketed, booleans
written ``TRUE`` / ``FALSE``. A child node goes to its ``containerField``
(or its type's default one). Script code held as XML text is written as the
first ``url`` string, as ClassicVRML has no other place for it.

VRML 97 (``.wrl``) is the same syntax with X3D's later names undone: access
types (``exposedField``, ...), Collision ``collide``, LOD ``level``, Switch
``choice``; IndexedTriangleSet (the shadows) becomes IndexedFaceSet; the head
(PROFILE, COMPONENT, UNIT, META) becomes comments, a length unit a scale
around the scene; an angle unit is refused (SceneError). Nodes VRML 97 lacks are
written as they are (X3D browsers read them); the ``class`` field that marks
shadowgeo's groups is kept, as X3D browsers accept it in VRML 97 files.
"""

from __future__ import annotations

from lxml import etree

from ...errors import SceneError
from .classic_read import classic_comment
from .classic_tokens import is_number, quote
from .fields import Element, Tree, local_name
from .fields import parse as parse_field
from .tables import CONTAINER_FIELDS, DEFAULTS, field_type

__all__ = [
    "CODE_NODES",
    "INDENT",
    "VRML97_ACCESS",
    "VRML97_FIELDS",
    "X3D4_DEFAULTS",
    "classic_text",
]

INDENT = "  "
# Nodes whose XML text content is code (a CDATA section), written as a url.
CODE_NODES = {"Script", "ShaderPart", "ShaderProgram", "PackagedShader"}
_SKIPPED = {"DEF", "USE", "containerField"}
# A node's IS connections: node field -> prototype field (as the XML spells them).
_Connects = dict[str | None, str | None]
# Children that are statements, not nodes.
_STATEMENTS = ("ROUTE", "IMPORT", "EXPORT", "ProtoDeclare", "ExternProtoDeclare")
# X3D names VRML 97 spells otherwise: (node, X3D field) -> VRML 97 field; access types.
VRML97_FIELDS = {("Collision", "enabled"): "collide", ("LOD", "children"): "level"}
# X3D fields VRML 97 lacks (its DirectionalLight keeps to its group anyway).
_NOT_VRML97 = frozenset(
    {("Shape", "castShadow")}
    | {(light, "global") for light in ("DirectionalLight", "PointLight", "SpotLight")}
)
VRML97_FIELDS[("Switch", "children")] = "choice"
_SPOT = DEFAULTS["SpotLight"]
X3D4_DEFAULTS = {("SpotLight", name): _SPOT[name][1] for name in ("beamWidth", "cutOffAngle")}
VRML97_ACCESS = {
    "initializeOnly": "field", "inputOutput": "exposedField", "inputOnly": "eventIn",
    "outputOnly": "eventOut",
}  # fmt: skip


def classic_text(tree: Tree | Element, vrml97: bool = False) -> str:
    """The ClassicVRML text of an X3D XML tree (``lxml`` tree or root element),
    or with ``vrml97`` its VRML 97 translation (see :data:`VRML97_FIELDS`).

    Examples
    --------
    >>> from lxml import etree
    >>> root = etree.fromstring(
    ...     '<X3D profile="Interchange" version="4.0"><Scene>'
    ...     '<Transform DEF="t" translation="0 1 0"><Shape><Box/></Shape></Transform>'
    ...     '</Scene></X3D>'
    ... )
    >>> print(classic_text(root), end="")
    #X3D V4.0 utf8
    PROFILE Interchange
    <BLANKLINE>
    DEF t Transform {
      translation 0 1 0
      children Shape {
        geometry Box { }
      }
    }
    """
    root = tree.getroot() if isinstance(tree, etree._ElementTree) else tree
    version = root.get("version", "4.0")
    writer = _Writer(vrml97, x3d4=not version.startswith(("3.", "2.")))
    lines = [f"#X3D V{version} utf8", f"PROFILE {root.get('profile') or 'Immersive'}"]
    if vrml97:
        lines = ["#VRML V2.0 utf8"]
    for part in root:
        if local_name(part) == "head":
            lines += [line for entry in part for line in writer.head(entry)]
    lines.append("")
    length = _vrml97_length(root) if vrml97 else 1.0
    for part in root:
        if local_name(part) == "Scene" and length != 1.0:
            lines += _scaled(writer, list(part), length)
        elif local_name(part) == "Scene":
            for child in part:
                lines += writer.statement(child, 0)
        elif not isinstance(part.tag, str):
            lines += writer.statement(part, 0)
    return "\n".join(lines) + "\n"


def _vrml97_length(root: Element) -> float:
    """The length unit's factor, for VRML 97 (which has no units); SceneError
    for an angle unit, which would change the meaning of every angle field."""
    factors = {}
    for head in (part for part in root if local_name(part) == "head"):
        for unit in (entry for entry in head if local_name(entry) == "unit"):
            factors[unit.get("category")] = unit.get("conversionFactor", "1")
    try:
        angle, length = float(factors.get("angle", 1)), float(factors.get("length", 1))
    except ValueError:
        raise SceneError(f"a unit's conversionFactor is not a number: {factors}") from None
    if angle != 1.0:
        raise SceneError(
            "VRML 97 has no angle unit, and this document's angles are in "
            f"{factors['angle']} radians; write .x3dv or .x3d instead"
        )
    return length


def _scaled(writer: _Writer, children: list[Element], length: float) -> list[str]:
    """The scene inside a Transform scaled to metres: VRML 97 has no length
    unit. Prototypes come first, routes last (VRML 97 allows neither among nodes)."""
    statements = ("ProtoDeclare", "ExternProtoDeclare", "ROUTE", "IMPORT", "EXPORT")
    protos = [c for c in children if local_name(c) in statements[:2]]
    routes = [c for c in children if local_name(c) in statements[2:]]
    nodes = [c for c in children if local_name(c) not in statements]
    lines = [f"# the document's length unit ({length!r} metres), as a scale", "Transform {"]
    lines.append(f"{INDENT}scale {length!r} {length!r} {length!r}")
    lines += [line for child in protos for line in writer.statement(child, 1)]
    lines.append(f"{INDENT}children [")
    lines += [line for child in nodes for line in writer.statement(child, 2)]
    lines.append(f"{INDENT}]")
    lines += [line for child in routes for line in writer.statement(child, 1)]
    return lines + ["}"]


class _Writer:
    def __init__(self, vrml97: bool = False, x3d4: bool = True) -> None:
        self.vrml97 = vrml97
        # defaults X3D 4 changed, written out when VRML 97 (read as 3.x) would change them
        self.explicit = X3D4_DEFAULTS if vrml97 and x3d4 else {}
        self.protos: dict[str, dict[str, str]] = {}  # prototype name -> field -> type

    def head(self, entry: Element) -> list[str]:
        tag = local_name(entry)
        lines = []
        if tag == "component":
            lines = [f"COMPONENT {entry.get('name')}:{entry.get('level', '1')}"]
        elif tag == "unit":
            words = [entry.get(key, "") for key in ("category", "name", "conversionFactor")]
            lines = ["UNIT " + " ".join(words)]
        elif tag == "meta":
            lines = [f"META {quote(entry.get('name', ''))} {quote(entry.get('content', ''))}"]
        elif not isinstance(entry.tag, str):
            return self.statement(entry, 0)
        # VRML 97 has no head: its entries stay as comments
        return [f"# {line}" for line in lines] if self.vrml97 else lines

    # -- statements --------------------------------------------------------------
    def statement(self, element: Element, depth: int) -> list[str]:
        pad = INDENT * depth
        if isinstance(element, etree._Comment):
            text = classic_comment(element.text or "")
            return [pad + "#" + line for line in text.split("\n")]
        if not isinstance(element.tag, str):
            return []
        tag = local_name(element)
        get = element.get
        if tag == "ROUTE":
            route = f"{get('fromNode')}.{get('fromField')} TO {get('toNode')}.{get('toField')}"
            return [f"{pad}ROUTE {route}"]
        if tag == "IMPORT":
            alias = f" AS {get('AS')}" if get("AS") else ""
            return [f"{pad}IMPORT {get('inlineDEF')}.{get('importedDEF')}{alias}"]
        if tag == "EXPORT":
            alias = f" AS {get('AS')}" if get("AS") else ""
            return [f"{pad}EXPORT {get('localDEF')}{alias}"]
        if tag in ("ProtoDeclare", "ExternProtoDeclare"):
            return self.proto(element, depth)
        return self.node(element, depth, pad)

    def proto(self, element: Element, depth: int) -> list[str]:
        pad, name = INDENT * depth, element.get("name", "")
        external = local_name(element) == "ExternProtoDeclare"
        interface = element if external else _child(element, "ProtoInterface")
        fields = [] if interface is None else [f for f in interface if local_name(f) == "field"]
        self.protos[name] = {f.get("name"): f.get("type") for f in fields}
        lines = [f"{pad}{'EXTERNPROTO' if external else 'PROTO'} {name} ["]
        for field in fields:
            lines += self.declaration(field, depth + 1, with_value=not external)
        if external:
            urls = parse_field(element.get("url", ""), "MFString")
            return lines + [f"{pad}] [ {' '.join(map(quote, urls))} ]"]
        lines.append(f"{pad}]")
        lines.append(f"{pad}{{")
        body = _child(element, "ProtoBody")
        for child in [] if body is None else body:
            lines += self.statement(child, depth + 1)
        return lines + [f"{pad}}}"]

    def declaration(
        self, field: Element, depth: int, with_value: bool, connected: str | None = None
    ) -> list[str]:
        """``accessType type name [value | IS name]`` of a ``<field>``."""
        pad = INDENT * depth
        kind, access = field.get("type", ""), field.get("accessType", "initializeOnly")
        written = VRML97_ACCESS.get(access, access) if self.vrml97 else access
        start = f"{pad}{written} {kind} {field.get('name')}"
        if connected:
            return [f"{start} IS {connected}"]
        if not with_value or access not in ("initializeOnly", "inputOutput"):
            return [start]
        nodes = [child for child in field if isinstance(child.tag, str)]
        if kind.endswith("Node"):
            return self.nodes(start, nodes, depth, many=kind == "MFNode")
        return [f"{start} {self.value(field.get('value', ''), kind)}"]

    # -- nodes -------------------------------------------------------------------
    def node(self, element: Element, depth: int, start: str) -> list[str]:
        if element.get("USE") is not None:
            return [f"{start}USE {element.get('USE')}"]
        tag = local_name(element)
        instance = tag == "ProtoInstance"
        kind = element.get("name", "") if instance else tag
        if self.vrml97 and tag == "IndexedTriangleSet":
            kind = "IndexedFaceSet"  # VRML 97 has no triangle sets
        if element.get("DEF") is not None:
            start += f"DEF {element.get('DEF')} "
        body = self.body(element, tag, kind, instance, depth + 1)
        if not body:
            return [f"{start}{kind} {{ }}"]
        return [f"{start}{kind} {{", *body, INDENT * depth + "}"]

    def body(self, element: Element, tag: str, kind: str, instance: bool, depth: int) -> list[str]:
        connects = _connects(element)
        lines = self.attributes(element, tag, instance, connects, depth)
        declared = {f.get("name") for f in element if local_name(f) == "field"}
        lines += [
            f"{INDENT * depth}{name} IS {proto_field}"
            for name, proto_field in connects.items()
            if name not in declared
        ]
        return lines + self.children(element, tag, kind, connects, depth)

    def attributes(
        self, element: Element, tag: str, instance: bool, connects: _Connects, depth: int
    ) -> list[str]:
        """``name value`` per written attribute, then a script's inline code as its url."""
        pad = INDENT * depth
        attributes = dict(element.attrib)
        for (node, name), default in self.explicit.items():
            if node == tag and name not in attributes:
                attributes[name] = default
        lines = []
        for name, text in attributes.items():
            if not self.writes(tag, name, instance, connects):
                continue
            kind_of = field_type(tag, name)
            if self.vrml97 and tag == "IndexedTriangleSet" and name == "index":
                name, text = "coordIndex", _faces(text)
            if self.vrml97:
                name = VRML97_FIELDS.get((tag, name), name)
            lines.append(f"{pad}{name} {self.value(text, kind_of)}")
        code = (element.text or "").strip()
        if tag in CODE_NODES and code and element.get("url") is None:
            lines.append(f"{pad}url [ {quote(code)} ]")
        return lines

    def writes(self, tag: str, name: str, instance: bool, connects: _Connects) -> bool:
        """Whether attribute ``name`` of ``tag`` is written as a field."""
        if name in _SKIPPED or (instance and name == "name") or name in connects:
            return False
        if name.startswith("{"):
            return False  # namespaced attributes (xsd:...) are XML-only
        return not (self.vrml97 and (tag, name) in _NOT_VRML97)

    def children(
        self, element: Element, tag: str, kind: str, connects: _Connects, depth: int
    ) -> list[str]:
        """Declarations, field values, statements and node-valued fields, in document order."""
        lines: list[str] = []
        groups: dict[str, list[Element]] = {}
        pending: list[Element] = []  # comments go with the node after them
        for child in element:
            child_tag = local_name(child)
            if isinstance(child, etree._Comment):
                pending.append(child)
            elif child_tag == "field":
                lines += self.declaration(child, depth, True, connects.get(child.get("name")))
            elif child_tag == "fieldValue":
                lines += self.field_value(child, kind, depth)
            elif child_tag in _STATEMENTS:
                # After the nodes before it (it may USE their DEFs), before those after it.
                lines += self.groups(groups, tag, depth) + self.comments(pending, depth)
                groups, pending = {}, []
                lines += self.statement(child, depth)
            elif child_tag and child_tag != "IS":
                groups.setdefault(_container(child, child_tag), []).extend([*pending, child])
                pending = []
        return lines + self.groups(groups, tag, depth) + self.comments(pending, depth)

    def comments(self, pending: list[Element], depth: int) -> list[str]:
        return [line for comment in pending for line in self.statement(comment, depth)]

    def groups(self, groups: dict[str, list[Element]], tag: str, depth: int) -> list[str]:
        """Node-valued fields: ``field`` and its nodes, per field."""
        lines = []
        for field, items in groups.items():
            if self.vrml97:
                field = VRML97_FIELDS.get((tag, field), field)
            many = sum(isinstance(item.tag, str) for item in items) > 1
            lines += self.nodes(f"{INDENT * depth}{field}", items, depth, many)
        return lines

    def nodes(self, start: str, items: list[Element], depth: int, many: bool) -> list[str]:
        """``field Node { }`` or ``field [ ... ]`` (comments among the nodes kept)."""
        nodes = [item for item in items if isinstance(item.tag, str)]
        if not nodes:
            return [f"{start} {'[ ]' if many else 'NULL'}"]
        if len(nodes) == 1 and not many:
            comments = [line for item in items[:-1] for line in self.statement(item, depth)]
            return comments + self.node(nodes[0], depth, start + " ")
        lines = [f"{start} ["]
        for item in items:
            lines += self.statement(item, depth + 1)
        return lines + [INDENT * depth + "]"]

    def field_value(self, holder: Element, proto: str, depth: int) -> list[str]:
        pad, name = INDENT * depth, holder.get("name")
        kind = self.protos.get(proto, {}).get(name)
        nodes = [child for child in holder if isinstance(child.tag, str)]
        if nodes or (kind or "").endswith("Node"):
            return self.nodes(
                f"{pad}{name}", nodes, depth, many=kind != "SFNode" and len(nodes) > 1
            )
        return [f"{pad}{name} {self.value(holder.get('value', ''), kind)}"]

    # -- values ------------------------------------------------------------------
    def value(self, text: str, kind: str | None) -> str:
        """An XML attribute value in ClassicVRML syntax for field type ``kind``."""
        if kind is None:
            kind = _guess(text)
        if kind in ("SFBool", "MFBool"):
            words = text.replace(",", " ").split()
            written = " ".join(word.upper() for word in words)
            return written if kind == "SFBool" else f"[ {written} ]"
        if kind == "SFString":
            return quote(text)
        if kind == "MFString":
            return "[ " + " ".join(quote(item) for item in parse_field(text, "MFString")) + " ]"
        if kind.startswith("MF"):
            return f"[ {text.strip()} ]"
        return text.strip() or '""'


def _faces(index: str) -> str:
    """IndexedTriangleSet ``index`` as IndexedFaceSet ``coordIndex`` (-1 after each triangle)."""
    values = index.replace(",", " ").split()
    triangles = [" ".join(values[start : start + 3]) for start in range(0, len(values), 3)]
    return " -1 ".join(triangles) + (" -1" if triangles else "")


def _connects(element: Element) -> _Connects:
    """A node's ``<IS><connect>`` pairs: node field -> prototype field."""
    return {
        connect.get("nodeField"): connect.get("protoField")
        for holder in element
        if local_name(holder) == "IS"
        for connect in holder
        if local_name(connect) == "connect"
    }


def _container(child: Element, child_tag: str) -> str:
    """The field a child node goes in: its containerField, or its kind's default."""
    if child_tag == "ProtoInstance":
        return child.get("containerField") or "children"
    default = CONTAINER_FIELDS.get(child_tag, "children")
    return child.get("containerField") or default


def _child(element: Element, tag: str) -> Element | None:
    return next((child for child in element if local_name(child) == tag), None)


def _guess(text: str) -> str:
    """A field type for a value whose field the schema does not know."""
    words = text.replace(",", " ").split()
    if words and all(word.lower() in ("true", "false") for word in words):
        return "SFBool" if len(words) == 1 else "MFBool"
    if text.lstrip().startswith('"'):
        return "MFString"
    if words and all(is_number(word) for word in words):
        return "SFFloat" if len(words) == 1 else "SFVec3f"  # written bare
    return "SFString"
