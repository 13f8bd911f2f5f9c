"""The X3D writer: the input document kept, shadows added, valid against the
X3D 4.0 schema; fresh documents for scenes that did not come from X3D."""

from __future__ import annotations

import gzip
import math
from pathlib import Path

import numpy as np
import pytest
from lxml import etree
from x3d_schema import new_schema_errors, x3d_schema_errors

import shadowgeo as sg
from shadowgeo.io.x3d import numbers as x3d_numbers
from shadowgeo.io.x3d import write as x3d_write

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "scenes" / "courtyard.x3d"
SAFE = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False)


def parse(path):
    data = Path(path).read_bytes()
    if data[:2] == b"\x1f\x8b":
        data = gzip.decompress(data)
    return etree.fromstring(data, SAFE).getroottree()


def shadow_shape(name="shadow_lamp_ground", group="shadows_lamp", transparency=0.3):
    # Coordinates that need all 17 digits to round-trip.
    vertices = np.array([[0.1, 1e-3, 0.2], [1 / 3, 1e-3, 0.2], [0.1, 1e-3, 2 / 7]])
    return sg.Shape(
        vertices,
        [[0, 2, 1]],
        material=sg.Material((0.0, 0.0, 0.0), transparency=transparency),
        name=name,
        solid=False,
        role="shadow",
        group=group,
    )


def document_scene(path=EXAMPLE, shapes=()):
    return sg.Scene(list(shapes), [], path=str(path), document=parse(path))


def floats(text):
    return np.array(text.replace(",", " ").split(), dtype=np.float64)


def written(tmp_path, text):
    """The scene read from X3D ``text`` and the path it was written back to."""
    source = tmp_path / "in.x3d"
    source.write_text(text)
    scene = sg.load(source)
    target = tmp_path / "out.x3d"
    sg.save(scene, target)
    return scene, target


def test_document_is_kept_and_one_group_per_light_is_added(tmp_path, x3d_schema):
    scene = document_scene(shapes=[shadow_shape(), shadow_shape("other", transparency=0.5)])
    original = etree.tostring(scene.document)
    out = tmp_path / "out.x3d"
    x3d_write.write(scene, out)
    assert etree.tostring(scene.document) == original  # the scene is not modified
    text = out.read_text()
    assert text.startswith("<?xml")
    assert '<!DOCTYPE X3D PUBLIC "ISO//Web3D//DTD X3D 4.0//EN"' in text
    assert "<!-- shadowgeo convert keeps this comment" in text
    written = parse(out)
    body = written.getroot().find("Scene")
    (group,) = body.findall("Group")
    assert group.get("DEF") == "shadows_lamp"
    assert [s.get("DEF") for s in group.findall("Shape")] == ["shadow_lamp_ground", "other"]
    # Every original node of <Scene> is still there, in order, unchanged.
    before = [etree.tostring(e) for e in scene.document.getroot().find("Scene")]
    after = [etree.tostring(e) for e in body if e is not group]
    assert [b.strip() for b in before] == [a.strip() for a in after]
    assert written.getroot().get("version") == "4.0"
    assert x3d_schema_errors(out, x3d_schema) == []


def test_added_shape_fields_and_exact_coordinates(tmp_path):
    shape = shadow_shape()
    out = tmp_path / "out.x3d"
    x3d_write.write(document_scene(shapes=[shape]), out)
    node = parse(out).getroot().find("Scene/Group/Shape")
    material = node.find("Appearance/Material")
    assert floats(material.get("diffuseColor")).tolist() == [0, 0, 0]
    assert float(material.get("transparency")) == 0.3
    geometry = node.find("IndexedTriangleSet")
    assert geometry.get("solid") == "false"
    assert floats(geometry.get("index")).tolist() == [0, 2, 1]
    points = floats(geometry.find("Coordinate").get("point")).reshape(-1, 3)
    assert np.array_equal(points, shape.vertices)  # bit for bit


def test_added_shapes_are_in_world_coordinates(tmp_path):
    shape = shadow_shape()
    shape.transform = np.array([[2, 0, 0, 1], [0, 2, 0, 0], [0, 0, 2, 0], [0, 0, 0, 1.0]])
    out = tmp_path / "out.x3d"
    x3d_write.write(document_scene(shapes=[shape]), out)
    point = parse(out).getroot().find("Scene/Group/Shape/IndexedTriangleSet/Coordinate")
    assert np.allclose(floats(point.get("point"))[:3], [1.2, 2e-3, 0.4], rtol=1e-15)


