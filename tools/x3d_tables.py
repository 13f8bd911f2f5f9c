"""Regenerate ``shadowgeo/io/x3d/tables.py``: what the X3D readers and writers
know of X3D 4.0, from its two schemas, in one table.

- The X3D 4.0 XML Schema (``x3d-4.0.xsd``; a gzipped copy is committed as
  ``tests/data/x3d-schema/x3d-4.0.xsd.gz``) declares every field of every node
  and statement as an attribute with its X3D type and default, inherited
  through ``xs:extension`` from abstract types such as ``X3DLightNode``, and
  each node's default ``containerField`` (also inherited).
- The X3D JSON schema (``x3d-4.0-JSONSchema.json``) adds the node fields
  (``-children``: an SFNode object or an MFNode array) and the nodes of the
  extensions that the XML Schema leaves out. Where both type a field they
  agree; this tool stops if they ever do not.

The table: ``NODES[node] = (default containerField, "name:type ...")`` for every
node and statement, and ``DEFAULT_VALUES[node][field]`` for the nodes the
reader models (their defaults as the schema writes them). The npm package
x_ite's ``dist/X3DUOM.xml`` was meant to be the source, but the copy it ships is
only X_ITE's extension of the object model (45 nodes, none of Transform, Box or
the lights). Users need no schema: the table is committed.

Usage::

    python tools/x3d_tables.py [path/to/x3d-4.0.xsd [path/to/x3d-4.0-JSONSchema.json]]
"""

from __future__ import annotations

import collections
import json
import pprint
import subprocess
import sys
import textwrap
from pathlib import Path

from lxml import etree

ROOT = Path(__file__).resolve().parents[1]
SCHEMAS = ROOT.parent / "shared" / "schemas" / "x3d"
XML_SCHEMA = SCHEMAS / "x3d-4.0.xsd"
JSON_SCHEMA = SCHEMAS / "x3d-4.0-JSONSchema.json"
OUTPUT = ROOT / "shadowgeo" / "io" / "x3d" / "tables.py"
XS = "{http://www.w3.org/2001/XMLSchema}"

# The nodes the reader models: their fields' defaults go in the table.
MODELLED = [
    "Anchor", "Appearance", "Billboard", "Box", "CADAssembly", "CADFace", "CADLayer", "CADPart",
    "Collision", "Color", "ColorRGBA", "Cone",
    "Coordinate", "CoordinateDouble", "Cylinder", "DirectionalLight", "ElevationGrid", "Extrusion",
    "Group",
    "IndexedFaceSet", "IndexedQuadSet", "IndexedTriangleFanSet", "IndexedTriangleSet",
    "IndexedTriangleStripSet", "Inline", "LOD", "Material", "NavigationInfo", "PhysicalMaterial",
    "PointLight",
    "QuadSet", "Shape", "Sphere", "SpotLight", "StaticGroup", "Switch", "Transform",
    "TriangleFanSet", "TriangleSet", "TriangleStripSet", "TwoSidedMaterial", "UnlitMaterial",
    "Viewpoint",
]  # fmt: skip
# Nodes outside X3D 4.0 that real files use (Castle Game Engine, VRML 97):
# node -> (default containerField, {field: (type, default)}).
EXTRA = {
    "MatrixTransform": (
        "children",
        {
            "-children": ("MFNode", ""),
            "-metadata": ("SFNode", ""),
            "matrix": ("SFMatrix4f", "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1"),
        },
    ),
}
# Statements: elements of the schemas that are not nodes.
STATEMENTS = {"X3D", "head", "Scene", "component", "unit", "meta", "field", "fieldValue",
              "connect", "IS", "ProtoDeclare", "ProtoInterface", "ProtoBody",
              "ExternProtoDeclare", "ProtoInstance", "ROUTE", "IMPORT", "EXPORT"}  # fmt: skip
# XML attributes that are bookkeeping, not fields.
SKIP = {"DEF", "USE", "class", "id", "style", "containerField", "IS"}


def _simple_base(schema, name: str) -> str:
    """Follow named simpleType restrictions down to an X3D field type."""
    seen = set()
    while name and not name.startswith(("SF", "MF")) and name not in seen:
        seen.add(name)
        found = schema.find(f"{XS}simpleType[@name='{name}']")
        restriction = None if found is None else found.find(f"{XS}restriction")
        if restriction is None:
            return name
        name = restriction.get("base", "")
    return name


def _attribute_type(schema, attribute) -> str:
    if attribute.get("type"):
        return _simple_base(schema, attribute.get("type"))
    restriction = attribute.find(f"{XS}simpleType/{XS}restriction")
    return "" if restriction is None else _simple_base(schema, restriction.get("base", ""))


