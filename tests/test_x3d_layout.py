"""X3D XML written from ClassicVRML, VRML 97 and X3D JSON: one element a line,
indented two spaces a level (shadowgeo.io.x3d.layout), the same scene read
back, a Script's source and comments unchanged; XML input keeps its author's
layout byte for byte."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from lxml import etree

import shadowgeo as sg

SOURCE = "\necmascript:\nfunction initialize() { a = b < c; }\n"
# One scene, by hand in each encoding: a lamp over a floor, a box on a
# plinth inside two Transforms, a triangle, a Script and comments.
CLASSIC = """#X3D V3.3 utf8
PROFILE Immersive
# a lamp over a crate
DEF lamp PointLight { location 0 6 0 }
DEF floor Shape { geometry IndexedFaceSet {
  coord Coordinate { point [-5 0 -5, -5 0 5, 5 0 5, 5 0 -5] }
  coordIndex [0 1 2 3 -1] solid FALSE } }
Transform { translation 0 1 0 children [
  # the crate
  DEF crate Shape { appearance Appearance { material Material { } } geometry Box { size 1 2 1 } }
  Transform { translation 2 0 0 children [
    DEF wedge Shape { geometry IndexedFaceSet {
      coord Coordinate { point [0 0 0, 1 0 0, 0 1 0] } coordIndex [0 1 2 -1] solid FALSE } } ] } ] }