def test_def_names_never_collide_with_the_document(tmp_path, x3d_schema):
    # The example already has DEF="lamp" and DEF="ground": the group and the shape
    # named like them get new names, and the schema (xs:ID) sees no duplicate.
    scene = document_scene(shapes=[shadow_shape(name="ground", group="lamp")])
    out = tmp_path / "out.x3d"
    x3d_write.write(scene, out)
    defs = parse(out).xpath("//@DEF")
    assert len(defs) == len(set(defs))
    assert {"lamp_2", "ground_2"} <= set(defs)
    assert x3d_schema_errors(out, x3d_schema) == []


def test_x3dz_is_gzip_of_the_same_document(tmp_path):
    scene = document_scene(shapes=[shadow_shape()])
    x3d_write.write(scene, tmp_path / "a.x3d")
    x3d_write.write(scene, tmp_path / "a.x3dz")
    packed = (tmp_path / "a.x3dz").read_bytes()
    assert packed[:2] == b"\x1f\x8b"
    assert gzip.decompress(packed) == (tmp_path / "a.x3d").read_bytes()


def test_failed_write_leaves_the_old_file_and_no_partial_one(tmp_path):
    out = tmp_path / "out.x3d"
    out.write_text("old")
    broken = sg.Scene([shadow_shape()], document=etree.ElementTree(etree.Element("X3D")))
    with pytest.raises(sg.SceneError, match="no <Scene>"):
        x3d_write.write(broken, out)
    assert out.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.x3d"]


def test_x3d_3_input_gets_no_new_schema_errors(tmp_path, corpus_dir, x3d_schema):
    source = corpus_dir / "lights_materials" / "light_street_lights_radius.x3d"
    before = x3d_schema_errors(source, x3d_schema)
    assert before  # this 3.0 file has its own errors (Shape shading="...")
    out = tmp_path / "out.x3d"
    x3d_write.write(document_scene(source, [shadow_shape()]), out)
    assert new_schema_errors(before, x3d_schema_errors(out, x3d_schema)) == []
    assert parse(out).getroot().get("version") == "3.0"


# -- fresh documents ---------------------------------------------------------------------


def rotation_matrix(axis_angle):
    """Rodrigues' formula, written out here independently of the writer."""
    x, y, z, angle = axis_angle
    axis = np.array([x, y, z]) / np.linalg.norm([x, y, z])
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


def x3d_transform_matrix(node):
    """X3D's Transform: P' = T R SR S SR^-1 P (center 0), from the written fields."""
    translation = floats(node.get("translation", "0 0 0"))
    rotation = rotation_matrix(floats(node.get("rotation", "0 0 1 0")))
    scale = np.diag(floats(node.get("scale", "1 1 1")))
    orientation = rotation_matrix(floats(node.get("scaleOrientation", "0 0 1 0")))
    matrix = np.eye(4)
    matrix[:3, :3] = rotation @ orientation @ scale @ orientation.T
    matrix[:3, 3] = translation
    return matrix


