"""The X3D JSON encoding: read into the same scene as its XML twin, written
valid against the X3D JSON schema, the author's document kept."""

from __future__ import annotations

import copy
import gzip
import json
import math
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from lxml import etree
from needs import absent, need
from x3d_json_schema import json_schema_errors, json_validator
from x3d_schema import x3d_schema_errors

import shadowgeo as sg
from shadowgeo.io.x3d import json as x3d_json
from shadowgeo.io.x3d import parse as x3d_parse

HALF_PI = math.pi / 2

# A small scene in XML and, by hand, in JSON as X3dToJson writes it: every kind
# of statement, typed values of each shape, a comment, DEF/USE and a prototype.
XML = f"""<?xml version="1.0" encoding="UTF-8"?>
<X3D profile="Immersive" version="4.0">
  <head>
    <unit category="length" name="centimetre" conversionFactor="0.01"/>
    <meta name="title" content="twins"/>
  </head>
  <Scene>
    <!-- a lamp and a crate -->
    <PointLight DEF="lamp" location="0 10 0" shadows="true"/>
    <ProtoDeclare name="Crate">
      <ProtoInterface>
        <field name="size" type="SFVec3f" accessType="initializeOnly" value="1 1 1"/>
      </ProtoInterface>
      <ProtoBody>
        <Shape><Box><IS><connect nodeField="size" protoField="size"/></IS></Box></Shape>
      </ProtoBody>
    </ProtoDeclare>
    <Transform DEF="lift" translation="0 1 0" rotation="0 1 0 {HALF_PI!r}">
      <Shape DEF="tri">
        <Appearance><Material diffuseColor="1 0 0"/></Appearance>
        <IndexedFaceSet coordIndex="0 1 2 -1" solid="false">
          <Coordinate point="0 0 0, 2 0 0, 0 0 3"/>
        </IndexedFaceSet>
      </Shape>
    </Transform>
    <Transform translation="5 0 0"><Shape USE="tri"/></Transform>
    <Transform translation="0 0 -5">
      <ProtoInstance name="Crate" DEF="crate">
        <fieldValue name="size" value="2 4 6"/>
      </ProtoInstance>
    </Transform>
    <TimeSensor DEF="clock" loop="true" cycleInterval="4"/>
    <PositionInterpolator DEF="mover" key="0 1" keyValue="0 1 0, 0 2 0"/>
    <ROUTE fromNode="clock" fromField="fraction_changed" toNode="mover" toField="set_fraction"/>
    <ROUTE fromNode="mover" fromField="value_changed" toNode="lift" toField="set_translation"/>
    <Viewpoint description='the "front"' position="0 2 20"/>
    <WorldInfo info='"a b" "q\\"uote"'/>
  </Scene>
</X3D>
"""

