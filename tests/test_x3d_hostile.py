"""Bad and hostile X3D: a SceneError naming file, line and node, or a warning;
never a traceback, never an entity expanded, never the network."""

from __future__ import annotations

import gzip
import json
import socket

import numpy as np
import pytest

import shadowgeo as sg
from shadowgeo.io.x3d import parse as x3d_parse
from shadowgeo.io.x3d import read as x3d_read

TRIANGLE = '<Coordinate point="0 0 0 1 0 0 0 1 0"/>'


def write(tmp_path, text: str, name: str = "scene.x3d"):
    path = tmp_path / name
    path.write_text(text)
    return path


def scene(tmp_path, body: str, name: str = "scene.x3d"):
    return write(tmp_path, f'<X3D version="4.0"><Scene>\n{body}\n</Scene></X3D>', name)


@pytest.fixture
def no_network(monkeypatch):
    """Any attempt to open a socket fails the test."""

    def refuse(*args, **kwargs):
        raise AssertionError("the reader tried to use the network")

    monkeypatch.setattr(socket, "socket", refuse)
    monkeypatch.setattr(socket, "create_connection", refuse)


def test_malformed_xml_gives_the_line(tmp_path):
    path = write(tmp_path, '<X3D version="4.0"><Scene>\n<Group>\n<Shape>\n</Group></Scene></X3D>')
    with pytest.raises(sg.SceneError, match=r"scene.x3d line 4: malformed XML") as error:
        sg.load(path)
    assert error.value.line == 4


def test_not_x3d(tmp_path):
    path = write(tmp_path, "<html><body/></html>")
    with pytest.raises(sg.SceneError, match=r"root element is <html>, not <X3D>"):
        sg.load(path)
    path = write(tmp_path, '<X3D version="4.0"><head/></X3D>')
    with pytest.raises(sg.SceneError, match=r"no <Scene> element"):
        sg.load(path)


def warnings_of(path) -> str:
    return "\n".join(sg.load(path).warnings)


def test_text_in_a_vector_field_takes_the_default_with_a_note(tmp_path):
    body = (
        '<Transform DEF="arm" translation="1 abc 3" scale="2 2 2"><Shape><Box/></Shape></Transform>'
    )
    path = scene(tmp_path, body)
    result = sg.load(path)
    (shape,) = result.shapes  # the rest of the node is read: scaled, not moved
    np.testing.assert_array_equal(shape.world_vertices.min(axis=0), [-2, -2, -2])
    (warning,) = result.warnings
    assert warning == (
        f"{path} line 2, Transform DEF='arm': field translation: '1 abc 3' is not numbers "
        "(SFVec3f: 'abc' is not a number); the default '0 0 0' is used"
    )


@pytest.mark.parametrize(
    "body, expected",
    [
        ('<Transform scale="1 2"/>', "field scale: '1 2' is not 3 numbers"),
        ('<Shape><Sphere solid="maybe"/></Shape>', "field solid: 'maybe' is not a boolean"),
        ('<Shape><Box size="1 nan 1"/></Shape>', "field size: '1 nan 1' has a value that is not"),
        ('<Switch whichChoice="1.5"/>', "field whichChoice: '1.5' is not an integer"),
        (f'<Shape><IndexedFaceSet coordIndex="0 1 2.5">{TRIANGLE}</IndexedFaceSet></Shape>',
         "field coordIndex: '0 1 2.5' has a value that is not an integer"),
        ('<Shape><IndexedFaceSet coordIndex="0 1 2"><Coordinate point="0 0 0 1 0"/>'
         "</IndexedFaceSet></Shape>", "field point: '0 0 0 1 0' has 5 numbers, not a multiple"),
    ],
)  # fmt: skip
def test_wrong_field_types_take_the_default_with_a_note(tmp_path, body, expected):
    path = scene(tmp_path, body + "\n<Shape DEF='after'><Box/></Shape>")
    result = sg.load(path)
    assert result.shapes[-1].name == "after"  # the reader goes on
    text = "\n".join(result.warnings)
    assert "line 2, " in text and expected in text and "; the default '" in text


