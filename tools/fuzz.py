"""Fuzzing campaign for shadowgeo: mutated real scenes through the converter, and
random geometry through the core API.

Converter mode mutates real scenes (``../shared/corpus/**``, ``examples/scenes``;
glTF, glb, USD and x3dz seeds are made from the X3D ones with shadowgeo's own
writers) at three levels:

* bytes: bit flips, truncation, splices of two seeds, repeated or deleted
  chunks, inserted bytes;
* structure: elements, attributes, JSON keys or brace blocks dropped,
  duplicated, reordered or renamed to another node type;
* meaning: numbers turned into 0, -0, 1e308, 1e-320, nan, inf, huge counts or
  negative indices, fields emptied, deep nesting, DEF/USE cycles.

Each mutant runs through ``cli.main.main(argv)`` in a forked worker with a time
budget (a CPU-time alarm, so that other work on a shared machine does not
count; then a kill by wall clock at four times the budget) and an
address-space limit, so a hang or a blow-up is recorded, not fatal. A run
fails when it raises anything but ``SystemExit`` 1/2, returns a code outside
{0, 1, 2}, leaves an output (or a temporary file) after failing, writes no
output after succeeding, modifies its input, writes NaN or inf, or exceeds
the time or memory budget; with ``--sun`` and ``--plane`` the shadow area
must also match the textbook one (shapely union of the projected
triangles). Geometry mode (``--geometry N``) sends random casters, planes
and lights through ``project_shadow``, ``silhouette`` and ``shadow_volume``.

Failures are grouped by signature (exception type and innermost shadowgeo
frame, or the check that failed), each group's first input is shrunk by delta
debugging, and everything goes to ``--out``: ``summary.md``, ``results.jsonl``
and one folder per signature with the original and the smallest input.

Usage::

    python tools/fuzz.py --inputs 2000 --seed 1 --out /tmp/fuzz --jobs 2
    python tools/fuzz.py --inputs 0 --geometry 5000 --seed 1 --out /tmp/fuzz-geo

Exit status 1 when any run failed. ``kill -USR1`` the campaign to stop starting
runs early and go on to shrinking and the summary.
"""

from __future__ import annotations

import argparse
import contextlib
import gzip
import hashlib
import io
import json
import math
import os
import random
import re
import resource
import shutil
import signal
import struct
import sys
import tempfile
import time
import traceback
import warnings
import zlib
from collections import Counter, defaultdict
from copy import deepcopy
from dataclasses import dataclass, field
from multiprocessing import get_context
from multiprocessing.connection import wait
from pathlib import Path

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
import shapely  # noqa: E402
import trimesh  # noqa: E402

import shadowgeo  # noqa: E402
from cli.main import main as cli_main  # noqa: E402
from shadowgeo.io.x3d_defaults import DEFAULTS as X3D_FIELDS  # noqa: E402

SHARED = ROOT.parent / "shared"
EXAMPLES = ROOT / "examples" / "scenes"
KNOWN = SHARED / "findings" / "robustness"

# Encoding name -> the suffix its mutants get; every one is tried, whether the
# reader knows it or not (an exit 1 "cannot read" is a correct, clear error).
ENCODINGS = {
    "x3d": ".x3d",
    "x3dz": ".x3dz",
    "x3dv": ".x3dv",
    "wrl": ".wrl",
    "json": ".json",
    "x3dj": ".x3dj",
    "glb": ".glb",
    "gltf": ".gltf",
    "usda": ".usda",
    "usdc": ".usdc",
    "obj": ".obj",
    "stl": ".stl",
    "ply": ".ply",
    "off": ".off",
}
# Seeds written from the X3D seeds: by shadowgeo, or (meshes that shadowgeo
# reads but does not write) by trimesh.
WRITTEN = ("glb", "gltf", "usda", "usdc", "obj", "stl", "ply", "off")
MESH_SUFFIXES = (".obj", ".stl", ".ply", ".off")
TEXT_ENCODINGS = {"x3d", "x3dv", "wrl", "json", "x3dj", "gltf", "usda"}
XML_ENCODINGS = {"x3d"}
JSON_ENCODINGS = {"json", "x3dj", "gltf"}

SUN = "0.3,-1,0.2"
GROUND = "0,1,0,0"
# Command lines a mutant runs with; IN and OUT are filled in. The one with
# --sun and --plane also gets the independent shadow-area check.
TEMPLATES = [
    ("convert", "IN", "OUT.x3d"),
    ("convert", "IN", "OUT.glb", "--sun", SUN, "--plane", GROUND),
    ("convert", "IN", "OUT.usda", "--sun", "0.2,-1,-0.1"),
    ("convert", "IN", "OUT.x3d", "--method", "volume", "--sun", SUN),
    ("info", "IN"),
    ("convert", "IN", "OUT.gltf"),
    ("convert", "IN", "OUT.x3dz", "--sun=-0.5,-1,0.3", "--method", "planar"),
]
REFERENCE_TEMPLATE = 1

SPECIAL_FLOATS = ["0", "-0", "1e308", "-1e308", "1e-320", "nan", "inf", "-inf", "1e155", "3e38"]
SPECIAL_INTS = ["2147483647", "-1", "-2", "-2147483648", "999999999", "4294967296", "-1000"]
NODE_NAMES = (
    "Transform Group Shape Box Sphere Cone Cylinder IndexedFaceSet IndexedTriangleSet "
    "TriangleSet Coordinate Extrusion ElevationGrid PointLight SpotLight DirectionalLight "
    "Inline Switch LOD Billboard Collision Appearance Material Viewpoint ProtoInstance "
    "ProtoDeclare ExternProtoDeclare IndexedLineSet Text Anchor StaticGroup Scene X3D "
    "fieldValue field IS connect ROUTE MetadataFloat TextureTransform"
).split()
NUMBER = re.compile(rb"(?<![\w.#])[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?(?![\w.])")
TOKEN = re.compile(rb'"(?:[^"\\\n]|\\.)*"|#[^\n]*|[A-Za-z_][\w.:-]*|[-+.\d][\w.+-]*|\S')
MAX_MUTANT = 4 << 20


# ---------------------------------------------------------------------------------------------
# Seeds
# ---------------------------------------------------------------------------------------------


def collect_seeds(pool: Pool, max_bytes: int, encodings=ENCODINGS) -> dict[str, list]:
    """Seed files per encoding: (name, content). Missing folders are skipped.
    glb, glTF, USD and mesh (OBJ, STL, PLY, OFF) seeds are the X3D ones written by
    shadowgeo (meshes by trimesh), in a worker
    (the parent never starts USD's threads, so forking stays safe)."""
    seeds: dict[str, list[tuple[str, bytes]]] = defaultdict(list)
    roots = [p for p in (SHARED / "corpus", EXAMPLES) if p.is_dir()]
    for root in roots:
        for path in sorted(root.rglob("*")):
            suffix = path.suffix.lower().lstrip(".")
            if path.is_file() and suffix in ENCODINGS and path.stat().st_size <= max_bytes:
                seeds[suffix].append((str(path), path.read_bytes()))
    for name, data in seeds["x3d"]:
        seeds["x3dz"].append((name + ".gz", gzip.compress(data, mtime=0)))
    for name, data in seeds["json"]:
        seeds["x3dj"].append((name, data))
    tasks = [
        {"kind": "seed", "path": name, "suffix": ENCODINGS[encoding], "encoding": encoding}
        for name, _ in seeds["x3d"]
        for encoding in WRITTEN
        if encoding in encodings
    ]
    for task, result in pool.run(tasks):
        if result.get("data"):
            seeds[task["encoding"]].append((f"{task['path']} as {task['suffix']}", result["data"]))
    for encoding in WRITTEN:  # made in completion order: sort, to replay
        seeds[encoding] = sorted(seeds[encoding])
    return dict(seeds)


def run_seed(task: dict, scratch: Path) -> dict:
    """An X3D seed written in another format: its bytes when it loads, has
    shapes and fits in one file (an external .bin would not be mutated)."""
    folder = scratch / "run"
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir()
    target = folder / f"seed{task['suffix']}"
    try:
        scene = shadowgeo.load(task["path"])
        if scene.shapes and task["suffix"] in MESH_SUFFIXES:
            import trimesh

            meshes = [
                trimesh.Trimesh(shape.world_vertices, shape.faces, process=False)
                for shape in scene.shapes
                if len(shape.faces)
            ]
            trimesh.util.concatenate(meshes).export(target)
        elif scene.shapes:
            shadowgeo.save(scene, target)
    except (shadowgeo.SceneError, shadowgeo.GeometryError, OSError):
        pass
    files = list(folder.iterdir())
    data = target.read_bytes() if files == [target] else None
    return {"ok": True, "signature": None, "detail": "", "data": data}


# ---------------------------------------------------------------------------------------------
# Mutations
# ---------------------------------------------------------------------------------------------


