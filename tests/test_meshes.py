"""Mesh-format input (glTF, OBJ, STL, PLY, OFF) and the glTF round trip."""

from __future__ import annotations

import base64
import json
import math
import sys

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st
from validators import one_triangle_gltf

import shadowgeo as sg

# glTF positions are float32: a local coordinate x comes back within |x| * 2**-24.
FLOAT32 = 2.0**-24


def _triangles(shape: sg.Shape) -> np.ndarray:
    """(m, 3, 3) world-space triangles, in the shape's face order."""
    return shape.world_vertices[shape.faces]


def _local_bound(shape: sg.Shape) -> float:
    """Largest world error float32 local coordinates can cause in ``shape``."""
    linear = np.linalg.norm(shape.transform[:3, :3], 2)
    return 2 * FLOAT32 * float(np.abs(shape.vertices).max()) * linear * math.sqrt(3)


def _scene() -> sg.Scene:
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=1.5)
    box = trimesh.creation.box(extents=[2.0, 1.0, 0.5])
    far = np.eye(4)
    far[:3, :3] = trimesh.transformations.rotation_matrix(0.7, [1, 2, 3])[:3, :3] * 3.0
    far[:3, 3] = [1.0e5, -2.5, 3.0e4]  # far from the origin: the transform keeps float64
    mirrored = np.diag([-1.0, 1.0, 1.0, 1.0])
    return sg.Scene(
        shapes=[
            sg.Shape(sphere.vertices, sphere.faces, far, name="ball"),
            sg.Shape(
                box.vertices,
                box.faces,
                mirrored,
                name="crate",
                material=sg.Material((0.25, 0.5, 0.75), (0.1, 0, 0), transparency=0.4),
                solid=False,
            ),
            sg.Shape(box.vertices, box.faces, name="crate"),  # a duplicate name
            sg.Shape(box.vertices, box.faces),  # no name
            sg.Shape(
                [[0, 0, 0], [1, 0, 0], [0, 0, -1]], [[0, 1, 2]], role="shadow", group="sun group"
            ),
            sg.Shape(
                [[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], role="volume", group="sun group"
            ),
        ],
        lights=[
            sg.SceneLight(sg.PointLight([1, 5, 2], radius=12.5), name="bulb", color=(1, 0.5, 0.25)),
            sg.SceneLight(sg.DirectionalLight([1, -2, 0.5]), name="sun", shadows=True),
            sg.SceneLight(
                sg.SpotLight([0, 4, 0], [0, -1, 0.2], cut_off_angle=0.6, radius=30),
                name="spot",
                beam_width=0.25,
                intensity=0.8,
                on=False,
                shadow_intensity=0.5,
                attenuation=(1.0, 0.5, 0.0),
            ),
        ],
    )


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_gltf_round_trip_keeps_triangles_transforms_names_and_roles(tmp_path, suffix):
    scene = _scene()
    path = tmp_path / f"scene{suffix}"
    sg.save(scene, path)
    back = sg.load(path)

    assert [s.name for s in back.shapes] == [s.name for s in scene.shapes]
    assert [s.role for s in back.shapes] == [s.role for s in scene.shapes]
    assert [s.group for s in back.shapes] == [s.group for s in scene.shapes]
    assert [s.solid for s in back.shapes] == [s.solid for s in scene.shapes]
    for original, read in zip(scene.shapes, back.shapes, strict=True):
        # Transforms are JSON float64: exact.
        np.testing.assert_array_equal(read.transform, original.transform)
        np.testing.assert_allclose(
            _triangles(read), _triangles(original), rtol=0, atol=_local_bound(original)
        )
    # Float32 in world coordinates would be ~8e-3 off at 1e5; local keeps it ~1e-6.
    assert _local_bound(scene.shapes[0]) < 1e-5

    crate = back.shapes[1].material
    np.testing.assert_allclose(crate.diffuse_color, (0.25, 0.5, 0.75))
    np.testing.assert_allclose(crate.emissive_color, (0.1, 0, 0))
    assert crate.transparency == pytest.approx(0.4)
    assert back.shapes[0].material.transparency == 0.0


def test_gltf_round_trip_keeps_lights(tmp_path):
    scene = _scene()
    path = tmp_path / "lights.glb"
    sg.save(scene, path)
    lights = {light.name: light for light in sg.load(path).lights}
    assert sorted(lights) == ["bulb", "spot", "sun"]

    bulb = lights["bulb"]
    assert isinstance(bulb.light, sg.PointLight)
    np.testing.assert_allclose(bulb.light.position, [1, 5, 2], atol=1e-12)
    assert bulb.light.radius == 12.5 and bulb.color == (1, 0.5, 0.25)

    sun = lights["sun"]
    assert isinstance(sun.light, sg.DirectionalLight) and sun.shadows
    np.testing.assert_allclose(
        sun.light.direction, np.array([1, -2, 0.5]) / math.sqrt(5.25), atol=1e-12
    )

    spot = lights["spot"]
    assert isinstance(spot.light, sg.SpotLight)
    np.testing.assert_allclose(spot.light.position, [0, 4, 0], atol=1e-12)
    np.testing.assert_allclose(
        spot.light.direction, np.array([0, -1, 0.2]) / math.sqrt(1.04), atol=1e-12
    )
    assert spot.light.cut_off_angle == 0.6 and spot.light.radius == 30
    assert spot.beam_width == 0.25 and spot.intensity == 0.8 and not spot.on
    assert spot.shadow_intensity == 0.5 and spot.attenuation == (1.0, 0.5, 0.0)


def test_z_up_centimetre_scene_reads_back_in_y_up_metres(tmp_path):
    triangle = sg.Shape([[0, 0, 0], [100, 0, 0], [0, 0, 200]], [[0, 1, 2]], name="t")
    light = sg.SceneLight(sg.DirectionalLight([0, 0, -1]), name="down")
    path = tmp_path / "z.glb"
    sg.save(sg.Scene(shapes=[triangle], lights=[light], up_axis="Z", meters_per_unit=0.01), path)
    back = sg.load(path)
    assert back.up_axis == "Y" and back.meters_per_unit == 1.0
    # (x, y, z) cm Z-up -> (x, z, -y) m Y-up, worked by hand.
    np.testing.assert_allclose(
        _triangles(back.shapes[0])[0], [[0, 0, 0], [1, 0, 0], [0, 2, 0]], atol=1e-7
    )
    np.testing.assert_allclose(back.lights[0].light.direction, [0, -1, 0], atol=1e-12)


def test_reads_a_gltf_written_by_trimesh(tmp_path):
    # An independent writer: trimesh's exporter, with a node hierarchy.
    box = trimesh.creation.box()
    cone = trimesh.creation.cone(radius=1, height=2)
    shifted = trimesh.transformations.translation_matrix([3, 0, 0])
    turned = trimesh.transformations.rotation_matrix(math.pi / 2, [0, 0, 1])
    exported = trimesh.Scene()
    exported.add_geometry(box, node_name="boxnode", geom_name="box", transform=shifted)
    exported.add_geometry(cone, node_name="conenode", geom_name="cone", transform=turned)
    path = tmp_path / "trimesh.glb"
    exported.export(path)

    back = {shape.name: shape for shape in sg.load(path).shapes}
    assert sorted(back) == ["boxnode", "conenode"]
    np.testing.assert_allclose(
        _triangles(back["boxnode"]), (box.vertices + [3, 0, 0])[box.faces], atol=1e-6
    )
    expected = trimesh.transformations.transform_points(cone.vertices, turned)[cone.faces]
    np.testing.assert_allclose(_triangles(back["conenode"]), expected, atol=1e-6)


@pytest.mark.parametrize("suffix", [".obj", ".stl", ".ply", ".off"])
def test_reads_plain_mesh_formats(tmp_path, suffix):
    mesh = trimesh.creation.icosphere(subdivisions=1)
    mesh.apply_translation([1, 2, 3])
    path = tmp_path / f"ball{suffix}"
    mesh.export(path)
    scene = sg.load(path)
    assert len(scene.shapes) == 1
    shape = scene.shapes[0]
    assert shape.name == "ball" and shape.role == "geometry"
    # Same triangles as the mesh we wrote (text formats round to ~1e-8).
    expected = {tuple(np.round(t, 6).ravel()) for t in mesh.vertices[mesh.faces]}
    got = {tuple(np.round(t, 6).ravel()) for t in _triangles(shape)}
    assert got == expected
    # Outward orientation survives: the closed mesh has positive volume.
    assert trimesh.Trimesh(shape.world_vertices, shape.faces, process=False).volume > 0


def test_missing_and_corrupt_files_name_the_file(tmp_path):
    with pytest.raises(sg.SceneError, match=r"nowhere\.glb.*no such file"):
        sg.load(tmp_path / "nowhere.glb")
    cases = {
        "junk.glb": b"glTF\x02\x00\x00\x00",
        "junk.gltf": b"{ this is not json",
        "array.gltf": b"[1, 2, 3]",
        "old.gltf": json.dumps({"asset": {"version": "1.0"}}).encode(),
        "junk.stl": b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 nonsense\n",
        "junk.ply": b"ply\nformat ascii 1.0\nelement vertex 3\nend_header\n0 0\n",
        "junk.obj": b"\x00\xff\x00" * 10,
    }
    for name, data in cases.items():
        path = tmp_path / name
        path.write_bytes(data)
        with pytest.raises(sg.SceneError) as caught:
            sg.load(path)
        assert name in str(caught.value), str(caught.value)


def _gltf_with_buffer_uri(uri: str) -> dict:
    return {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": 36, "uri": uri}],
        "scenes": [{"nodes": []}],
    }


@pytest.mark.parametrize(
    "uri, reason",
    [
        ("../secret.bin", "leaves the file's folder"),
        ("/etc/passwd", "not a relative path"),
        ("http://example.com/buffer.bin", "not a relative path"),
        ("file:///etc/passwd", "not a relative path"),
        ("missing.bin", "missing external file"),
    ],
)
def test_gltf_resources_outside_the_folder_are_refused(tmp_path, uri, reason):
    folder = tmp_path / "scene"
    folder.mkdir()
    (tmp_path / "secret.bin").write_bytes(b"\0" * 36)
    path = folder / "scene.gltf"
    path.write_text(json.dumps(_gltf_with_buffer_uri(uri)))
    with pytest.raises(sg.SceneError, match=reason) as caught:
        sg.load(path)
    assert "scene.gltf" in str(caught.value) and "buffers[0]" in str(caught.value)


_coordinates = st.floats(-1e4, 1e4, allow_nan=False, allow_infinity=False)


@st.composite
def _trs_shapes(draw):
    """Shapes with translation x rotation x scale transforms, as glTF stores
    them, far from the origin or not, and any names."""
    n_vertices = draw(st.integers(3, 8))
    vertices = draw(
        st.lists(
            st.tuples(_coordinates, _coordinates, _coordinates),
            min_size=n_vertices,
            max_size=n_vertices,
        )
    )
    faces = draw(st.lists(st.tuples(*[st.integers(0, n_vertices - 1)] * 3), min_size=1, max_size=6))
    angle = draw(st.floats(-math.pi, math.pi))
    axis = draw(st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda a: np.linalg.norm(a) > 0.1))
    magnitudes = draw(st.tuples(*[st.floats(0.01, 100)] * 3))
    signs = draw(st.tuples(*[st.sampled_from([-1.0, 1.0])] * 3))  # mirrors too
    scale = np.multiply(magnitudes, signs)
    transform = trimesh.transformations.rotation_matrix(angle, axis) @ np.diag([*scale, 1.0])
    transform[:3, 3] = draw(st.tuples(*[st.floats(-1e7, 1e7)] * 3))
    name = draw(st.one_of(st.none(), st.text(max_size=12)))
    return sg.Shape(vertices, faces, transform, name=name, solid=draw(st.booleans()))