JSON = {
    "X3D": {
        "encoding": "UTF-8",
        "@profile": "Immersive",
        "@version": "4.0",
        "JSON schema": x3d_json.JSON_SCHEMA,
        "head": {
            "unit": [{"@category": "length", "@name": "centimetre", "@conversionFactor": 0.01}],
            "meta": [{"@name": "title", "@content": "twins"}],
        },
        "Scene": {
            "-children": [
                {"#comment": " a lamp and a crate "},
                {"PointLight": {"@DEF": "lamp", "@location": [0, 10, 0], "@shadows": True}},
                {
                    "ProtoDeclare": {
                        "@name": "Crate",
                        "ProtoInterface": {
                            "field": [
                                {
                                    "@name": "size",
                                    "@type": "SFVec3f",
                                    "@accessType": "initializeOnly",
                                    "@value": [1, 1, 1],
                                }
                            ]
                        },
                        "ProtoBody": {
                            "-children": [
                                {
                                    "Shape": {
                                        "-geometry": {
                                            "Box": {
                                                "IS": {
                                                    "connect": [
                                                        {
                                                            "@nodeField": "size",
                                                            "@protoField": "size",
                                                        }
                                                    ]
                                                }
                                            }
                                        }
                                    }
                                }
                            ]
                        },
                    }
                },
                {
                    "Transform": {
                        "@DEF": "lift",
                        "@translation": [0, 1, 0],
                        "@rotation": [0, 1, 0, HALF_PI],
                        "-children": [
                            {
                                "Shape": {
                                    "@DEF": "tri",
                                    "-appearance": {
                                        "Appearance": {
                                            "-material": {"Material": {"@diffuseColor": [1, 0, 0]}}
                                        }
                                    },
                                    "-geometry": {
                                        "IndexedFaceSet": {
                                            "@coordIndex": [0, 1, 2, -1],
                                            "@solid": False,
                                            "-coord": {
                                                "Coordinate": {
                                                    "@point": [0, 0, 0, 2, 0, 0, 0, 0, 3]
                                                }
                                            },
                                        }
                                    },
                                }
                            }
                        ],
                    }
                },
                {
                    "Transform": {
                        "@translation": [5, 0, 0],
                        "-children": [{"Shape": {"@USE": "tri"}}],
                    }
                },
                {
                    "Transform": {
                        "@translation": [0, 0, -5],
                        "-children": [
                            {
                                "ProtoInstance": {
                                    "@name": "Crate",
                                    "@DEF": "crate",
                                    "fieldValue": [{"@name": "size", "@value": [2, 4, 6]}],
                                }
                            }
                        ],
                    }
                },
                {"TimeSensor": {"@DEF": "clock", "@loop": True, "@cycleInterval": 4}},
                {
                    "PositionInterpolator": {
                        "@DEF": "mover",
                        "@key": [0, 1],
                        "@keyValue": [0, 1, 0, 0, 2, 0],
                    }
                },
                {
                    "ROUTE": {
                        "@fromNode": "clock",
                        "@fromField": "fraction_changed",
                        "@toNode": "mover",
                        "@toField": "set_fraction",
                    }
                },
                {
                    "ROUTE": {
                        "@fromNode": "mover",
                        "@fromField": "value_changed",
                        "@toNode": "lift",
                        "@toField": "set_translation",
                    }
                },
                {"Viewpoint": {"@description": 'the "front"', "@position": [0, 2, 20]}},
                {"WorldInfo": {"@info": ["a b", 'q"uote']}},
            ]
        },
    }
}

# Hand-derived: the triangle turned a quarter about +y ((x, y, z) -> (z, y, -x))
# and lifted 1; its USE moved 5 along x; the crate's Box 2 x 4 x 6 at z = -5.
TRIANGLE = np.array([[0.0, 1, 0], [0, 1, -2], [3, 1, 0]])
TRIANGLE_USED = np.array([[5.0, 0, 0], [7, 0, 0], [5, 0, 3]])
CRATE_BOUNDS = np.array([[-1.0, -2, -8], [1, 2, -2]])


def write_twins(folder: Path) -> tuple[Path, Path]:
    xml, js = folder / "twins.x3d", folder / "twins.json"
    xml.write_text(XML)
    js.write_text(json.dumps(JSON, indent=2))
    return xml, js


def scene_facts(scene: sg.Scene) -> list:
    shapes = [
        (shape.name, shape.faces.tolist(), np.round(shape.world_vertices, 12).tolist())
        for shape in scene.shapes
    ]
    lights = [(light.name, light.light.position.tolist()) for light in scene.lights]
    return [shapes, lights, scene.meters_per_unit]


BAKED_COMMENT = (
    " shadowgeo: the shadows of this light are baked into the scene as shapes; its runtime "
    'shadows are off (shadows="false") so that a browser does not darken them twice '
)


def without_added(document: dict) -> dict:
    """The JSON document less the groups of shadows shadowgeo added, and the
    Viewpoint it adds to a document without one."""
    document = copy.deepcopy(document)
    children = document["X3D"]["Scene"]["-children"]
    document["X3D"]["Scene"]["-children"] = [
        item
        for item in children
        if not ("Group" in item and item["Group"].get("@class", "").startswith("shadowgeo-shadows"))
        and not ("Viewpoint" in item and item["Viewpoint"].get("@class") == "shadowgeo-overview")
    ]
    return document


def added_groups(document: dict) -> list[dict]:
    return [
        item["Group"]
        for item in document["X3D"]["Scene"]["-children"]
        if "Group" in item and item["Group"].get("@class") == "shadowgeo-shadows"
    ]


@pytest.fixture(scope="session")
def json_schema(shared_dir):
    """A validator of the X3D 4.0 JSON schema (see ``x3d_json_schema``), or skip."""
    import jsonschema

    path = shared_dir / "schemas" / "x3d" / "x3d-4.0-JSONSchema.json"
    if not path.is_file():
        absent(f"{path} is absent")
    validator = json_validator(str(path))
    assert type(validator) is jsonschema.Draft202012Validator  # what the schema's $schema says
    return validator