def mutate(data: bytes, encoding: str, rng: random.Random, others: list[bytes]):
    """One mutant of ``data``: (bytes, list of the operations applied)."""
    if encoding == "x3dz" and rng.random() < 0.85:
        inner, ops = mutate(_gunzip(data), "x3d", rng, [_gunzip(o) for o in others[:3]])
        return gzip.compress(inner, mtime=0), ["gunzip", *ops]
    if encoding == "glb" and rng.random() < 0.7:
        return mutate_glb(data, rng)
    ops = []
    for _ in range(rng.choice((1, 1, 1, 2, 3))):
        level = rng.choices(("bytes", "structure", "meaning"), (3, 3, 4))[0]
        if level == "bytes" or encoding not in TEXT_ENCODINGS:
            data, op = mutate_bytes(data, rng, others)
        elif level == "structure":
            data, op = mutate_structure(data, encoding, rng)
        else:
            data, op = mutate_meaning(data, encoding, rng)
        ops.append(op)
    return data[:MAX_MUTANT], ops


def _gunzip(data: bytes) -> bytes:
    try:
        return gzip.decompress(data)
    except (OSError, EOFError, ValueError, zlib.error):
        return data


def mutate_bytes(data: bytes, rng: random.Random, others: list[bytes]):
    size = max(len(data), 1)
    at = rng.randrange(size)
    kind = rng.choice(("flip", "set", "truncate", "splice", "repeat", "delete", "insert"))
    if kind == "flip":
        buffer = bytearray(data)
        for _ in range(rng.randint(1, 8)):
            if buffer:
                buffer[rng.randrange(len(buffer))] ^= 1 << rng.randrange(8)
        return bytes(buffer), "bytes:flip"
    if kind == "set":
        buffer = bytearray(data)
        if buffer:
            buffer[at % len(buffer)] = rng.choice((0, 0xFF, 0x7F, 0x80, ord("<"), ord("{")))
        return bytes(buffer), "bytes:set"
    if kind == "truncate":
        return data[:at], f"bytes:truncate@{at}"
    if kind == "splice" and others:
        other = rng.choice(others)
        return data[:at] + other[rng.randrange(max(len(other), 1)) :], "bytes:splice"
    if kind == "repeat":
        chunk = data[at : at + rng.randint(1, 200)]
        return data[:at] + chunk * rng.randint(2, 60) + data[at:], "bytes:repeat"
    if kind == "delete":
        return data[:at] + data[at + rng.randint(1, 400) :], "bytes:delete"
    junk = rng.choice(
        (b"<", b"&", b"\x00", b"\xff\xfe", b"]]>", b"{", b'"', b"&#0;", b"\xc3", b"[", b"}")
    )
    return data[:at] + junk * rng.randint(1, 4) + data[at:], "bytes:insert"


