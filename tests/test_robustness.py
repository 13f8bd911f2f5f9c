"""Issue 12, "Nothing breaks it": one regression test per fuzz finding.

Each finding is pinned twice: as a self-contained case written here (runs in
any clone), and through the smallest input the fuzzer found, in
``../shared/findings/robustness`` (skipped only when that folder is absent).
References are analytic (ray-plane projection, circle areas, shapely) or the
same configuration at unit scale: shadows scale exactly, areas by ``s**2``.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import shapely
import shapely.affinity
import trimesh
from lxml import etree
from needs import absent
from reference import ray_plane

import shadowgeo as sg
from cli.main import main
from shadowgeo import limits, plane2d
from shadowgeo.io.x3d import write as x3d_write
from shadowgeo.scene import primitives

ROOT = Path(__file__).resolve().parents[1]
GROUND = (
    '<Shape DEF="ground"><IndexedFaceSet solid="false" coordIndex="0 1 2 3 -1">'
    '<Coordinate point="-9 0 -9 9 0 -9 9 0 9 -9 0 9"/></IndexedFaceSet></Shape>'
)
LAMP = '<PointLight location="1 8 1" shadows="true"/>'
FLOOR = sg.Plane([0, 1, 0], 0)


def x3d(tmp_path, body: str, name: str = "scene.x3d") -> Path:
    path = tmp_path / name
    path.write_text(f'<X3D version="4.0"><Scene>{body}</Scene></X3D>')
    return path


def run(capsys, *args):
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def one_clear_line(code: int, err: str) -> None:
    """Exit 0, or exit 1 with one line naming the problem: never a traceback."""
    assert "Traceback" not in err
    assert code in (0, 1)
    if code == 1:
        lines = [line for line in err.splitlines() if not line.startswith("note:")]
        assert len(lines) == 1 and lines[0].startswith("shadowgeo "), err


def named(code: int, out: str, err: str, shown: str) -> None:
    """The value is named: in the one error line (exit 1) or, where X3D
    browsers are lenient and the reader takes the field's default or skips the
    Shape, in a note (exit 0)."""
    one_clear_line(code, err)
    if code == 1:
        assert shown in err
    else:
        notes = [line for line in (out + err).splitlines() if shown in line]
        assert notes and ("default" in notes[0] or "skipped" in notes[0]), out + err


def unit_box(scale: float = 1.0, height: float = 2.0) -> trimesh.Trimesh:
    """A cube of side ``scale`` centred ``height * scale`` above the floor."""
    box = trimesh.creation.box()
    vertices = (box.vertices + [0, height, 0]) * scale
    return trimesh.Trimesh(vertices, box.faces, process=False)


# -- the one coordinate range ---------------------------------------------------------------


def test_limits_name_the_value():
    assert limits.check_length(2, "Sphere radius") == 2.0
    assert limits.check_length(math.inf, "radius", infinite=True) == math.inf
    with pytest.raises(sg.GeometryError, match=r"Sphere radius 1e-320 is below .* 1e-75"):
        limits.check_length(1e-320, "Sphere radius")
    with pytest.raises(sg.GeometryError, match=r"radius 1e\+155 is above .* \(use inf"):
        limits.check_length(1e155, "radius", infinite=True)
    with pytest.raises(sg.GeometryError, match=r"caster point 1 has coordinate -1e\+80"):
        limits.check_coordinates([[0, 0, 0], [0, -1e80, 0]], "caster")
    with pytest.raises(sg.GeometryError, match="not finite"):
        limits.check_coordinates([[0, math.nan, 0]], "caster")


@pytest.mark.parametrize("scale", [1.5e-75, 1e-40, 1e40, 1e75 / 8])
@pytest.mark.parametrize(
    "light",
    [sg.PointLight([0.4, 6, 0.3]), sg.DirectionalLight([0.3, -1, 0.2])],
    ids=["point", "directional"],
)
def test_the_whole_range_gives_the_unit_scale_shadow(scale, light):
    # Within the range every formula stays finite: the shadow is the unit
    # scene's, scaled (areas by s^2, volumes by s^3), front faces identical.
    box = unit_box()
    reference = sg.project_shadow(box, light, FLOOR)
    reference_volume = sg.shadow_volume(box, light).volume
    scaled_light = (
        sg.PointLight(light.position * scale) if isinstance(light, sg.PointLight) else light
    )
    big = trimesh.Trimesh(box.vertices * scale, box.faces, process=False)
    shadow = sg.project_shadow(big, scaled_light, FLOOR)
    assert shadow.diagnostics.empty_reason is None
    assert shadow.area / scale / scale == pytest.approx(reference.area, rel=1e-9)
    outline = sg.silhouette(big, scaled_light)
    assert outline.front.tolist() == sg.silhouette(box, light).front.tolist()
    volume = sg.shadow_volume(big, scaled_light)
    unit = trimesh.Trimesh(volume.vertices / scale, volume.faces, process=False)
    assert volume.is_watertight and unit.volume == pytest.approx(reference_volume, rel=1e-9)


@pytest.mark.parametrize("scale", [1e102, 1e103, 1e150])
def test_coordinates_past_the_range_are_an_error_not_an_empty_shadow(scale):
    # Finding 3: at 1e103 the facing test overflowed: an empty shadow, exit 0.
    box = unit_box(scale)
    light = sg.DirectionalLight([0.3, -1, 0.2])
    for compute in (
        lambda: sg.project_shadow(box, light, FLOOR),
        lambda: sg.silhouette(box, light),
        lambda: sg.shadow_volume(box, light),
    ):
        with pytest.raises(sg.GeometryError, match="outside the supported range"):
            compute()


def test_a_scene_below_the_smallest_size_is_an_error():
    # Finding 2: scale**2 overflowed (OverflowError) for a box 1e-150 across.
    with pytest.raises(sg.GeometryError, match="below the smallest supported size"):
        sg.project_shadow(unit_box(1e-150), sg.DirectionalLight([0.3, -1, 0.2]), FLOOR)


def test_a_triangle_near_1e150_is_an_error_not_a_traceback():
    # Finding 2: np.repeat with negative counts (NaN facing) in the silhouette.
    vertices = np.array(
        [
            [7.87e149, 1.38e150, 4.04e149],
            [6.54e149, -1.94e150, -9.85e149],
            [1.0e150, -3.8e149, -3.1e149],
        ]
    )
    light = sg.PointLight([-2.26e150, 1.2e151, 4.48e149])
    with pytest.raises(sg.GeometryError, match="outside the supported range"):
        sg.project_shadow((vertices, [[0, 1, 2]]), light, sg.Plane([0, 1, 0], 6.67e150))
    # The same triangle brought into the range casts a finite, non-negative shadow.
    shrink = 1e-77
    shadow = sg.project_shadow(
        (vertices * shrink, [[0, 1, 2]]),
        sg.PointLight(light.position * shrink),
        sg.Plane([0, 1, 0], 6.67e150 * shrink),
    )
    assert np.isfinite(shadow.area) and shadow.area >= 0


def test_a_volume_near_the_range_end_is_outward():
    # Finding 3: a triangle soup at 1e150 gave a watertight but inside-out volume.
    rng = np.random.default_rng(7)
    vertices = rng.normal(size=(15, 3)) * 1e74 / 3
    faces = np.arange(15).reshape(5, 3)
    light = sg.PointLight([-1.7e74, 6.4e74, -5e74])
    volume = sg.shadow_volume((vertices, faces), light)
    unit = trimesh.Trimesh(volume.vertices / 1e74, volume.faces, process=False)
    assert volume.is_watertight and unit.volume > 0
    with pytest.raises(sg.GeometryError, match="outside the supported range"):
        sg.shadow_volume((vertices * 1e76, faces), sg.PointLight(light.position * 1e76))


# -- light radius ---------------------------------------------------------------------------


def test_a_radius_past_the_range_is_an_error():
    # Finding 2: radius**2 overflowed for a radius of 1e155.
    triangle = ([[0, 1, 0], [1, 1, 0], [0, 1, 1]], [[0, 1, 2]])
    with pytest.raises(sg.GeometryError, match=r"light radius 1e\+155 is above"):
        sg.project_shadow(triangle, sg.PointLight([0, 5, 0], radius=1e155), FLOOR)


@pytest.mark.parametrize("size, radius", [(1e-12, 1.0), (1.0, 1e70)])
def test_a_radius_much_larger_than_the_scene_limits_nothing(size, radius):
    # Finding 2: the lit disc, 1e20 times the bound, exceeded Clipper2's range.
    box = unit_box(size)
    position = np.array([0.0, 5.0, 0.0]) * size
    limited = sg.project_shadow(box, sg.PointLight(position, radius=radius), FLOOR)
    # The shadow of the box's top face: its corners projected from the light.
    top = box.vertices[box.vertices[:, 1] == box.vertices[:, 1].max()]
    image = ray_plane(top, position, np.array([0.0, 1.0, 0.0]), 0.0)[:, [0, 2]]
    expected = shapely.MultiPoint(image).convex_hull.area
    assert limited.area == pytest.approx(expected, rel=1e-9)
    assert "range" not in limited.diagnostics.limits


@pytest.mark.parametrize("centre", [0.0, 5e5])
def test_a_range_disc_crossing_the_shadow_is_cut_exactly(centre):
    # A 2 x 2 plate at height 1 centred at x = c, the light at (0, 2, 0): the
    # shadow is the 4 x 4 square centred at x = 2c. The lit disc about the
    # light's foot cuts it: inside the square (c = 0), or 1e6 away with its
    # edge through the square's middle, where only the arc over the receiver
    # is cut into segments.
    plate = trimesh.Trimesh(
        np.array([[-1, 1, -1], [1, 1, -1], [1, 1, 1], [-1, 1, 1]]) + [centre, 0, 0],
        [[0, 2, 1], [0, 3, 2]],
        process=False,
    )
    lit = 1.5 if centre == 0 else 2 * centre
    light = sg.PointLight([0, 2, 0], radius=math.hypot(lit, 2))
    receiver = np.array([[-3, 0, -3], [3, 0, -3], [3, 0, 3], [-3, 0, 3]]) + [2 * centre, 0, 0]
    shadow = sg.project_shadow(plate, light, FLOOR, receiver=receiver)
    assert "range" in shadow.diagnostics.limits
    square = shapely.box(2 * centre - 2, -2, 2 * centre + 2, 2)
    # the disc, or for the far one the pie slice over the square, with a
    # sagitta far below the tolerance (1e-7 and 1e-12)
    reach = math.pi if centre == 0 else math.asin(3 / lit)
    angles = np.linspace(-reach, reach, 1 << 15)
    arc = lit * np.column_stack([np.cos(angles), np.sin(angles)])
    disc = shapely.Polygon(arc if centre == 0 else np.vstack([[0, 0], arc]))
    reference = square.intersection(disc)
    polygon = shapely.MultiPolygon(
        [shapely.Polygon(loops[0], loops[1:]) for loops in shadow.polygons]
    )
    # the same region in the plane's own 2-D frame, where shadow.polygons live
    reference2d = shapely.transform(
        reference, lambda xy: FLOOR.to_2d(np.column_stack([xy[:, 0], 0 * xy[:, 0], xy[:, 1]]))
    )
    tolerance = sg.Tolerance.for_points(plate.bounds, light.position, receiver)
    assert shadow.area <= reference.area * (1 + 1e-6)
    assert polygon.symmetric_difference(reference2d).area <= (
        tolerance.chord_length * reference.length
    )
    assert shadow.area == pytest.approx(reference.area, rel=1e-2)


def test_range_discs_in_every_position_match_shapely():
    # The disc inside, across or beside the shadow, its foot in or far
    # outside the receiver: the shadow is the projected plate cut by the
    # lit disc, to within the chord tolerance along the boundary.
    rng = np.random.default_rng(12)
    for _ in range(40):
        size = rng.uniform(0.2, 3)
        centre = rng.normal(size=2) * rng.choice([1, 10, 1e4])
        corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * size + centre
        height = rng.uniform(0.5, 3)
        plate = trimesh.Trimesh(
            np.column_stack([corners[:, 0], np.full(4, height), corners[:, 1]]),
            [[0, 2, 1], [0, 3, 2]],
            process=False,
        )
        position = np.array([rng.normal(), height + rng.uniform(0.5, 4), rng.normal()])
        image = ray_plane(plate.vertices, position, np.array([0.0, 1.0, 0.0]), 0.0)[:, [0, 2]]
        square = shapely.MultiPoint(image).convex_hull
        middle = np.array(square.centroid.coords[0])
        distance = float(np.hypot(*(middle - position[[0, 2]])))
        lit = distance + rng.uniform(-1, 1) * float(np.ptp(image, axis=0).max())
        lit = max(lit, 0.1)
        light = sg.PointLight(position, radius=math.hypot(lit, position[1]))
        low, high = image.min(axis=0) - 1, image.max(axis=0) + 1
        receiver = [[low[0], 0, low[1]], [high[0], 0, low[1]], [high[0], 0, high[1]]]
        receiver.append([low[0], 0, high[1]])
        shadow = sg.project_shadow(plate, light, FLOOR, receiver=receiver)
        angles = np.linspace(0, 2 * np.pi, 1 << 16, endpoint=False)
        disc = shapely.Polygon(lit * np.column_stack([np.cos(angles), np.sin(angles)]))
        reference = square.intersection(shapely.affinity.translate(disc, *position[[0, 2]]))
        reference2d = shapely.transform(
            reference, lambda xy: FLOOR.to_2d(np.column_stack([xy[:, 0], 0 * xy[:, 0], xy[:, 1]]))
        )
        polygon = shapely.MultiPolygon(
            [shapely.Polygon(loops[0], loops[1:]) for loops in shadow.polygons]
        )
        tolerance = sg.Tolerance.for_points(plate.bounds, position, receiver)
        slack = tolerance.chord_length * (reference.length + 1e-9) + 1e-9
        assert polygon.symmetric_difference(reference2d).area <= slack
        assert shadow.area >= 0


# -- never a negative area ------------------------------------------------------------------


def test_a_near_degenerate_triangle_never_has_a_negative_area():
    # Finding 3: Clipper2 rounded a sliver inside out: area -6.4e-12.
    vertices = np.array(
        [
            [0.3333928567981801, 0.26025819245045695, -0.7491074187663926],
            [0.8682942406566608, 0.9580939278964206, 0.8876075893682491],
            [0.3333928567981813, 0.2602581924504565, -0.7491074187663923],
        ]
    )
    light = sg.PointLight([-2.2310346676090704, 0.9231934915103037, -0.5082786116092068])
    shadow = sg.project_shadow((vertices, [[0, 1, 2]]), light, sg.Plane([0, 1, 0], -0.0348))
    assert 0 <= shadow.area < 1e-9
    for loops in shadow.polygons:
        assert plane2d.signed_areas(loops).sum() >= 0


def test_components_drop_parts_rounded_inside_out():
    # A sliver far thinner than Clipper2's 1e-8 grid, 1e8 long: whatever
    # rounding does to it, no part with a negative area comes back.
    for offset in (1e-10, 3e-9, 7e-9):
        sliver = np.array([[1e8, -4e7], [1e6, 9e4], [1e8, -4e7 + offset], [1e8 - 1e-7, -4e7]])
        parts = plane2d.components(plane2d.unite([sliver]))
        assert plane2d.parts_area(parts) >= 0
        assert all(plane2d.signed_areas(loops).sum() > 0 for loops in parts)


# -- duplicated and zero-area faces ---------------------------------------------------------


def test_copies_of_one_triangle_reach_the_union_once():
    # Finding 5: 300,000 copies of one triangle were united one by one
    # (quadratic). n_loops counts what reaches the 2-D union.
    vertices = np.array([[0, 2, 0], [1, 2, 0], [0, 2, 1]], dtype=float)
    faces = np.tile([[0, 1, 2]], (300_000, 1))
    light = sg.PointLight([1, 8, 1])
    shadow = sg.project_shadow((vertices, faces), light, FLOOR)
    image = ray_plane(vertices, light.position, np.array([0.0, 1.0, 0.0]), 0.0)[:, [0, 2]]
    assert shadow.area == pytest.approx(shapely.Polygon(image).area, rel=1e-12)
    assert shadow.diagnostics.n_loops == 1
    # Copies with vertices of their own, turned round, and zero-area faces, too.
    repeated = np.concatenate([vertices] * 50)
    own = np.arange(150).reshape(50, 3)
    own[1::2] = own[1::2, ::-1]
    flat = np.array([[0, 0, 1], [0, 1, 1]])  # two corners at one point
    caster = sg.Caster(repeated, np.concatenate([own, flat + [0, 3, 6]]))
    assert int(caster.distinct.sum()) == 1
    again = sg.project_shadow(caster, light, FLOOR)
    assert again.area == pytest.approx(shadow.area, rel=1e-12)
    assert again.diagnostics.n_loops == 1


# -- tessellation bounded by the tolerance ---------------------------------------------------


def test_sphere_cost_depends_on_chord_over_radius_only():
    # Finding 5: spheres of radius 1e-320 took 95 s and 1.6 GB.
    unit_vertices, unit_faces = primitives.sphere(1.0, chord=1e-3)
    tiny_vertices, tiny_faces = primitives.sphere(1e-70, chord=1e-73)
    assert len(tiny_faces) == len(unit_faces)
    assert np.allclose(np.linalg.norm(tiny_vertices, axis=1), 1e-70, rtol=1e-12)
    with pytest.raises(sg.GeometryError, match="Sphere radius 1e-320 is below"):
        primitives.sphere(1e-320, chord=1e-3)


def test_denormal_spheres_in_a_file_are_named_and_skipped(tmp_path, capsys):
    body = "".join(f'<Shape><Sphere radius="{k}e-320"/></Shape>' for k in range(1, 5))
    code, out, err = run(capsys, "info", x3d(tmp_path, body))
    named(code, out, err, "line 1, Sphere: field radius: 1e-320 is below the smallest")


# -- the X3D reader's numbers ---------------------------------------------------------------


@pytest.mark.parametrize(
    "body, shown",
    [
        (GROUND + '<Transform translation="0 2 0"><Shape><Box/></Shape></Transform>'
         '<PointLight location="1 8 1" radius="1e155" shadows="true"/>', "1e+155"),
        (GROUND + '<Transform translation="0 2 0"><Shape><Box/></Shape></Transform>'
         '<PointLight location="1 8 1" radius="1e100" shadows="true"/>', "1e+100"),
        ('<Transform translation="1e300 0 0"><Shape><Box/></Shape></Transform>'
         '<PointLight location="1e300 8 0" shadows="true"/>', "1e+300"),
        ('<Transform scale="1e103 1e103 1e103">' + GROUND + '<Transform translation="0 2 0">'
         "<Shape><Box/></Shape></Transform></Transform>"
         '<DirectionalLight direction="0.3 -1 0.2" shadows="true"/>', "1e+103"),
    ],
    ids=["radius-1e155", "radius-1e100", "shape-at-1e300", "scale-1e103"],
)  # fmt: skip
def test_numbers_past_the_range_in_a_file_are_named(tmp_path, capsys, body, shown):
    code, out, err = run(capsys, "convert", x3d(tmp_path, body), tmp_path / "out.x3d")
    named(code, out, err, shown)
    line = next(line for line in (out + err).splitlines() if shown in line)
    assert "outside the supported range" in line and "line 1" in line  # the reader found it
    assert (tmp_path / "out.x3d").exists() == (code == 0)


def test_a_scale_product_past_the_range_is_one_clear_error(tmp_path, capsys):
    # Each scale is in range; the world coordinates are not (the add_shadows check).
    nested = '<Transform scale="1e40 1e40 1e40">' * 2
    body = nested + GROUND + "</Transform>" * 2 + LAMP
    code, _, err = run(capsys, "convert", x3d(tmp_path, body), tmp_path / "out.x3d")
    one_clear_line(code, err)
    assert code == 1 and "outside the supported range" in err


def test_a_far_box_with_a_sun_is_one_clear_error(tmp_path, capsys):
    # Finding 2: ZeroDivisionError when scale**2 underflowed.
    body = '<Transform translation="1e300 1e300 1e300"><Shape><Box/></Shape></Transform>'
    out = tmp_path / "out.glb"
    code, out_text, err = run(
        capsys, "convert", x3d(tmp_path, body), out, "--sun", "0.3,-1,0.2", "--plane", "0,1,0,0"
    )
    named(code, out_text, err, "1e+300")


@pytest.mark.parametrize("field, default", [("orientation", "0 0 1 0"), ("scale", "1 1")])
def test_an_empty_extrusion_field_takes_its_default(tmp_path, field, default):
    # Finding 2: zip(strict=True) raised on an empty orientation or scale.
    empty = sg.load(x3d(tmp_path, f'<Shape><Extrusion {field}=""/></Shape>', "a.x3d"))
    given = sg.load(x3d(tmp_path, f'<Shape><Extrusion {field}="{default}"/></Shape>', "b.x3d"))
    assert np.array_equal(empty.shapes[0].vertices, given.shapes[0].vertices)
    assert np.array_equal(empty.shapes[0].faces, given.shapes[0].faces)
    assert len(empty.shapes[0].faces) == 12  # X3D's default Extrusion: a 2 x 1 x 2 box
    assert any(f"field {field} is empty" in note for note in empty.warnings)


def test_a_scene_near_the_range_end_gets_its_shadow(tmp_path):
    # The receiver search squared the length tolerance (overflow at 1e300).
    body = (
        '<Transform scale="1e37 1e37 1e37">' + GROUND + '<Transform translation="0 2 0">'
        '<Shape><Box/></Shape></Transform><PointLight location="1 8 1" shadows="true"/>'
        "</Transform>"
    )
    scene = sg.load(x3d(tmp_path, body))
    result = sg.add_shadows(scene)
    (shadow,) = result.shapes_with_role("shadow")
    unit = sg.add_shadows(sg.load(x3d(tmp_path, body.replace("1e37 1e37 1e37", "1 1 1"), "u.x3d")))
    (reference,) = unit.shapes_with_role("shadow")
    area = trimesh.Trimesh(shadow.world_vertices / 1e37, shadow.faces).area
    assert area == pytest.approx(trimesh.Trimesh(reference.world_vertices, reference.faces).area)


# -- the X3D writer copies nothing hostile ---------------------------------------------------

HOSTILE = """<?xml version="1.0" encoding="UTF-8"?>
<?xml-stylesheet href="file:///etc/passwd"?>
<!DOCTYPE X3D SYSTEM "file:///etc/passwd">
<X3D xmlns:xi="http://www.w3.org/2001/XInclude" version="4.0">
  <Scene>
    <xi:include href="file:///etc/passwd" parse="text"/>
    {GROUND}
    <Transform translation="0 2 0"><Shape><Box/></Shape></Transform>
    <Viewpoint DEF="nan" position="0 inf 0" orientation="0 1 0 1e999" description="inf"/>
    {LAMP}
  </Scene>