DEF s Script { url "ecmascript: function initialize() { }" }
"""
VRML97 = CLASSIC.replace("#X3D V3.3 utf8\nPROFILE Immersive", "#VRML V2.0 utf8")


def _shape(name: str, geometry: dict) -> dict:
    return {"Shape": {"@DEF": name, "-geometry": geometry}}


def _faces(points: list[float], index: list[int]) -> dict:
    coordinate = {"Coordinate": {"@point": points}}
    return {"IndexedFaceSet": {"@coordIndex": index, "@solid": False, "-coord": coordinate}}


FIELD = {"@name": "a", "@type": "SFFloat", "@accessType": "inputOutput", "@value": 1}
JSON = {
    "X3D": {
        "@profile": "Immersive",
        "@version": "3.3",
        "Scene": {
            "-children": [
                {"#comment": " a lamp over a crate "},
                {"PointLight": {"@DEF": "lamp", "@location": [0, 6, 0]}},
                _shape("floor", _faces([-5, 0, -5, -5, 0, 5, 5, 0, 5, 5, 0, -5], [0, 1, 2, 3, -1])),
                {
                    "Transform": {
                        "@translation": [0, 1, 0],
                        "-children": [
                            {"#comment": " the crate "},
                            _shape("crate", {"Box": {"@size": [1, 2, 1]}}),
                            {
                                "Transform": {
                                    "@translation": [2, 0, 0],
                                    "-children": [
                                        _shape(
                                            "wedge",
                                            _faces([0, 0, 0, 1, 0, 0, 0, 1, 0], [0, 1, 2, -1]),
                                        )
                                    ],
                                }
                            },
                        ],
                    }
                },
                {
                    "Script": {
                        "@DEF": "s",
                        "field": [FIELD],
                        "#sourceCode": SOURCE.split("\n"),
                    }
                },
                {"Script": {"@DEF": "blank", "field": [FIELD], "#sourceCode": [" ", "  "]}},
            ]
        },
    }
}


def world(scene: sg.Scene) -> list:
    """Each shape as (name, rounded sorted world vertices, face count), sorted."""
    out = []
    for shape in scene.shapes:
        points = sorted(map(tuple, np.round(shape.world_vertices, 9).tolist()))
        out.append((shape.name, points, shape.n_faces))
    return sorted(out, key=repr)


def assert_laid_out(path: Path) -> etree._Element:
    """Every element and comment starts its own line, indented two spaces a
    level deeper than its parent, and each end tag of an element with
    children its own line at the parent's indentation -- except where the
    text before an element is the author's (a Script's source), never
    changed to make room."""
    data = path.read_bytes()
    root = etree.fromstring(data)
    lines = data.decode("utf-8").split("\n")
    # comments and CDATA may hold markup of their own: left out, their lines kept
    markup = re.sub(
        r"<!--.*?-->|<!\[CDATA\[.*?\]\]>",
        lambda found: "\n" * found.group().count("\n"),
        data.decode("utf-8"),
        flags=re.DOTALL,
    )
    for line in markup.split("\n"):
        assert len(re.findall(r"<[A-Za-z]", line)) <= 1, line[:200]
    assert lines[1].startswith("<X3D ")
    checked = 0
    for element in root.iter():
        parent = element.getparent()
        if parent is None:
            continue
        depth = sum(1 for _ in element.iterancestors())
        previous = element.getprevious()
        before = parent.text if previous is None else previous.tail
        if previous is None and parent.tag == "Script" and parent.text is not None:
            continue  # the Script's source, then its first field
        assert before == "\n" + "  " * depth, (etree.tostring(element)[:80], before)
        line = lines[element.sourceline - 1]
        assert line.startswith("  " * depth + "<") and not line.startswith("  " * depth + " ")
        checked += 1
        if element.getnext() is None:
            assert element.tail == "\n" + "  " * (depth - 1)  # the parent's end tag
    assert checked > 10
    return root


def converted(source: Path, tmp_path: Path, shadows: bool = False) -> tuple[Path, sg.Scene]:
    scene = sg.load(source)
    out = tmp_path / (source.stem + ".x3d")
    sg.save(sg.add_shadows(scene, lights=["lamp"]) if shadows else scene, out)
    return out, scene


@pytest.mark.parametrize(
    ("name", "text"),
    [("scene.x3dv", CLASSIC), ("scene.wrl", VRML97), ("scene.x3dj", json.dumps(JSON))],
)
def test_each_encoding_is_written_as_xml_one_element_a_line(tmp_path, name, text):
    source = tmp_path / name
    source.write_text(text)
    out, scene = converted(source, tmp_path)
    root = assert_laid_out(out)
    # the content is unchanged: the same scene reads back, comments kept
    again = sg.load(out)
    assert world(again) == world(scene)
    assert [shape[0] for shape in world(again)] == ["crate", "floor", "wedge"]
    crate = next(shape for shape in again.shapes if shape.name == "crate")
    assert np.ptp(crate.world_vertices, axis=0).tolist() == [1.0, 2.0, 1.0]
    comments = [comment.text for comment in root.iter(etree.Comment)]
    assert [text.strip() for text in comments] == ["a lamp over a crate", "the crate"]
    # Transform > Transform > Shape: three levels under <Scene>
    wedge = root.find(".//Shape[@DEF='wedge']")
    assert etree.tostring(wedge).startswith(b"<Shape")
    assert f'\n{" " * 8}<Shape DEF="wedge">' in out.read_text()


def test_a_scripts_source_keeps_every_character(tmp_path):
    source = tmp_path / "scene.x3dj"
    source.write_text(json.dumps(JSON))
    out, _ = converted(source, tmp_path)
    root = etree.parse(str(out)).getroot()
    script = root.find("Scene/Script[@DEF='s']")
    assert script.text == SOURCE  # before its field, not re-indented
    assert [field.get("name") for field in script] == ["a"]
    blank = root.find("Scene/Script[@DEF='blank']")
    assert blank.text == " \n  " and len(blank) == 1  # whitespace is source too
    assert b"<![CDATA[\necmascript:\nfunction initialize() { a = b < c; }\n]]>" in out.read_bytes()


def test_added_shadow_groups_follow_the_same_layout(tmp_path):
    source = tmp_path / "scene.x3dv"
    source.write_text(CLASSIC)
    out, _ = converted(source, tmp_path, shadows=True)
    root = assert_laid_out(out)
    group = root.find("Scene/Group[@DEF='shadows_lamp']")
    assert group is not None and len(group) > 0
    assert '\n    <Group DEF="shadows_lamp"' in out.read_text()


@pytest.mark.parametrize(
    "text",
    [
        # the author's own layout: tabs, a blank line, two nodes on one line (each
        # scene has its Viewpoint, so the writer adds none)
        '<?xml version="1.0" encoding="UTF-8"?>\n<X3D profile="Interchange" version="4.0">\n'
        '\t<Scene><Viewpoint position="0 1 10"/>\n\n\t\t<Transform translation="0 1 0">'
        '<Shape DEF="crate"><Box/></Shape></Transform>\n'
        "   <!-- odd -->\n\t</Scene>\n</X3D>\n",
        # and none at all: XML is never laid out again
        '<?xml version="1.0" encoding="UTF-8"?>\n<X3D profile="Interchange" version="4.0">'
        '<Scene><Viewpoint position="0 1 10"/><Transform translation="0 1 0"><Shape DEF="crate">'
        "<Box/></Shape></Transform></Scene></X3D>\n",
    ],
)
def test_xml_input_keeps_its_authors_layout(tmp_path, text):
    source = tmp_path / "scene.x3d"
    source.write_text(text)
    out = tmp_path / "out.x3d"
    sg.save(sg.load(source), out)
    assert out.read_text() == text


def test_corpus_classic_vrml97_and_json_are_laid_out(classic_corpus_dir, pairs_dir, tmp_path):
    sources = [
        classic_corpus_dir / "x3d" / "kings_head.x3dv",
        classic_corpus_dir / "vrml_engine_doc_simple_examples" / "creaseangle.wrl",
        pairs_dir / "BoxEm.json",
    ]
    for source in sources:
        folder = tmp_path / source.suffix[1:]
        folder.mkdir()
        out, scene = converted(source, folder)
        root = assert_laid_out(out)
        assert len(out.read_text().splitlines()) > sum(1 for _ in root.iter())
        again = sg.load(out)
        assert world(again) == world(scene) and len(scene.shapes) > 0