def test_coord_index_out_of_range_skips_that_shape(tmp_path):
    body = f'<Shape><IndexedFaceSet DEF="roof" coordIndex="0 1 17 -1">{TRIANGLE}</IndexedFaceSet>'
    body += "</Shape>\n<Shape DEF='after'><Box/></Shape>"
    path = scene(tmp_path, body)
    result = sg.load(path)
    assert [shape.name for shape in result.shapes] == ["after"]
    assert result.warnings == [
        f"{path} line 2, IndexedFaceSet DEF='roof': "
        "coordIndex 17 is out of range (3 points); the Shape is skipped"
    ]


def test_index_out_of_range_in_triangle_sets(tmp_path):
    body = f'<Shape><IndexedTriangleSet index="0 1 3">{TRIANGLE}</IndexedTriangleSet></Shape>'
    assert "line 2, IndexedTriangleSet: index 3 is out of range" in warnings_of(
        scene(tmp_path, body)
    )
    body = f'<Shape><IndexedFaceSet coordIndex="0 1 -2">{TRIANGLE}</IndexedFaceSet></Shape>'
    assert "coordIndex -2 is out of range" in warnings_of(scene(tmp_path, body))


def test_empty_geometry_is_skipped_with_a_warning(tmp_path):
    body = (
        '<Shape><IndexedFaceSet coordIndex=""><Coordinate/></IndexedFaceSet></Shape>\n'
        '<Shape><IndexedFaceSet coordIndex="0 1 -1">' + TRIANGLE + "</IndexedFaceSet></Shape>\n"
        '<Shape><ElevationGrid xDimension="1" zDimension="1" height="0"/></Shape>\n'
        "<Shape/>\n"
        '<Shape><IndexedFaceSet coordIndex="0 1 2"/></Shape>\n'
        '<Shape><Box size="1 1 1"/></Shape>'
    )
    result = sg.load(scene(tmp_path, body))
    assert len(result.shapes) == 1 and result.shapes[0].n_faces == 12
    text = "\n".join(result.warnings)
    assert "line 2, IndexedFaceSet: empty geometry" in text
    assert "line 3, IndexedFaceSet: 1 polygon(s) with fewer than 3 points skipped" in text
    assert "line 3, IndexedFaceSet: empty geometry" in text
    assert "line 4, ElevationGrid: empty geometry" in text
    assert "line 5, Shape: Shape without geometry" in text
    assert "line 6, IndexedFaceSet: no Coordinate node" in text


def test_def_cycle_is_refused(tmp_path):
    body = '<Transform DEF="loop"><Group><Transform USE="loop"/></Group></Transform>'
    with pytest.raises(sg.SceneError, match=r"line 2, Transform USE='loop': DEF/USE cycle"):
        sg.load(scene(tmp_path, body))


def test_use_of_an_unknown_def_is_skipped(tmp_path):
    path = scene(tmp_path, '<Group USE="ghost"/><Shape><Box/></Shape>')
    result = sg.load(path)
    assert len(result.shapes) == 1
    assert result.warnings == [
        f"{path} line 2, Group USE='ghost': USE='ghost' names no DEF in this file; skipped"
    ]


def test_external_entity_is_refused_and_never_read(tmp_path, no_network):
    secret = write(tmp_path, "TOP-SECRET", "secret.txt")
    text = (
        f'<?xml version="1.0"?>\n<!DOCTYPE X3D [ <!ENTITY leak SYSTEM "file://{secret}"> ]>\n'
        '<X3D version="4.0"><Scene><WorldInfo title="&leak;"/></Scene></X3D>'
    )
    with pytest.raises(sg.SceneError, match="entit") as error:
        sg.load(write(tmp_path, text))
    assert "TOP-SECRET" not in str(error.value)