def mutate_meaning(data: bytes, encoding: str, rng: random.Random):
    kinds = ["number", "number", "field", "count", "empty", "nest", "cycle"]
    if encoding in XML_ENCODINGS:
        kinds += ["set-field", "set-field", "add-node", "add-node"]
    kind = rng.choice(kinds)
    if kind in ("set-field", "add-node"):
        mutated = mutate_x3d_fields(data, rng, add=kind == "add-node")
        if mutated is not None:
            return mutated, f"meaning:{kind}"
        kind = "number"
    if kind == "nest":
        return deep_nesting(data, encoding, rng), "meaning:deep-nesting"
    if kind == "cycle":
        return def_use_cycle(data, encoding, rng), "meaning:def-use-cycle"
    if kind == "empty":
        return empty_field(data, encoding, rng), "meaning:empty-field"
    numbers = list(NUMBER.finditer(data))
    if not numbers:
        return mutate_bytes(data, rng, [])
    if kind == "number":
        match = rng.choice(numbers)
        is_int = re.fullmatch(rb"[-+]?\d+", match.group()) is not None
        value = rng.choice(SPECIAL_INTS if is_int and rng.random() < 0.6 else SPECIAL_FLOATS)
        return data[: match.start()] + value.encode() + data[match.end() :], f"meaning:{value}"
    if kind == "field":  # every number of one run (a field's values) becomes the same special
        first = rng.randrange(len(numbers))
        value = rng.choice(SPECIAL_FLOATS + SPECIAL_INTS).encode()
        run = [numbers[first]]
        for match in numbers[first + 1 :]:
            if re.fullmatch(rb"[\s,]*", data[run[-1].end() : match.start()]) is None:
                break
            run.append(match)
        # one join, not one copy of the whole file per number: after a count
        # mutation a run can hold a million numbers
        pieces, done = [], 0
        for match in run:
            pieces += [data[done : match.start()], value]
            done = match.end()
        return b"".join([*pieces, data[done:]]), f"meaning:field={value.decode()}"
    # count: a run of numbers repeated many times (a huge index or point list)
    match = rng.choice(numbers)
    end = min(len(data), match.end() + rng.randint(10, 400))
    stop = max((m.end() for m in numbers if match.start() <= m.end() <= end), default=match.end())
    chunk = data[match.start() : stop] + b" "
    times = rng.choice((100, 1000, 10000))
    if len(chunk) * times > MAX_MUTANT:
        times = max(2, MAX_MUTANT // max(len(chunk), 1))
    return data[:stop] + b" " + chunk * times + data[stop:], f"meaning:count*{times}"


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


def empty_field(data: bytes, encoding: str, rng: random.Random) -> bytes:
    if encoding in XML_ENCODINGS:
        spans = list(re.finditer(rb'(\w+)=("[^"]*"|\'[^\']*\')', data))
        if spans:
            match = rng.choice(spans)
            return data[: match.start(2)] + b'""' + data[match.end(2) :]
    spans = list(re.finditer(rb"\[[^\[\]]*\]", data))
    if spans:
        match = rng.choice(spans)
        return data[: match.start()] + b"[]" + data[match.end() :]
    return data


def deep_nesting(data: bytes, encoding: str, rng: random.Random) -> bytes:
    depth = rng.choice((50, 500, 5000))
    if encoding in XML_ENCODINGS:
        match = re.search(rb"<Scene[^>]*>", data)
        if match:
            head, tail = b"<Transform>" * depth, b"</Transform>" * depth
            close = data.rfind(b"</Scene>")
            if close > match.end():
                inner = data[match.end() : close]
                return data[: match.end()] + head + inner + tail + data[close:]
    if encoding in JSON_ENCODINGS:
        try:
            document = json.loads(data)
        except (ValueError, UnicodeDecodeError):
            return data
        nested = document
        for _ in range(min(depth, 250)):  # json.dumps recurses
            nested = {"Transform": {"-children": [nested]}} if encoding != "gltf" else [nested]
        return json.dumps({"X3D": nested} if encoding != "gltf" else nested).encode()
    if encoding == "usda":
        head, tail = b'def Xform "n" {\n' * depth, b"}\n" * depth
        return data + b"\n" + head + tail
    return (
        data
        + b"\n"
        + b"Group { children [ " * depth
        + b"Shape { geometry Box {} } "
        + (b"] } " * depth)
    )


def def_use_cycle(data: bytes, encoding: str, rng: random.Random) -> bytes:
    if encoding in XML_ENCODINGS:
        defs = list(re.finditer(rb'<(\w+)([^>]*?)DEF=(["\'])([^"\']*)\3([^>]*?)(?<!/)>', data))
        if defs:
            match = rng.choice(defs)
            name = match.group(4)
            return data[: match.end()] + b'<Group USE="' + name + b'"/>' + data[match.end() :]
        match = re.search(rb"<(Transform|Group)(\s[^>]*)?(?<!/)>", data)
        if match:
            insert = b' DEF="cyc"'
            at = match.start() + 1 + len(match.group(1))
            body = data[:at] + insert + data[at : match.end()] + b'<Transform USE="cyc"/>'
            return body + data[match.end() :]
        return data
    if encoding in JSON_ENCODINGS:
        text = data.decode("utf-8", "replace")
        match = re.search(r'"@DEF"\s*:\s*"([^"]*)"', text)
        name = match.group(1) if match else "cyc"
        spot = text.find('"-children"')
        if spot < 0:
            return data
        bracket = text.find("[", spot)
        use = '{"Group": {"@USE": "' + name + '"}},'
        if not match:
            use = '{"Transform": {"@DEF": "cyc", "-children": [{"Group": {"@USE": "cyc"}}]}},'
        return (text[: bracket + 1] + use + text[bracket + 1 :]).encode()
    if encoding == "usda":
        return data + b'\nover "cyc" (references = </cyc>) {}\n'
    defs = list(re.finditer(rb"DEF\s+([\w-]+)\s+(\w+)\s*\{", data))
    if defs:
        match = rng.choice(defs)
        children = data.find(b"children", match.end())
        bracket = data.find(b"[", children) if children >= 0 else -1
        if bracket >= 0:
            return data[: bracket + 1] + b" USE " + match.group(1) + b" " + data[bracket + 1 :]
    return data + b"\nDEF cyc Group { children [ USE cyc ] }\n"


def mutate_structure(data: bytes, encoding: str, rng: random.Random):
    if encoding in XML_ENCODINGS:
        mutated = mutate_xml(data, rng)
        if mutated is not None:
            return mutated
    if encoding in JSON_ENCODINGS:
        mutated = mutate_json(data, rng)
        if mutated is not None:
            return mutated
    return mutate_tokens(data, rng)


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


def mutate_json(data: bytes, rng: random.Random):
    try:
        document = json.loads(data)
    except (ValueError, UnicodeDecodeError, RecursionError):
        return None
    containers = []

    def walk(value, depth=0):
        if depth > 200:
            return
        if isinstance(value, dict | list) and value:
            containers.append(value)
            for item in value.values() if isinstance(value, dict) else value:
                walk(item, depth + 1)

    walk(document)
    if not containers:
        return None
    node = rng.choice(containers)
    kind = rng.choice(("drop", "duplicate", "reorder", "retype", "rename"))
    keys = list(node) if isinstance(node, dict) else list(range(len(node)))
    key = rng.choice(keys)
    if kind == "drop":
        del node[key]
    elif kind == "duplicate" and isinstance(node, list):
        node.insert(key, json.loads(json.dumps(node[key])))
    elif kind == "reorder" and isinstance(node, list):
        rng.shuffle(node)
    elif kind == "retype":
        node[key] = rng.choice(([], {}, "", 0, -1, None, True, "x", [0, 0], {"@USE": "x"}))
    elif kind == "rename" and isinstance(node, dict):
        names = [n for n in NODE_NAMES] + ["@DEF", "@USE", "-children", "@point", "@coordIndex"]
        node[rng.choice(names)] = node.pop(key)
    else:
        return None
    return json.dumps(document).encode(), f"structure:json-{kind}"


def mutate_tokens(data: bytes, rng: random.Random):
    tokens = list(TOKEN.finditer(data))
    if not tokens:
        return mutate_bytes(data, rng, [])
    kind = rng.choice(("drop", "duplicate", "swap", "swap-name", "drop-block", "dup-block"))
    token = rng.choice(tokens)
    start, end = token.span()
    if kind == "drop":
        return data[:start] + data[end:], "structure:token-drop"
    if kind == "duplicate":
        return data[:end] + b" " + token.group() + data[end:], "structure:token-dup"
    if kind == "swap":
        other = rng.choice(tokens)
        (a, b), (c, d) = sorted([token.span(), other.span()])
        if b <= c:
            return data[:a] + data[c:d] + data[b:c] + data[a:b] + data[d:], "structure:token-swap"
    if kind == "swap-name":
        names = [t for t in tokens if t.group()[:1].isupper()]
        if names:
            name = rng.choice(names)
            new = rng.choice(NODE_NAMES + [n.group().decode("latin-1") for n in names])
            return (
                data[: name.start()] + new.encode("latin-1") + data[name.end() :],
                "structure:swap-name",
            )
    block = _brace_block(data, rng)
    if block is not None:
        a, b = block
        if kind == "dup-block":
            return data[:b] + b"\n" + data[a:b] + data[b:], "structure:block-dup"
        return data[:a] + data[b:], "structure:block-drop"
    return data[:start] + data[end:], "structure:token-drop"


def _brace_block(data: bytes, rng: random.Random):
    """(start, end) of a random ``Name { ... }`` block, braces balanced."""
    opens = [m.start() for m in re.finditer(rb"\{", data)]
    if not opens:
        return None
    at = rng.choice(opens)
    depth = 0
    for index in range(at, len(data)):
        if data[index] == ord("{"):
            depth += 1
        elif data[index] == ord("}"):
            depth -= 1
            if depth == 0:
                name = re.search(rb"[\w\"]+\s*$", data[max(0, at - 80) : at])
                start = at - (len(name.group()) if name else 0)
                return start, index + 1
    return None


def split_glb(data: bytes):
    """(json text, binary chunk) of a glb, or None."""
    if len(data) < 20 or data[:4] != b"glTF":
        return None
    length, kind = struct.unpack_from("<I4s", data, 12)
    if kind != b"JSON":
        return None
    text = data[20 : 20 + length]
    rest = data[20 + length :]
    binary = b""
    if len(rest) >= 8:
        size = struct.unpack_from("<I", rest, 0)[0]
        binary = rest[8 : 8 + size]
    return text, binary


def join_glb(text: bytes, binary: bytes) -> bytes:
    text = text + b" " * (-len(text) % 4)
    binary = binary + b"\0" * (-len(binary) % 4)
    chunks = struct.pack("<I4s", len(text), b"JSON") + text
    if binary:
        chunks += struct.pack("<I4s", len(binary), b"BIN\0") + binary
    return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks


def mutate_glb(data: bytes, rng: random.Random):
    """Mutate the JSON chunk as text, or poke special values into the binary
    chunk, and repack with correct lengths so the container still parses."""
    parts = split_glb(data)
    if parts is None:
        return mutate_bytes(data, rng, [])
    text, binary = parts
    if binary and rng.random() < 0.4:
        buffer = bytearray(binary)
        for _ in range(rng.randint(1, 6)):
            at = rng.randrange(0, max(len(buffer) - 4, 1)) & ~3
            value = rng.choice(
                (float("nan"), float("inf"), 3.4e38, 1e-45, -0.0, 0.0, 2**31 - 1, 0xFFFFFFFF)
            )
            packed = (
                struct.pack("<I", value) if isinstance(value, int) else struct.pack("<f", value)
            )
            buffer[at : at + 4] = packed
        return join_glb(text, bytes(buffer)), ["glb:bin-special"]
    if rng.random() < 0.5:
        text, op = mutate_meaning(text, "gltf", rng)
    else:
        text, op = mutate_structure(text, "gltf", rng)
    return join_glb(text, binary), ["glb:json", op]


# ---------------------------------------------------------------------------------------------
# Worker: one run, in a forked process with limits
# ---------------------------------------------------------------------------------------------


class BudgetExceeded(BaseException):
    """Raised by the alarm in a worker when a run exceeds its CPU-time budget."""


def _alarm(signum, frame):
    raise BudgetExceeded()


def signature_of(error: BaseException) -> str:
    """Exception type and the innermost frame inside shadowgeo or cli."""
    frames = traceback.extract_tb(error.__traceback__)
    where = "outside shadowgeo"
    for frame in reversed(frames):
        path = Path(frame.filename)
        for package in ("shadowgeo", "cli"):
            if package in path.parts and str(ROOT) in str(path):
                where = f"{path.relative_to(ROOT)}:{frame.name}"
                break
        else:
            continue
        break
    name = "timeout" if isinstance(error, BudgetExceeded) else type(error).__name__
    if isinstance(error, MemoryError):
        name = "memory budget (MemoryError)"
    return f"{name} @ {where}"


def worker_main(connection, memory_bytes: int, time_budget: float) -> None:
    """Serve runs from ``connection`` until it sends None."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.dup2(devnull, 2)
    signal.signal(signal.SIGPROF, _alarm)
    scratch = Path(tempfile.mkdtemp(prefix="shadowgeo-fuzz-"))
    try:
        while True:
            task = connection.recv()
            if task is None:
                break
            if memory_bytes:  # the budget is per run, on top of what the process holds now
                limit = _vm_size() + memory_bytes
                resource.setrlimit(resource.RLIMIT_AS, (limit, resource.RLIM_INFINITY))
            started, cpu_started = time.perf_counter(), time.process_time()
            children_started = _children_cpu_seconds()
            signal.setitimer(signal.ITIMER_PROF, time_budget)  # CPU seconds
            try:
                if task["kind"] == "geometry":
                    result = run_geometry(task["case"])
                elif task["kind"] == "seed":
                    result = run_seed(task, scratch)
                elif task["kind"] == "script":
                    result = run_script(task["source"])
                else:
                    result = run_converter(task, scratch)
            except BudgetExceeded as error:
                result = failure(signature_of(error), traceback.format_exc(limit=-8))
            except MemoryError as error:
                result = failure(signature_of(error), traceback.format_exc(limit=-8))
            finally:
                signal.setitimer(signal.ITIMER_PROF, 0)
            result["seconds"] = time.perf_counter() - started
            # The alarm counts this process only; CPU spent by child processes
            # the run started and waited for (the USD text check) counts too.
            children = _children_cpu_seconds() - children_started
            result["cpu_seconds"] = time.process_time() - cpu_started + children
            if result["ok"] and result["cpu_seconds"] > time_budget:
                result = {
                    **failure(
                        "timeout (CPU with child processes)",
                        f"{result['cpu_seconds']:.1f} CPU-s, {children:.1f} of them in children",
                    ),
                    "seconds": result["seconds"],
                    "cpu_seconds": result["cpu_seconds"],
                }
            shutil.rmtree(scratch / "run", ignore_errors=True)
            connection.send(result)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def _children_cpu_seconds() -> float:
    """User and system CPU seconds of this process's waited-for children."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _cpu_seconds(pid: int) -> float:
    """User and system CPU seconds of process ``pid`` so far (0 when unknown)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _vm_size() -> int:
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmSize:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def failure(signature: str, detail: str = "", **extra) -> dict:
    return {"ok": False, "signature": signature, "detail": detail, **extra}


def run_script(source: str) -> dict:
    """A known finding's reproducer script, for its signature."""
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            exec(compile(source, "<finding>", "exec"), {"__name__": "__finding__"})
    except (BudgetExceeded, MemoryError):
        raise
    except Exception as error:  # noqa: BLE001 - the signature is what we want
        return failure(signature_of(error), traceback.format_exc(limit=-8))
    return {"ok": True, "signature": None, "detail": ""}


def run_converter(task: dict, scratch: Path) -> dict:
    folder = scratch / "run"
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir()
    source = folder / f"input{task['suffix']}"
    source.write_bytes(task["data"])
    before = hashlib.sha256(task["data"]).hexdigest()
    argv = [str(source) if a == "IN" else a for a in task["argv"]]
    target = None
    for index, argument in enumerate(argv):
        if argument.startswith("OUT"):
            target = folder / "out" / ("output" + argument[3:])
            argv[index] = str(target)
    stdout, stderr = io.StringIO(), io.StringIO()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
                code = cli_main(argv)
        except SystemExit as error:
            code = error.code if isinstance(error.code, int) else 1
        except (BudgetExceeded, MemoryError):
            raise
        except Exception as error:  # noqa: BLE001 - any other exception is the finding
            return failure(signature_of(error), traceback.format_exc(limit=-8))
    numeric = sum(1 for w in caught if issubclass(w.category, RuntimeWarning))
    extra = {"code": code, "runtime_warnings": numeric}
    if hashlib.sha256(source.read_bytes()).hexdigest() != before:
        return failure("check:input-modified", **extra)
    if code not in (0, 1, 2):
        return failure(f"check:exit-code-{code}", stderr.getvalue()[-2000:], **extra)
    left = sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file())
    left = [p for p in left if p != source.name]
    if code != 0 and left:
        return failure("check:output-after-failure", f"left behind: {left}", **extra)
    if code == 0 and target is not None:
        if left != [str(target.relative_to(folder))]:
            return failure("check:output-files", f"after success: {left}", **extra)
        problem = non_finite_in_output(target)
        if problem:
            return failure("check:non-finite-in-output", problem, **extra)
        if task.get("reference"):
            try:
                problem = reference_area_problem(source, task["argv"])
            except (BudgetExceeded, MemoryError):
                raise
            except Exception as error:  # noqa: BLE001 - the CLI passed, the library did not
                return failure(signature_of(error), traceback.format_exc(limit=-8), **extra)
            if problem:
                return failure("check:shadow-area-vs-reference", problem, **extra)
    return {"ok": True, "signature": None, "detail": stderr.getvalue()[-300:], **extra}