def test_fresh_document_is_valid_x3d_4_with_exact_transforms(tmp_path, x3d_schema):
    rng = np.random.default_rng(7)
    transforms = [np.eye(4)]
    for determinant_sign in (1, -1):
        matrix = np.eye(4)
        matrix[:3, :3] = rng.normal(size=(3, 3))  # rotation, scale and shear
        if np.sign(np.linalg.det(matrix[:3, :3])) != determinant_sign:
            matrix[:3, 0] *= -1
        matrix[:3, 3] = rng.normal(size=3) * 10
        transforms.append(matrix)
    transforms.append(np.diag([1.0, 1.0, -1.0, 1.0]))  # a mirror
    shapes = [
        sg.Shape([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], transform=t, name=f"s{i}")
        for i, t in enumerate(transforms)
    ]
    lights = [
        sg.SceneLight(sg.PointLight([1, 2, 3]), name="bulb", shadows=True),
        sg.SceneLight(sg.DirectionalLight([0, -1, 0]), name="sun", intensity=0.5),
        sg.SceneLight(sg.SpotLight([0, 5, 0], [0, -1, 0], 0.5, radius=20), name="spot"),
    ]
    out = tmp_path / "fresh.x3d"
    x3d_write.write(sg.Scene([*shapes, shadow_shape()], lights), out)
    assert x3d_schema_errors(out, x3d_schema) == []
    root = parse(out).getroot()
    assert root.get("version") == "4.0"
    for shape, transform in zip(shapes, transforms, strict=True):
        node = root.find(f".//Shape[@DEF='{shape.name}']")
        parent = node.getparent()
        written = x3d_transform_matrix(parent) if parent.tag == "Transform" else np.eye(4)
        assert np.allclose(written, transform, rtol=0, atol=1e-12)
    bulb = root.find(".//PointLight[@DEF='bulb']")
    assert floats(bulb.get("location")).tolist() == [1, 2, 3] and bulb.get("shadows") == "true"
    assert floats(root.find(".//DirectionalLight").get("direction")).tolist() == [0, -1, 0]
    spot = root.find(".//SpotLight")
    assert float(spot.get("cutOffAngle")) == 0.5 and float(spot.get("radius")) == 20
    assert root.find("Scene/Group[@DEF='shadows_lamp']/Shape") is not None


# -- through the reader ------------------------------------------------------------------


def test_converting_a_converted_file_again_changes_nothing(tmp_path):
    first, second = tmp_path / "first.x3d", tmp_path / "second.x3d"
    sg.save(sg.add_shadows(sg.load(EXAMPLE)), first)
    group = parse(first).getroot().find("Scene/Group")
    assert group.get("class") == "shadowgeo-shadows"
    again = sg.add_shadows(sg.load(first))
    assert any("added by an earlier run" in w for w in again.warnings)
    sg.save(again, second)
    assert second.read_bytes() == first.read_bytes()
    # Read and written back without add_shadows, the baked group stays.
    plain = tmp_path / "plain.x3d"
    sg.save(sg.load(first), plain)
    assert len(parse(plain).getroot().findall("Scene/Group")) == 1
    assert plain.read_bytes() == first.read_bytes()
    # Re-run where no shadow falls any more: the old group goes too.
    moved = sg.load(first)
    moved.lights[0].light = sg.PointLight([3.0, -8.0, 4.0])  # below the ground
    gone = tmp_path / "gone.x3d"
    sg.save(sg.add_shadows(moved, lights=["lamp"], surfaces=False), gone)
    assert parse(gone).getroot().findall("Scene/Group") == []


def test_fresh_document_reads_back_the_same(tmp_path):
    rng = np.random.default_rng(3)
    matrix = np.eye(4)
    matrix[:3, :3] = rng.normal(size=(3, 3))
    matrix[:3, 3] = [5.0, -2.0, 1.0]
    vertices = rng.normal(size=(6, 3))
    faces = np.array([[0, 1, 2], [3, 4, 5], [0, 2, 4]])
    shape = sg.Shape(vertices, faces, transform=matrix, name="thing", solid=False)
    shape.material = sg.Material((0.2, 0.4, 0.6), transparency=0.25)
    lights = [
        sg.SceneLight(sg.PointLight([1, 2, 3], radius=50), name="bulb", shadows=True),
        sg.SceneLight(sg.DirectionalLight([0.0, -1.0, 0.0]), name="sun", shadow_intensity=0.4),
    ]
    out = tmp_path / "fresh.x3d"
    x3d_write.write(sg.Scene([shape], lights), out)
    back = sg.load(out)
    (read,) = back.shapes
    assert read.name == "thing" and not read.solid
    assert np.allclose(read.world_vertices[read.faces], shape.world_vertices[faces], atol=1e-9)
    assert read.material.diffuse_color == pytest.approx((0.2, 0.4, 0.6))
    assert read.material.transparency == pytest.approx(0.25)
    by_name = {light.name: light for light in back.lights}
    assert by_name["bulb"].shadows and by_name["bulb"].light.radius == 50
    assert np.allclose(by_name["bulb"].light.position, [1, 2, 3])
    assert by_name["sun"].shadow_intensity == pytest.approx(0.4)
    assert np.allclose(by_name["sun"].light.direction, [0, -1, 0])