@settings(max_examples=30, deadline=None)
@given(shapes=st.lists(_trs_shapes(), min_size=1, max_size=4))
def test_any_trs_scene_round_trips_through_glb(tmp_path_factory, shapes):
    path = tmp_path_factory.mktemp("gltf") / "scene.glb"
    sg.save(sg.Scene(shapes=shapes), path)
    back = sg.load(path)
    assert [s.name or None for s in back.shapes] == [s.name or None for s in shapes]
    assert [s.solid for s in back.shapes] == [s.solid for s in shapes]
    for original, read in zip(shapes, back.shapes, strict=True):
        np.testing.assert_array_equal(read.transform, original.transform)
        error = np.abs(_triangles(read) - _triangles(original)).max()
        assert error <= _local_bound(original)


def test_foreign_gltf_lights_take_the_spec_defaults(tmp_path):
    # KHR_lights_punctual: innerConeAngle defaults to 0, outerConeAngle to pi/4,
    # no range means unlimited; the node's -Z is the direction.
    document = {
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "spot", "spot": {}}]}},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {
                "name": "lamp",
                "translation": [1, 2, 3],
                "rotation": [-math.sqrt(0.5), 0, 0, math.sqrt(0.5)],  # -90 deg about x
                "extensions": {"KHR_lights_punctual": {"light": 0}},
            }
        ],
    }
    path = tmp_path / "lamp.gltf"
    path.write_text(json.dumps(document))
    (lamp,) = sg.load(path).lights
    assert lamp.name == "lamp" and isinstance(lamp.light, sg.SpotLight)
    assert lamp.light.cut_off_angle == pytest.approx(math.pi / 4) and lamp.beam_width == 0
    assert lamp.light.radius == math.inf
    np.testing.assert_allclose(lamp.light.position, [1, 2, 3])
    # -90 degrees about x turns -Z into -Y: the lamp points down.
    np.testing.assert_allclose(lamp.light.direction, [0, -1, 0], atol=1e-12)