def test_remote_external_entity_never_fetched(tmp_path, no_network):
    text = (
        '<?xml version="1.0"?>\n<!DOCTYPE X3D [ <!ENTITY remote SYSTEM "http://example.com/x"> ]>\n'
        '<X3D version="4.0"><Scene><WorldInfo title="&remote;"/></Scene></X3D>'
    )
    with pytest.raises(sg.SceneError, match="entit"):
        sg.load(write(tmp_path, text))


def test_billion_laughs_is_refused(tmp_path):
    levels = ['<!ENTITY lol0 "lol">'] + [
        f'<!ENTITY lol{i} "{("&lol" + str(i - 1) + ";") * 10}">' for i in range(1, 10)
    ]
    text = (
        f'<?xml version="1.0"?>\n<!DOCTYPE X3D [ {" ".join(levels)} ]>\n'
        '<X3D version="4.0"><Scene><WorldInfo title="&lol9;"/></Scene></X3D>'
    )
    with pytest.raises(sg.SceneError, match="entit"):
        sg.load(write(tmp_path, text))


def test_public_doctype_without_entities_is_fine(tmp_path, no_network):
    text = (
        '<?xml version="1.0"?>\n<!DOCTYPE X3D PUBLIC "ISO//Web3D//DTD X3D 3.0//EN" '
        '"https://www.web3d.org/specifications/x3d-3.0.dtd">\n'
        '<X3D version="3.0"><Scene><Shape><Box/></Shape></Scene></X3D>'
    )
    assert len(sg.load(write(tmp_path, text)).shapes) == 1


def test_deep_nesting_is_an_error_not_a_crash(tmp_path):
    body = "<Group>" * 5000 + "</Group>" * 5000
    with pytest.raises(sg.SceneError, match="malformed XML"):
        sg.load(scene(tmp_path, body))


def test_x3dz_reads_and_inflation_is_bounded(tmp_path, monkeypatch):
    text = '<X3D version="4.0"><Scene><Shape><Box/></Shape></Scene></X3D>'
    path = tmp_path / "scene.x3dz"
    path.write_bytes(gzip.compress(text.encode()))
    assert sg.load(path).shapes[0].n_faces == 12
    monkeypatch.setattr(x3d_parse, "MAX_BYTES", 40)
    with pytest.raises(sg.SceneError, match="larger than 40 bytes; refused"):
        sg.load(path)
    path.write_bytes(b"\x1f\x8bnot gzip at all")
    with pytest.raises(sg.SceneError, match="cannot read"):
        sg.load(path)


# -- Inline ---------------------------------------------------------------------------


def test_inline_outside_the_scene_folder_is_skipped_and_never_read(tmp_path, monkeypatch):
    folder = tmp_path / "scene"
    folder.mkdir()
    scene(tmp_path, "<Shape><Box/></Shape>", "outside.x3d")
    opened = []
    real_parse = x3d_parse.parse
    monkeypatch.setattr(
        x3d_parse, "parse", lambda path, *notes: opened.append(path) or real_parse(path, *notes)
    )
    path = scene(folder, '<Inline url=\'"../outside.x3d" "/etc/passwd"\'/>\n<Shape><Box/></Shape>')
    result = sg.load(path)
    assert len(result.shapes) == 1 and result.shapes[0].source.startswith("scene.x3d line 3")
    (warning,) = result.warnings
    assert warning.startswith(f"{path} line 2, Inline: Inline skipped: ")
    assert "'../outside.x3d' leaves the scene's folder" in warning
    assert "'/etc/passwd' is not a relative path" in warning
    assert opened == [path]  # only the scene itself was parsed


def test_remote_and_missing_inlines_warn_and_never_fetch(tmp_path, no_network):
    path = scene(tmp_path, '<Inline url=\'"https://example.com/a.x3d" "missing.x3d"\'/>')
    result = sg.load(path)
    assert result.shapes == []
    (warning,) = result.warnings
    assert "line 2, Inline: Inline skipped" in warning
    assert "'https://example.com/a.x3d' is remote (never fetched)" in warning
    assert "'missing.x3d' not found" in warning