def test_z_up_usd_scene_stands_upright_in_x3d(tmp_path, x3d_schema):
    # A Z-up scene (as USD often is): its "up" is +z, X3D's is +y, so (x, y, z)
    # must come back as (x, z, -y), lights included.
    vertices = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 5.0]])
    shape = sg.Shape(vertices, [[0, 1, 2]], name="spire", solid=False)
    lamp = sg.SceneLight(sg.PointLight([1.0, 2.0, 3.0]), name="lamp")
    sun = sg.SceneLight(sg.DirectionalLight([0.0, 0.0, -1.0]), name="sun")
    usd = tmp_path / "z_up.usda"
    sg.save(sg.Scene([shape], [lamp, sun], up_axis="Z"), usd)
    assert sg.load(usd).up_axis == "Z"
    out = tmp_path / "z_up.x3d"
    sg.save(sg.load(usd), out)
    assert x3d_schema_errors(out, x3d_schema) == []
    back = sg.load(out)
    (read,) = back.shapes
    expected = vertices[:, [0, 2, 1]] * [1, 1, -1]
    assert np.allclose(read.world_vertices[read.faces], expected[[0, 1, 2]], atol=1e-12)
    by_name = {light.name: light.light for light in back.lights}
    assert np.allclose(by_name["lamp"].position, [1.0, 3.0, -2.0], atol=1e-12)
    assert np.allclose(by_name["sun"].direction, [0.0, -1.0, 0.0], atol=1e-12)


def test_added_shadows_read_back_in_world_coordinates(tmp_path):
    result = sg.add_shadows(sg.load(EXAMPLE))
    (shadow,) = result.shapes_with_role("shadow")
    out = tmp_path / "out.x3d"
    sg.save(result, out)
    read = {s.name: s for s in sg.load(out).shapes}["shadow_lamp_ground"]
    assert np.array_equal(read.world_vertices[read.faces], shadow.world_vertices[shadow.faces])


@pytest.mark.parametrize("method", ["planar", "volume"])
def test_added_shapes_read_back_with_their_role_not_as_casters(tmp_path, method):
    scene = sg.load(EXAMPLE)
    result = sg.add_shadows(scene, method=method)
    role = "shadow" if method == "planar" else "volume"
    added = {s.name: s.group for s in result.shapes_with_role(role)}
    assert added
    out = tmp_path / "out.x3d"
    sg.save(result, out)
    back = sg.load(out)
    assert {s.name: s.group for s in back.shapes if s.role == role} == added
    # The scene's own shapes are all that is left as geometry.
    own = sorted(s.name or "" for s in scene.shapes)
    assert sorted(s.name or "" for s in back.shapes_with_role("geometry")) == own


def test_core_profile_gets_the_components_the_shadows_need(tmp_path, x3d_schema):
    source = tmp_path / "core.x3d"
    source.write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n<X3D profile="Core" version="4.0">'
        '<head><meta name="title" content="core"/></head><Scene/></X3D>\n'
    )
    out = tmp_path / "out.x3d"
    x3d_write.write(document_scene(source, [shadow_shape()]), out)
    head = parse(out).getroot().find("head")
    # Navigation for the Viewpoint added to a document that has none
    assert [(c.get("name"), c.get("level")) for c in head.findall("component")] == [
        ("Grouping", "1"), ("Rendering", "3"), ("Shape", "1"), ("Navigation", "1")
    ]  # fmt: skip
    assert [child.tag for child in head] == ["component"] * 4 + ["meta"]
    assert x3d_schema_errors(out, x3d_schema) == []


@pytest.mark.parametrize(("axis", "scale", "message"), [("X", 1.0, "up axis"), ("Y", 0.0, "> 0")])
def test_fresh_document_refuses_an_unknown_axis_or_scale(tmp_path, axis, scale, message):
    scene = sg.Scene([shadow_shape()], up_axis=axis, meters_per_unit=scale)
    scene.shapes[0].role = "geometry"
    with pytest.raises(sg.SceneError, match=message):
        x3d_write.write(scene, tmp_path / "bad.x3d")
    assert not (tmp_path / "bad.x3d").exists()


def test_fresh_document_states_a_unit_other_than_metres(tmp_path, x3d_schema):
    shape = shadow_shape()
    shape.role = "geometry"
    out = tmp_path / "cm.x3d"
    x3d_write.write(sg.Scene([shape], meters_per_unit=0.01), out)
    (unit,) = parse(out).getroot().findall("head/unit")
    assert unit.get("category") == "length" and float(unit.get("conversionFactor")) == 0.01
    assert x3d_schema_errors(out, x3d_schema) == []