def test_gltf_writer_refuses_a_scale_that_is_not_positive(tmp_path):
    with pytest.raises(sg.SceneError, match=r"metersPerUnit must be > 0"):
        sg.save(sg.Scene(meters_per_unit=0.0), tmp_path / "zero.glb")
    assert list(tmp_path.iterdir()) == []


def test_hand_written_gltf_reads(tmp_path):
    path = tmp_path / "tri.gltf"
    path.write_text(json.dumps(one_triangle_gltf()))
    (shape,) = sg.load(path).shapes
    assert shape.name == "tri"
    np.testing.assert_array_equal(_triangles(shape)[0], [[0, 0, 0], [1, 0, 0], [0, 1, 0]])


def _hostile(document: dict, change: str) -> dict:
    if change == "extras are a string":
        document["nodes"][0]["extras"] = {"shadowgeo": "not an object"}
    elif change == "a node is its own child":
        document["nodes"][0]["children"] = [0]
    elif change == "light index out of range":
        document["extensions"] = {"KHR_lights_punctual": {"lights": []}}
        document["nodes"][0]["extensions"] = {"KHR_lights_punctual": {"light": 5}}
    elif change == "unknown light type":
        document["extensions"] = {"KHR_lights_punctual": {"lights": [{"type": "laser"}]}}
        document["nodes"][0]["extensions"] = {"KHR_lights_punctual": {"light": 0}}
    elif change == "negative light range":
        lights = [{"type": "point", "range": -1}]
        document["extensions"] = {"KHR_lights_punctual": {"lights": lights}}
        document["nodes"][0]["extensions"] = {"KHR_lights_punctual": {"light": 0}}
    elif change == "mesh index out of range":
        document["nodes"][0]["mesh"] = 7
    elif change == "accessor longer than its buffer":
        document["accessors"][0]["count"] = 3000
    return document