def _xml_fields(schema, complex_type) -> dict[str, tuple[str, str]]:
    """field -> (type, default) of ``complex_type`` and its bases (base first,
    so a redeclaration wins)."""
    out: dict[str, tuple[str, str]] = {}
    extension = complex_type.find(f"{XS}complexContent/{XS}extension")
    holders = [complex_type]
    if extension is not None:
        base = schema.find(f"{XS}complexType[@name='{extension.get('base')}']")
        if base is not None:
            out.update(_xml_fields(schema, base))
        holders.append(extension)
    for holder in holders:
        for attribute in holder.findall(f"{XS}attribute"):
            name = attribute.get("name")
            if name is None or name in SKIP:
                continue
            kind = _attribute_type(schema, attribute)
            if kind.startswith(("SF", "MF")):
                out[name] = (kind, attribute.get("default", ""))
    return out


def _container(types: dict, complex_type) -> str | None:
    """The default containerField declared by ``complex_type`` or a base."""
    for attribute in complex_type.iter(f"{XS}attribute"):
        if attribute.get("name") == "containerField" and attribute.get("default"):
            return str(attribute.get("default"))
    extension = complex_type.find(f"{XS}complexContent/{XS}extension")
    if extension is not None and extension.get("base") in types:
        return _container(types, types[extension.get("base")])
    return None


def xml_elements(xsd_path: Path) -> dict[str, tuple[str, dict[str, tuple[str, str]]]]:
    """element -> (default containerField, {field: (type, default)}) of the
    XML Schema, in the schema's order."""
    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False)
    schema = etree.parse(str(xsd_path), parser).getroot()
    types = {found.get("name"): found for found in schema.findall(f"{XS}complexType")}
    out = {}
    for element in schema.findall(f"{XS}element"):
        complex_type = element.find(f"{XS}complexType")
        if complex_type is not None:
            container = _container(types, complex_type) or "children"
            out[element.get("name")] = (container, _xml_fields(schema, complex_type))
    return out


def _properties(definition: dict) -> dict:
    if "oneOf" in definition:  # [USE form, full form]
        return definition["oneOf"][-1]["properties"]
    return definition.get("properties", {})


def _json_type(name: str, schema: dict) -> str | None:
    """The type of JSON property ``name`` (``@field`` or ``-field``), None for
    comments and statements."""
    if name.startswith("-"):
        reference = schema.get("$ref", "")
        return next((kind for kind in ("SFNode", "MFNode") if reference.endswith(kind)), None)
    if name == "@geoSystem":
        return "MFString"
    kind = schema.get("$comment", "").split(" ")[0]
    return kind if kind.startswith(("SF", "MF")) else "SFString"


def json_nodes(json_path: Path) -> dict[str, dict[str, str]]:
    """node -> {field: type} of the JSON schema (node fields as ``-name``)."""
    definitions = json.loads(json_path.read_text())["$defs"]
    out = {}
    for node, definition in sorted(definitions.items()):
        if node.startswith(("-", "@")) or node in STATEMENTS:
            continue
        fields = {}
        for name, schema in _properties(definition).items():
            if name in ("@DEF", "@USE") or not name.startswith(("@", "-")):
                continue
            kind = _json_type(name, schema)
            if kind is not None:
                fields[name.removeprefix("@")] = kind
        out[node] = fields
    return out


def _merged(elements: dict, from_json: dict) -> dict[str, tuple[str, dict[str, str]]]:
    """node -> (containerField, {field: type}) over both schemas, sorted;
    SystemExit where they type a field differently."""
    nodes: dict[str, tuple[str, dict[str, str]]] = {}
    for node in sorted(set(elements) | set(from_json)):
        container, xml = elements.get(node, ("children", {}))
        fields = {name: kind for name, (kind, _) in xml.items()}
        for name, kind in from_json.get(node, {}).items():
            if kind == "SFString":
                continue  # (JSON types what the XML Schema leaves untyped: enumerations)
            if fields.setdefault(name, kind) != kind:
                raise SystemExit(f"{node}.{name}: {fields[name]} in the XML Schema, {kind} in JSON")
        nodes[node] = (container, dict(sorted(fields.items())))
    for node, (container, extra) in EXTRA.items():
        nodes[node] = (container, {name: kind for name, (kind, _) in extra.items()})
    return dict(sorted(nodes.items()))