def test_the_schema_check_asserts_urls_and_types(json_schema):
    def errors(node):
        return list(json_schema.iter_errors({"X3D": {
            "encoding": "UTF-8", "@profile": "Full", "@version": "4.0",
            "Scene": {"-children": [node]}}}))  # fmt: skip

    assert errors({"Anchor": {"@url": ["../a%20b.x3d", "https://example.org/ü.x3d"]}}) == []
    assert errors({"Anchor": {"@url": ["a b.x3d"]}})  # a space is no IRI
    assert errors({"Transform": {"@translation": [0, 1]}})  # SFVec3f has 3 numbers
    assert errors({"Transform": {"@visible": "true"}})  # SFBool is a JSON boolean


def schema_errors(validator, path: Path) -> list[str]:
    return json_schema_errors(validator, path)


# -- reading ------------------------------------------------------------------------------


def test_json_twin_reads_as_the_same_scene_as_xml(tmp_path):
    xml, js = write_twins(tmp_path)
    from_xml, from_json = sg.load(xml), sg.load(js)
    assert scene_facts(from_json) == scene_facts(from_xml)
    names = [shape.name for shape in from_json.shapes]
    assert names == ["tri", "tri", "crate"]
    assert np.allclose(from_json.shapes[0].world_vertices, TRIANGLE, rtol=0, atol=1e-12)
    assert np.allclose(from_json.shapes[1].world_vertices, TRIANGLE_USED, rtol=0, atol=1e-12)
    crate = from_json.shapes[2].world_vertices
    assert np.allclose([crate.min(axis=0), crate.max(axis=0)], CRATE_BOUNDS, atol=1e-12)
    assert from_json.lights[0].light.position.tolist() == [0.0, 10.0, 0.0]
    assert from_json.meters_per_unit == 0.01
    assert tuple(from_json.shapes[0].material.diffuse_color) == (1.0, 0.0, 0.0)
    assert not from_json.shapes[0].solid


@pytest.mark.parametrize("suffix", [".x3dj", ".json"])
def test_json_becomes_the_xml_reader_tree(tmp_path, suffix):
    path = tmp_path / f"twins{suffix}"
    path.write_text(json.dumps(JSON))
    root = x3d_parse.parse(path).getroot()
    assert root.tag == "X3D" and root.get("profile") == "Immersive"
    scene = root.find("Scene")
    assert isinstance(scene[0], etree._Comment) and scene[0].text == " a lamp and a crate "
    ifs = scene.find("Transform/Shape/IndexedFaceSet")
    assert ifs.get("coordIndex") == "0 1 2 -1" and ifs.get("solid") == "false"
    assert ifs.get("containerField") is None  # geometry is the default
    assert ifs.find("Coordinate").get("point") == "0 0 0 2 0 0 0 0 3"
    assert scene.find("Transform").get("rotation") == f"0 1 0 {HALF_PI!r}"
    assert scene.find("PointLight").get("shadows") == "true"
    assert scene.find("WorldInfo").get("info") == '"a b" "q\\"uote"'
    assert scene.find("Viewpoint").get("description") == 'the "front"'
    assert root.find("head/unit").get("conversionFactor") == "0.01"
    routes = scene.findall("ROUTE")
    assert [route.get("toNode") for route in routes] == ["mover", "lift"]
    assert scene.find("ProtoDeclare/ProtoBody/Shape/Box/IS/connect").get("nodeField") == "size"


def test_values_of_every_json_shape_become_attribute_text(tmp_path):
    node = {
        "@vector": [[0, 0.5], [1e-300, -2]],  # nested arrays are flattened
        "@flag": False,
        "@flags": [True, False],
        "@count": 7,
        "@ratio": 0.1,
        "@words": ["a\\b", ""],
        "@text": 'as is "quoted"',
    }
    path = tmp_path / "values.x3dj"
    path.write_text(json.dumps({"X3D": {"Scene": {"-children": [{"WorldInfo": node}]}}}))
    info = x3d_parse.parse(path).getroot().find("Scene/WorldInfo")
    assert dict(info.attrib) == {
        "vector": "0 0.5 1e-300 -2",
        "flag": "false",
        "flags": "true false",
        "count": "7",
        "ratio": "0.1",
        "words": '"a\\\\b" ""',
        "text": 'as is "quoted"',
    }


