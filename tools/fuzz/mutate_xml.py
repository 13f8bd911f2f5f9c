"""X3D XML mutants: elements dropped, duplicated, reordered, moved or
renamed, attributes dropped or repeated (structure); a numeric field of a
node the reader models set to a hostile value, or such a node added
(meaning)."""

from __future__ import annotations

import random
from copy import deepcopy

from shadowgeo.io.x3d.tables import DEFAULTS as X3D_FIELDS

from .inputs import NODE_NAMES, SPECIAL_FLOATS, SPECIAL_INTS

# Arity of the numeric X3D field types (MF types repeat it).
_ARITY = {"Float": 1, "Double": 1, "Time": 1, "Int32": 1, "Vec2f": 2, "Vec3f": 3, "Vec3d": 3}
_ARITY.update({"Rotation": 4, "Color": 3, "ColorRGBA": 4, "Vec4f": 4, "Vec2d": 2})
_GEOMETRY_NODES = ("Box", "Sphere", "Cone", "Cylinder", "IndexedFaceSet", "IndexedTriangleSet")
_GEOMETRY_NODES += ("TriangleSet", "Extrusion", "ElevationGrid", "IndexedQuadSet", "QuadSet")


def field_value(kind: str, rng: random.Random) -> str:
    """A hostile value for an X3D field of type ``kind`` (``SFVec3f``, ``MFInt32``, ...)."""
    if kind.endswith("Bool"):
        return rng.choice(("true", "false", "TRUE", "1", "", "maybe"))
    arity = _ARITY.get(kind[2:], 1)
    ordinary = ["0", "1", "-1", "0.5", "2", "3", "-2.5", "10"]
    special = SPECIAL_INTS if kind.endswith("Int32") else SPECIAL_FLOATS
    if kind.startswith("MF"):
        count = rng.choice((0, 1, 2, 3, 4, 8, 12, 1000, 20000)) * arity
    else:
        count = rng.choice((arity, arity, arity, arity - 1, arity + 1, 0))
    values = [rng.choice(ordinary) for _ in range(max(count, 0))]
    for _ in range(rng.randint(0, 2) if values else 0):
        values[rng.randrange(len(values))] = rng.choice(special)
    if kind.endswith("Int32") and kind.startswith("MF") and rng.random() < 0.5:
        values = [rng.choice(("0", "1", "2", "3", "-1", "-2", "7", "2147483647")) for _ in values]
    return " ".join(values)


def mutate_x3d_fields(data: bytes, rng: random.Random, add: bool) -> bytes | None:
    """Set a numeric field of a node the reader models to a hostile value, or
    add such a node (a light, a transform, a shape with geometry) to the scene."""
    from lxml import etree

    parser = etree.XMLParser(resolve_entities=False, no_network=True, huge_tree=True)
    try:
        tree = etree.fromstring(data, parser).getroottree()
    except etree.XMLSyntaxError:
        return None
    scene = tree.getroot().find(".//Scene")
    modelled = [e for e in tree.iter() if isinstance(e.tag, str) and e.tag in X3D_FIELDS]
    if add or not modelled:
        if scene is None:
            return None
        preferred = [t for t in X3D_FIELDS if "Light" in t or t in _GEOMETRY_NODES]
        tag = rng.choice(preferred + ["Transform"] if rng.random() < 0.7 else sorted(X3D_FIELDS))
        element = etree.Element(tag)
        host = rng.choice([scene, *[e for e in scene.iter() if e.tag in ("Transform", "Group")]])
        if tag in _GEOMETRY_NODES or "solid" in X3D_FIELDS[tag]:
            shape = etree.SubElement(host, "Shape")
            shape.append(element)
            if tag.startswith(("Indexed", "Triangle", "Quad")):
                points = field_value("MFVec3f", rng) or "0 0 0 1 0 0 0 1 0"
                etree.SubElement(element, "Coordinate", point=points)
                element.set("coordIndex", field_value("MFInt32", rng))
        else:
            host.append(element)
        if "Light" in tag:
            element.set("shadows", "true")
        modelled = [element]
    element = rng.choice(modelled)
    fields = [
        (name, kind)
        for name, (kind, _) in X3D_FIELDS[element.tag].items()
        if kind[2:] in _ARITY or kind.endswith("Bool")
    ]
    for name, kind in rng.sample(fields, min(len(fields), rng.randint(1, 3))):
        element.set(name, field_value(kind, rng))
    return etree.tostring(tree)


def mutate_xml(data: bytes, rng: random.Random):
    from lxml import etree

    parser = etree.XMLParser(resolve_entities=False, no_network=True, huge_tree=True)
    try:
        tree = etree.fromstring(data, parser).getroottree()
    except etree.XMLSyntaxError:
        return None
    elements = [e for e in tree.iter() if isinstance(e.tag, str)]
    if len(elements) < 2:
        return None
    element = rng.choice(elements[1:])
    parent = element.getparent()
    kind = rng.choice(
        ("drop", "duplicate", "reorder", "drop-attr", "swap-name", "move", "dup-attr")
    )
    if kind == "drop":
        parent.remove(element)
    elif kind == "duplicate":
        parent.insert(parent.index(element), deepcopy(element))
    elif kind == "reorder":
        children = list(parent)
        rng.shuffle(children)
        for child in children:
            parent.remove(child)
            parent.append(child)
    elif kind == "drop-attr" and element.attrib:
        del element.attrib[rng.choice(sorted(element.attrib))]
    elif kind == "swap-name":
        names = sorted({e.tag for e in elements if isinstance(e.tag, str)} | set(NODE_NAMES))
        element.tag = rng.choice(names)
    elif kind == "move":
        target = rng.choice(elements)
        if element not in target.iterancestors() and target is not element:
            parent.remove(element)
            target.append(element)
    elif kind == "dup-attr" and element.attrib:
        # Duplicate attributes are an XML error, so this one is textual.
        name = rng.choice(sorted(element.attrib))
        text = etree.tostring(tree)
        marker = f'{name}="'.encode()
        spot = text.find(marker)
        if spot >= 0:
            return text[:spot] + marker + b'0" ' + text[spot:], "structure:dup-attr"
    return etree.tostring(tree), f"structure:{kind}"