def test_non_finite_numbers_of_the_input_are_not_copied(tmp_path):
    scene, target = written(
        tmp_path,
        '<X3D version="4.0"><Scene>\n'
        '<Transform DEF="nan" translation="0 INF 0" scale="1e5 1E-5 2" rotation="0 1 0 -Infinity">'
        '<Shape><Appearance><Material diffuseColor="NaN 0 0" emissiveColor="0.1 0.2 0.3"/>'
        '</Appearance><TriangleSet><Coordinate point="0 0 0, 1 0 0, 0 1e999 0"/></TriangleSet>'
        '</Shape></Transform>\n<WorldInfo title="inf and nan" info=\'"nan"\'/>\n'
        "</Scene></X3D>",
    )
    transform = parse(target).find(".//Transform")
    # non-finite values (spelled or overflowing) dropped; finite ones and text kept
    assert "translation" not in transform.attrib and "rotation" not in transform.attrib
    assert transform.get("scale") == "1e5 1E-5 2" and transform.get("DEF") == "nan"
    material = transform.find(".//Material")
    assert "diffuseColor" not in material.attrib
    assert material.get("emissiveColor") == "0.1 0.2 0.3"
    assert "point" not in transform.find(".//Coordinate").attrib
    info = parse(target).find(".//WorldInfo")
    assert info.get("title") == "inf and nan" and info.get("info") == '"nan"'
    notes = [note for note in scene.warnings if "is not finite; not written" in note]
    assert len(notes) == 4
    assert "translation='0 INF 0'" in notes[0]  # in document order


@pytest.mark.parametrize("fast", [True, False])
def test_point_and_index_text_reads_back_exactly(monkeypatch, fast):
    from shadowgeo.io.x3d.fields import parse as parse_field

    if not fast:
        monkeypatch.setattr(x3d_numbers, "orjson", None)
    elif x3d_numbers.orjson is None:
        pytest.skip("orjson not installed: only the repr path exists")
    rng = np.random.default_rng(3)
    points = rng.normal(size=(500, 3)) * 10.0 ** rng.integers(-60, 60, size=(500, 3))
    points[0] = [-0.0, 1 / 3, 2**-40]
    text = x3d_numbers.points_text(points).decode("ascii")
    assert text.count(", ") == len(points) - 1  # one comma between points
    read = parse_field(text, "MFVec3f")
    assert np.array_equal(read, points) and np.signbit(read[0, 0])
    faces = rng.integers(0, 2**31 - 1, size=(300, 3))
    indices = x3d_numbers.integers_text(faces).decode("ascii")
    assert np.array_equal(parse_field(indices, "MFInt32"), faces.ravel())
    assert x3d_numbers.points_text(np.zeros((0, 3))) == b""
    assert x3d_numbers.integers_text(np.zeros(0)) == b""
    # many points: spaces only (orjson's one pass), the same numbers
    many = rng.normal(size=(x3d_numbers._FLAT_POINTS, 3)) * 10.0 ** rng.integers(-60, 60)
    text = x3d_numbers.points_text(many).decode("ascii")
    assert ("," not in text) == fast and np.array_equal(parse_field(text, "MFVec3f"), many)
    many[-1, 2] = np.nan
    with pytest.raises(sg.SceneError, match="non-finite"):
        x3d_numbers.points_text(many)