@pytest.mark.parametrize(
    ("kind", "text", "value"),
    [
        ("SFString", ' keep  "this" ', ' keep  "this" '),
        ("MFString", '"a b" "c\\"d" "e\\\\"', ["a b", 'c"d', "e\\"]),
        ("MFString", "bare", ["bare"]),
        ("SFBool", "TRUE", True),
        ("MFBool", "true false", [True, False]),
        ("SFInt32", "-3", -3),
        ("SFImage", "1 2 1 0xFF 0x0a", [1, 2, 1, 255, 10]),
        ("SFFloat", "2.5e-1", 0.25),
        ("SFTime", "4", 4),
        ("SFVec3f", "1, 2.5 -0", [1, 2.5, 0]),
        ("MFVec3f", "0 0 0, 1 1 1", [0, 0, 0, 1, 1, 1]),
        ("MFInt32", "", []),
    ],
)
def test_xml_text_becomes_typed_json(kind, text, value):
    got = x3d_json.typed(kind, text)
    assert got == value and type(got) is type(value)


@pytest.mark.parametrize(
    ("kind", "text"),
    [("SFVec3f", "1 2 x"), ("SFBool", "yes"), ("SFFloat", "1 2"), ("SFFloat", "nan")],
)
def test_text_not_of_its_type_is_refused_by_the_writer(tmp_path, kind, text):
    with pytest.raises(ValueError):
        x3d_json.typed(kind, text)
    field = {"SFVec3f": "size", "SFBool": "solid", "SFFloat": "radius"}[kind]
    node = "Box" if kind != "SFFloat" else "Sphere"
    root = etree.fromstring(f'<X3D><Scene><Shape><{node} {field}="{text}"/></Shape></Scene></X3D>')
    with pytest.raises(sg.SceneError, match=f"{node} field {field}"):
        x3d_json.dumps(root)


# -- writing ------------------------------------------------------------------------------


def test_xml_written_as_json_is_what_x3dtojson_writes(tmp_path):
    xml, _ = write_twins(tmp_path)
    document = x3d_json.dumps(sg.load(xml).document)
    assert json.loads(document) == JSON


def test_json_to_x3dj_keeps_the_document_and_adds_the_shadows(tmp_path, json_schema):
    from cli.main import main

    _, source = write_twins(tmp_path)
    target = tmp_path / "out.x3dj"
    assert main(["convert", str(source), str(target), "--plane", "0,1,0,0"]) == 0
    written = json.loads(target.read_text())
    # the lamp's shadows are baked: its runtime shadows are off, marked and said so
    expected = copy.deepcopy(JSON)
    children = expected["X3D"]["Scene"]["-children"]
    lamp = children[1]["PointLight"]
    lamp.update({"@shadows": False, "@class": "shadowgeo-shadows-baked"})
    children.insert(1, {"#comment": BAKED_COMMENT})
    assert without_added(written) == expected  # DEF names, ROUTEs, PROTOs, comments, values
    (group,) = added_groups(written)
    assert group["@DEF"] == "shadows_lamp"
    assert schema_errors(json_schema, target) == []
    back = sg.load(target)
    shadows = [shape for shape in back.shapes if shape.role == "shadow"]
    heights = np.concatenate([shape.world_vertices[:, 1] for shape in shadows])
    assert np.ptp(heights) < 1e-9 and 0 <= heights[0] < 0.05  # on the plane, lifted a hair
    assert scene_facts(back)[0][:3] == scene_facts(sg.load(source))[0]


def test_xml_output_of_json_input_is_valid_x3d(tmp_path, x3d_schema):
    from cli.main import main

    _, source = write_twins(tmp_path)
    target = tmp_path / "out.x3d"
    assert main(["convert", str(source), str(target), "--plane", "0,1,0,0"]) == 0
    assert x3d_schema_errors(target, x3d_schema) == []
    comments = [c.text for c in etree.parse(str(target)).iter(etree.Comment)]
    assert comments == [" a lamp and a crate ", BAKED_COMMENT]


def test_fresh_document_as_json_is_valid_and_reads_back(tmp_path, json_schema):
    vertices = np.array([[0.1, 0.0, 0.2], [1 / 3, 0.0, 0.2], [0.1, 2 / 7, 0.2]])
    shape = sg.Shape(vertices, [[0, 1, 2]], name="tri", transform=np.diag([2.0, 1, 1, 1]))
    light = sg.SceneLight(sg.PointLight([0, 5, 0]), name="sun")
    path = tmp_path / "fresh.x3dj"
    sg.save(sg.Scene([shape], [light]), path)
    assert schema_errors(json_schema, path) == []
    back = sg.load(path)
    assert np.array_equal(back.shapes[0].world_vertices, vertices * [2, 1, 1])
    assert back.lights[0].light.position.tolist() == [0.0, 5.0, 0.0]