@pytest.mark.parametrize(
    "change, error",
    [
        ("extras are a string", None),
        ("a node is its own child", None),
        ("light index out of range", "malformed GLTF"),
        ("unknown light type", "unknown light type 'laser'"),
        ("negative light range", "radius must be > 0"),
        ("mesh index out of range", r"nodes\[0\] .tri.: mesh 7 does not exist"),
        ("accessor longer than its buffer", "GLTF"),
    ],
)
def test_hostile_gltf_gives_a_scene_error_or_reads(tmp_path, change, error):
    path = tmp_path / "hostile.gltf"
    path.write_text(json.dumps(_hostile(one_triangle_gltf(), change)))
    if error is None:
        scene = sg.load(path)
        assert [s.role for s in scene.shapes] == ["geometry"]
    else:
        with pytest.raises(sg.SceneError, match=error) as caught:
            sg.load(path)
        assert "hostile.gltf" in str(caught.value)


def test_deeply_nested_json_is_refused(tmp_path):
    path = tmp_path / "deep.gltf"
    path.write_text('{"asset": ' + "[" * 100_000 + "]" * 100_000 + "}")
    with pytest.raises(sg.SceneError, match=r"deep\.gltf.*(nested too deeply|asset)"):
        sg.load(path)


@pytest.mark.parametrize("suffix", [".glb", ".gltf", ".usda"])
def test_a_shape_without_triangles_keeps_its_place(tmp_path, suffix):
    triangle = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
    moved = np.eye(4)
    moved[:3, 3] = [1, 2, 3]
    shapes = [
        sg.Shape(triangle, [[0, 1, 2]], name="first"),
        sg.Shape(np.zeros((0, 3)), np.zeros((0, 3)), moved, name="empty", role="shadow", group="g"),
        sg.Shape(triangle, [[0, 1, 2]], name="last"),
    ]
    path = tmp_path / f"scene{suffix}"
    sg.save(sg.Scene(shapes=shapes), path)
    back = sg.load(path).shapes
    assert [s.name for s in back] == ["first", "empty", "last"]
    assert [s.n_faces for s in back] == [1, 0, 1]
    assert (back[1].role, back[1].group) == ("shadow", "g")
    np.testing.assert_array_equal(back[1].transform, moved)