</X3D>
"""


def test_the_writer_drops_what_must_never_be_copied(tmp_path, capsys):
    # Findings 4 and 6: a Viewpoint at inf, a DOCTYPE SYSTEM id and an
    # xi:include were copied verbatim into the output.
    source = tmp_path / "hostile.x3d"
    source.write_text(HOSTILE.format(GROUND=GROUND, LAMP=LAMP))
    out = tmp_path / "out.x3d"
    code, _, err = run(capsys, "convert", source, out)
    assert code == 0
    text = out.read_text()
    for forbidden in ("passwd", "DOCTYPE", "xi:", "XInclude", "<?xml-stylesheet", "inf", "1e999"):
        assert forbidden not in text.replace('description="inf"', ""), forbidden
    tree = etree.fromstring(out.read_bytes())
    viewpoint = tree.find("Scene/Viewpoint")
    assert viewpoint.get("DEF") == "nan" and viewpoint.get("description") == "inf"  # text kept
    assert viewpoint.get("position") is None and viewpoint.get("orientation") is None
    assert tree.find("Scene/Group") is not None  # the shadows are there
    for reason in ("DOCTYPE", "processing instruction", "xi:include", "position='0 inf 0'"):
        assert reason in err, reason


def test_the_standard_doctype_is_written_anew(tmp_path):
    source = tmp_path / "standard.x3d"
    source.write_text(
        '<?xml version="1.0"?>\n<!DOCTYPE X3D PUBLIC "ISO//Web3D//DTD X3D 3.3//EN" '
        '"http://www.web3d.org/specifications/x3d-3.3.dtd">\n'
        f'<X3D version="3.3"><Scene>{GROUND}</Scene></X3D>\n'
    )
    scene = sg.load(source)
    out = tmp_path / "out.x3d"
    x3d_write.write(scene, out)
    assert (
        '<!DOCTYPE X3D PUBLIC "ISO//Web3D//DTD X3D 3.3//EN" '
        '"https://www.web3d.org/specifications/x3d-3.3.dtd">' in out.read_text()
    )
    assert not any("DOCTYPE" in note for note in scene.warnings)


def test_the_writer_refuses_a_non_finite_number_of_its_own(tmp_path):
    shape = sg.Shape([[0, 0, 0], [1, 0, 0], [0, math.inf, 0]], [[0, 1, 2]])
    with pytest.raises(sg.SceneError, match="non-finite"):
        x3d_write.write(sg.Scene([shape]), tmp_path / "out.x3d")
    assert not (tmp_path / "out.x3d").exists()


# -- the fuzzer's smallest inputs (../shared/findings/robustness) ---------------------------

CLI_RUNS = {
    "r1_pointlight_radius_overflow.x3d": ("convert", "1e+155"),
    "r9_pointlight_radius_clipper_range.x3d": ("convert", "1e+100"),
    "r2_extrusion_empty_orientation.x3d": ("info", None),
    "r2b_extrusion_empty_scale.x3d": ("info", None),
    "r3_far_shape_receiver_overflow.x3d": ("convert", "1e+300"),
    "r10_zero_division.x3d": ("convert-sun", "1e+300"),
    "r4_viewpoint_inf_copied.x3d": ("convert", None),
    "r5_huge_coords_silent_empty.x3d": ("convert-plane", "1e+103"),
    "r5_control_1e102.x3d": ("convert-plane", "1e+102"),
    "r8_denormal_spheres_slow.x3d": ("info", "Sphere: field radius: 1e-320"),
}


@pytest.mark.parametrize("name", sorted(CLI_RUNS))
def test_finding_files_give_an_output_or_one_clear_error(shared_dir, tmp_path, capsys, name):
    path = shared_dir / "findings" / "robustness" / "cli" / name
    if not path.exists():
        absent(f"{path} is absent")
    how, shown = CLI_RUNS[name]
    out = tmp_path / ("out.glb" if how == "convert-sun" else "out.x3d")
    extra = {
        "convert-sun": ["--sun", "0.3,-1,0.2", "--plane", "0,1,0,0"],
        "convert-plane": ["--plane", "0,1,0,0"],
    }.get(how, [])
    command = "info" if how == "info" else "convert"
    args = [command, path] + ([out] if command == "convert" else []) + extra
    code, out_text, err = run(capsys, *args)
    one_clear_line(code, err)
    if shown is None:
        assert code == 0
        if command == "convert":
            assert "inf" not in out.read_text() and "wrote" not in err
    else:
        named(code, out_text, err, shown)


def test_finding_duplicate_faces_generator(shared_dir, tmp_path, capsys):
    generator = shared_dir / "findings" / "robustness" / "cli" / "r7_dup_faces_gen.py"
    if not generator.exists():
        absent(f"{generator} is absent")
    source = tmp_path / "copies.x3d"
    made = subprocess.run(
        [sys.executable, str(generator), "30000"], capture_output=True, text=True, check=True
    )
    source.write_text(made.stdout)
    out = tmp_path / "out.x3d"
    code, stdout, err = run(capsys, "convert", source, out)
    one_clear_line(code, err)
    assert code == 0 and "1 shadow shape(s)" in stdout
    (shadow,) = sg.load(out).shapes_with_role("shadow")
    triangle = np.array([[0, 2, 0], [1, 2, 0], [0, 2, 1]], dtype=float)
    image = ray_plane(triangle, np.array([1.0, 8.0, 1.0]), np.array([0.0, 1.0, 0.0]), 0.0)
    area = trimesh.Trimesh(shadow.world_vertices, shadow.faces).area
    assert area == pytest.approx(shapely.Polygon(image[:, [0, 2]]).area, rel=1e-6)


API_ERRORS = {
    "a1_radius_overflow.py": "light radius 1e+155",
    "a3_scale_overflow_result.py": "below the smallest supported size",
    "a4_huge_coords_silent_empty.py": "outside the supported range",
    "a5_silhouette_negative_repeats.py": "outside the supported range",
    "a7_volume_inside_out.py": "outside the supported range",
}


@pytest.mark.parametrize("number", range(1, 8))
def test_finding_scripts_give_a_result_or_a_geometry_error(shared_dir, tmp_path, number):
    folder = shared_dir / "findings" / "robustness" / "api"
    found = sorted(folder.glob(f"a{number}_*.py"))
    if not found:
        absent(f"a{number}_*.py is absent from {folder}")
    script = found[0]
    environment = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run(
        [sys.executable, str(script)],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=environment,
        timeout=120,
    )
    expected = API_ERRORS.get(script.name)
    if expected is None:
        assert done.returncode == 0, done.stderr
        if "area" in done.stdout:
            area = float(done.stdout.split()[1])
            assert area >= 0
    else:
        last = done.stderr.strip().splitlines()[-1]
        assert last.startswith("shadowgeo.errors.GeometryError:") and expected in last, last


def test_add_shadows_checks_the_range_whatever_the_tolerance():
    ground = sg.Shape([[-9, 0, -9], [9, 0, -9], [9, 0, 9], [-9, 0, 9]], [[0, 2, 1], [0, 3, 2]])
    far = sg.Shape(unit_box().vertices + [1e80, 0, 0], unit_box().faces)
    scene = sg.Scene([ground, far], [sg.SceneLight(sg.PointLight([1, 8, 1]), shadows=True)])
    with pytest.raises(sg.GeometryError, match=r"scene bounds .* 1e\+80"):
        sg.add_shadows(scene, tolerance=sg.Tolerance())
    near = sg.Scene([ground], [sg.SceneLight(sg.PointLight([1, 8, 1], radius=1e80), name="lamp")])
    with pytest.raises(sg.GeometryError, match=r"light 'lamp' radius 1e\+80 is above"):
        sg.add_shadows(near)