def test_script_source_and_xml_comments_are_kept(tmp_path, json_schema):
    source = "\necmascript:\nfunction initialize() { a = b < c; }\n"
    root = etree.fromstring(
        '<X3D profile="Full" version="4.0"><!-- top --><Scene><Script DEF="s">'
        '<field name="a" type="MFString" accessType="inputOutput" value=\'"x" "y"\'/>'
        f"<![CDATA[{source}]]></Script>"
        "<Shape><!-- inside --><Box/></Shape></Scene></X3D>"
    )
    path = tmp_path / "script.x3dj"
    path.write_bytes(x3d_json.dumps(root))
    assert schema_errors(json_schema, path) == []
    document = json.loads(path.read_text())
    script = document["X3D"]["Scene"]["-children"][0]["Script"]
    assert "\n".join(script["#sourceCode"]) == source
    assert script["field"][0]["@value"] == ["x", "y"]
    shape = document["X3D"]["Scene"]["-children"][1]["Shape"]
    assert shape["-children"] == [{"#comment": " inside "}]
    assert document["X3D"]["-children"] == [{"#comment": " top "}]
    again = x3d_parse.parse(path).getroot()
    assert again.find("Scene/Script").text == source
    assert [c.text for c in again.iter(etree.Comment)] == [" top ", " inside "]
    # CDATA cannot hold "]]>"; such source is kept as escaped text
    script["#sourceCode"] = ["x = a[b[0]]>1;"]
    path.write_text(json.dumps(document))
    text = etree.tostring(x3d_parse.parse(path).getroot().find("Scene/Script"))
    assert b"x = a[b[0]]&gt;1;" in text


# -- the corpus of twins -------------------------------------------------------------------


def pairs(folder: Path) -> list[Path]:
    found = sorted(folder.glob("*.json"))
    assert len(found) == 11
    return found


def test_corpus_json_reads_as_its_xml_twin(pairs_dir):
    for source in pairs(pairs_dir):
        from_json, from_xml = sg.load(source), sg.load(source.with_suffix(".x3d"))
        assert len(from_json.shapes) == len(from_xml.shapes), source.name
        for a, b in zip(from_json.shapes, from_xml.shapes, strict=True):
            assert a.name == b.name and np.array_equal(a.faces, b.faces), source.name
            assert np.allclose(a.world_vertices, b.world_vertices, rtol=0, atol=1e-9)
            assert np.allclose(a.material.diffuse_color, b.material.diffuse_color)
        assert scene_facts(from_json)[1] == scene_facts(from_xml)[1]


def test_corpus_converts_to_valid_json_and_valid_xml(pairs_dir, tmp_path, json_schema, x3d_schema):
    from cli.main import main

    lit = ["--sun", "0.3,-1,0.2", "--plane", "0,1,0,0"]
    for source in pairs(pairs_dir):
        target = tmp_path / f"{source.stem}.x3dj"
        assert main(["convert", str(source), str(target), *lit]) == 0, source.name
        assert schema_errors(json_schema, target) == [], source.name
        original = json.loads(source.read_text())
        written = without_added(json.loads(target.read_text()))
        assert _normalised(written) == _normalised(original), source.name
        assert main(["convert", str(source), str(tmp_path / "out.x3d"), *lit]) == 0
        assert x3d_schema_errors(tmp_path / "out.x3d", x3d_schema) == [], source.name


def _normalised(value):
    """A JSON document with #sourceCode as one text (X3dToJson splits lines at
    newlines it wrote unescaped; the text is the same) and no schema pointer."""
    if isinstance(value, dict):
        return {
            key: "\n".join(item) if key == "#sourceCode" else _normalised(item)
            for key, item in value.items()
            if key != "JSON schema"
        }
    if isinstance(value, list):
        return [_normalised(item) for item in value]
    return value


# -- hostile input -------------------------------------------------------------------------