def test_inline_cycle_is_refused(tmp_path):
    scene(tmp_path, "<Inline url='\"b.x3d\"'/>", "a.x3d")
    scene(tmp_path, "<Inline url='\"a.x3d\"'/>", "b.x3d")
    with pytest.raises(sg.SceneError, match="Inline cycle: a.x3d includes itself"):
        sg.load(tmp_path / "a.x3d")


def test_inline_of_an_unreadable_file_is_skipped_naming_it(tmp_path):
    write(tmp_path, "<X3D><Scene><Shape>", "broken.x3d")
    write(tmp_path, '<X3D version="4.0"><head/></X3D>', "empty.x3d")
    body = "<Inline url='\"broken.x3d\"'/>\n<Inline url='\"empty.x3d\"'/><Shape><Box/></Shape>"
    result = sg.load(scene(tmp_path, body))
    assert len(result.shapes) == 1
    broken, empty = result.warnings
    assert broken.startswith(f"{tmp_path / 'scene.x3d'} line 2, Inline: Inline skipped: ")
    assert (
        "'broken.x3d' cannot be read: " in broken and "broken.x3d line 1: malformed XML" in broken
    )
    assert "line 3, Inline: Inline skipped: 'empty.x3d' cannot be read: it has no <Scene>" in empty


def test_unknown_and_unmodelled_nodes_warn(tmp_path):
    body = (
        '<Script DEF="s"/><TimeSensor/><TimeSensor/><Background/><FancyNode/>'
        '<ProtoInstance name="P"/><Shape><Text string=\'"hi"\'/></Shape>'
    )
    result = sg.load(scene(tmp_path, body))
    text = "\n".join(result.warnings)
    for name in [
        "Script DEF='s'",
        "TimeSensor",
        "Background",
        "FancyNode",
        "ProtoInstance",
        "Text",
    ]:
        assert f"line 2, {name}" in text
    assert "(2 such nodes)" in text


def test_read_never_mutates_the_file(tmp_path):
    path = scene(
        tmp_path,
        '<Shape><IndexedFaceSet coordIndex="0 1 2" ccw="false">'
        + TRIANGLE
        + "</IndexedFaceSet></Shape>",
    )
    before = path.read_bytes()
    x3d_read.read(path)
    assert path.read_bytes() == before


def test_def_use_expansion_bomb_is_refused(tmp_path):
    # each level uses the previous one ten times: 10 ** 7 boxes from a few lines
    levels = ['<Group DEF="g0"><Shape><Box/></Shape></Group>']
    for level in range(1, 8):
        levels.append(f'<Group DEF="g{level}">' + f'<Group USE="g{level - 1}"/>' * 10 + "</Group>")
    # refused by the memory budget, before a Box is built, naming the first
    # level past it: g6 stands for 10 ** 6 boxes of 12 triangles
    with pytest.raises(sg.SceneError, match="DEF='g6': .* about 1.3e\\+08 triangles"):
        sg.load(scene(tmp_path, "\n".join(levels)))


@pytest.mark.parametrize(
    "body",
    [
        "<Shape><Box/></Shape>" * 10,  # no USE: the elements counted by XPath
        '<Shape DEF="s"><Box/></Shape>' + '<Shape USE="s"/>' * 9,  # USE: expanded one by one
    ],
)
def test_the_node_budget_counts_a_scene_exactly_with_or_without_use(tmp_path, monkeypatch, body):
    # Scene + 10 Shapes + 10 Boxes = 21 nodes either way: refused with a budget of 20 only
    path = scene(tmp_path, "<!-- a comment is no node -->" + body)
    monkeypatch.setattr(x3d_read, "MAX_NODES", 21)
    assert len(sg.load(path).shapes) == 10
    monkeypatch.setattr(x3d_read, "MAX_NODES", 20)
    with pytest.raises(sg.SceneError, match="expands .* to more than 20 nodes"):
        sg.load(path)