# ---------------------------------------------------------------------------------------------
# Output checks
# ---------------------------------------------------------------------------------------------

_SKIPPED_ATTRIBUTES = {"content", "description", "name", "DEF", "USE", "url", "title", "string"}
_ATTRIBUTE = re.compile(r'([\w:.-]+)\s*=\s*("([^"]*)"|\'([^\']*)\')')
_NONFINITE = re.compile(r"(?<![\w\"])[-+]?(nan|inf|infinity)(?![\w\"])", re.IGNORECASE)


def non_finite_in_output(path: Path) -> str | None:
    """A description of the first NaN or infinity the writer put in ``path``."""
    suffix = path.suffix.lower()
    data = path.read_bytes()
    if suffix in (".x3d", ".x3dz"):
        text = _gunzip(data).decode("utf-8", "replace")
        # A comment's text is no field value (a commented-out node may say "nan").
        text = re.sub(r"<!--.*?-->", "", text, flags=re.S)
        for match in _ATTRIBUTE.finditer(text):
            name, value = match.group(1), match.group(3) or match.group(4) or ""
            if name in _SKIPPED_ATTRIBUTES:
                continue
            words = [w for w in re.split(r"[\s,]+", value) if w]
            if (
                words
                and all(_is_number(w) for w in words)
                and not all(math.isfinite(float(w)) for w in words)
            ):
                return f'{name}="{value[:80]}"'
        return None
    if suffix == ".usda":
        text = data.decode("utf-8", "replace")
        text = re.sub(r'"(?:[^"\\]|\\.)*"', '""', text)
        text = re.sub(r"#[^\n]*", "", text)
        match = _NONFINITE.search(text)
        return None if match is None else text[max(0, match.start() - 60) : match.end() + 20]
    if suffix in (".glb", ".gltf"):
        return non_finite_in_gltf(data, path)
    return None


def _is_number(word: str) -> bool:
    try:
        float(word)
    except ValueError:
        return False
    return True


def non_finite_in_gltf(data: bytes, path: Path) -> str | None:
    if path.suffix.lower() == ".glb":
        parts = split_glb(data)
        if parts is None:
            return "not a glb"
        text, binary = parts
    else:
        text, binary = data, b""

    def refuse(constant):
        raise ValueError(f"JSON constant {constant}")

    try:
        document = json.loads(text, parse_constant=refuse)
    except ValueError as error:
        return str(error)
    buffers = []
    for index, buffer in enumerate(document.get("buffers", [])):
        uri = buffer.get("uri")
        if uri is None:
            buffers.append(binary if index == 0 else b"")
        elif uri.startswith("data:"):
            import base64

            buffers.append(base64.b64decode(uri.split(",", 1)[1]))
        else:
            external = path.parent / uri
            buffers.append(external.read_bytes() if external.is_file() else b"")
    views = document.get("bufferViews", [])
    for index, accessor in enumerate(document.get("accessors", [])):
        if accessor.get("componentType") != 5126 or "bufferView" not in accessor:
            continue
        view = views[accessor["bufferView"]]
        raw = buffers[view.get("buffer", 0)]
        start = view.get("byteOffset", 0) + accessor.get("byteOffset", 0)
        width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}.get(
            accessor.get("type"), 1
        )
        stride = view.get("byteStride") or 4 * width
        count = accessor.get("count", 0)
        try:
            if stride == 4 * width:
                rows = np.frombuffer(raw, "<f4", count * width, start)
            else:
                rows = np.array(
                    [np.frombuffer(raw, "<f4", width, start + i * stride) for i in range(count)]
                )
        except ValueError as error:
            return f"accessor {index} unreadable: {error}"
        if rows.size and not np.all(np.isfinite(rows)):
            return f"accessor {index} has NaN or inf"
    return None


def reference_area_problem(source: Path, argv) -> str | None:
    """Compare the converter's shadow area with --sun and --plane against the
    shapely union of the textbook-projected triangles, where that reference is
    well conditioned (no triangle crosses or nearly touches the plane, sizes
    far from overflow); None when they agree or the reference does not apply."""
    options = dict(zip(argv[3::2], argv[4::2], strict=False))
    direction = np.array([float(v) for v in options["--sun"].split(",")])
    coefficients = np.array([float(v) for v in options["--plane"].split(",")])
    scene = shadowgeo.load(source)
    sun = shadowgeo.SceneLight(shadowgeo.DirectionalLight(direction), name="sun", shadows=True)
    plane = shadowgeo.Plane.from_coefficients(coefficients)
    result = shadowgeo.add_shadows(scene, plane=plane, extra_lights=[sun])
    if any("does not cast" in note for note in result.warnings):
        return None
    casters = [s for s in result.shapes if s.role == "geometry" and s.n_faces]
    if not casters:
        return None
    triangles = np.concatenate([s.world_vertices[s.faces] for s in casters])
    if not np.all(np.isfinite(triangles)) or np.abs(triangles).max() > 1e100:
        return None
    low, high = triangles.reshape(-1, 3).min(axis=0), triangles.reshape(-1, 3).max(axis=0)
    diagonal = float(np.linalg.norm(high - low))
    if not 1e-100 < diagonal < 1e100 or diagonal < 1e-9 * float(np.abs(triangles).max()):
        return None
    normal = coefficients[:3] / np.linalg.norm(coefficients[:3])
    offset = coefficients[3] / np.linalg.norm(coefficients[:3])
    distance = triangles @ normal + offset
    # On the plane means far within shadowgeo's own tolerance (1e-9 of the
    # scene's size): a triangle a little higher than that casts there, and
    # one between that and `large` is in neither class (obj mutant 2966: boxes
    # 0.2-5 above the plane beside a side 8e7 long were taken as on it).
    small, large = 1e-12 * diagonal, 1e-5 * diagonal
    nearest, farthest = distance.min(axis=1), distance.max(axis=1)
    below = farthest <= -small
    on_plane = np.abs(distance).max(axis=1) <= small
    cast = (nearest >= -small) & (farthest > large)
    if not np.all(below | on_plane | cast):
        return None  # crossing or nearly touching triangles: not well conditioned
    expected = textbook_area(triangles[cast], np.append(-direction, 0.0), normal, offset)
    shadows = [s for s in result.shapes if s.role == "shadow"]
    got = sum(_mesh_area(s.world_vertices[s.faces]) for s in shadows)
    if abs(got - expected) > 1e-6 * expected + 1e-12 * diagonal**2:
        return f"shadow area {got!r}, textbook union {expected!r}"
    return None