def test_non_x3d_json_is_refused(tmp_path):
    path = tmp_path / "model.json"
    path.write_text(json.dumps({"asset": {"version": "2.0"}, "nodes": []}))
    with pytest.raises(sg.SceneError, match="not an X3D JSON document: its top-level keys"):
        sg.load(path)
    path.write_text("[1, 2]")
    with pytest.raises(sg.SceneError, match="not a JSON object"):
        sg.load(path)


def test_malformed_json_gives_the_line(tmp_path):
    path = tmp_path / "bad.x3dj"
    path.write_text('{"X3D": {\n  "Scene": {\n    "-children": [,]\n  }\n}}')
    with pytest.raises(sg.SceneError, match=r"bad.x3dj line 3: malformed JSON"):
        sg.load(path)


def test_reader_errors_name_the_json_line(tmp_path):
    document = copy.deepcopy(JSON)
    transform = document["X3D"]["Scene"]["-children"][3]["Transform"]
    geometry = transform["-children"][0]["Shape"]["-geometry"]["IndexedFaceSet"]
    geometry["@coordIndex"] = [0, 1, 9, -1]
    # braces and escaped quotes in strings before it must not shift the count
    document["X3D"]["head"]["meta"][0]["@content"] = 'tricky } { "{" \\'
    text = json.dumps(document, indent=2)
    lines = [line.strip() for line in text.splitlines()]
    line = lines.index('"IndexedFaceSet": {') + 1
    path = tmp_path / "bad.x3dj"
    path.write_text(text)
    # the Shape is skipped, as X3D browsers do, with a note naming the JSON line
    notes = [note for note in sg.load(path).warnings if "IndexedFaceSet" in note]
    assert notes and re.search(rf"bad.x3dj line {line}, IndexedFaceSet.*9", notes[0]), notes


@pytest.mark.parametrize(
    ("node", "message"),
    [
        ({"Box": {"@size": None}}, "Box/@size: a field value cannot be null"),
        ({"Box": {"@size": {"x": 1}}}, "a field value cannot be an object"),
        ({"Box": {"@size": [1, "2", 3]}}, "mixes strings and other values"),
        ({"Box": [1]}, "Box must be a JSON object, not an array"),
        ({"Box": {"-metadata": 3}}, "a node field holds objects, not a number"),
        ({"Bad Name": {}}, "'Bad Name' is not a node or statement name"),
        ({"WorldInfo": {"@title": "nul \u0000"}}, "WorldInfo/@title: cannot be an X3D field"),
        ({"Box": {"#comment": "\ud800"}}, "cannot be held in an X3D document"),
    ],
)
def test_values_json_has_but_x3d_does_not_are_refused(tmp_path, node, message):
    path = tmp_path / "bad.x3dj"
    text = json.dumps({"X3D": {"Scene": {"-children": [{"Shape": {"-geometry": node}}]}}})
    path.write_text(text.replace("Infinity", "1e400"))
    with pytest.raises(sg.SceneError, match=message):
        sg.load(path)


def test_a_non_finite_field_value_is_skipped_with_a_note(tmp_path):
    path = tmp_path / "bad.x3dj"
    node = {"Box": {"@size": [1e400, 1, 1]}}
    text = json.dumps({"X3D": {"Scene": {"-children": [{"Shape": {"-geometry": node}}]}}})
    path.write_text(text.replace("Infinity", "1e400"))
    loaded = sg.load(path)  # the field takes its default, as X3D browsers do
    assert any("'1e+400 1 1' has a value that is not finite" in n for n in loaded.warnings)
    np.testing.assert_allclose(np.ptp(loaded.shapes[0].world_vertices, axis=0), [2, 2, 2])


def test_deep_nesting_is_an_error_not_a_crash(tmp_path):
    path = tmp_path / "deep.x3dj"
    path.write_text('{"X3D": ' + "[" * 100_000 + "]" * 100_000 + "}")
    with pytest.raises(sg.SceneError, match="nested too deeply"):
        sg.load(path)
    group: dict = {}
    document = {"X3D": {"Scene": {"-children": [{"Group": group}]}}}
    for _ in range(x3d_json.MAX_DEPTH + 10):
        inner: dict = {}
        group["-children"] = [{"Group": inner}]
        group = inner
    path.write_text(json.dumps(document))
    with pytest.raises(sg.SceneError, match="nested"):  # by the decoder or the builder
        sg.load(path)