def test_inline_expansion_bomb_is_refused(tmp_path, monkeypatch):
    # no document is large, but each inlines the next twice: 2 ** 6 copies of the last
    monkeypatch.setattr(x3d_read, "MAX_NODES", 50)
    scene(tmp_path, "<Shape><Box/></Shape>", "level0.x3d")
    for level in range(1, 7):
        inline = f"<Inline DEF='next' url='\"level{level - 1}.x3d\"'/><Inline USE='next'/>"
        scene(tmp_path, inline, f"level{level}.x3d")
    with pytest.raises(sg.SceneError, match="expands .* to more than 50 nodes"):
        sg.load(tmp_path / "level6.x3d")


def test_prototype_body_expansion_bomb_is_refused(tmp_path):
    # the DEF/USE bomb of test_def_use_expansion_bomb_is_refused, inside a ProtoBody
    levels = ['<Group DEF="g0"><Shape><Box/></Shape></Group>']
    for level in range(1, 8):
        levels.append(f'<Group DEF="g{level}">' + f'<Group USE="g{level - 1}"/>' * 10 + "</Group>")
    body = (
        '<ProtoDeclare name="Bomb"><ProtoBody><Group>' + "".join(levels) + "</Group>"
        '</ProtoBody></ProtoDeclare>\n<ProtoInstance name="Bomb"/>'
    )
    with pytest.raises(sg.SceneError, match="line 3, ProtoInstance: .*expands .* more than"):
        sg.load(scene(tmp_path, body))


def test_invisible_nodes_are_skipped_with_a_warning(tmp_path):
    body = (
        '<Transform visible="false"><Shape><Box/></Shape></Transform>'
        '<Shape visible="false"><Box/></Shape><Shape><Box/></Shape>'
    )
    result = sg.load(scene(tmp_path, body))
    assert len(result.shapes) == 1
    assert sum("visible='false': skipped" in warning for warning in result.warnings) == 2


def test_deep_def_use_chain_is_an_error_not_a_crash(tmp_path):
    levels = ['<Group DEF="g0"><Shape><Box/></Shape></Group>']
    levels += [f'<Group DEF="g{i}"><Group USE="g{i - 1}"/></Group>' for i in range(1, 1500)]
    # the DEFs at the top make 1500 * 1501 / 2 groups to walk: refused before the walk
    with pytest.raises(sg.SceneError, match="MAX_VISITS"):
        sg.load(scene(tmp_path, "\n".join(levels)))
    # a chain that each level USEs once, from the bottom up, is walked until it is too deep
    levels = ['<Group DEF="g0"><Shape><Box/></Shape></Group>']
    levels += [f'<Group DEF="g{i}"><Group USE="g{i - 1}"/></Group>' for i in range(1, 300)]
    top = '<Group DEF="top"><Group USE="g299"/></Group>'
    body = "<Switch whichChoice='-1'>" + "\n".join(levels) + "</Switch>" + top
    with pytest.raises(sg.SceneError, match="nested too deeply"):
        sg.load(scene(tmp_path, body))


def test_an_attribute_over_libxml2s_10_mb_limit_is_read(tmp_path):
    # 270,000 triangles of distinct points: 2.43M numbers, ~17 MB in one attribute
    n_triangles = 270_000
    values = np.arange(n_triangles * 9, dtype=np.float64) * 0.25 - 1000.0
    points = " ".join(map(repr, values.tolist()))
    assert len(points) > 10_000_000
    body = f'<Shape><TriangleSet><Coordinate point="{points}"/></TriangleSet></Shape>'
    shapes = sg.load(scene(tmp_path, body)).shapes
    assert len(shapes) == 1 and shapes[0].n_faces == n_triangles
    # whatever the reader's vertex order, the points are the written ones
    written = values.reshape(-1, 3)
    triangles = shapes[0].vertices[shapes[0].faces].reshape(-1, 3)
    assert np.array_equal(np.unique(triangles, axis=0), written)  # written is sorted