def textbook_area(triangles: np.ndarray, light_h: np.ndarray, normal, offset: float) -> float:
    """Area of the union of the triangles projected through the shadow matrix
    ``M = (P . L) I - L P^T`` (the textbook method, independent of shadowgeo),
    in a frame centred on the triangles so that far-off scenes keep their digits."""
    if len(triangles) == 0:
        return 0.0
    origin = 0.5 * (triangles.reshape(-1, 3).min(axis=0) + triangles.reshape(-1, 3).max(axis=0))
    triangles = triangles - origin
    offset = offset + float(normal @ origin)
    if light_h[3] != 0:
        light_h = np.append(light_h[:3] - origin, 1.0)
    plane_vector = np.append(normal, offset)
    matrix = (plane_vector @ light_h) * np.eye(4) - np.outer(light_h, plane_vector)
    points = triangles.reshape(-1, 3)
    homogeneous = np.column_stack([points, np.ones(len(points))]) @ matrix.T
    projected = homogeneous[:, :3] / homogeneous[:, 3:]
    axis = np.zeros(3)
    axis[int(np.argmin(np.abs(normal)))] = 1.0
    u = axis - (axis @ normal) * normal
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)
    flat = np.column_stack([projected @ u, projected @ v]).reshape(-1, 3, 2)
    # Slivers are left out: each adds at most its own (negligible) area, and
    # GEOS's union can lose whole triangles beside them.
    edge1, edge2 = flat[:, 1] - flat[:, 0], flat[:, 2] - flat[:, 0]
    areas = 0.5 * np.abs(edge1[:, 0] * edge2[:, 1] - edge1[:, 1] * edge2[:, 0])
    extent = float(np.ptp(flat.reshape(-1, 2), axis=0).max())
    polygons = shapely.polygons(flat[areas > 1e-12 * extent**2])
    return float(shapely.union_all(polygons).area)


def _mesh_area(triangles: np.ndarray) -> float:
    """Sum of triangle areas, computed on coordinates scaled to 1 so that
    squares of large coordinates do not overflow."""
    if len(triangles) == 0:
        return 0.0
    largest = float(np.abs(triangles).max())
    if not (largest > 0 and math.isfinite(largest)):
        return _plain(triangles)
    with np.errstate(over="ignore"):
        return float(np.float64(largest) ** 2 * _plain(triangles / largest))


def _plain(triangles: np.ndarray) -> float:
    cross = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    return float(0.5 * np.linalg.norm(cross, axis=1).sum())


# ---------------------------------------------------------------------------------------------
# Geometry mode
# ---------------------------------------------------------------------------------------------


def geometry_case(seed: int, index: int) -> dict:
    """A random caster, plane and light: plain numbers, so it pickles and prints."""
    rng = np.random.default_rng([seed, index])
    scale = 10.0 ** rng.choice([0] * 8 + [-300, -150, -12, -6, 3, 6, 12, 50, 100, 150, 300])
    kind = rng.choice(["soup", "hull", "box", "sphere", "degenerate", "grid", "duplicate"])
    if kind == "hull" or kind == "duplicate":
        mesh = trimesh.convex.convex_hull(rng.normal(size=(int(rng.integers(4, 20)), 3)))
        vertices, faces = mesh.vertices, mesh.faces
        if kind == "duplicate":
            faces = np.concatenate([faces, faces[: int(rng.integers(1, len(faces) + 1))]])
    elif kind == "box":
        mesh = trimesh.creation.box(extents=rng.uniform(0.01, 2, size=3))
        vertices, faces = mesh.vertices, mesh.faces
    elif kind == "sphere":
        # most with a dent (not convex: its folds cast outline loops inside
        # the outline, the many-loop certificate's case); drawn apart so the
        # other kinds' cases stay as they were
        dent = np.random.default_rng([seed, index, 7])
        mesh = trimesh.creation.icosphere(subdivisions=int(dent.integers(1, 4)))
        vertices, faces = mesh.vertices.copy(), mesh.faces
        if dent.random() < 0.7:  # the cap above a level pressed in: a crater, still embedded
            axis = dent.normal(size=3)
            axis /= np.linalg.norm(axis)
            level, depth = dent.uniform(0.2, 0.9), dent.uniform(0.3, 0.95)
            height = vertices @ axis
            above = height > level
            vertices[above] -= ((1 - depth) * height[above])[:, None] * axis
    elif kind == "grid":
        vertices = np.array([[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1.0]]) + rng.normal(size=3)
        faces = np.array([[0, 1, 2], [0, 2, 3]])
    else:
        count = int(rng.integers(1, 12))
        vertices = rng.normal(size=(3 * count, 3))
        faces = np.arange(3 * count).reshape(-1, 3)
        if kind == "degenerate":
            for face in faces[: int(rng.integers(1, count + 1))]:
                if rng.random() < 0.5:
                    vertices[face[2]] = vertices[face[0]]  # a repeated vertex
                else:
                    vertices[face[2]] = 2 * vertices[face[1]] - vertices[face[0]]  # collinear
    vertices = np.asarray(vertices, dtype=np.float64)
    normal = np.array([0.0, 1.0, 0.0]) if rng.random() < 0.5 else rng.normal(size=3)
    normal /= np.linalg.norm(normal)
    # Place the caster above the plane (mostly), across it, or below it.
    heights = vertices @ normal
    lift = rng.choice([2.0, 2.0, 2.0, 0.0, -3.0]) - heights.min()
    vertices = vertices + lift * normal
    heights = vertices @ normal
    top = float(heights.max())
    light_kind = rng.choice(
        ["point", "point", "near-vertex", "on-plane", "between", "spot", "sun", "grazing"]
    )
    light: dict = {"kind": "point"}
    tangent = np.cross(normal, rng.normal(size=3))
    if light_kind in ("point", "spot"):
        position = (top + rng.uniform(0.5, 10)) * normal + rng.normal(size=3)
        light = {"kind": light_kind, "position": position}
        if light_kind == "spot":
            light.update(direction=-normal + 0.3 * rng.normal(size=3), angle=rng.uniform(0.05, 1.5))
    elif light_kind == "near-vertex":
        vertex = vertices[int(rng.integers(len(vertices)))]
        gap = 10.0 ** rng.uniform(-15, -1)
        light = {"kind": "point", "position": vertex + gap * (normal + 0.1 * tangent)}
    elif light_kind == "on-plane":
        tiny = rng.choice([0.0, 1e-15, 1e-12, -1e-15])
        light = {"kind": "point", "position": 3 * tangent + tiny * normal}
    elif light_kind == "between":
        light = {"kind": "point", "position": rng.uniform(0.1, max(top, 0.2)) * normal + tangent}
    elif light_kind == "sun":
        light = {"kind": "sun", "direction": -normal + 0.5 * rng.normal(size=3)}
    else:
        cosine = 10.0 ** -rng.uniform(1, 16)
        direction = -cosine * normal + tangent / np.linalg.norm(tangent)
        light = {"kind": "sun", "direction": direction}
    if light["kind"] != "sun" and rng.random() < 0.25:
        light["radius"] = float(10.0 ** rng.uniform(-1, 200))
    shift = rng.normal(size=3) * (10.0 ** rng.choice([0, 0, 0, 3, 8, 15]))
    if not np.all(np.isfinite(shift * scale * 100)):
        shift = np.zeros(3)  # keep every generated number finite
    for name in ("position",):
        if name in light:
            light[name] = (np.asarray(light[name]) + shift) * scale
    vertices = (vertices + shift) * scale
    offset = float(-float(normal @ shift) * scale)
    return {
        "seed": seed,
        "index": index,
        "kind": str(kind),
        "light_kind": str(light_kind),
        "vertices": vertices.tolist(),
        "faces": np.asarray(faces).tolist(),
        "normal": normal.tolist(),
        "scale": float(scale),
        "offset": offset,
        "light": {k: (np.asarray(v).tolist() if k != "kind" else str(v)) for k, v in light.items()},
    }


def make_light(spec: dict):
    extra = {"radius": spec["radius"]} if "radius" in spec else {}
    if spec["kind"] == "sun":
        return shadowgeo.DirectionalLight(spec["direction"])
    if spec["kind"] == "spot":
        return shadowgeo.SpotLight(spec["position"], spec["direction"], spec["angle"], **extra)
    return shadowgeo.PointLight(spec["position"], **extra)


def run_geometry(case: dict) -> dict:
    """project_shadow, silhouette and shadow_volume on one case, checked."""
    vertices = np.asarray(case["vertices"], dtype=np.float64)
    faces = np.asarray(case["faces"], dtype=np.int64).reshape(-1, 3)
    step = "setup"
    try:
        light = make_light(case["light"])
        plane = shadowgeo.Plane(case["normal"], case["offset"])
        step = "project_shadow"
        problem = check_shadow(vertices, faces, light, plane)
        if problem:
            return failure(f"check:project_shadow:{problem[0]}", problem[1])
        step = "silhouette"
        problem = check_silhouette(vertices, faces, light)
        if problem:
            return failure(f"check:silhouette:{problem[0]}", problem[1])
        step = "shadow_volume"
        problem = check_volume(vertices, faces, light)
        if problem:
            return failure(f"check:shadow_volume:{problem[0]}", problem[1])
    except shadowgeo.GeometryError as error:
        detail = f"{step}: GeometryError: {error}"[:300]
        return {"ok": True, "signature": None, "detail": detail, "code": 1}
    except (BudgetExceeded, MemoryError):
        raise
    except Exception as error:  # noqa: BLE001 - any other exception is the finding
        return failure(signature_of(error), traceback.format_exc(limit=-8))
    return {"ok": True, "signature": None, "detail": "", "code": 0}