def test_external_buffer_in_the_folder_is_read(tmp_path):
    document = one_triangle_gltf()
    uri = document["buffers"][0]["uri"]
    (tmp_path / "bin").mkdir()
    (tmp_path / "bin" / "tri data.bin").write_bytes(base64.b64decode(uri.split(",", 1)[1]))
    document["buffers"][0]["uri"] = "bin/tri%20data.bin"
    path = tmp_path / "external.gltf"
    path.write_text(json.dumps(document))
    (shape,) = sg.load(path).shapes
    np.testing.assert_array_equal(_triangles(shape)[0], [[0, 0, 0], [1, 0, 0], [0, 1, 0]])


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_duplicate_names_with_braces_survive(tmp_path, suffix):
    # trimesh formats duplicate names with str.format, so "{" once broke reading.
    triangle = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
    names = ["{", "{", "node0", "a_1", "a", "a", "world"]
    shapes = [sg.Shape(triangle, [[0, 1, 2]], name=name) for name in names]
    path = tmp_path / f"braces{suffix}"
    sg.save(sg.Scene(shapes=shapes), path)
    assert [s.name for s in sg.load(path).shapes] == names


def test_a_missing_texture_is_a_warning_not_an_error(tmp_path):
    document = one_triangle_gltf()
    document["images"] = [{"uri": "textures/brick%20wall.png"}]
    document["samplers"] = [{}]
    document["textures"] = [{"source": 0, "sampler": 0}]
    document["materials"] = [
        {
            "pbrMetallicRoughness": {
                "baseColorFactor": [0.5, 0.25, 1, 1],
                "baseColorTexture": {"index": 0},
            },
            "normalTexture": {"index": 0},
        }
    ]
    document["meshes"][0]["primitives"][0]["material"] = 0
    path = tmp_path / "textured.gltf"
    path.write_text(json.dumps(document))
    scene = sg.load(path)
    assert scene.shapes[0].material.diffuse_color == (0.5, 0.25, 1.0)
    assert scene.warnings == [
        "textured.gltf: images[0] uri 'textures/brick%20wall.png': missing texture image, ignored"
    ]
    # Outside the folder is still refused, texture or not.
    document["images"] = [{"uri": "../secret.png"}]
    path.write_text(json.dumps(document))
    with pytest.raises(sg.SceneError, match=r"images\[0\].*leaves the file's folder"):
        sg.load(path)