def test_spliced_numbers_reach_the_file_whatever_the_chunks():
    # lxml writes in chunks: a placeholder split across two of them must
    # still become its numbers, each exactly once, and nothing else change.
    import io

    from shadowgeo.io.x3d.numbers import Splicer

    splicer = Splicer()
    root = etree.Element("X3D")
    texts = [b"1 2 3", b"", b"4.5 -6e-7 8, 9 10 11", b"12"]
    for index, text in enumerate(texts):
        splicer.set(etree.SubElement(root, "Coordinate", DEF=f"c{index}"), "point", text)
    serialised = etree.tostring(root)
    assert serialised.count(splicer.prefix) == len(texts)
    expected = (
        b"<X3D>"
        + b"".join(
            b'<Coordinate DEF="c%d" point="%s"/>' % (index, text)
            for index, text in enumerate(texts)
        )
        + b"</X3D>"
    )
    assert splicer.splice(serialised) == expected
    rng = np.random.default_rng(0)
    for size in [1, 2, 7, len(splicer.prefix) + 3, 64, 10_000]:
        out = io.BytesIO()
        writer = splicer.writer(out)
        start = 0
        while start < len(serialised):
            step = int(rng.integers(1, size + 1))
            writer.write(serialised[start : start + step])
            start += step
        writer.close()
        assert out.getvalue() == expected
    broken = splicer.writer(io.BytesIO())
    broken.write(serialised[: serialised.index(splicer.prefix) + 5])
    with pytest.raises(sg.SceneError, match="internal error: 0 of 4"):
        broken.close()
    splicer.fill()  # the encodings that read the tree get the text itself
    assert [c.get("point") for c in root] == [t.decode() for t in texts]


@pytest.mark.parametrize("suffix", [".x3d", ".x3dz", ".x3dv", ".x3dj"])
def test_every_encoding_writes_the_shapes_numbers_exactly(tmp_path, suffix):
    rng = np.random.default_rng(4)
    vertices = rng.normal(size=(40, 3)) * 10.0 ** rng.integers(-30, 30, size=(40, 3))
    faces = rng.integers(0, 40, size=(25, 3))
    shadow = sg.Shape(vertices[::-1], faces, role="shadow", group="shadows_sun", name="dark")
    scene = sg.Scene([sg.Shape(vertices, faces, name="thing"), shadow])
    target = tmp_path / f"out{suffix}"
    sg.save(scene, target)
    back = sg.load(target)
    shapes = {shape.name: shape for shape in back.shapes}
    assert np.array_equal(shapes["thing"].world_vertices, vertices)
    assert np.array_equal(shapes["thing"].faces, faces)
    assert np.array_equal(shapes["dark"].world_vertices, vertices[::-1])
    assert shapes["dark"].role == "shadow"
    data = target.read_bytes()
    assert b"shadowgeo-numbers" not in (gzip.decompress(data) if suffix == ".x3dz" else data)


@pytest.mark.parametrize(
    ("value", "non_finite"),
    [
        ("1e99 2 -3.5e-400", False),  # underflow is finite
        ("1.7e308 1", False),
        ("1.8e308 1", True),
        ("2 1E+0400", True),
        ("9" * 250 + "e99", True),  # a long mantissa overflows with a small exponent
        ("1" + "0" * 308 + " 4", False),
        ("1" + "0" * 309 + "e0", True),
        ("1" + "0" * 309 + "e-400", False),
        ("0 NaN 1", True),
        ("1 2 inf", True),
        ("1 e 3", False),  # not all numbers: text, left alone
        ("9" * 400, True),  # no exponent at all (outsider-2: was copied)
        ("1 2 " + "9" * 400, True),
    ],
)
def test_non_finite_attributes_are_found_without_parsing_every_number(value, non_finite):
    assert x3d_write._non_finite(value) == non_finite


@pytest.mark.parametrize(
    ("value", "kind", "non_finite"),
    [
        # outsider-2: beside a word that is no number, Infinity was copied
        ("0 0 0 1 1_000 Infinity", "numbers", True),
        ("0 0 0 1 oops 1e999", "numbers", True),
        ("0 0 0 1 1_000 Infinity", "unknown", False),  # may be text: left alone
        ("nan", "other", False),  # a string field that spells nan
        ("0 0 oops 3", "numbers", False),
    ],
)
def test_a_field_of_numbers_with_any_non_finite_word_is_found(value, kind, non_finite):
    assert x3d_write._non_finite(value, kind) == non_finite