def check_shadow(vertices, faces, light, plane):
    shadow = shadowgeo.project_shadow((vertices, faces), light, plane)
    mesh_vertices = np.asarray(shadow.mesh.vertices)
    if not math.isfinite(shadow.area) or not np.all(np.isfinite(mesh_vertices)):
        return "non-finite", f"area {shadow.area!r}"
    if any(not np.all(np.isfinite(loop)) for part in shadow.polygons for loop in part):
        return "non-finite", "polygon loops"
    if shadow.area < 0:
        return "negative-area", f"area {shadow.area!r}"
    mesh_area = _mesh_area(mesh_vertices[np.asarray(shadow.mesh.faces)])
    resolution = area_resolution(vertices, shadow)
    if 1e-250 < shadow.area < 1e250 and abs(mesh_area - shadow.area) > 1e-5 * shadow.area:
        if abs(mesh_area - shadow.area) > resolution:
            return "mesh-area-mismatch", f"mesh {mesh_area!r} vs area {shadow.area!r}"
    expected = geometry_reference(vertices, faces, light, plane, shadow)
    if expected is not None:
        if abs(shadow.area - expected) > 1e-6 * expected + resolution:
            return "area-vs-reference", f"area {shadow.area!r}, textbook union {expected!r}"
    return None


def area_resolution(vertices, shadow) -> float:
    """The area float64 can resolve: a sliver as long as the shadow and a
    thousand units in the last place of the largest coordinate wide."""
    points = [np.abs(vertices).reshape(-1, 3)]
    points += [np.abs(loop) for part in shadow.polygons for loop in part]
    magnitude = max(float(p.max()) for p in points if p.size)
    extent = max(
        (float(np.ptp(loop, axis=0).max()) for p in shadow.polygons for loop in p), default=0
    )
    extent = max(extent, float(np.ptp(vertices.reshape(-1, 3), axis=0).max()))
    return 1e3 * np.finfo(np.float64).eps * max(magnitude, extent) * extent


def geometry_reference(vertices, faces, light, plane, shadow) -> float | None:
    """Textbook area where it is well conditioned: every triangle strictly
    between the plane and the light, no radius or cone, sizes far from
    overflow, the shadow not cut by the default bound."""
    if shadow.diagnostics.bounded_artificially or isinstance(light, shadowgeo.SpotLight):
        return None
    if not np.all(np.abs(vertices) < 1e100):
        return None
    used = vertices[faces]
    size = float(np.ptp(used.reshape(-1, 3), axis=0).max()) if len(used) else 0.0
    if not 1e-100 < size < 1e100 or size < 1e-9 * float(np.abs(used).max()):
        return None
    distance = used @ plane.normal + plane.offset
    if isinstance(light, shadowgeo.DirectionalLight):
        if -float(plane.normal @ light.direction) < 0.05 or distance.min() <= 1e-3 * size:
            return None
        light_h = np.append(-light.direction, 0.0)
    else:
        height = float(plane.normal @ light.position + plane.offset)
        if not math.isinf(light.radius) or height <= 0:
            return None
        if distance.min() <= 1e-3 * height or distance.max() >= (1 - 1e-3) * height:
            return None
        light_h = np.append(light.position, 1.0)
    return textbook_area(used, light_h, plane.normal, plane.offset)


def check_silhouette(vertices, faces, light):
    outline = shadowgeo.silhouette((vertices, faces), light)
    if outline.front.shape != (len(faces),):
        return "front-shape", str(outline.front.shape)
    if outline.loops:
        edges = np.concatenate([np.column_stack([lp, np.roll(lp, -1)]) for lp in outline.loops])
        leaving = Counter(edges[:, 0].tolist())
        arriving = Counter(edges[:, 1].tolist())
        if leaving != arriving:
            return "open-loop", "a loop vertex has unequal in and out edges"
    return None


def check_volume(vertices, faces, light):
    volume = shadowgeo.shadow_volume((vertices, faces), light)
    if len(volume.faces) == 0:
        return None
    points = np.asarray(volume.vertices)
    if not np.all(np.isfinite(points)):
        return "non-finite", "vertices"
    if not volume.is_watertight:
        return "not-watertight", f"{len(volume.faces)} faces"
    if not volume.is_winding_consistent:
        return "winding-inconsistent", f"{len(volume.faces)} faces"
    centred = points - points.mean(axis=0)
    largest = float(np.abs(centred).max())
    if largest > 0:
        normalised = trimesh.Trimesh(centred / largest, volume.faces, process=False)
        if isinstance(light, shadowgeo.DirectionalLight):
            problem = thinner_than_a_prism(vertices, faces, light, volume)
            if problem:
                return "flat (zero volume)", problem
        else:
            # A volume float64 cannot tell from zero at its own scale.
            resolution = 1e3 * np.finfo(np.float64).eps * float(normalised.area)
            if abs(normalised.volume) <= resolution:
                return "flat (zero volume)", (
                    f"normalised volume {float(normalised.volume)!r} <= {resolution!r}"
                )
        if not normalised.volume > 0:
            return "inside-out", f"normalised volume {float(normalised.volume)!r}"
    return None