def test_nesting_up_to_the_limit_reads(tmp_path):
    shape = {"Shape": {"-geometry": {"Box": {}}}}
    for _ in range(x3d_json.MAX_DEPTH - 4):  # X3D, Scene, Transforms, Shape, Box
        shape = {"Transform": {"@translation": [0, 1, 0], "-children": [shape]}}
    path = tmp_path / "deep.x3dj"
    path.write_text(json.dumps({"X3D": {"Scene": {"-children": [shape]}}}))
    vertices = sg.load(path).shapes[0].world_vertices
    assert vertices[:, 1].min() == x3d_json.MAX_DEPTH - 5


def test_size_and_inflation_are_bounded(tmp_path, monkeypatch):
    text = json.dumps({"X3D": {"Scene": {"-children": [{"Shape": {"-geometry": {"Box": {}}}}]}}})
    path = tmp_path / "scene.x3dj"
    path.write_bytes(gzip.compress(text.encode()))
    assert sg.load(path).shapes[0].n_faces == 12  # gzip JSON is read, like .x3dz
    monkeypatch.setattr(x3d_parse, "MAX_BYTES", 40)
    with pytest.raises(sg.SceneError, match="larger than 40 bytes; refused"):
        sg.load(path)


def test_inlines_of_json_and_from_json_follow_the_xml_rules(tmp_path):
    folder = tmp_path / "scene"
    folder.mkdir()
    box = {"X3D": {"Scene": {"-children": [{"Shape": {"-geometry": {"Box": {}}}}]}}}
    (folder / "box.x3dj").write_text(json.dumps(box))
    (tmp_path / "outside.x3dj").write_text(json.dumps(box))
    main = folder / "main.x3d"
    main.write_text(
        '<X3D version="4.0"><Scene><Transform translation="0 3 0">'
        "<Inline url='\"box.x3dj\"'/></Transform></Scene></X3D>"
    )
    inlined = sg.load(main).shapes[0].world_vertices
    assert inlined[:, 1].min() == 2.0 and inlined[:, 1].max() == 4.0
    outside = {"X3D": {"Scene": {"-children": [{"Inline": {"@url": ["../outside.x3dj"]}}]}}}
    (folder / "escape.json").write_text(json.dumps(outside))
    escaped = sg.load(folder / "escape.json")  # skipped with a note, never read
    assert escaped.shapes == []
    assert any("leaves the scene's folder" in note for note in escaped.warnings)
    cycle = {"X3D": {"Scene": {"-children": [{"Inline": {"@url": ["cycle.x3dj"]}}]}}}
    (folder / "cycle.x3dj").write_text(json.dumps(cycle))
    with pytest.raises(sg.SceneError, match="Inline cycle"):
        sg.load(folder / "cycle.x3dj")


# -- in a browser -------------------------------------------------------------------------


def test_x_ite_shows_the_shadow_of_an_x3dj_output(tmp_path):
    """X_ITE loads the JSON ``shadowgeo convert`` writes and draws its baked
    shadow: the scene, server and pixel check of test_browser, in JSON."""
    import shapely
    from test_browser import BOX, HALF_VIEW, PIXELS, SCENE, reference_shadow, screenshot

    from cli.main import main

    (tmp_path / "scene.x3d").write_text(SCENE)
    target = tmp_path / "converted.x3dj"
    assert main(["convert", str(tmp_path / "scene.x3d"), str(target)]) == 0
    assert "X3D" in json.loads(target.read_text())
    need("x_ite")
    image = screenshot(tmp_path, need("chromium"), "converted.x3dj")

    centres = (np.arange(PIXELS) + 0.5) / PIXELS * 2 * HALF_VIEW - HALF_VIEW
    x, z = np.meshgrid(centres, centres)  # rows run along +z, columns along +x
    points = shapely.points(x.ravel(), z.ravel())
    shadow = reference_shadow()
    box = shapely.box(*BOX[0, [0, 2]], *BOX[1, [0, 2]])
    margin = 2.5 * 2 * HALF_VIEW / PIXELS
    inside = shapely.contains(shadow.buffer(-margin).difference(box.buffer(margin)), points)
    outside = ~shapely.intersects(shadow.union(box).buffer(margin), points)
    brightness = image.astype(float).mean(axis=2).ravel()
    assert inside.sum() > 1000
    assert np.mean(brightness[inside] < 40) > 0.99, np.percentile(brightness[inside], 99)
    # lit by the lamp alone: the far corners of the ground, at a grazing angle, get 66
    assert np.mean(brightness[outside] > 55) > 0.99, np.percentile(brightness[outside], 1)