def test_shapes_sharing_a_look_or_not_each_get_their_own_materials_text(tmp_path):
    # (a Material's text is made once per look: a cached value must never
    # leak from one look to another)
    box = sg.Shape(np.eye(3) * [1, 2, 3], np.array([[0, 1, 2]]))
    looks = [
        sg.Material((0.1, 0.2, 0.3)),
        sg.Material((0.1, 0.2, 0.3), emissive_color=(0.5, 0.0, 0.0)),
        sg.Material(np.array([0.1, 0.2, 0.3]), specular_color=(1, 1, 1), shininess=0.7),
        sg.Material((0.1, 0.2, 0.3)),
        sg.Material((0.1, 0.2, 0.3), transparency=0.5),
    ]
    shapes = []
    for look in looks:
        shape = sg.Shape(box.vertices, box.faces)
        shape.material = look
        shapes.append(shape)
    out = tmp_path / "looks.x3d"
    x3d_write.write(sg.Scene(shapes, []), out)
    written = [dict(m.attrib) for m in etree.parse(str(out)).iter("Material")]
    assert written == [
        {"diffuseColor": "0.1 0.2 0.3", "transparency": "0.0"},
        {"diffuseColor": "0.1 0.2 0.3", "emissiveColor": "0.5 0.0 0.0", "transparency": "0.0"},
        {
            "diffuseColor": "0.1 0.2 0.3",
            "specularColor": "1.0 1.0 1.0",
            "shininess": "0.7",
            "transparency": "0.0",
        },
        {"diffuseColor": "0.1 0.2 0.3", "transparency": "0.0"},
        {"diffuseColor": "0.1 0.2 0.3", "transparency": "0.5"},
    ]
    shapes[0].material = sg.Material((0.1, math.nan, 0.3))
    with pytest.raises(sg.SceneError, match="non-finite"):
        x3d_write.write(sg.Scene(shapes, []), tmp_path / "bad.x3d")


@pytest.mark.parametrize("scanned", [7, 64, 1 << 20])
def test_a_long_run_of_digits_is_found_across_the_pieces_scanned(monkeypatch, scanned):
    # 310 digits in a row overflow (1e309); two runs of 151 do not, and the
    # text is not even parsed. The scan goes a piece at a time: a run across
    # two pieces must still be found.
    monkeypatch.setattr(x3d_write, "_SCANNED", scanned)
    for lead in range(12):
        assert x3d_write._non_finite("1 " * lead + "1" + "0" * 309 + "e0 2")
        assert not x3d_write._non_finite("1 " * lead + "1" + "0" * 150 + "e0 " + "0" * 150 + "e0")


def test_long_number_attributes_are_written_as_lxml_writes_them(tmp_path, monkeypatch):
    # Long attributes of number characters reach the file from bytes, past
    # lxml's buffers; text that XML escapes (& < " and newlines, in a text
    # and among numbers) stays with lxml. The file is the same either way.
    rng = np.random.default_rng(3)
    points = " ".join(map(repr, rng.normal(size=30_000).tolist()))
    # line breaks written as character references: a newline in the value,
    # which XML writes back as &#10;
    index = "&#10;".join(
        " ".join(map(str, row)) for row in rng.integers(0, 10_000, (3_000, 10)).tolist()
    )
    info = "a &amp; b &lt; c &quot;quoted&quot; &#10; " * 4_000  # escaped in the file
    source = tmp_path / "in.x3d"
    source.write_text(
        '<X3D version="4.0"><Scene>\n'
        f'<WorldInfo title="big" info="{info}"/>\n'
        f'<Shape><IndexedTriangleSet index="{index}"><Coordinate point="{points}"/>'
        "</IndexedTriangleSet></Shape>\n</Scene></X3D>"
    )
    with monkeypatch.context() as patch:  # the reader holds nothing: the writer's part
        patch.setattr(x3d_numbers, "LONG_VALUE", 1 << 60)
        scene = sg.load(source)
    assert not scene.numbers.texts
    handed = []
    splicer_set = x3d_numbers.Splicer.set

    def counted(self, element, name, text):
        handed.append(name)
        splicer_set(self, element, name, text)

    monkeypatch.setattr(x3d_numbers.Splicer, "set", counted)
    for suffix in (".x3d", ".x3dz", ".x3dj", ".x3dv"):  # (JSON and Classic: filled back)
        handed.clear()
        spliced = tmp_path / f"spliced{suffix}"
        sg.save(scene, spliced)
        assert handed == ["point"]  # the point went past lxml; the others did not
        with monkeypatch.context() as patch:
            patch.setattr(x3d_write, "LONG_VALUE", 1 << 60)
            plain = tmp_path / f"plain{suffix}"
            sg.save(scene, plain)
        assert spliced.read_bytes() == plain.read_bytes()
    spliced = tmp_path / "spliced.x3d"
    assert parse(spliced).find(".//Coordinate").get("point") == points
    assert parse(spliced).find(".//WorldInfo").get("info").startswith('a & b < c "quoted" \n')