def test_a_mesh_of_two_primitives_gives_two_shapes_on_one_node(tmp_path):
    document = one_triangle_gltf()
    document["nodes"][0]["translation"] = [0, 0, 5]
    primitive = document["meshes"][0]["primitives"][0]
    indices = np.array([0, 2, 1], dtype="<u2").tobytes() + b"\0\0"
    raw = base64.b64decode(document["buffers"][0]["uri"].split(",", 1)[1]) + indices
    document["buffers"][0] = {
        "byteLength": len(raw),
        "uri": "data:application/octet-stream;base64," + base64.b64encode(raw).decode(),
    }
    document["bufferViews"].append({"buffer": 0, "byteOffset": 36, "byteLength": 6})
    document["accessors"].append(
        {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
    )
    document["materials"] = [
        {"pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 1]}},
        {"pbrMetallicRoughness": {"baseColorFactor": [0, 0, 1, 1]}},
    ]
    flipped = {"attributes": {"POSITION": 0}, "indices": 1, "material": 1}
    document["meshes"][0]["primitives"] = [{**primitive, "material": 0}, flipped]
    path = tmp_path / "two.gltf"
    path.write_text(json.dumps(document))
    shapes = sg.load(path).shapes
    assert [s.name for s in shapes] == ["tri", "tri"]
    colours = sorted(s.material.diffuse_color for s in shapes)
    assert colours == [(0.0, 0.0, 1.0), (1.0, 0.0, 0.0)]
    normals = sorted(
        float(np.cross(*(_triangles(s)[0, 1:] - _triangles(s)[0, 0]))[2]) for s in shapes
    )
    assert normals == [-1.0, 1.0]  # one wound each way
    assert all(np.all(_triangles(s)[..., 2] == 5) for s in shapes)


@pytest.mark.parametrize("extension", ["EXT_meshopt_compression", "KHR_draco_mesh_compression"])
def test_compressed_geometry_trimesh_cannot_decode_is_refused(tmp_path, monkeypatch, extension):
    monkeypatch.setitem(sys.modules, "DracoPy", None)  # as if the draco extra were not installed
    document = one_triangle_gltf()
    document["extensionsUsed"] = [extension]
    document["extensionsRequired"] = [extension]
    path = tmp_path / "packed.gltf"
    path.write_text(json.dumps(document))
    with pytest.raises(sg.SceneError, match=rf"packed\.gltf.*{extension}") as error:
        sg.load(path)
    if extension == "KHR_draco_mesh_compression":
        assert 'pip install "shadowgeo[draco]"' in str(error.value)


def test_normalized_integer_positions_are_refused(tmp_path):
    # KHR_mesh_quantization allows them; trimesh would read the raw integers.
    document = one_triangle_gltf()
    positions = np.array([[0, 0, 0], [127, 0, 0], [0, 127, 0]], dtype="<i1")
    raw = np.zeros((3, 4), dtype="<i1")
    raw[:, :3] = positions  # each element padded to 4 bytes, as the spec requires
    document["extensionsUsed"] = document["extensionsRequired"] = ["KHR_mesh_quantization"]
    document["buffers"][0] = {
        "byteLength": 12,
        "uri": "data:application/octet-stream;base64," + base64.b64encode(raw.tobytes()).decode(),
    }
    document["bufferViews"][0] = {"buffer": 0, "byteLength": 12, "byteStride": 4}
    document["accessors"][0].update(componentType=5120, normalized=True, max=[1, 1, 0])
    path = tmp_path / "quantized.gltf"
    path.write_text(json.dumps(document))
    with pytest.raises(sg.SceneError, match=r"quantized\.gltf.*POSITION accessor 0.*normalized"):
        sg.load(path)
