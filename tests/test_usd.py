"""USD reader and writer: validated by usd-core's own validators, checked
against the stage as usd-core reads it, and round-tripped."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st
from pxr import Gf, Sdf, Usd, UsdGeom, UsdLux
from validators import usd_errors

import shadowgeo as sg


def test_validator_flags_missing_stage_metadata(tmp_path):
    path = tmp_path / "bare.usda"
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.Xform.Define(stage, "/World")
    stage.Save()
    errors = usd_errors(path)
    assert any("defaultPrim" in e for e in errors)
    assert any("upAxis" in e for e in errors)
    assert any("metersPerUnit" in e for e in errors)

    stage.SetDefaultPrim(stage.GetPrimAtPath("/World"))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.Save()
    assert usd_errors(path) == []


def _scene() -> sg.Scene:
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=1.5)
    box = trimesh.creation.box(extents=[2.0, 1.0, 0.5])
    far = np.eye(4)
    far[:3, :3] = trimesh.transformations.rotation_matrix(0.7, [1, 2, 3])[:3, :3] * 3.0
    far[:3, 3] = [1.0e7, -2.5, 3.0e4]  # far from the origin: float32 would be off by ~1
    sheared = np.eye(4)
    sheared[0, 1] = 0.5
    return sg.Scene(
        shapes=[
            sg.Shape(sphere.vertices, sphere.faces, far, name="ball"),
            sg.Shape(
                box.vertices,
                box.faces,
                sheared,
                name="3 crates!",
                material=sg.Material((0.25, 0.5, 0.75), (0.5, 0, 0), transparency=0.5),
                solid=False,
            ),
            sg.Shape(box.vertices + 0.1, box.faces, name="3 crates!"),
            sg.Shape(box.vertices * 2, box.faces, name="Looks"),
            sg.Shape([[0, 0, 0], [1, 0, 0], [0, 0, -1]], [[0, 1, 2]], role="shadow", group="sun"),
            sg.Shape([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], role="volume", group="sun"),
        ],
        lights=[
            sg.SceneLight(sg.PointLight([1, 5, 2], radius=12.5), name="bulb", color=(1, 0.5, 0.25)),
            sg.SceneLight(sg.PointLight([0, 9, 0]), name="sky lamp"),
            sg.SceneLight(sg.DirectionalLight([1, -2, 0.5]), name="sun", shadows=True),
            sg.SceneLight(
                sg.SpotLight([0, 4, 0], [0, -1, 0.2], cut_off_angle=0.6, radius=30),
                name="spot",
                beam_width=0.25,
                on=False,
                shadow_intensity=0.5,
                attenuation=(1.0, 0.5, 0.0),
            ),
        ],
        up_axis="Z",
        meters_per_unit=0.01,
    )


@pytest.mark.parametrize("suffix", [".usda", ".usdc", ".usd"])
def test_written_file_passes_every_usd_validator(tmp_path, suffix):
    path = tmp_path / f"scene{suffix}"
    sg.save(_scene(), path)
    assert usd_errors(path, warnings=True) == []
    header = path.read_bytes()[:8]
    assert header == (b"#usda 1." if suffix == ".usda" else b"PXR-USDC")


def test_stage_layout_as_usd_core_reads_it(tmp_path):
    scene = _scene()
    path = tmp_path / "scene.usda"
    sg.save(scene, path)
    stage = Usd.Stage.Open(str(path))
    assert stage.GetDefaultPrim().GetPath() == Sdf.Path("/World")
    assert UsdGeom.GetStageUpAxis(stage) == "Z"
    assert UsdGeom.GetStageMetersPerUnit(stage) == 0.01

    meshes = [p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
    assert [p.GetDisplayName() for p in meshes] == [s.name or "" for s in scene.shapes]
    names = [str(p.GetPath()) for p in meshes]
    assert len(set(names)) == len(names)
    # Tf.MakeValidIdentifier replaces each invalid character (a leading digit too).
    assert names[1] == "/World/__crates_" and names[2] == "/World/__crates__1"
    assert names[3] != "/World/Looks"  # the materials' scope keeps its name
    assert names[4].startswith("/World/sun/") and names[5].startswith("/World/sun/")

    ball = UsdGeom.Mesh(meshes[0])
    points = np.array(ball.GetPointsAttr().Get())
    assert set(ball.GetFaceVertexCountsAttr().Get()) == {3}
    assert ball.GetOrientationAttr().Get() == "rightHanded"
    assert ball.GetSubdivisionSchemeAttr().Get() == "none"
    assert ball.GetDoubleSidedAttr().Get() is False
    assert UsdGeom.Mesh(meshes[1]).GetDoubleSidedAttr().Get() is True
    np.testing.assert_array_equal(ball.GetExtentAttr().Get(), [points.min(0), points.max(0)])
    # Flat shading: each corner carries its face's unit normal.
    assert ball.GetNormalsInterpolation() == "faceVarying"
    corners = points[np.array(ball.GetFaceVertexIndicesAttr().Get()).reshape(-1, 3)]
    expected = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    expected /= np.linalg.norm(expected, axis=1, keepdims=True)
    normals = np.array(ball.GetNormalsAttr().Get()).reshape(-1, 3, 3)
    np.testing.assert_allclose(normals, np.repeat(expected[:, None], 3, axis=1), atol=1e-6)
    world = np.array(ball.ComputeLocalToWorldTransform(Usd.TimeCode.Default())).T
    np.testing.assert_array_equal(world, scene.shapes[0].transform)

    crate = UsdGeom.Mesh(meshes[1])
    assert crate.GetDisplayOpacityPrimvar().Get()[0] == 0.5
    assert tuple(crate.GetDisplayColorPrimvar().Get()[0]) == (0.25, 0.5, 0.75)

    spot = stage.GetPrimAtPath("/World/spot")
    assert spot.IsA(UsdLux.SphereLight) and spot.HasAPI(UsdLux.ShapingAPI)
    angle = UsdLux.ShapingAPI(spot).GetShapingConeAngleAttr().Get()
    assert angle == pytest.approx(math.degrees(0.6), rel=1e-7)
    placed = np.array(UsdGeom.Xformable(spot).ComputeLocalToWorldTransform(0)).T
    direction = placed[:3, :3] @ [0, 0, -1]  # UsdLux lights shine down their -Z
    np.testing.assert_allclose(direction, np.array([0, -1, 0.2]) / math.sqrt(1.04), atol=1e-15)
    np.testing.assert_allclose(placed[:3, 3], [0, 4, 0], atol=0)
    assert UsdGeom.Imageable(spot).ComputeVisibility() == "invisible"
    sun = stage.GetPrimAtPath("/World/sun_1")
    assert sun.IsA(UsdLux.DistantLight)
    assert UsdLux.ShadowAPI(sun).GetShadowEnableAttr().Get() is True
    bulb = UsdLux.SphereLight(stage.GetPrimAtPath("/World/bulb"))
    assert bulb.GetTreatAsPointAttr().Get() is True


@pytest.mark.parametrize("suffix", [".usda", ".usdc"])
def test_round_trip_is_exact(tmp_path, suffix):
    scene = _scene()
    path = tmp_path / f"scene{suffix}"
    sg.save(scene, path)
    back = sg.load(path)
    assert (back.up_axis, back.meters_per_unit) == ("Z", 0.01)
    assert [s.name for s in back.shapes] == [s.name for s in scene.shapes]
    assert [s.role for s in back.shapes] == [s.role for s in scene.shapes]
    assert [s.group for s in back.shapes] == [s.group for s in scene.shapes]
    assert [s.solid for s in back.shapes] == [s.solid for s in scene.shapes]
    for original, read in zip(scene.shapes, back.shapes, strict=True):
        np.testing.assert_array_equal(read.transform, original.transform)
        triangles = read.world_vertices[read.faces]
        expected = original.world_vertices[original.faces]
        assert np.abs(triangles - expected).max() <= 1e-9
    crate = back.shapes[1].material
    np.testing.assert_allclose(crate.diffuse_color, (0.25, 0.5, 0.75))
    np.testing.assert_allclose(crate.emissive_color, (0.5, 0, 0))
    assert crate.transparency == 0.5

    lights = {light.name: light for light in back.lights}
    assert sorted(lights) == ["bulb", "sky lamp", "spot", "sun"]
    assert isinstance(lights["bulb"].light, sg.PointLight)
    np.testing.assert_array_equal(lights["bulb"].light.position, [1, 5, 2])
    assert lights["bulb"].light.radius == 12.5 and lights["bulb"].color == (1, 0.5, 0.25)
    assert lights["sky lamp"].light.radius == math.inf
    sun = lights["sun"]
    assert isinstance(sun.light, sg.DirectionalLight) and sun.shadows
    np.testing.assert_allclose(
        sun.light.direction, np.array([1, -2, 0.5]) / math.sqrt(5.25), atol=1e-15
    )
    spot = lights["spot"]
    assert isinstance(spot.light, sg.SpotLight)
    assert spot.light.cut_off_angle == 0.6 and spot.light.radius == 30
    np.testing.assert_allclose(
        spot.light.direction, np.array([0, -1, 0.2]) / math.sqrt(1.04), atol=1e-15
    )
    assert spot.beam_width == 0.25 and not spot.on and spot.shadow_intensity == 0.5
    assert spot.attenuation == (1.0, 0.5, 0.0)


def _author(path, build) -> None:
    """A USD file written directly with pxr: an independent author."""
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    build(stage)
    stage.Save()


def _triangle(stage, prim_path):
    """One triangle mesh at ``prim_path``, authored with pxr."""
    mesh = UsdGeom.Mesh.Define(stage, prim_path)
    mesh.CreatePointsAttr([(0, 0, 0), (1, 0, 0), (0, 1, 0)])
    mesh.CreateFaceVertexCountsAttr([3])
    mesh.CreateFaceVertexIndicesAttr([0, 1, 2])
    return mesh


def test_reads_polygons_orientation_and_nesting_from_another_author(tmp_path):
    def build(stage):
        parent = UsdGeom.Xform.Define(stage, "/Root")
        parent.AddTranslateOp().Set(Gf.Vec3d(10, 0, 0))
        quad = UsdGeom.Mesh.Define(stage, "/Root/Quad")
        quad.AddScaleOp().Set(Gf.Vec3f(2, 2, 2))
        quad.CreatePointsAttr([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (5, 5, 5)])
        quad.CreateFaceVertexCountsAttr([4, 2])  # a quad and a degenerate "face"
        quad.CreateFaceVertexIndicesAttr([0, 1, 2, 3, 0, 4])
        left = UsdGeom.Mesh.Define(stage, "/Root/Left")
        left.CreatePointsAttr([(0, 0, 0), (1, 0, 0), (0, 1, 0)])
        left.CreateFaceVertexCountsAttr([3])
        left.CreateFaceVertexIndicesAttr([0, 1, 2])
        left.CreateOrientationAttr("leftHanded")
        hidden = UsdGeom.Mesh.Define(stage, "/Root/Hidden")
        hidden.CreatePointsAttr([(0, 0, 0), (1, 0, 0), (0, 1, 0)])
        hidden.CreateFaceVertexCountsAttr([3])
        hidden.CreateFaceVertexIndicesAttr([0, 1, 2])
        hidden.MakeInvisible()
        UsdGeom.Cube.Define(stage, "/Root/Cube")
        UsdLux.CylinderLight.Define(stage, "/Root/Panel")

    path = tmp_path / "other.usda"
    _author(path, build)
    scene = sg.load(path)
    assert scene.up_axis == "Z"
    assert [s.name for s in scene.shapes] == ["Quad", "Left"]
    quad, left = scene.shapes
    triangles = quad.world_vertices[quad.faces]
    # The unit square scaled by 2 and moved 10 along x: area 4, normal +z.
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    assert len(triangles) == 2 and np.allclose(normals[:, :2], 0) and np.all(normals[:, 2] > 0)
    assert 0.5 * normals[:, 2].sum() == pytest.approx(4.0)
    assert triangles[..., 0].min() == 10 and triangles[..., 0].max() == 12
    # leftHanded: clockwise seen from +z is the front, so the normal flips to -z.
    triangle = left.world_vertices[left.faces[0]]
    assert np.cross(triangle[1] - triangle[0], triangle[2] - triangle[0])[2] < 0
    warnings = " ".join(scene.warnings)
    assert "Cube </Root/Cube>" in warnings and "CylinderLight </Root/Panel>" in warnings
    assert "skipped 1" in warnings


def test_edited_points_win_over_a_stale_float64_copy(tmp_path):
    path = tmp_path / "scene.usda"
    triangle = sg.Shape([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], name="t")
    sg.save(sg.Scene(shapes=[triangle]), path)
    stage = Usd.Stage.Open(str(path))
    UsdGeom.Mesh(stage.GetPrimAtPath("/World/t")).GetPointsAttr().Set(
        [(0, 0, 0), (3, 0, 0), (0, 3, 0)]
    )
    stage.Save()
    np.testing.assert_array_equal(sg.load(path).shapes[0].vertices[1], [3, 0, 0])


def test_bad_files_name_the_file_and_the_prim(tmp_path):
    with pytest.raises(sg.SceneError, match=r"nowhere\.usda.*no such file"):
        sg.load(tmp_path / "nowhere.usda")
    for name, data in {
        "broken.usda": b'#usda 1.0\ndef Mesh "x" {\n  int[] faceVertexCounts = [3\n',
        "garbage.usdc": b"PXR-USDC" + b"\xff" * 64,
        "empty.usd": b"",
    }.items():
        path = tmp_path / name
        path.write_bytes(data)
        with pytest.raises(sg.SceneError, match=name.replace(".", r"\.")):
            sg.load(path)

    def out_of_range(stage):
        mesh = UsdGeom.Mesh.Define(stage, "/Bad")
        mesh.CreatePointsAttr([(0, 0, 0), (1, 0, 0), (0, 1, 0)])
        mesh.CreateFaceVertexCountsAttr([3])
        mesh.CreateFaceVertexIndicesAttr([0, 1, 9])

    path = tmp_path / "range.usda"
    _author(path, out_of_range)
    with pytest.raises(sg.SceneError, match=r"range\.usda.*Mesh </Bad>.*point 9 of 3"):
        sg.load(path)

    def negative_count(stage):
        mesh = UsdGeom.Mesh.Define(stage, "/Bad")
        mesh.CreatePointsAttr([(0, 0, 0), (1, 0, 0), (0, 1, 0)])
        mesh.CreateFaceVertexCountsAttr([5, -2])
        mesh.CreateFaceVertexIndicesAttr([0, 1, 2])

    _author(path, negative_count)
    with pytest.raises(sg.SceneError, match=r"range\.usda.*Mesh </Bad>.*faceVertexCounts holds -2"):
        sg.load(path)


@pytest.mark.parametrize(
    "asset, reason",
    [
        ("../outside.usda", "leaves the file's folder"),
        ("/etc/hosts", "not a relative path"),
        ("http://example.com/x.usda", "not a relative path"),
        ("missing.usda", "missing layer"),
    ],
)
def test_references_outside_the_folder_are_refused(tmp_path, asset, reason):
    folder = tmp_path / "scene"
    folder.mkdir()
    outside = tmp_path / "outside.usda"
    _author(
        outside, lambda stage: stage.SetDefaultPrim(UsdGeom.Xform.Define(stage, "/O").GetPrim())
    )

    def referencing(stage):
        UsdGeom.Xform.Define(stage, "/World").GetPrim().GetReferences().AddReference(asset)

    path = folder / "main.usda"
    _author(path, referencing)
    with pytest.raises(sg.SceneError, match=reason) as caught:
        sg.load(path)
    assert "main.usda" in str(caught.value) and asset in str(caught.value)


def test_a_reference_inside_the_folder_is_followed(tmp_path):
    def part(stage):
        mesh = UsdGeom.Mesh.Define(stage, "/Part")
        mesh.CreatePointsAttr([(0, 0, 0), (1, 0, 0), (0, 1, 0)])
        mesh.CreateFaceVertexCountsAttr([3])
        mesh.CreateFaceVertexIndicesAttr([0, 1, 2])
        stage.SetDefaultPrim(mesh.GetPrim())

    (tmp_path / "parts").mkdir()
    _author(tmp_path / "parts" / "part.usda", part)
    _author(
        tmp_path / "main.usda",
        lambda stage: (
            UsdGeom.Mesh.Define(stage, "/Placed")
            .GetPrim()
            .GetReferences()
            .AddReference("parts/part.usda")
        ),
    )
    scene = sg.load(tmp_path / "main.usda")
    assert [s.name for s in scene.shapes] == ["Placed"] and scene.shapes[0].n_faces == 1


def test_failed_write_leaves_the_existing_file_untouched(tmp_path, monkeypatch):
    path = tmp_path / "scene.usda"
    path.write_text("previous contents")
    real_export = Sdf.Layer.Export

    def export_half_then_fail(layer, filename, *args, **kwargs):
        real_export(layer, filename, *args, **kwargs)
        with open(filename, "r+b") as handle:
            handle.truncate(10)
        return False

    monkeypatch.setattr(Sdf.Layer, "Export", export_half_then_fail)
    with pytest.raises(sg.SceneError, match=r"scene\.usda.*could not save"):
        sg.save(_scene(), path)
    with pytest.raises(sg.SceneError, match="could not save"):
        sg.save(_scene(), tmp_path / "new.usdc")
    monkeypatch.undo()
    assert path.read_text() == "previous contents"
    assert [p.name for p in tmp_path.iterdir()] == ["scene.usda"]


_coordinates = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False)
# USD strings end at a NUL character (C strings underneath) and are UTF-8 (no lone
# surrogates, which the writer replaces), so the names here have neither.
_names = st.one_of(
    st.none(),
    st.text(st.characters(exclude_characters="\x00", exclude_categories=["Cs"]), max_size=12),
)


@st.composite
def _shapes(draw):
    n_vertices = draw(st.integers(3, 8))
    vertices = draw(
        st.lists(
            st.tuples(_coordinates, _coordinates, _coordinates),
            min_size=n_vertices,
            max_size=n_vertices,
        )
    )
    faces = draw(st.lists(st.tuples(*[st.integers(0, n_vertices - 1)] * 3), min_size=1, max_size=6))
    transform = np.eye(4)
    transform[:3, :] = np.array(
        draw(st.lists(st.floats(-1e3, 1e3, allow_nan=False), min_size=12, max_size=12))
    ).reshape(3, 4)
    role = draw(st.sampled_from(["geometry", "shadow", "volume"]))
    group = draw(_names) if role != "geometry" else None
    return sg.Shape(
        vertices,
        faces,
        transform,
        name=draw(_names),
        role=role,
        group=group,
        solid=draw(st.booleans()),
    )


@settings(max_examples=30, deadline=None)
@given(shapes=st.lists(_shapes(), min_size=1, max_size=4), binary=st.booleans())
def test_any_scene_round_trips_exactly(tmp_path_factory, shapes, binary):
    # Any affine transform (shears, mirrors, singular ones), any names.
    path = tmp_path_factory.mktemp("usd") / ("scene.usdc" if binary else "scene.usda")
    sg.save(sg.Scene(shapes=shapes), path)
    back = sg.load(path)
    assert [(s.name or None) for s in back.shapes] == [(s.name or None) for s in shapes]
    assert [s.role for s in back.shapes] == [s.role for s in shapes]
    assert [(s.group or None) for s in back.shapes] == [(s.group or None) for s in shapes]
    for original, read in zip(shapes, back.shapes, strict=True):
        np.testing.assert_array_equal(read.transform, original.transform)
        np.testing.assert_array_equal(read.vertices[read.faces], original.vertices[original.faces])
        assert read.solid == original.solid


def test_corpus_scenes_write_valid_gltf_and_usd(tmp_path, corpus_dir):
    """Every real X3D scene the reader accepts writes a .glb and a .usdc that
    their validators pass and that read back with the same triangles and lights."""
    from validators import gltf_problems, gltf_reports

    written = []
    for source in sorted(corpus_dir.rglob("*.x3d")):
        try:
            scene = sg.load(source)
        except sg.SceneError:
            continue  # the X3D reader's own tests judge these
        n_faces = sum(s.n_faces for s in scene.shapes)
        for suffix in (".glb", ".usdc"):
            path = tmp_path / f"{source.stem}{suffix}"
            sg.save(scene, path)
            back = sg.load(path)
            assert sum(s.n_faces for s in back.shapes) == n_faces, path.name
            assert len(back.lights) == len(scene.lights), path.name
        assert usd_errors(tmp_path / f"{source.stem}.usdc", warnings=True) == [], source.name
        written.append(tmp_path / f"{source.stem}.glb")
    assert len(written) >= 10
    for path, report in zip(written, gltf_reports(written), strict=True):
        assert gltf_problems(report) == [], path.name


def test_an_animated_stage_reads_at_its_first_time_sample(tmp_path):
    def build(stage):
        mesh = UsdGeom.Mesh.Define(stage, "/Moving")
        mesh.CreateFaceVertexCountsAttr([3])
        mesh.CreateFaceVertexIndicesAttr([0, 1, 2])
        points = mesh.CreatePointsAttr()
        points.Set([(0, 0, 0), (1, 0, 0), (0, 1, 0)], 10.0)
        points.Set([(0, 0, 0), (5, 0, 0), (0, 5, 0)], 20.0)
        move = mesh.AddTranslateOp()
        move.Set(Gf.Vec3d(1, 2, 3), 10.0)
        move.Set(Gf.Vec3d(9, 9, 9), 20.0)

    path = tmp_path / "moving.usda"
    _author(path, build)
    (shape,) = sg.load(path).shapes
    np.testing.assert_array_equal(
        shape.world_vertices[shape.faces[0]], [[1, 2, 3], [2, 2, 3], [1, 3, 3]]
    )


def test_a_name_python_allows_but_utf8_does_not_is_replaced(tmp_path):
    path = tmp_path / "surrogate.usda"
    shape = sg.Shape([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], name="a\ud800b")
    sg.save(sg.Scene(shapes=[shape]), path)
    assert usd_errors(path) == []
    assert sg.load(path).shapes[0].name == "a\ufffdb"


def test_concave_polygons_are_triangulated_not_fanned(tmp_path):
    # An L-shaped hexagon (area 3), a concave quad (a dart, area 0.5), a square
    # hole and a hole index out of range.
    ell = [(0, 0, 0), (2, 0, 0), (2, 1, 0), (1, 1, 0), (1, 2, 0), (0, 2, 0)]
    dart = [(5, 0, 0), (6, 1, 0), (5, 0.5, 0), (4, 1, 0)]
    hole = [(8, 0, 0), (9, 0, 0), (9, 1, 0), (8, 1, 0)]

    def build(stage):
        mesh = UsdGeom.Mesh.Define(stage, "/Floor")
        mesh.CreatePointsAttr(ell + dart + hole)
        mesh.CreateFaceVertexCountsAttr([6, 4, 4])
        # Each polygon starts where a fan would fold a triangle over.
        mesh.CreateFaceVertexIndicesAttr([2, 3, 4, 5, 0, 1, 7, 8, 9, 6, 10, 11, 12, 13])
        mesh.CreateHoleIndicesAttr([2, 99])

    path = tmp_path / "floor.usda"
    _author(path, build)
    (floor,) = sg.load(path).shapes
    triangles = floor.world_vertices[floor.faces]
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    # Every triangle faces +z (a wrong fan folds one over) and the areas add up.
    assert np.all(normals[:, 2] > 0)
    assert 0.5 * normals[:, 2].sum() == pytest.approx(3.0 + 0.5)
    assert len(triangles) == 4 + 2
    assert triangles[..., 0].max() <= 6  # the hole's polygon is gone


def test_lights_from_another_author(tmp_path):
    def build(stage):
        sun = UsdLux.DistantLight.Define(stage, "/Sun")
        sun.AddRotateXOp().Set(-90.0)  # turns -Z to -Y: shining straight down
        sun.CreateIntensityAttr(3.0)
        spot = UsdLux.SphereLight.Define(stage, "/Spot")
        spot.AddTranslateOp().Set(Gf.Vec3d(1, 2, 3))
        spot.AddRotateXOp().Set(-90.0)
        shaping = UsdLux.ShapingAPI.Apply(spot.GetPrim())
        shaping.CreateShapingConeAngleAttr(30.0)
        shaping.CreateShapingConeSoftnessAttr(0.5)
        bulb = UsdLux.SphereLight.Define(stage, "/Bulb")
        bulb.AddTranslateOp().Set(Gf.Vec3d(0, 5, 0))
        bulb.CreateColorAttr(Gf.Vec3f(1, 0.5, 0.25))
        bulb.CreateRadiusAttr(0.5)
        UsdLux.DomeLight.Define(stage, "/Sky")

    path = tmp_path / "lights.usda"
    _author(path, build)
    scene = sg.load(path)
    lights = {light.name: light for light in scene.lights}
    assert sorted(lights) == ["Bulb", "Spot", "Sun"]
    assert isinstance(lights["Sun"].light, sg.DirectionalLight)
    np.testing.assert_allclose(lights["Sun"].light.direction, [0, -1, 0], atol=1e-12)
    assert lights["Sun"].intensity == 3.0
    spot = lights["Spot"]
    assert isinstance(spot.light, sg.SpotLight)
    np.testing.assert_allclose(spot.light.position, [1, 2, 3])
    np.testing.assert_allclose(spot.light.direction, [0, -1, 0], atol=1e-12)
    assert spot.light.cut_off_angle == pytest.approx(math.pi / 6)
    assert spot.beam_width == pytest.approx(0.5 * math.pi / 6)  # softness 0.5: half the cone
    bulb = lights["Bulb"]
    assert isinstance(bulb.light, sg.PointLight) and bulb.light.radius == math.inf
    np.testing.assert_allclose(bulb.light.position, [0, 5, 0])
    assert bulb.color == (1.0, 0.5, 0.25)
    assert any("DomeLight </Sky>" in warning for warning in scene.warnings)


@pytest.mark.parametrize(
    ("scene", "message"),
    [(sg.Scene(up_axis="X"), "up axis"), (sg.Scene(meters_per_unit=0.0), "metersPerUnit")],
)
def test_usd_writer_refuses_an_unknown_up_axis_or_scale(tmp_path, scene, message):
    with pytest.raises(sg.SceneError, match=rf"bad\.usda.*{message}"):
        sg.save(scene, tmp_path / "bad.usda")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("value", [float("-inf"), float("nan"), 1e155])
def test_a_non_finite_display_colour_is_an_error_not_copied_out(tmp_path, value):
    """Found by the fuzzing campaign (usda mutants 317, 1003, 6902, 6996,
    8763): a displayColor of -inf, nan or a number past float32 (inf once
    stored) was read into the material and written into the output."""

    def build(stage):
        _triangle(stage, "/World/Column").CreateDisplayColorPrimvar().Set([(0.85, 0.85, value)])

    path = tmp_path / "colour.usda"
    _author(path, build)
    with pytest.raises(sg.SceneError, match=r"colour\.usda.*Mesh </World/Column>.*displayColor"):
        sg.load(path)
    assert "0.85" in path.read_text()  # the input is untouched


def test_a_finite_display_colour_is_read(tmp_path):
    def build(stage):
        _triangle(stage, "/World/Column").CreateDisplayColorPrimvar().Set([(0.25, 0.5, 0.75)])

    path = tmp_path / "colour.usda"
    _author(path, build)
    (shape,) = sg.load(path).shapes
    assert shape.material.diffuse_color == pytest.approx((0.25, 0.5, 0.75))


def test_a_corrupt_crate_is_a_scene_error_wherever_its_bytes_break(tmp_path):
    """Found by fuzzing .usdc (12 of 2,560 mutants): usd-core reads a crate's
    values lazily, so corrupt bytes surface as Tf.ErrorException from any
    Get() (LZ4 data that will not decompress, a value range past the file's
    end, a relationship that is not one) or as a value of another type (a
    token where faceVertexCounts belong, a name that is not UTF-8), and
    some single bytes make usd-core abort the process when a value is
    unpacked (bytes 96 and 99 of this crate with usd-core 26.11). Bytes of a
    written crate set to 0xFF, one at a time, either still read or are
    refused as a SceneError naming the file."""
    box = trimesh.creation.box()
    scene = sg.Scene(
        [sg.Shape(box.vertices, box.faces, name="crate", material=sg.Material((0.2, 0.4, 0.6)))],
        [sg.SceneLight(sg.PointLight([0, 5, 0]), name="bulb")],
    )
    original = tmp_path / "scene.usdc"
    sg.save(scene, original)
    data = original.read_bytes()
    refused = 0
    for at in [96, 99, *range(0, len(data), 97)]:
        broken = tmp_path / f"broken{at}.usdc"
        broken.write_bytes(data[:at] + b"\xff" + data[at + 1 :])
        try:
            sg.load(broken)
        except sg.SceneError as error:
            assert str(broken) in str(error)
            refused += 1
        broken.unlink()
    assert refused > 0  # the loop did reach corrupt values


_TYPED_LAYER = """#usda 1.0
(
    upAxis = "Z"
    metersPerUnit = 1
)
def Xform "World"
{
    %(World)s
    def Mesh "Column"
    {
        %(Column)s
        point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
        int[] faceVertexCounts = [3]
        int[] faceVertexIndices = [0, 1, 2]
    }
}
def SphereLight "Bulb"
{
    %(Bulb)s
}
"""


@pytest.mark.parametrize("suffix", [".usda", ".usdc"])
@pytest.mark.parametrize(
    ("prim", "line", "kind"),
    [
        ("Column", "custom double3[] shadowgeo:role = [(1, 2, 3)]", "not text"),
        ("Column", 'custom string shadowgeo:castsShadow = "yes"', "not true or false"),
        ("Column", "custom double shadowgeo:index = 2.5", "not an integer"),
        ("Column", "float3 doubleSided = (1, 2, 3)", "not true or false"),
        ("Column", "float primvars:displayColor = 0.5", "not colours"),
        ("World", "custom int shadowgeo:group = 7", "not text"),
        ("Bulb", "custom double3[] shadowgeo:range = [(1, 2, 3)]", "not a number"),
        ("Bulb", "custom double shadowgeo:attenuation = 1", "not three numbers"),
        ("Bulb", 'custom token shadowgeo:shadowIntensity = "dark"', "not a number"),
        ("Bulb", "double inputs:color = 1", "not three numbers"),
        ("Bulb", "float3 inputs:intensity = (1, 2, 3)", "not a number"),
        ("Bulb", 'string inputs:shadow:enable = "on"', "not true or false"),
    ],
)
def test_a_value_of_the_wrong_type_is_a_scene_error_naming_it(tmp_path, suffix, prim, line, kind):
    """Found by fuzzing .usdc (mutant 5067 of the campaign's seed 12): one
    corrupt byte made a crate's shadowgeo:range hand back the points of a
    mesh, and float() of them raised a ValueError traceback; a text layer
    authoring a schema attribute with another type (a float displayColor)
    raised a TypeError. A corrupt crate can give any attribute another's
    value, and a hand-edited layer can author any type: every value the
    reader uses is checked to be of the kind it needs, else a SceneError
    names the file, the prim and the attribute."""
    lines = dict.fromkeys(["World", "Column", "Bulb"], "")
    lines[prim] = line
    text = tmp_path / "typed.usda"
    text.write_text(_TYPED_LAYER % lines)
    path = tmp_path / f"typed{suffix}"
    if suffix == ".usdc":
        assert Sdf.Layer.FindOrOpen(str(text)).Export(str(path))
    with pytest.raises(sg.SceneError) as caught:
        sg.load(path)
    message = str(caught.value)
    where = {"World": "</World/Column>", "Column": "</World/Column>", "Bulb": "</Bulb>"}[prim]
    name = line.split(" = ")[0].split()[-1].split(":")[-1]
    assert path.name in message and where in message and kind in message
    assert name in message


def test_light_sizes_read_from_usdlux_and_written_back_exactly(tmp_path):
    # UsdLux's own defaults: a DistantLight's angle 0.53 degrees (the sun), a
    # SphereLight's radius 0.5; treatAsPoint makes it a point; a scaled
    # transform scales the radius
    def build(stage):
        UsdLux.DistantLight.Define(stage, "/Sun")
        UsdLux.DistantLight.Define(stage, "/Wide").CreateAngleAttr(5.0)
        UsdLux.SphereLight.Define(stage, "/Bulb")
        big = UsdLux.SphereLight.Define(stage, "/Big")
        big.CreateRadiusAttr(0.25)
        big.AddScaleOp().Set(Gf.Vec3f(2, 2, 2))
        point = UsdLux.SphereLight.Define(stage, "/Point")
        point.CreateTreatAsPointAttr(True)
        _triangle(stage, "/Tri")

    path = tmp_path / "lights.usda"
    _author(path, build)
    lights = {light.name: light.light for light in sg.load(path).lights}
    assert lights["Sun"].angle == pytest.approx(math.radians(0.53), rel=1e-6)
    assert lights["Wide"].angle == pytest.approx(math.radians(5.0), rel=1e-7)
    assert lights["Bulb"].source_radius == pytest.approx(0.5)
    assert lights["Big"].source_radius == pytest.approx(0.5, rel=1e-6)
    assert lights["Point"].source_radius == 0.0
    # written back and read again: the same sizes, to the last bit
    scene = sg.Scene(
        [sg.Shape([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], name="tri")],
        [
            sg.SceneLight(sg.DirectionalLight([0, 0, -1], angle=0.1234567891), name="sun"),
            sg.SceneLight(sg.DirectionalLight([0, 0, -1]), name="hard"),
            sg.SceneLight(sg.PointLight([0, 0, 5], source_radius=0.3333333333), name="bulb"),
            sg.SceneLight(sg.PointLight([0, 0, 5]), name="point"),
        ],
    )
    out = tmp_path / "out.usda"
    sg.save(scene, out)
    back = {light.name: light.light for light in sg.load(out).lights}
    assert back["sun"].angle == 0.1234567891 and back["hard"].angle == 0.0
    assert back["bulb"].source_radius == 0.3333333333 and back["point"].source_radius == 0.0


@pytest.mark.parametrize("suffix", [".x3d", ".glb"])
def test_a_light_size_x3d_and_gltf_cannot_hold_is_noted(tmp_path, suffix):
    def build(stage):
        UsdLux.DistantLight.Define(stage, "/Sun")
        UsdLux.SphereLight.Define(stage, "/Point").CreateTreatAsPointAttr(True)
        _triangle(stage, "/Tri")

    path = tmp_path / "lights.usda"
    _author(path, build)
    scene = sg.load(path)
    sg.save(scene, tmp_path / f"out{suffix}")
    notes = [note for note in scene.warnings if "no field for a light's size" in note]
    assert len(notes) == 1 and "Sun, angle 0.53 degrees" in notes[0] and "Point" not in notes[0]
    sg.save(scene, tmp_path / "out.usda")  # USD holds it: no second note
    assert len([n for n in scene.warnings if "no field for a light's size" in n]) == 1


def test_rect_and_disk_lights_read_from_usdlux_placed_by_their_transforms(tmp_path):
    # Hand-derived: UsdLux lights emit along local -Z, a RectLight's width
    # along local X and height along local Y. Turned 90 degrees about X
    # (y -> z, z -> -y, so -z -> y) and moved to (1, 2, 3), a 2 x 0.5 panel
    # emits along +y, its height along +z.
    # Scaled by 3 along X, a disc of radius 0.25 grows to the mean of X's
    # and Y's scales: 0.25 * 2 = 0.5.
    def build(stage):
        panel = UsdLux.RectLight.Define(stage, "/Panel")
        panel.CreateWidthAttr(2.0)
        panel.CreateHeightAttr(0.5)
        panel.AddTranslateOp().Set(Gf.Vec3d(1, 2, 3))
        panel.AddRotateXOp().Set(90.0)
        UsdLux.RectLight.Define(stage, "/Plain")  # UsdLux's defaults: 1 x 1
        disc = UsdLux.DiskLight.Define(stage, "/Disc")
        disc.CreateRadiusAttr(0.25)
        disc.AddScaleOp().Set(Gf.Vec3f(3, 1, 1))
        _triangle(stage, "/Tri")

    path = tmp_path / "areas.usda"
    _author(path, build)
    scene = sg.load(path)
    lights = {light.name: light for light in scene.lights}
    panel = lights["Panel"].area
    assert isinstance(panel, sg.RectLight)
    assert np.allclose(panel.position, [1, 2, 3]) and np.allclose(panel.direction, [0, 1, 0])
    assert np.allclose(panel.up, [0, 0, 1])
    assert panel.width == pytest.approx(2.0) and panel.height == pytest.approx(0.5)
    plain = lights["Plain"].area
    assert plain.width == 1.0 and plain.height == 1.0
    assert np.allclose(plain.direction, [0, 0, -1])
    disc = lights["Disc"].area
    assert isinstance(disc, sg.DiskLight) and disc.radius == pytest.approx(0.5)
    # where only a light with no size fits: a spot light at the centre,
    # lighting the half-space in front
    stand_in = lights["Panel"].light
    assert isinstance(stand_in, sg.SpotLight)
    assert stand_in.cut_off_angle == pytest.approx(math.pi / 2, abs=1e-6)
    assert np.allclose(stand_in.position, [1, 2, 3]) and np.allclose(stand_in.direction, [0, 1, 0])
    assert not any("Panel" in note or "Disc" in note for note in scene.warnings)


def test_rect_and_disk_lights_written_back_exactly(tmp_path):
    panel = sg.RectLight([0.1, 3.3, -0.7], [0.3, -1, 0.2], 1.2345678901, 0.3333333333, up=[0, 0, 1])
    disc = sg.DiskLight([2, 4.1, 1], [-0.2, -1, 0.1], 0.7777777777)
    scene = sg.Scene(
        [sg.Shape([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], name="tri")],
        [sg.SceneLight(panel, name="panel"), sg.SceneLight(disc, name="disc")],
    )
    out = tmp_path / "out.usda"
    sg.save(scene, out)
    assert usd_errors(out) == []
    stage = Usd.Stage.Open(str(out))
    assert stage.GetPrimAtPath("/World/panel").IsA(UsdLux.RectLight)
    assert stage.GetPrimAtPath("/World/disc").IsA(UsdLux.DiskLight)
    back = {light.name: light.area for light in sg.load(out).lights}
    for want, got in ((panel, back["panel"]), (disc, back["disc"])):
        assert type(got) is type(want)
        assert np.array_equal(got.position, want.position)
        assert np.abs(got.direction - want.direction).max() <= 1e-15
    assert back["panel"].width == panel.width and back["panel"].height == panel.height
    assert np.abs(back["panel"].up - panel.up).max() <= 1e-15
    assert back["disc"].radius == disc.radius


@pytest.mark.parametrize("suffix", [".x3d", ".glb"])
def test_rect_and_disk_lights_x3d_and_gltf_cannot_hold_are_noted(tmp_path, suffix):
    panel = sg.RectLight([0, 3, 0], [0, -1, 0], 1.5, 0.5, up=[0, 0, 1])
    scene = sg.Scene(
        [sg.Shape([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], name="tri")],
        [sg.SceneLight(panel, name="panel")],
    )
    sg.save(scene, tmp_path / f"out{suffix}")
    (note,) = [note for note in scene.warnings if "no field for a light's size" in note]
    assert "panel, a 1.5 x 0.5 rectangle" in note and "spot light" in note
    back = sg.load(tmp_path / f"out{suffix}").lights
    assert len(back) == 1 and isinstance(back[0].light, sg.SpotLight)
    assert np.allclose(back[0].light.position, [0, 3, 0])
    assert back[0].light.cut_off_angle == pytest.approx(math.pi / 2)


def test_a_scene_past_float32s_range_gets_a_finite_camera_clipping_range(tmp_path):
    # The fuzz campaign (seed 36, wrl mutant 572) wrote clippingRange = (3e35, inf):
    # the far end is the scene's size times 1000, in a float2 attribute.
    source = tmp_path / "huge.x3d"
    source.write_text(
        '<X3D profile="Interchange" version="4.0"><Scene><Shape>'
        '<IndexedTriangleSet index="0 1 2"><Coordinate point="0 0 0 3e36 0 0 0 3e36 0"/>'
        "</IndexedTriangleSet></Shape></Scene></X3D>"
    )
    target = tmp_path / "huge.usda"
    sg.save(sg.load(source), target)
    stage = Usd.Stage.Open(str(target))
    ranges = [
        tuple(UsdGeom.Camera(prim).GetClippingRangeAttr().Get())
        for prim in stage.Traverse()
        if prim.IsA(UsdGeom.Camera)
    ]
    assert ranges
    for near, far in ranges:
        assert math.isfinite(near) and math.isfinite(far) and 0 < near < far


def test_face_vertex_counts_that_are_not_numbers_name_the_mesh(tmp_path):
    # The fuzz campaign (seed 37, usdc mutant 2720): a flipped byte turned
    # faceVertexCounts into text, and the triangle count before the budget
    # raised a bare ValueError.
    source = tmp_path / "bad.usda"
    source.write_text(
        "#usda 1.0\n"
        'def Mesh "tri"\n{\n'
        "    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n"
        '    string faceVertexCounts = "int[]"\n'
        "    int[] faceVertexIndices = [0, 1, 2]\n}\n"
    )
    with pytest.raises(sg.SceneError, match=r"bad\.usda.*tri.*faceVertexCounts holds str"):
        sg.load(source)