def test_instructions_and_foreign_elements_are_noted_in_document_order_once(tmp_path):
    # An instruction before the root and two inside, a foreign element
    # holding another (noted once, as the outer one) and one deep in a
    # Transform: each left out, in the order a reader meets them.
    scene, target = written(
        tmp_path,
        '<?xml version="1.0"?>\n<?first a?>\n'
        '<X3D version="4.0" xmlns:ext="https://example.org/ext"><Scene>\n'
        "<?second b?>\n"
        "<ext:outer><ext:inner/></ext:outer>\n"
        "<Transform><?third c?><ext:deep/><Shape><Box/></Shape></Transform>\n"
        "</Scene></X3D>\n",
    )
    text = target.read_text()
    assert "<?" not in text.split("\n", 1)[1] and "ext:" not in text
    notes = [note for note in scene.warnings if "not written" in note]
    assert [note.split(": ", 1)[1] for note in notes] == [
        "processing instruction <?first ...?> not written",
        "processing instruction <?second ...?> not written",
        "processing instruction <?third ...?> not written",
        "<ext:outer> is not X3D (never followed); not written",
        "<ext:deep> is not X3D (never followed); not written",
    ]


@pytest.mark.parametrize("version", ["3.3", "4.0"])
def test_added_shapes_cast_no_runtime_shadow_in_x3d_4(tmp_path, version, x3d_schema):
    # a browser drawing runtime shadows over the baked ones (--keep-runtime-
    # shadows) must not cast the baked overlays themselves; castShadow is an
    # X3D 4 field, left out of a 3.x document and of VRML 97
    text = EXAMPLE.read_text().replace('version="4.0"', f'version="{version}"', 1)
    source = tmp_path / "in.x3d"
    source.write_text(text)
    result = sg.add_shadows(sg.load(source))
    out = tmp_path / "out.x3d"
    sg.save(result, out)
    added = parse(out).xpath("//Shape[starts-with(@class, 'shadowgeo-shadows-')]")
    assert added
    flags = {shape.get("castShadow") for shape in added}
    assert flags == ({"false"} if version == "4.0" else {None})
    assert (
        new_schema_errors(x3d_schema_errors(source, x3d_schema), x3d_schema_errors(out, x3d_schema))
        == []
    )
    wrl = tmp_path / "out.wrl"
    sg.save(result, wrl)
    assert "castShadow" not in wrl.read_text()


def test_a_prototype_instances_non_finite_field_value_is_not_copied(tmp_path):
    # The fuzz campaign (seed 37, x3d mutant 1928) found a ProtoInstance's
    # <fieldValue value="-2 -inf 0"> copied verbatim: its type is in the
    # ProtoDeclare's interface, not on the element. A string field's value
    # that spells inf is text, and stays.
    scene, target = written(
        tmp_path,
        '<X3D version="4.0"><Scene>\n'
        '<ProtoDeclare name="Moved"><ProtoInterface>'
        '<field name="at" type="SFVec3f" accessType="inputOutput" value="0 0 0"/>'
        '<field name="label" type="SFString" accessType="inputOutput" value=\'"x"\'/>'
        "</ProtoInterface><ProtoBody><Transform><IS>"
        '<connect nodeField="translation" protoField="at"/></IS>'
        "<Shape><Box/></Shape></Transform></ProtoBody></ProtoDeclare>\n"
        '<ProtoInstance name="Moved"><fieldValue name="at" value="-2 -inf 0"/>'
        '<fieldValue name="label" value=\'"inf"\'/></ProtoInstance>\n'
        '<ProtoInstance name="Moved"><fieldValue name="at" value="1 2 3"/></ProtoInstance>\n'
        "</Scene></X3D>",
    )
    values = {
        (i, v.get("name")): v.get("value")
        for i, instance in enumerate(parse(target).iter("ProtoInstance"))
        for v in instance.iter("fieldValue")
    }
    assert values[(0, "at")] is None  # dropped: the declaration's default applies
    assert values[(0, "label")] == '"inf"' and values[(1, "at")] == "1 2 3"
    assert any("fieldValue: value='-2 -inf 0' is not finite" in n for n in scene.warnings)