def test_container_fields_follow_x3d_rules_not_only_the_table(tmp_path, json_schema):
    """A ProtoInstance goes where its body's first node goes; a node whose
    default field its parent lacks goes to children; X3D 3 metadata goes to
    metadata; an IS given twice keeps both connects."""
    root = etree.fromstring(
        '<X3D profile="Full" version="3.3"><Scene>'
        '<ProtoDeclare name="Red"><ProtoInterface><field name="c" type="SFColor" '
        'accessType="inputOutput" value="1 0 0"/></ProtoInterface><ProtoBody><!-- first -->'
        "<Material><IS><connect nodeField='diffuseColor' protoField='c'/></IS>"
        "<IS><connect nodeField='emissiveColor' protoField='c'/></IS></Material>"
        "</ProtoBody></ProtoDeclare>"
        '<Shape><MetadataString name="m" value=\'"x"\'/><Appearance>'
        '<ProtoInstance name="Red"><fieldValue name="c" value="0 1 0"/></ProtoInstance>'
        "</Appearance><Box/></Shape>"
        "<Group><HAnimMotion/></Group><HAnimHumanoid><HAnimMotion/></HAnimHumanoid>"
        "</Scene></X3D>"
    )
    path = tmp_path / "rules.x3dj"
    path.write_bytes(x3d_json.dumps(root))
    assert schema_errors(json_schema, path) == []
    children = json.loads(path.read_text())["X3D"]["Scene"]["-children"]
    material = children[0]["ProtoDeclare"]["ProtoBody"]["-children"][1]["Material"]
    assert [c["@nodeField"] for c in material["IS"]["connect"]] == ["diffuseColor", "emissiveColor"]
    shape = children[1]["Shape"]
    assert shape["-metadata"] == {"MetadataString": {"@name": "m", "@value": ["x"]}}
    instance = shape["-appearance"]["Appearance"]["-material"]["ProtoInstance"]
    assert instance["fieldValue"] == [{"@name": "c", "@value": [0, 1, 0]}]
    assert children[2]["Group"]["-children"] == [{"HAnimMotion": {}}]
    assert children[3]["HAnimHumanoid"]["-motions"] == [{"HAnimMotion": {}}]
    # and back: each node lands in the field it came from
    again = x3d_parse.parse(path).getroot()
    assert again.find("Scene/Shape/Appearance/ProtoInstance").get("containerField") == "material"
    assert again.find("Scene/Shape/MetadataString").get("containerField") == "metadata"
    assert again.find("Scene/Group/HAnimMotion").get("containerField") == "children"
    assert again.find("Scene/HAnimHumanoid/HAnimMotion").get("containerField") is None


def test_castle_corpus_xml_as_json_is_valid_and_the_same_scene(corpus_dir, tmp_path, json_schema):
    """Every XSD-valid X3D file of the corpus, written as JSON beside it (so its
    Inlines resolve alike), passes the JSON schema and reads as the same scene."""
    xsd = corpus_dir.parents[1] / "schemas" / "x3d" / "x3d-4.0.xsd"
    copy_dir = tmp_path / "corpus"
    shutil.copytree(corpus_dir, copy_dir)
    checked = 0
    for source in sorted(copy_dir.rglob("*.x3d")):
        if x3d_schema_errors(source, xsd):
            continue  # an invalid input may give an invalid translation
        try:
            from_xml = sg.load(source)
        except sg.SceneError:
            continue  # refused as XML too
        target = source.with_suffix(".x3dj")
        target.write_bytes(x3d_json.dumps(from_xml.document))
        assert schema_errors(json_schema, target) == [], source.name
        from_json = sg.load(target)
        assert scene_facts(from_json) == scene_facts(from_xml), source.name
        checked += 1
    assert checked >= 10


def test_converting_a_converted_x3dj_again_replaces_its_shadows(tmp_path):
    from cli.main import main

    _, source = write_twins(tmp_path)
    once, twice = tmp_path / "once.x3dj", tmp_path / "twice.x3dj"
    assert main(["convert", str(source), str(once), "--plane", "0,1,0,0"]) == 0
    assert main(["convert", str(once), str(twice), "--plane", "0,1,0,0"]) == 0
    first, second = json.loads(once.read_text()), json.loads(twice.read_text())
    assert len(added_groups(second)) == 1
    assert second == first  # the same shadows, in the same place, written the same