def thinner_than_a_prism(vertices, faces, light, volume) -> str | None:
    """A sun's shadow volume holds the prism that each casting face sweeps
    (its area times the cosine with the light times the sweep length): a
    volume smaller than half the largest such prism is flat where it should
    not be. Faces within ten times the library's angle or length tolerance of
    edge-on are left out (the library may rightly drop them), and so is the
    check when no face remains. Computed in the caster's frame scaled to 1."""
    sweep = volume.metadata.get("shadowgeo", {}).get("sweep")
    triangles = np.asarray(vertices, dtype=np.float64)[np.asarray(faces).reshape(-1, 3)]
    if sweep is None or not len(triangles):
        return None
    centre = 0.5 * (triangles.reshape(-1, 3).min(axis=0) + triangles.reshape(-1, 3).max(axis=0))
    size = float(np.abs(triangles - centre).max())
    if not size > 0:
        return None
    tolerance = shadowgeo.Tolerance.for_points(triangles.reshape(-1, 3))
    unit = (triangles - centre) / size
    doubled = np.cross(unit[:, 1] - unit[:, 0], unit[:, 2] - unit[:, 0])
    longest = np.abs(unit - unit[:, [1, 2, 0]]).max(axis=(1, 2))
    direction = np.asarray(light.direction, dtype=np.float64)
    direction = direction / np.linalg.norm(direction)
    norms = np.linalg.norm(doubled, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        cosine = np.abs(doubled @ direction) / norms
    casting = (np.abs(doubled).max(axis=1) > 10 * tolerance.length / size * longest) & (
        cosine > 10 * tolerance.angle
    )
    if not casting.any():
        return None
    prism = float((0.5 * norms * cosine)[casting].max()) * float(sweep) / size
    mesh = trimesh.Trimesh(
        (np.asarray(volume.vertices) - centre) / size, volume.faces, process=False
    )
    if abs(float(mesh.volume)) < 0.5 * prism:
        return f"volume {float(mesh.volume)!r} < half the largest face prism {prism!r} (scaled)"
    return None


def geometry_reproducer(case: dict) -> str:
    return (
        f"# found by tools/fuzz.py --geometry (seed {case['seed']}, case {case['index']})\n"
        "from shadowgeo import *\n"
        f"vertices = {case['vertices']!r}\nfaces = {case['faces']!r}\n"
        f"light = {case['light']!r}\nplane = Plane({case['normal']!r}, {case['offset']!r})\n"
        "kind = light.pop('kind'); radius = light.pop('radius', float('inf'))\n"
        "L = (DirectionalLight(light['direction']) if kind == 'sun' else SpotLight("
        "light['position'], light['direction'], light['angle'], radius) if kind == 'spot' "
        "else PointLight(light['position'], radius))\n"
        "print('area', project_shadow((vertices, faces), L, plane).area)\n"
        "print('loops', [len(loop) for loop in silhouette((vertices, faces), L).loops])\n"
        "volume = shadow_volume((vertices, faces), L)\n"
        "import trimesh\n"
        "if len(volume.faces):\n"
        "    centred = volume.vertices - volume.vertices.mean(axis=0)\n"
        "    unit = trimesh.Trimesh(centred / abs(centred).max(), volume.faces, process=False)\n"
        "    print('watertight', volume.is_watertight, 'normalised volume', unit.volume)\n"
    )


# ---------------------------------------------------------------------------------------------
# The pool: forked workers, killed and replaced on a hang or a crash
# ---------------------------------------------------------------------------------------------


@dataclass
class Worker:
    process: object
    connection: object
    task: dict | None = None
    started: float = 0.0
    cpu_started: float = 0.0
    runs: int = 0


@dataclass
class Pool:
    jobs: int
    time_budget: float
    memory_bytes: int
    max_runs: int = 100
    workers: list[Worker] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.context = get_context("fork")
        self.workers = [self._start() for _ in range(self.jobs)]

    def _start(self) -> Worker:
        parent, child = self.context.Pipe()
        process = self.context.Process(
            target=worker_main, args=(child, self.memory_bytes, self.time_budget), daemon=True
        )
        process.start()
        child.close()
        return Worker(process, parent)

    def _replace(self, worker: Worker) -> None:
        if worker.process.is_alive():
            worker.process.kill()
        worker.process.join(5)
        worker.connection.close()
        self.workers[self.workers.index(worker)] = self._start()

    def run(self, tasks):
        """Yield (task, result) for every task, ``jobs`` at a time, in completion order."""
        pending = iter(tasks)
        exhausted = False
        while True:
            for worker in list(self.workers):
                if worker.task is None and not exhausted:
                    task = next(pending, None)
                    if task is None:
                        exhausted = True
                        break
                    worker.task, worker.started = task, time.monotonic()
                    worker.cpu_started = _cpu_seconds(worker.process.pid)
                    worker.connection.send(task)
            busy = [w for w in self.workers if w.task is not None]
            if not busy:
                return
            # The worker's own alarm counts CPU seconds; past 1.5 times the
            # budget in CPU (stuck in C code), or three times the budget plus
            # a minute of wall clock (blocked, using no CPU: a hang), it is
            # killed. The wall-clock margin lets a busy shared machine slow a
            # run down without its being called hung.
            hard_cpu = self.time_budget * 1.5 + 10
            hard_wall = self.time_budget * 3 + 60
            ready = wait([w.connection for w in busy], 1.0)
            for worker in busy:
                task = worker.task
                if worker.connection in ready:
                    try:
                        result = worker.connection.recv()
                    except (EOFError, OSError):
                        code = worker.process.exitcode
                        worker.process.join(1)
                        code = worker.process.exitcode if code is None else code
                        result = failure(f"worker crash (exit {code})", "the worker died")
                        result["seconds"] = time.monotonic() - worker.started
                        worker.task = None
                        self._replace(worker)
                        yield task, result
                        continue
                    worker.task = None
                    worker.runs += 1
                    if worker.runs >= self.max_runs or not result["ok"]:
                        self._replace(worker)  # a fresh process after any failure
                    yield task, result
                elif (
                    over_cpu := _cpu_seconds(worker.process.pid) - worker.cpu_started > hard_cpu
                ) or time.monotonic() - worker.started > hard_wall:
                    result = failure(
                        "timeout (hard kill, no Python frame)" if over_cpu else "hang (wall clock)",
                        "killed",
                    )
                    result["seconds"] = time.monotonic() - worker.started
                    worker.task = None
                    self._replace(worker)
                    yield task, result

    def map(self, tasks: list[dict]) -> list[dict]:
        """Results in the order of ``tasks``."""
        for index, task in enumerate(tasks):
            task["slot"] = index
        results: list[dict] = [{}] * len(tasks)
        for task, result in self.run(tasks):
            results[task["slot"]] = result
        return results

    def close(self) -> None:
        for worker in self.workers:
            with contextlib.suppress(OSError, BrokenPipeError):
                worker.connection.send(None)
        for worker in self.workers:
            worker.process.join(5)
            if worker.process.is_alive():
                worker.process.kill()


# ---------------------------------------------------------------------------------------------
# Shrinking
# ---------------------------------------------------------------------------------------------


def ddmin(items: list, reproduces, budget: list[int]) -> list:
    """Delta debugging: a smaller list of ``items`` for which ``reproduces``
    (called on a batch of candidates, returning the index of the first that
    reproduces or None) still holds; ``budget[0]`` runs at most."""
    granularity = 2
    while len(items) >= 2 and budget[0] > 0:
        size = max(1, len(items) // granularity)
        chunks = [items[i : i + size] for i in range(0, len(items), size)]
        complements = [
            [x for j, chunk in enumerate(chunks) if j != i for x in chunk]
            for i in range(len(chunks))
        ]
        # Two chunks: each is the other's complement; more: complements first.
        candidates = (chunks if len(chunks) <= 2 else complements)[: budget[0]]
        budget[0] -= len(candidates)
        found = reproduces(candidates)
        if found is not None:
            items = candidates[found]
            granularity = max(granularity - 1, 2) if len(chunks) > 2 else 2
            continue
        if granularity >= len(items):
            break
        granularity = min(len(items), granularity * 2)
    return items


def shrink_input(pool: Pool, task: dict, signature: str, tries: int) -> bytes:
    """The smallest input found that still fails with ``signature``."""
    encoding = task["encoding"]
    wrap = (lambda b: gzip.compress(b, mtime=0)) if encoding == "x3dz" else (lambda b: b)
    inner = _gunzip(task["data"]) if encoding == "x3dz" else task["data"]
    if encoding == "x3dz" and not _same(pool, task, wrap(inner), signature):
        inner, wrap = task["data"], (lambda b: b)
    budget = [tries]

    def reproduces(candidates) -> int | None:
        tasks = [dict(task, data=wrap(b"".join(c))) for c in candidates]
        for index, result in enumerate(pool.map(tasks)):
            if result.get("signature") == signature:
                return index
        return None

    pieces = re.split(rb"(?<=\n)", inner)
    inner = b"".join(ddmin([p for p in pieces if p], reproduces, budget))
    if encoding in XML_ENCODINGS or encoding == "x3dz":
        inner = b"".join(ddmin(re.split(rb"(?=<)", inner), reproduces, budget))
    inner = b"".join(ddmin([t for t in re.split(rb"(\s+)", inner) if t], reproduces, budget))
    inner = b"".join(ddmin([bytes([b]) for b in inner], reproduces, [min(budget[0], 200)]))
    return wrap(inner)


def _same(pool: Pool, task: dict, data: bytes, signature: str) -> bool:
    return pool.map([dict(task, data=data)])[0].get("signature") == signature


def shrink_case(pool: Pool, case: dict, signature: str, tries: int) -> dict:
    """Fewest faces (then fewest vertices) for which the case still fails."""
    budget = [tries]

    def reproduces(candidates) -> int | None:
        tasks = [{"kind": "geometry", "case": dict(case, faces=c)} for c in candidates]
        for index, result in enumerate(pool.map(tasks)):
            if result.get("signature") == signature:
                return index
        return None

    faces = ddmin(list(case["faces"]), reproduces, budget)
    used = sorted({i for face in faces for i in face})
    remap = {old: new for new, old in enumerate(used)}
    smaller = dict(
        case,
        faces=[[remap[i] for i in face] for face in faces],
        vertices=[case["vertices"][i] for i in used],
    )
    result = pool.map([{"kind": "geometry", "case": smaller}])[0]
    return smaller if result.get("signature") == signature else dict(case, faces=faces)


# ---------------------------------------------------------------------------------------------
# The campaign
# ---------------------------------------------------------------------------------------------


def converter_tasks(seeds, encodings, count: int, seed: int, first: int = 0):
    """``count`` mutants per encoding, interleaved, from index ``first`` (mutant
    ``i`` is the same whatever chunk it is run in)."""
    plans = [e for e in encodings if seeds.get(e)]
    for index in range(first, first + count):
        for encoding in plans:
            yield converter_task(seeds, encoding, index, seed)


def converter_task(seeds, encoding: str, index: int, seed: int) -> dict:
    """Mutant ``index`` of ``encoding``: the same for the same seed files and ``seed``."""
    rng = random.Random(f"{seed}:{encoding}:{index}")
    pool = seeds[encoding]
    name, data = pool[rng.randrange(len(pool))]
    others = [d for _, d in rng.sample(pool, min(3, len(pool)))]
    try:
        mutant, ops = mutate(data, encoding, rng, others)
    except Exception as error:  # noqa: BLE001 - a mutator's own limit must not end the campaign
        mutant, ops = data[: len(data) // 2], [f"bytes:truncate (mutator: {type(error).__name__})"]
    template = rng.randrange(len(TEMPLATES))
    return {
        "kind": "convert",
        "encoding": encoding,
        "index": index,
        "seed_file": name,
        "ops": ops,
        "data": mutant,
        "suffix": ENCODINGS[encoding],
        "argv": list(TEMPLATES[template]),
        "reference": template == REFERENCE_TEMPLATE,
    }


def known_signatures(pool: Pool) -> dict[str, list[str]]:
    """Signatures of the findings already filed (README in ../shared/findings/robustness),
    so the summary can say which failures are known."""
    tasks = []
    for path in sorted((KNOWN / "api").glob("*.py")):
        tasks.append({"kind": "script", "source": path.read_text(), "known": f"api/{path.name}"})
    for path in sorted((KNOWN / "cli").glob("*.x3d")):
        for template in (TEMPLATES[0], TEMPLATES[REFERENCE_TEMPLATE], TEMPLATES[4]):
            tasks.append(
                {
                    "kind": "convert",
                    "encoding": "x3d",
                    "data": path.read_bytes(),
                    "suffix": ".x3d",
                    "argv": list(template),
                    "reference": False,
                    "known": f"cli/{path.name}",
                }
            )
    found: dict[str, list[str]] = defaultdict(list)
    for task, result in pool.run(tasks):
        if result["signature"] and task["known"] not in found[result["signature"]]:
            found[result["signature"]].append(task["known"])
    return found


def slug(text: str) -> str:
    return re.sub(r"[^\w.-]+", "_", text).strip("_")[:90]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--inputs", type=int, default=200, help="mutants per encoding")
    parser.add_argument("--geometry", type=int, default=0, help="random geometry cases")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--first-index", type=int, default=0, help="index of the first mutant (to run in chunks)"
    )
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--encodings", default=",".join(ENCODINGS))
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--time-budget", type=float, default=20.0, help="CPU seconds per input")
    parser.add_argument("--memory-budget", type=float, default=1.5, help="GiB per worker")
    parser.add_argument("--shrink-tries", type=int, default=300)
    parser.add_argument("--max-seed-bytes", type=int, default=64 << 10)
    parser.add_argument(
        "--max-minutes", type=float, default=0, help="stop starting runs after this (0: never)"
    )
    parser.add_argument(
        "--replay",
        type=Path,
        metavar="RESULTS",
        help="no new runs: re-create the first failing run of each signature in a results.jsonl "
        "made with the same --seed, and shrink those",
    )
    parser.add_argument("--no-known", action="store_true", help="skip matching known findings")
    parser.add_argument("--quiet", action="store_true")
    args = parser.parse_args(argv)
    encodings = [e.strip() for e in args.encodings.split(",") if e.strip()]
    unknown = [e for e in encodings if e not in ENCODINGS]
    if unknown:
        parser.error(f"unknown encodings {unknown}; known: {', '.join(ENCODINGS)}")
    args.out.mkdir(parents=True, exist_ok=True)
    pool = Pool(args.jobs, args.time_budget, int(args.memory_budget * (1 << 30)))
    signal.signal(signal.SIGTERM, lambda signum, frame: sys.exit(143))  # so the pool closes
    try:
        seeds = collect_seeds(pool, args.max_seed_bytes, encodings) if args.inputs else {}
        return campaign(args, encodings, seeds, pool)
    finally:
        pool.close()


def replay(args, seeds, pool: Pool) -> int:
    """Shrink the failures a results.jsonl recorded (e.g. of a campaign that was stopped)."""
    first: dict[str, dict] = {}
    by_signature: Counter = Counter()
    counts: dict[str, Counter] = defaultdict(Counter)
    for line in args.replay.read_text().splitlines():
        entry = json.loads(line)
        group = entry.get("encoding", "geometry")
        counts[group]["runs"] += 1
        counts[group][f"exit {entry.get('code')}" if entry["ok"] else "FAIL"] += 1
        if entry["ok"]:
            continue
        signature = entry["signature"]
        by_signature[signature] += 1
        counts[group][signature] += 1
        if signature in first:
            continue
        if "case" in entry:
            task = {"kind": "geometry", "case": geometry_case(args.seed, entry["case"])}
        else:
            task = converter_task(seeds, entry["encoding"], entry["index"], args.seed)
        result = pool.map([dict(task)])[0]
        if result.get("signature") != signature:
            print(f"not reproduced: {signature} (now {result.get('signature')})", file=sys.stderr)
        task.pop("slot", None)
        first[signature] = dict(task, result=dict(result, detail=entry.get("detail", "")))
    known = {} if args.no_known else known_signatures(pool)
    rows = write_failures(args, pool, first, by_signature, known)
    summary = summary_table(counts, rows, 0.0, args)
    (args.out / "summary.md").write_text(summary)
    print(summary)
    return 1 if by_signature else 0


def campaign(args, encodings, seeds, pool: Pool) -> int:
    if args.replay:
        return replay(args, seeds, pool)
    started = time.monotonic()
    known = {} if args.no_known else known_signatures(pool)
    counts: dict[str, Counter] = defaultdict(Counter)
    first: dict[str, dict] = {}
    by_signature: Counter = Counter()
    log = (args.out / "results.jsonl").open("w")
    total = args.inputs * len([e for e in encodings if seeds.get(e)]) + args.geometry
    done = 0

    def record(task, result):
        nonlocal done
        done += 1
        group = task.get("encoding", "geometry")
        counts[group]["runs"] += 1
        counts[group][f"exit {result.get('code')}" if result["ok"] else "FAIL"] += 1
        entry = {k: v for k, v in task.items() if k not in ("data", "case", "slot")}
        if "case" in task:
            entry.update(case=task["case"]["index"], kind=task["case"]["kind"])
        entry.update({k: v for k, v in result.items() if k != "detail"})
        if not result["ok"]:
            by_signature[result["signature"]] += 1
            counts[group][result["signature"]] += 1
            first.setdefault(result["signature"], dict(task, result=result))
            entry["detail"] = result["detail"][-600:]
        log.write(json.dumps(entry, default=str) + "\n")
        if not args.quiet and (done % 25 == 0 or not result["ok"]):
            rate = done / max(time.monotonic() - started, 1e-9)
            print(
                f"\r[{done}/{total}] {rate:5.1f} runs/s, {sum(by_signature.values())} failures, "
                f"{len(by_signature)} signatures",
                end="",
                file=sys.stderr,
                flush=True,
            )

    deadline = [started + 60 * args.max_minutes if args.max_minutes else math.inf]

    def stop_now(signum, frame):  # SIGUSR1: start no more runs, shrink and summarise
        deadline[0] = 0.0

    signal.signal(signal.SIGUSR1, stop_now)

    def until_deadline(tasks):
        for task in tasks:
            if time.monotonic() > deadline[0]:
                return
            yield task

    # Geometry first when both run: it is quick, and a deadline then cuts mutants.
    cases = (
        {"kind": "geometry", "case": geometry_case(args.seed, i)} for i in range(args.geometry)
    )
    for task, result in pool.run(until_deadline(cases)):
        record(task, result)
    mutants = converter_tasks(seeds, encodings, args.inputs, args.seed, args.first_index)
    for task, result in pool.run(until_deadline(mutants)):
        record(task, result)
    log.close()
    if not args.quiet:
        print(file=sys.stderr)
    rows = write_failures(args, pool, first, by_signature, known)
    summary = summary_table(counts, rows, time.monotonic() - started, args)
    (args.out / "summary.md").write_text(summary)
    print(summary)
    return 1 if by_signature else 0


def write_failures(args, pool: Pool, first, by_signature, known) -> list[list[str]]:
    rows = []
    for number, (signature, count) in enumerate(by_signature.most_common(), start=1):
        task = first[signature]
        folder = args.out / "failures" / f"{number:02d}_{slug(signature)}"
        folder.mkdir(parents=True, exist_ok=True)
        result = task["result"]
        tries = args.shrink_tries if not signature.startswith("timeout") else 8
        if task["kind"] == "geometry":
            (folder / "original.py").write_text(geometry_reproducer(task["case"]))
            small = shrink_case(pool, task["case"], signature, tries)
            (folder / "smallest.py").write_text(geometry_reproducer(small))
            smallest = f"{len(small['faces'])} faces"
            run = f"python {folder.name}/smallest.py"
        else:
            suffix = task["suffix"]
            (folder / f"original{suffix}").write_bytes(task["data"])
            small_data = shrink_input(pool, task, signature, tries)
            (folder / f"smallest{suffix}").write_bytes(small_data)
            smallest = f"{len(small_data)} bytes"
            argv = [
                f"smallest{suffix}" if a == "IN" else ("out" + a[3:] if a.startswith("OUT") else a)
                for a in task["argv"]
            ]
            run = "shadowgeo " + " ".join(argv)
        note = {k: v for k, v in task.items() if k not in ("data", "result", "slot", "case")}
        if "case" in task:
            note.update({k: task["case"][k] for k in ("seed", "index", "kind", "light_kind")})
        (folder / "README.txt").write_text(
            f"signature: {signature}\nruns failing this way: {count}\nreproduce: {run}\n"
            f"task: {json.dumps(note, default=str)}\n\n{result['detail']}\n"
        )
        also = ", ".join(known.get(signature, [])) or "-"
        rows.append([str(number), signature, str(count), smallest, run, also])
    return rows


def summary_table(counts, rows, seconds: float, args) -> str:
    lines = [
        f"# shadowgeo fuzz: seed {args.seed}, {args.inputs} mutants per encoding, "
        f"{args.geometry} geometry cases, {seconds:.0f} s, jobs {args.jobs}, "
        f"budget {args.time_budget:g} s / {args.memory_budget:g} GiB",
        "",
        "| encoding | runs | exit 0 | exit 1 | exit 2 | failures |",
        "|---|---|---|---|---|---|",
    ]
    for group in sorted(counts):
        c = counts[group]
        lines.append(
            f"| {group} | {c['runs']} | {c['exit 0']} | {c['exit 1']} | {c['exit 2']} "
            f"| {c['FAIL']} |"
        )
    lines += ["", "| # | signature | runs | smallest | reproduce | known finding |"]
    lines.append("|---|---|---|---|---|---|")
    lines += ["| " + " | ".join(row) + " |" for row in rows] or ["| - | no failures | | | | |"]
    per = [
        f"| {group} | {sig} | {n} |"
        for group in sorted(counts)
        for sig, n in counts[group].most_common()
        if sig not in ("runs", "FAIL") and not sig.startswith("exit ")
    ]
    if per:
        lines += ["", "| encoding | signature | runs |", "|---|---|---|", *per]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    sys.exit(main())
