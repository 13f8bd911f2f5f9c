"""Prototypes across files and through nesting, and Scripts that build geometry:
small scenes written here in ClassicVRML, XML and JSON, checked against box
corners derived by hand, and the corpus's EXTERNPROTO teapot."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

import shadowgeo as sg

HEAD = "#X3D V4.0 utf8\nPROFILE Immersive\n"


def xml(body: str) -> str:
    declaration = '<?xml version="1.0" encoding="UTF-8"?>'
    return f'{declaration}\n<X3D version="4.0"><Scene>\n{body}\n</Scene></X3D>\n'


def corners(low, high) -> set[tuple[float, float, float]]:
    """The eight corners of the box from ``low`` to ``high``."""
    return {
        (x, y, z) for x in (low[0], high[0]) for y in (low[1], high[1]) for z in (low[2], high[2])
    }


def boxes(scene) -> list[set[tuple[float, float, float]]]:
    """Each shape's distinct world vertices (a Box's are its eight corners)."""
    found = []
    for shape in scene.shapes:
        points = np.unique(np.round(shape.world_vertices, 9), axis=0)
        found.append({tuple(float(v) for v in point) for point in points})
    return found


def proto_notes(scene) -> list[str]:
    return [note for note in scene.warnings if "ProtoInstance" in note]


# -- EXTERNPROTO in a sibling file --------------------------------------------------------

# A library of two prototypes: First (a box of its size at the origin) and
# Crate (a box of its size, default 2 2 2, lifted 5 along y).
LIB_CLASSIC = (
    HEAD
    + """
PROTO First [ initializeOnly SFVec3f size 1 1 1 ] { Shape { geometry Box { size IS size } } }
PROTO Crate [ initializeOnly SFVec3f size 2 2 2 ] {
  Transform { translation 0 5 0 children Shape { geometry Box { size IS size } } }
}
"""
)
MAIN_CLASSIC = (
    HEAD
    + """
EXTERNPROTO MyCrate [ initializeOnly SFVec3f size ] [ "urn:x-none:Crate" "gone.x3dv#Crate"
  "lib.x3dv#Crate" ]