def test_entity_declarations_are_refused_before_libxml2_parses(tmp_path, monkeypatch):
    # with huge attributes allowed, libxml2's amplification guard is off: the
    # bytes are refused before lxml is called at all
    def never(*args, **kwargs):
        raise AssertionError("libxml2 was given a document declaring entities")

    monkeypatch.setattr(x3d_parse.etree, "parse", never)
    text = (
        '<?xml version="1.0"?>\n\n<!DOCTYPE X3D [ <!ENTITY a "aaaaaaaaaa"> ]>\n'
        '<X3D version="4.0"><Scene><WorldInfo title="&a;"/></Scene></X3D>'
    )
    with pytest.raises(sg.SceneError, match="line 3: the DOCTYPE declares entities"):
        sg.load(write(tmp_path, text))


def test_an_encoding_the_scan_cannot_read_keeps_libxml2s_limits(tmp_path):
    # UTF-16 hides "<!ENTITY" from a byte scan: libxml2 keeps its own guards,
    # so a billion-laughs bomb and an over-long attribute are still refused
    levels = ['<!ENTITY lol0 "lol">'] + [
        f'<!ENTITY lol{i} "{("&lol" + str(i - 1) + ";") * 10}">' for i in range(1, 10)
    ]
    text = (
        f'<?xml version="1.0" encoding="UTF-16"?>\n<!DOCTYPE X3D [ {" ".join(levels)} ]>\n'
        '<X3D version="4.0"><Scene><WorldInfo title="&lol9;"/></Scene></X3D>'
    )
    path = tmp_path / "bomb.x3d"
    path.write_bytes(text.encode("utf-16"))
    with pytest.raises(sg.SceneError, match="entit"):
        sg.load(path)
    points = " ".join(["1.25 2.5 3.75"] * 800_000)  # 11 MB in one attribute
    text = (
        '<?xml version="1.0" encoding="UTF-16"?>\n<X3D version="4.0"><Scene><Shape>'
        f'<TriangleSet><Coordinate point="{points}"/></TriangleSet></Shape></Scene></X3D>'
    )
    path.write_bytes(text.encode("utf-16"))
    with pytest.raises(sg.SceneError, match="longer than libxml2's 10 MB limit"):
        sg.load(path)
    # a declared encoding that is not ASCII-compatible keeps the limits too
    assert not x3d_parse._ascii_compatible(b'<?xml version="1.0" encoding="UTF-7"?><X3D/>')
    assert x3d_parse._ascii_compatible(b'<?xml version="1.0" encoding="iso-8859-1"?><X3D/>')


def test_nesting_past_the_depth_budget_is_refused(tmp_path):
    depth = x3d_parse.MAX_DEPTH  # <X3D><Scene> plus these Groups pass it by one
    body = "<Group>" * (depth - 1) + "</Group>" * (depth - 1)
    with pytest.raises(sg.SceneError, match=f"nested more than {depth} deep"):
        sg.load(scene(tmp_path, body))
    body = "<Group>" * (depth - 2) + "</Group>" * (depth - 2)
    assert sg.load(scene(tmp_path, body)).shapes == []