def _common_types(elements: dict) -> dict[str, str]:
    """The type a field name has in most elements (for a node the table
    lacks): counted over the XML Schema's elements in its order, as ties fall."""
    votes: dict[str, collections.Counter[str]] = collections.defaultdict(collections.Counter)
    for _, fields in [*elements.values(), *EXTRA.values()]:
        for name, (kind, _) in fields.items():
            if name[0] != "-":
                votes[name][kind] += 1
    return {name: counter.most_common(1)[0][0] for name, counter in sorted(votes.items())}


def tables(xsd_path: Path, json_path: Path):
    """(nodes, default values, common field types): ``nodes[node] =
    (containerField, {field: type})`` over both schemas, sorted."""
    elements = xml_elements(xsd_path)
    nodes = _merged(elements, json_nodes(json_path))
    values = {
        node: {name: default for name, (_, default) in sorted(elements[node][1].items())}
        for node in MODELLED
    }
    for node, (_, fields) in EXTRA.items():
        values[node] = {name: value for name, (_, value) in fields.items() if name[0] != "-"}
    return nodes, dict(sorted(values.items())), _common_types(elements)


def _node_lines(nodes: dict[str, tuple[str, dict[str, str]]]) -> str:
    lines = []
    for node, (container, fields) in nodes.items():
        text = " ".join(f"{name}:{kind}" for name, kind in fields.items())
        pieces = textwrap.wrap(text, 84, break_long_words=False) or [""]
        body = "\n".join(f'        "{piece} "' for piece in pieces[:-1])
        body += ("\n" if body else "") + f'        "{pieces[-1]}"'
        lines.append(f'    "{node}": (\n        "{container}",\n{body},\n    ),')
    return "NODES = {\n" + "\n".join(lines) + "\n}\n"


HEADER = '''"""What the X3D readers and writers know of X3D 4.0, in one table.

Generated by ``tools/x3d_tables.py`` from the X3D 4.0 XML Schema and the X3D
JSON schema; do not edit.

``NODES[node] = (default containerField, fields)`` for every node and
statement (:data:`STATEMENTS`), ``fields`` a space-separated list of
``name:type``, node fields as ``-name:SFNode`` / ``-name:MFNode``.
``DEFAULT_VALUES[node][field]`` is a field's default as the schema writes it,
for the nodes the reader models; ``FIELD_TYPES[field]`` the type a field name
has in most nodes (for a node the schemas do not know). Derived here, for
the readers and writers: :data:`FIELDS`, :data:`CONTAINER_FIELDS`,
:data:`DEFAULTS` and :func:`field_type`.
"""

from __future__ import annotations

__all__ = [
    "CONTAINER_FIELDS",
    "DEFAULTS",
    "DEFAULT_VALUES",
    "FIELDS",
    "FIELD_TYPES",
    "NODES",
    "STATEMENTS",
    "field_type",
]

'''

FOOTER = '''
# node -> (default containerField, {field: type}).
FIELDS: dict[str, tuple[str, dict[str, str]]] = {
    node: (container, dict(item.split(":") for item in fields.split()))
    for node, (container, fields) in NODES.items()
}
# node -> default containerField, where it is not "children".
CONTAINER_FIELDS = {node: entry[0] for node, entry in FIELDS.items() if entry[0] != "children"}
# node -> {field: (type, default as the schema writes it)}, for the modelled nodes.
DEFAULTS = {
    node: {field: (FIELDS[node][1][field], value) for field, value in values.items()}
    for node, values in DEFAULT_VALUES.items()
}


def field_type(node: str, field: str) -> str | None:
    """The X3D type (``"SFVec3f"``, ...) of ``node``'s non-node field ``field``,
    or None when the schemas do not know it."""
    kind = FIELDS[node][1].get(field) if node in FIELDS else None
    return kind or FIELD_TYPES.get(field)
'''


def main(argv: list[str]) -> None:
    xsd_path = Path(argv[1]) if len(argv) > 1 else XML_SCHEMA
    json_path = Path(argv[2]) if len(argv) > 2 else JSON_SCHEMA
    nodes, values, common = tables(xsd_path, json_path)
    statements = pprint.pformat(sorted(STATEMENTS), width=100, compact=True)
    OUTPUT.write_text(
        HEADER
        + _node_lines(nodes)
        + f"\nSTATEMENTS = frozenset({statements})\n"
        + f"\nDEFAULT_VALUES = {pprint.pformat(values, width=100, sort_dicts=False)}\n"
        + f"\nFIELD_TYPES = {pprint.pformat(common, width=100, compact=True)}\n"
        + FOOTER
    )
    subprocess.run([sys.executable, "-m", "ruff", "format", str(OUTPUT)], check=False)
    print(f"wrote {OUTPUT}")


if __name__ == "__main__":
    main(sys.argv)