EXTERNPROTO Plain [ initializeOnly SFVec3f size ] "lib.x3dv"
Transform { translation 10 0 0 children MyCrate { size 4 6 8 } }
MyCrate { }
Plain { }
"""
)

_SIZE_IS = '<IS><connect nodeField="size" protoField="size"/></IS>'


def _xml_proto(name: str, default: str, body: str) -> str:
    return (
        f'<ProtoDeclare name="{name}"><ProtoInterface><field name="size" type="SFVec3f" '
        f'accessType="initializeOnly" value="{default}"/></ProtoInterface>'
        f"<ProtoBody>{body}</ProtoBody></ProtoDeclare>"
    )


def _xml_extern(name: str, url: str) -> str:
    return (
        f'<ExternProtoDeclare name="{name}" url=\'{url}\'><field name="size" type="SFVec3f" '
        'accessType="initializeOnly"/></ExternProtoDeclare>'
    )


LIB_XML = xml(
    _xml_proto("First", "1 1 1", f"<Shape><Box>{_SIZE_IS}</Box></Shape>")
    + _xml_proto(
        "Crate",
        "2 2 2",
        f'<Transform translation="0 5 0"><Shape><Box>{_SIZE_IS}</Box></Shape></Transform>',
    )
)
MAIN_XML = xml(
    _xml_extern("MyCrate", '"urn:x-none:Crate" "gone.x3d#Crate" "lib.x3d#Crate"')
    + _xml_extern("Plain", '"lib.x3d"')
    + '<Transform translation="10 0 0"><ProtoInstance name="MyCrate">'
    '<fieldValue name="size" value="4 6 8"/></ProtoInstance></Transform>'
    '<ProtoInstance name="MyCrate"/><ProtoInstance name="Plain"/>'
)


def _json_document(children: list) -> str:
    document = {"X3D": {"encoding": "UTF-8", "@version": "4.0", "Scene": {"-children": children}}}
    return json.dumps(document, indent=1)


def _json_size_field(default=None) -> dict:
    field = {"@name": "size", "@type": "SFVec3f", "@accessType": "initializeOnly"}
    return field if default is None else {**field, "@value": default}


_JSON_BOX = {
    "Shape": {
        "-geometry": {"Box": {"IS": {"connect": [{"@nodeField": "size", "@protoField": "size"}]}}}
    }
}


def _json_proto(name: str, default: list, body: dict) -> dict:
    return {
        "ProtoDeclare": {
            "@name": name,
            "ProtoInterface": {"field": [_json_size_field(default)]},
            "ProtoBody": {"-children": [body]},
        }
    }


def _json_extern(name: str, urls: list) -> dict:
    return {"ExternProtoDeclare": {"@name": name, "@url": urls, "field": [_json_size_field()]}}


LIB_JSON = _json_document(
    [
        _json_proto("First", [1, 1, 1], _JSON_BOX),
        _json_proto(
            "Crate",
            [2, 2, 2],
            {"Transform": {"@translation": [0, 5, 0], "-children": [_JSON_BOX]}},
        ),
    ]
)
MAIN_JSON = _json_document(
    [
        _json_extern("MyCrate", ["urn:x-none:Crate", "gone.x3dj#Crate", "lib.x3dj#Crate"]),
        _json_extern("Plain", ["lib.x3dj"]),
        {
            "Transform": {
                "@translation": [10, 0, 0],
                "-children": [
                    {
                        "ProtoInstance": {
                            "@name": "MyCrate",
                            "fieldValue": [{"@name": "size", "@value": [4, 6, 8]}],
                        }
                    }
                ],
            }
        },
        {"ProtoInstance": {"@name": "MyCrate"}},
        {"ProtoInstance": {"@name": "Plain"}},
    ]
)

ENCODINGS = {
    "classic": (".x3dv", LIB_CLASSIC, MAIN_CLASSIC),
    "xml": (".x3d", LIB_XML, MAIN_XML),
    "json": (".x3dj", LIB_JSON, MAIN_JSON),
}


@pytest.mark.parametrize("encoding", list(ENCODINGS))
def test_externproto_of_a_sibling_file_is_expanded(tmp_path, encoding):
    suffix, lib, main = ENCODINGS[encoding]
    (tmp_path / f"lib{suffix}").write_text(lib)
    (tmp_path / f"main{suffix}").write_text(main)
    scene = sg.load(tmp_path / f"main{suffix}")
    # MyCrate: the url list's first local file that exists, its PROTO Crate
    # (a size-(4, 6, 8) box lifted 5, moved 10 along x; then the default
    # 2 x 2 x 2); Plain: no fragment, the file's first PROTO (a unit box)
    assert boxes(scene) == [
        corners((8, 2, -4), (12, 8, 4)),
        corners((-1, 4, -1), (1, 6, 1)),
        corners((-0.5, -0.5, -0.5), (0.5, 0.5, 0.5)),
    ]
    assert proto_notes(scene) == []
    # the shapes say which file their geometry comes from
    assert all(shape.source.startswith(f"lib{suffix} line ") for shape in scene.shapes)


def test_externproto_across_encodings_and_from_a_subfolder(tmp_path):
    """An XML scene's EXTERNPROTO names a ClassicVRML file in a subfolder,
    whose own EXTERNPROTO (relative to that file) names a JSON file beside it."""
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "lib.x3dv").write_text(
        HEAD + 'EXTERNPROTO Deep [ initializeOnly SFVec3f size ] "deep.x3dj#Crate"\n'
        "PROTO Outer [ initializeOnly SFVec3f size 3 3 3 ] { Deep { size IS size } }\n"
    )
    (tmp_path / "parts" / "deep.x3dj").write_text(LIB_JSON)
    (tmp_path / "main.x3d").write_text(
        xml(_xml_extern("Outer", '"parts/lib.x3dv#Outer"') + '<ProtoInstance name="Outer"/>')
    )
    scene = sg.load(tmp_path / "main.x3d")
    assert boxes(scene) == [corners((-1.5, 3.5, -1.5), (1.5, 6.5, 1.5))]
    assert scene.shapes[0].source.startswith("deep.x3dj line ")


def test_urls_are_taken_from_the_file_each_node_was_written_in(tmp_path):
    """The Inlines in the prototype's body and in its field's default are
    parts/box.x3dv (beside the prototype's file); the one the scene passes in
    through a field is box.x3dv beside the scene. (Two files of one name,
    boxes of two sizes.)"""
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "lib.x3dv").write_text(
        HEAD + "PROTO Holder [ initializeOnly MFNode content [ ]\n"
        "  initializeOnly MFNode fallback [\n"
        '    Transform { translation 0 20 0 children Inline { url "box.x3dv" } } ] ] {\n'
        '  Group { children [ Inline { url "box.x3dv" } Group { children IS content }\n'
        "                     Group { children IS fallback } ] }\n}\n"
    )
    (tmp_path / "parts" / "box.x3dv").write_text(HEAD + "Shape { geometry Box { size 2 2 2 } }\n")
    (tmp_path / "box.x3dv").write_text(HEAD + "Shape { geometry Box { size 6 6 6 } }\n")
    (tmp_path / "main.x3dv").write_text(
        HEAD + "EXTERNPROTO Holder [ initializeOnly MFNode content initializeOnly MFNode fallback ]"
        ' "parts/lib.x3dv#Holder"\n'
        'Holder { content Transform { translation 10 0 0 children Inline { url "box.x3dv" } } }\n'
    )
    scene = sg.load(tmp_path / "main.x3dv")
    assert boxes(scene) == [
        corners((-1, -1, -1), (1, 1, 1)),
        corners((7, -3, -3), (13, 3, 3)),
        corners((-1, 19, -1), (1, 21, 1)),
    ]
    assert not [note for note in scene.warnings if "Inline" in note]


UNRESOLVED = (
    HEAD
    + """Shape { geometry Box { } }
EXTERNPROTO Gone [ ] "missing.x3dv#Gone"
EXTERNPROTO Out [ ] "../outside.x3dv#Out"
EXTERNPROTO Far [ ] "https://example.com/far.x3dv#Far"
EXTERNPROTO Nameless [ ] "lib.x3dv#Nobody"
Gone { }
Out { }
Far { }
Nameless { }
"""
)


def test_externprotos_that_cannot_be_followed_are_skipped_with_a_note(tmp_path):
    folder = tmp_path / "scene"
    folder.mkdir()
    # a PROTO outside the scene's folder that would draw a box: never read
    (tmp_path / "outside.x3dv").write_text(HEAD + "PROTO Out [ ] { Shape { geometry Box { } } }\n")
    (folder / "lib.x3dv").write_text(LIB_CLASSIC)
    path = folder / "scene.x3dv"
    path.write_text(UNRESOLVED)
    scene = sg.load(path)
    assert len(scene.shapes) == 1  # the scene's own box only
    notes = proto_notes(scene)
    expected = [
        (8, "Gone", "'missing.x3dv#Gone' not found"),
        (9, "Out", "'../outside.x3dv#Out' leaves the scene's folder"),
        (10, "Far", "'https://example.com/far.x3dv#Far' is remote (never fetched)"),
        (11, "Nameless", "'lib.x3dv#Nobody': lib.x3dv declares no PROTO 'Nobody'"),
    ]
    assert len(notes) == len(expected)
    for note, (line, name, why) in zip(notes, expected, strict=True):
        assert note.startswith(f"{path} line {line}, ProtoInstance")
        assert f"ProtoInstance name='{name}' skipped" in note and why in note
        assert f"EXTERNPROTO at scene.x3dv line {line - 4}" in note


def test_an_xml_externproto_outside_the_folder_is_skipped_with_a_note(tmp_path):
    folder = tmp_path / "scene"
    folder.mkdir()
    (tmp_path / "outside.x3d").write_text(LIB_XML)
    path = folder / "scene.x3d"
    path.write_text(
        xml(_xml_extern("Out", '"../outside.x3d#First"') + '\n<ProtoInstance name="Out"/>')
    )
    scene = sg.load(path)
    assert scene.shapes == []
    (note,) = proto_notes(scene)
    assert note.startswith(f"{path} line 4, ProtoInstance")
    assert "'../outside.x3d#First' leaves the scene's folder" in note


def test_an_externproto_cycle_is_refused(tmp_path):
    # a.x3dv's EXTERNPROTO names b.x3dv's, which names a.x3dv's again
    (tmp_path / "a.x3dv").write_text(HEAD + 'EXTERNPROTO P [ ] "b.x3dv#P"\nP { }\n')
    (tmp_path / "b.x3dv").write_text(HEAD + 'EXTERNPROTO P [ ] "a.x3dv#P"\n')
    with pytest.raises(sg.SceneError, match="EXTERNPROTO cycle"):
        sg.load(tmp_path / "a.x3dv")


def test_prototypes_of_two_files_inside_each_other_are_refused(tmp_path):
    # a's P holds b's Q, whose body holds a's P again: a copy for ever
    (tmp_path / "a.x3dv").write_text(
        HEAD + 'EXTERNPROTO Q [ ] "b.x3dv#Q"\nPROTO P [ ] { Group { children Q { } } }\nP { }\n'
    )
    (tmp_path / "b.x3dv").write_text(
        HEAD + 'EXTERNPROTO P [ ] "a.x3dv#P"\n'
        "PROTO Q [ ] { Group { children [ Shape { geometry Box { } } P { } ] } }\n"
    )
    with pytest.raises(sg.SceneError, match=r"prototype '[PQ]' is used inside its own body"):
        sg.load(tmp_path / "a.x3dv")


def test_externproto_files_nested_beyond_the_limit_are_refused(tmp_path):
    from shadowgeo import limits

    # f0's PROTO holds f1's, which holds f2's, ... one file deeper each
    count = limits.MAX_INLINE_DEPTH + 2
    for k in range(count):
        (tmp_path / f"f{k}.x3dv").write_text(
            HEAD + f'EXTERNPROTO Next [ ] "f{k + 1}.x3dv#P"\n'
            "PROTO P [ ] { Group { children [ Shape { geometry Box { } } Next { } ] } }\n"
            + ("P { }\n" if k == 0 else "")
        )
    with pytest.raises(sg.SceneError, match=f"EXTERNPROTO files nested more than {count - 2}"):
        sg.load(tmp_path / "f0.x3dv")
    # the same chain, one file short of the limit, reads every box
    (tmp_path / f"f{count - 3}.x3dv").write_text(
        HEAD + "PROTO P [ ] { Shape { geometry Box { } } }\n"
    )
    assert len(sg.load(tmp_path / "f0.x3dv").shapes) == count - 2


# -- IS through nested prototypes ---------------------------------------------------------

NESTED_CLASSIC = (
    HEAD
    + """
PROTO InnerBox [ initializeOnly SFVec3f size 1 1 1  initializeOnly SFNode look NULL
                 initializeOnly MFNode extra [ ] ] {
  Group { children [ Shape { appearance IS look geometry Box { size IS size } }
                     Group { children IS extra } ] }
}
PROTO ABox [ initializeOnly SFVec3f boxSize 140 140 140
             initializeOnly SFNode boxLook Appearance { material Material { diffuseColor 1 0 0 } }
             initializeOnly MFNode boxExtra [
               Transform { translation 0 100 0
                           children Shape { geometry Box { size 2 2 2 } } } ] ] {
  InnerBox { size IS boxSize look IS boxLook extra IS boxExtra }
}
ABox { }
Transform { translation 500 0 0 children ABox {
  boxSize 2 4 6 boxLook Appearance { material Material { diffuseColor 0 0 1 } } } }
"""
)

_NESTED_INNER = (
    '<ProtoDeclare name="InnerBox"><ProtoInterface>'
    '<field name="size" type="SFVec3f" accessType="initializeOnly" value="1 1 1"/>'
    '<field name="look" type="SFNode" accessType="initializeOnly"/>'
    '<field name="extra" type="MFNode" accessType="initializeOnly"/>'
    "</ProtoInterface><ProtoBody><Group>"
    '<Shape><IS><connect nodeField="appearance" protoField="look"/></IS>'
    '<Box><IS><connect nodeField="size" protoField="size"/></IS></Box></Shape>'
    '<Group><IS><connect nodeField="children" protoField="extra"/></IS></Group>'
    "</Group></ProtoBody></ProtoDeclare>"
)
NESTED_XML = xml(
    _NESTED_INNER + '<ProtoDeclare name="ABox"><ProtoInterface>'
    '<field name="boxSize" type="SFVec3f" accessType="initializeOnly" value="140 140 140"/>'
    '<field name="boxLook" type="SFNode" accessType="initializeOnly">'
    '<Appearance><Material diffuseColor="1 0 0"/></Appearance></field>'
    '<field name="boxExtra" type="MFNode" accessType="initializeOnly">'
    '<Transform translation="0 100 0"><Shape><Box size="2 2 2"/></Shape></Transform></field>'
    "</ProtoInterface><ProtoBody>"
    '<ProtoInstance name="InnerBox"><IS><connect nodeField="size" protoField="boxSize"/>'
    '<connect nodeField="look" protoField="boxLook"/>'
    '<connect nodeField="extra" protoField="boxExtra"/></IS></ProtoInstance>'
    "</ProtoBody></ProtoDeclare>"
    '<ProtoInstance name="ABox"/>'
    '<Transform translation="500 0 0"><ProtoInstance name="ABox">'
    '<fieldValue name="boxSize" value="2 4 6"/><fieldValue name="boxLook">'
    '<Appearance><Material diffuseColor="0 0 1"/></Appearance></fieldValue>'
    "</ProtoInstance></Transform>"
)


def _connects(*pairs: tuple[str, str]) -> dict:
    return {"connect": [{"@nodeField": node, "@protoField": proto} for node, proto in pairs]}


def _look(colour: list) -> dict:
    return {"Appearance": {"-material": {"Material": {"@diffuseColor": colour}}}}


NESTED_JSON = _json_document(
    [
        {
            "ProtoDeclare": {
                "@name": "InnerBox",
                "ProtoInterface": {
                    "field": [
                        _json_size_field([1, 1, 1]),
                        {"@name": "look", "@type": "SFNode", "@accessType": "initializeOnly"},
                        {"@name": "extra", "@type": "MFNode", "@accessType": "initializeOnly"},
                    ]
                },
                "ProtoBody": {
                    "-children": [
                        {
                            "Group": {
                                "-children": [
                                    {
                                        "Shape": {
                                            "IS": _connects(("appearance", "look")),
                                            "-geometry": {
                                                "Box": {"IS": _connects(("size", "size"))}
                                            },
                                        }
                                    },
                                    {"Group": {"IS": _connects(("children", "extra"))}},
                                ]
                            }
                        }
                    ]
                },
            }
        },
        {
            "ProtoDeclare": {
                "@name": "ABox",
                "ProtoInterface": {
                    "field": [
                        {
                            "@name": "boxSize",
                            "@type": "SFVec3f",
                            "@accessType": "initializeOnly",
                            "@value": [140, 140, 140],
                        },
                        {
                            "@name": "boxLook",
                            "@type": "SFNode",
                            "@accessType": "initializeOnly",
                            "-children": [_look([1, 0, 0])],
                        },
                        {
                            "@name": "boxExtra",
                            "@type": "MFNode",
                            "@accessType": "initializeOnly",
                            "-children": [
                                {
                                    "Transform": {
                                        "@translation": [0, 100, 0],
                                        "-children": [
                                            {"Shape": {"-geometry": {"Box": {"@size": [2, 2, 2]}}}}
                                        ],
                                    }
                                }
                            ],
                        },
                    ]
                },
                "ProtoBody": {
                    "-children": [
                        {
                            "ProtoInstance": {
                                "@name": "InnerBox",
                                "IS": _connects(
                                    ("size", "boxSize"), ("look", "boxLook"), ("extra", "boxExtra")
                                ),
                            }
                        }
                    ]
                },
            }
        },
        {"ProtoInstance": {"@name": "ABox"}},
        {
            "Transform": {
                "@translation": [500, 0, 0],
                "-children": [
                    {
                        "ProtoInstance": {
                            "@name": "ABox",
                            "fieldValue": [
                                {"@name": "boxSize", "@value": [2, 4, 6]},
                                {"@name": "boxLook", "-children": [_look([0, 0, 1])]},
                            ],
                        }
                    }
                ],
            }
        },
    ]
)

NESTED = {
    "classic": (".x3dv", NESTED_CLASSIC),
    "xml": (".x3d", NESTED_XML),
    "json": (".x3dj", NESTED_JSON),
}


@pytest.mark.parametrize("encoding", list(NESTED))
def test_is_is_followed_through_nested_prototypes(tmp_path, encoding):
    suffix, text = NESTED[encoding]
    path = tmp_path / f"abox{suffix}"
    path.write_text(text)
    scene = sg.load(path)
    assert proto_notes(scene) == []
    # ABox's default boxSize 140 reaches InnerBox's Box: corners at +-70; its
    # default look (red) and extra box (2 wide, lifted 100) come along too.
    # The second ABox: its own size 2 4 6 and blue look, moved 500 along x,
    # with the default extra box.
    assert boxes(scene) == [
        corners((-70, -70, -70), (70, 70, 70)),
        corners((-1, 99, -1), (1, 101, 1)),
        corners((499, -2, -3), (501, 2, 3)),
        corners((499, 99, -1), (501, 101, 1)),
    ]
    colours = [shape.material.diffuse_color for shape in scene.shapes]
    assert colours[0] == (1, 0, 0) and colours[2] == (0, 0, 1)


def test_a_null_node_passed_on_overrides_the_inner_default(tmp_path):
    # Outer's look is NULL and reaches Inner's look through IS: the Shape has
    # no appearance (unlit, as X3D draws a Shape without one), not Inner's green
    # default; Outer's size (8) reaches the Box. Without IS, Inner's defaults.
    path = tmp_path / "defaults.x3dv"
    path.write_text(
        HEAD + "PROTO Inner [ initializeOnly SFNode look Appearance { material Material {"
        " diffuseColor 0 1 0 } } initializeOnly SFVec3f size 1 1 1 ] {"
        " Shape { appearance IS look geometry Box { size IS size } } }\n"
        "PROTO Outer [ initializeOnly SFNode look NULL initializeOnly SFVec3f size 8 8 8 ] {"
        " Inner { look IS look size IS size } }\n"
        "Outer { }\nTransform { translation 20 0 0 children Inner { } }\n"
    )
    scene = sg.load(path)
    assert boxes(scene) == [
        corners((-4, -4, -4), (4, 4, 4)),
        corners((19.5, -0.5, -0.5), (20.5, 0.5, 0.5)),
    ]
    unlit, green = (shape.material for shape in scene.shapes)
    assert unlit.emissive_color == (1, 1, 1) and green.diffuse_color == (0, 1, 0)


def test_a_prototype_passed_into_its_own_instance_is_no_cycle(tmp_path):
    # the inner Frame is written in the scene, not in Frame's body: finite
    path = tmp_path / "frames.x3dv"
    path.write_text(
        HEAD
        + "PROTO Frame [ initializeOnly MFNode inside [ ] initializeOnly SFVec3f at 0 0 0 ] {\n"
        "  Transform { translation IS at\n"
        "    children [ Shape { geometry Box { } } Group { children IS inside } ] } }\n"
        "Frame { at 10 0 0 inside [ Frame { at 0 10 0 } ] }\n"
    )
    scene = sg.load(path)
    assert boxes(scene) == [corners((9, -1, -1), (11, 1, 1)), corners((9, 9, -1), (11, 11, 1))]


# -- Scripts that build geometry ----------------------------------------------------------

SCRIPTS_CLASSIC = (
    HEAD
    + """DEF holder Group { }
Shape { geometry Box { } }
DEF builder Script {
  outputOnly MFNode made
  url "ecmascript: function initialize() { }"
}
ROUTE builder.made TO holder.addChildren
DEF other Script { url "ecmascript: function initialize() { }" }
"""
)
SCRIPTS_XML = xml(
    '<Group DEF="holder"/><Shape><Box/></Shape>\n'
    '<Script DEF="builder"><field name="made" type="MFNode" accessType="outputOnly"/></Script>\n'
    '<ROUTE fromNode="builder" fromField="made" toNode="holder" toField="addChildren"/>'
    '<Script DEF="other"/>'
)


@pytest.mark.parametrize(
    ("suffix", "text", "line"), [(".x3dv", SCRIPTS_CLASSIC, 5), (".x3d", SCRIPTS_XML, 4)]
)
def test_a_script_that_builds_geometry_is_named_in_one_note(tmp_path, suffix, text, line):
    path = tmp_path / f"scene{suffix}"
    path.write_text(text)
    scene = sg.load(path)
    assert len(scene.shapes) == 1
    notes = [note for note in scene.warnings if "Script" in note]
    assert notes == [
        f"{path} line {line}, Script DEF='builder': geometry is built by this Script, which "
        "shadowgeo does not run; what it builds casts no shadow"
    ]


def test_a_script_with_direct_output_to_coordinates_builds_geometry(tmp_path):
    path = tmp_path / "scene.x3d"
    path.write_text(
        xml(
            '<Shape><IndexedFaceSet coordIndex="0 1 2 -1"><Coordinate DEF="points" '
            'point="0 0 0 1 0 0 0 1 0"/></IndexedFaceSet></Shape>\n'
            '<Script DEF="mover" directOutput="true"><field name="target" type="SFNode" '
            'accessType="initializeOnly"><Coordinate USE="points"/></field></Script>'
        )
    )
    (note,) = [note for note in sg.load(path).warnings if "Script" in note]
    assert note.startswith(f"{path} line 4, Script DEF='mover': geometry is built by")


def test_scripts_that_build_no_geometry(tmp_path):
    # a Script driving a clock in a scene with geometry: the usual note only
    path = tmp_path / "clock.x3dv"
    path.write_text(
        HEAD + "Shape { geometry Box { } }\nDEF clock TimeSensor { }\n"
        'DEF tick Script { outputOnly SFTime at url "ecmascript: " }\n'
        "ROUTE tick.at TO clock.startTime\n"
    )
    notes = [note for note in sg.load(path).warnings if "Script" in note]
    assert len(notes) == 1 and re.search(r"line 5, Script DEF='tick': skipped", notes[0])
    # the same Script in a scene with no geometry: it may build what is missing
    path.write_text(
        HEAD + "DEF clock TimeSensor { }\n"
        'DEF tick Script { outputOnly SFTime at url "ecmascript: " }\n'
        "ROUTE tick.at TO clock.startTime\n"
    )
    notes = [note for note in sg.load(path).warnings if "Script" in note]
    assert notes == [
        f"{path} line 4, Script DEF='tick': no geometry was read, and this Script may build "
        "it when run, which shadowgeo does not do"
    ]


# -- the corpus ---------------------------------------------------------------------------


def test_corpus_teapot_drawn_through_an_externproto_casts(classic_corpus_dir):
    path = classic_corpus_dir / "prototypes" / "teapot_externproto.x3dv"
    scene = sg.load(path)
    assert len(scene.shapes) == 1 and proto_notes(scene) == []
    assert scene.shapes[0].source.startswith("teapot_fallback_implementation.x3dv line ")
    sun = sg.SceneLight(sg.DirectionalLight([0.3, -1, 0.2]), name="sun", shadows=True)
    lit = sg.Scene(scene.shapes, [sun], path=scene.path)
    shadows = sg.add_shadows(lit, plane=(0, 1, 0, 1)).shapes_with_role("shadow")
    assert shadows and sum(shadow.n_faces for shadow in shadows) > 0