@pytest.mark.parametrize("uri", ["../secret.bin", "https://example.com/buffer.bin"])
def test_inlined_gltf_reaching_outside_the_folder_is_skipped(tmp_path, no_network, uri):
    folder = tmp_path / "scene"
    folder.mkdir()
    (tmp_path / "secret.bin").write_bytes(bytes(36))
    gltf = {
        "asset": {"version": "2.0"},
        "buffers": [{"uri": uri, "byteLength": 36}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [0, 0, 0]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
    }  # fmt: skip
    (folder / "part.gltf").write_text(json.dumps(gltf))
    path = scene(folder, "<Inline url='\"part.gltf\"'/>")
    result = sg.load(path)
    assert result.shapes == []
    (warning,) = result.warnings
    assert f"line 2, Inline: Inline skipped: 'part.gltf' refers to '{uri}', outside" in warning


def test_transforms_overflowing_to_infinity(tmp_path):
    # Each scale is within shadowgeo.limits' range; their product is not finite.
    level = '<Transform scale="1e70 1e70 1e70">'
    body = level * 5 + "<Shape><Box/></Shape>" + "</Transform>" * 5
    with pytest.raises(
        sg.SceneError, match="line 2, Transform: the transforms down to here overflow"
    ):
        sg.load(scene(tmp_path, body))


def test_use_of_a_node_of_another_type_is_skipped(tmp_path):
    body = '<Transform DEF="T"/>\n<Shape><Box USE="T"/><Sphere/></Shape>'
    result = sg.load(scene(tmp_path, body))
    (shape,) = result.shapes  # the Sphere: the USE stood for no node
    assert shape.n_faces > 12
    (warning,) = result.warnings
    assert "line 3, Box USE='T': USE='T' names a Transform (line 2), not a Box; skipped" in warning


def test_a_number_outside_the_coordinate_range_is_a_bad_value(tmp_path):
    body = '<Transform scale="1e200 1e200 1e200"><Shape><Box/></Shape></Transform>'
    result = sg.load(scene(tmp_path, body))
    (shape,) = result.shapes  # the field takes its default, as X3D browsers do
    np.testing.assert_allclose(np.ptp(shape.world_vertices, axis=0), [2, 2, 2])
    (warning,) = result.warnings
    assert "line 2, Transform: field scale:" in warning
    assert "1e+200, outside the supported range" in warning


def test_angle_unit_overflowing_an_angle(tmp_path):
    path = write(
        tmp_path,
        '<X3D version="3.3"><head><unit category="angle" name="big" conversionFactor="1e308"/>'
        '</head><Scene>\n<Transform rotation="0 1 0 10"/></Scene></X3D>',
    )
    (warning,) = sg.load(path).warnings
    assert "line 2, Transform: field rotation: '0 1 0 10' is not finite in radians" in warning


def test_extrusion_that_would_explode_is_refused(tmp_path):
    spine = " ".join(f"0 {i} 0" for i in range(5000))
    section = " ".join(f"{i} 0" for i in range(5000))
    body = f'<Shape><Extrusion spine="{spine}" crossSection="{section}"/></Shape>'
    result = sg.load(scene(tmp_path, body))
    assert result.shapes == []
    (warning,) = result.warnings
    assert "5,000 spine points x 5,000 section points" in warning and "Shape is skipped" in warning


def test_a_def_name_given_again_rebinds_later_uses(tmp_path):
    body = (
        '<Transform DEF="T" translation="1 0 0"><Shape><Box/></Shape></Transform>'
        '<Group USE="T"/>\n'
        '<Transform DEF="T" translation="5 0 0"><Shape><Box/></Shape></Transform>'
        '<Group><Transform USE="T"/></Group>'
    )
    result = sg.load(scene(tmp_path, body))  # the first USE is a Group: skipped
    assert [float(s.world_vertices.mean(axis=0)[0]) for s in result.shapes] == [1, 5, 5]
    assert any("Group USE='T': USE='T' names a Transform" in w for w in result.warnings)
    body = body.replace('<Group USE="T"/>', '<Transform USE="T"/>')
    result = sg.load(scene(tmp_path, body))
    centres = [float(s.world_vertices.mean(axis=0)[0]) for s in result.shapes]
    assert centres == [1, 1, 5, 5]
    assert any("line 3, Transform DEF='T': DEF 'T' is defined again" in w for w in result.warnings)


def test_prototype_expansion_bomb_is_refused(tmp_path):
    # P0 is a box; each P(k) holds ten P(k-1): five levels make 11,111 copies
    declarations = [
        '<ProtoDeclare name="P0"><ProtoBody><Shape><Box/></Shape></ProtoBody></ProtoDeclare>'
    ]
    for level in range(1, 6):
        inner = f'<ProtoInstance name="P{level - 1}"/>' * 10
        body = f"<ProtoBody><Group>{inner}</Group></ProtoBody>"
        declarations.append(f'<ProtoDeclare name="P{level}">{body}</ProtoDeclare>')
    body = "".join(declarations) + '\n<ProtoInstance name="P5"/>'
    with pytest.raises(sg.SceneError, match="prototypes expand more than 10000 times"):
        sg.load(scene(tmp_path, body))


def test_unexpandable_prototype_as_a_material_is_skipped(tmp_path):
    body = '<Shape><Appearance><ProtoInstance name="Nope"/></Appearance><Box/></Shape>'
    loaded = sg.load(scene(tmp_path, body))
    (shape,) = loaded.shapes
    assert shape.material.emissive_color == (1, 1, 1)  # no Material: X3D's unlit white
    assert any("ProtoInstance name='Nope' skipped" in w for w in loaded.warnings)


def test_prototype_connect_to_a_bad_field_name(tmp_path):
    body = (
        '<ProtoDeclare name="P"><ProtoInterface><field name="r" type="SFFloat" value="1"/>'
        '</ProtoInterface><ProtoBody><Shape><Sphere><IS><connect nodeField="1e308" protoField="r"/>'
        '</IS></Sphere></Shape></ProtoBody></ProtoDeclare>\n<ProtoInstance name="P"/>'
    )
    with pytest.raises(sg.SceneError, match="line 2, connect: connect nodeField='1e308' is not"):
        sg.load(scene(tmp_path, body))


@pytest.mark.parametrize(
    "body, expected",
    [
        ('<ElevationGrid xDimension="3" zDimension="2" height="0 0 0"/>',
         "height has 3 values; xDimension 3 x zDimension 2 needs 6"),
        (f'<TriangleFanSet fanCount="2">{TRIANGLE}</TriangleFanSet>',
         "fanCount [2] needs counts >= 3 summing to <= 3"),
        (f'<TriangleStripSet stripCount="4">{TRIANGLE}</TriangleStripSet>',
         "stripCount [4] needs counts >= 3 summing to <= 3"),
    ],
)  # fmt: skip
def test_counts_that_do_not_fit_the_points_skip_the_shape(tmp_path, body, expected):
    result = sg.load(scene(tmp_path, f"<Shape>{body}</Shape>"))
    (warning,) = result.warnings
    assert result.shapes == [] and "line 2" in warning and expected in warning


def test_deep_nesting_is_refused_before_python_runs_out_of_stack(tmp_path):
    """Found by the fuzzing campaign (x3d mutant 7528): a prototype moved into
    its own body nested copies until Python's recursion limit, which numpy met
    first in a deeper stack and reported as a TypeError. The reader counts the
    grouping nodes it is inside and stops at MAX_NESTING, well inside the
    stack a caller leaves it. (A prototype inside itself is now refused as a
    cycle first: a chain of distinct prototypes, each inside the one before,
    nests as deep.)"""
    import sys

    from shadowgeo import limits

    count = limits.MAX_NESTING + 10
    body = (
        "".join(
            f'<ProtoDeclare name="P{k}"><ProtoBody><Transform><Shape><Box/></Shape>'
            f'<ProtoInstance name="P{k + 1}"/></Transform></ProtoBody></ProtoDeclare>'
            for k in range(count)
        )
        + '<ProtoInstance name="P0"/>'
    )
    path = scene(tmp_path, body)

    def nested(depth: int) -> None:  # the caller's stack already holds 900 frames
        if depth:
            return nested(depth - 1)
        with pytest.raises(sg.SceneError, match=f"more than {limits.MAX_NESTING} deep"):
            sg.load(path)

    before = sys.getrecursionlimit()
    sys.setrecursionlimit(1000)  # Python's default, whatever ran before
    try:
        nested(900)
        assert sys.getrecursionlimit() == 1000  # put back after the walk
    finally:
        sys.setrecursionlimit(before)
