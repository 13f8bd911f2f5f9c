"""Regression tests for what the long fuzz campaign of issue 12 found.

* A 2-D union whose edges cross millions of times (a soup of thousands of
  overlapping triangles, an Extrusion whose 20,000-point spine folds over
  itself) took minutes in Clipper2: ``plane2d.unite`` now estimates the
  crossings and refuses past ``limits.MAX_UNION_CROSSINGS``.
* Faces that leave a small receiver were clipped one by one in Python, for
  every receiver: they are clipped all at once, with the same result.
"""

from __future__ import annotations

import contextlib
import io

import numpy as np
import pytest
import shapely

import shadowgeo as sg
from cli.main import main as cli_main
from shadowgeo import limits, plane2d


def brute_force_crossings(starts: np.ndarray, ends: np.ndarray) -> int:
    """Proper crossings among all pairs of segments, every pair tested."""
    total = 0
    for index in range(len(starts) - 1):
        a, b = starts[index], ends[index]
        c, d = starts[index + 1 :], ends[index + 1 :]

        def side(origin, one, two):
            return np.sign(
                (one[..., 0] - origin[..., 0]) * (two[..., 1] - origin[..., 1])
                - (one[..., 1] - origin[..., 1]) * (two[..., 0] - origin[..., 0])
            )

        crossing = (side(a, b, c) * side(a, b, d) < 0) & (side(c, d, a) * side(c, d, b) < 0)
        total += int(np.count_nonzero(crossing))
    return total


def random_triangles(count: int, seed: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    return list(rng.uniform(0, 1, size=(count, 3, 2)))


def test_crossings_estimate_agrees_with_brute_force():
    loops = random_triangles(900, seed=4)  # 2,700 edges: 3.6e6 pairs, past the budget
    starts = np.concatenate(loops)
    ends = np.concatenate([np.roll(loop, -1, axis=0) for loop in loops])
    exact = brute_force_crossings(starts, ends)
    estimate, sampled = plane2d.crossings_estimate(loops)
    assert sampled > 1000
    assert abs(estimate - exact) < 0.05 * exact


def test_crossings_estimate_is_exactly_zero_below_the_budget():
    loops = random_triangles(100, seed=1)  # 300 edges: fewer pairs than the budget
    assert plane2d.crossings_estimate(loops) == (0.0, 0)


def test_fill_refuses_a_union_past_the_crossing_budget():
    loops = random_triangles(3000, seed=2)  # ~1e7 crossings: minutes of Clipper2
    with pytest.raises(sg.GeometryError, match="MAX_UNION_CROSSINGS"):
        plane2d.unite(loops)


def test_fill_unites_many_edges_that_do_not_cross():
    # 4,000 disjoint triangles: 8e7 edge pairs, no crossing, so no refusal.
    cells = np.stack(np.meshgrid(np.arange(80.0), np.arange(50.0)), axis=-1).reshape(-1, 2)
    loops = [cell + np.array([[0.1, 0.1], [0.8, 0.1], [0.1, 0.7]]) for cell in cells]
    region = plane2d.unite(loops)
    expected = shapely.union_all(shapely.polygons(np.array(loops))).area
    assert plane2d.parts_area(plane2d.components(region)) == pytest.approx(expected)
    assert expected == pytest.approx(4000 * 0.5 * 0.7 * 0.6)


def folded_extrusion_scene(path, spine_points: int) -> None:
    rng = np.random.default_rng(5)
    values = np.array([0, 1, -1, 0.5, 2, 3, -2.5, 10])
    spine = " ".join(f"{v:g}" for v in rng.choice(values, size=3 * spine_points))
    path.write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<X3D profile="Interchange" version="3.3"><Scene>\n'
        '<Transform translation="0 20 0"><Shape>'
        f'<Extrusion DEF="snake" spine="{spine}"/></Shape></Transform>\n'
        '<Shape><Box size="100 0.1 100"/></Shape>\n'
        "</Scene></X3D>\n"
    )


def test_extrusion_with_a_folded_20000_point_spine_is_refused_by_name(tmp_path):
    source = tmp_path / "snake.x3d"
    folded_extrusion_scene(source, 20_000)
    target = tmp_path / "out.x3d"
    stderr = io.StringIO()
    with contextlib.redirect_stderr(stderr), contextlib.redirect_stdout(io.StringIO()):
        code = cli_main(["convert", str(source), str(target), "--sun", "0.3,-1,0.2"])
    assert code == 0
    notes = [line for line in stderr.getvalue().splitlines() if "snake does not cast" in line]
    assert notes and "MAX_UNION_CROSSINGS" in notes[0]
    assert f"{limits.MAX_UNION_CROSSINGS:,}" in notes[0]
    assert target.is_file()


def textbook_shadow(triangles: np.ndarray, direction: np.ndarray) -> shapely.Geometry:
    """Union of the triangles projected along ``direction`` onto y = 0, as (x, z)."""
    steps = triangles[..., 1] / -direction[1]
    projected = triangles + steps[..., None] * direction
    return shapely.union_all(shapely.polygons(projected[..., [0, 2]]))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_faces_cut_by_a_small_receiver_give_the_textbook_shadow(seed):
    # Most faces of this soup leave the receiver, so most are clipped.
    rng = np.random.default_rng(seed)
    triangles = rng.uniform(-4, 4, size=(60, 3, 3))
    triangles[..., 1] = rng.uniform(1, 3, size=(60, 3))
    faces = np.arange(180).reshape(-1, 3)
    direction = np.array([0.3, -1.0, 0.2])
    square = np.array([[-1.5, 0, -1.0], [1.0, 0, -1.0], [1.0, 0, 1.5], [-1.5, 0, 1.5]])
    shadow = sg.project_shadow(
        (triangles.reshape(-1, 3), faces),
        sg.DirectionalLight(direction),
        sg.Plane([0, 1, 0], 0),
        receiver=square,
    )
    direction = direction / np.linalg.norm(direction)
    expected = textbook_shadow(triangles, direction).intersection(
        shapely.Polygon(square[:, [0, 2]])
    )
    assert shadow.area == pytest.approx(expected.area, rel=1e-9)
    assert shadow.diagnostics.clipped["outside_receiver"] > 10


def load_fuzz_checks():
    """tools/fuzz/check_geometry.py, the fuzzer's checks of geometry mode."""
    import importlib
    import sys
    from pathlib import Path

    folder = str(Path(__file__).resolve().parents[1] / "tools")  # tools/ is not a package
    if folder not in sys.path:
        sys.path.insert(0, folder)
    return importlib.import_module("fuzz.check_geometry")


def test_fuzz_flat_check_accepts_a_thin_slab_under_a_grazing_sun_and_flags_a_flat_one():
    # A unit square lit by a sun 1e-10 off its plane: its volume is a real
    # slab, area x cosine x sweep, 1.4e-8 thick (past the 1.4e-9 length
    # tolerance), which the old absolute threshold called flat.
    fuzz = load_fuzz_checks()
    vertices = np.array([[0, 1, 0], [1, 1, 0], [1, 1, 1], [0, 1, 1.0]])
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    direction = np.array([-0.9564962158535296, -1e-10, 0.2917447326994578])
    light = sg.DirectionalLight(direction)
    volume = sg.shadow_volume((vertices, faces), light)
    cosine = 1e-10 / np.linalg.norm(direction)
    sweep = volume.metadata["shadowgeo"]["sweep"]
    assert volume.volume == pytest.approx(1.0 * cosine * sweep, rel=1e-3)
    assert fuzz.thinner_than_a_prism(vertices, faces, light, volume) is None
    assert fuzz.check_volume(vertices, faces, light) is None
    steeper = sg.DirectionalLight([0.3, -1.0, 0.2])
    volume = sg.shadow_volume((vertices, faces), steeper)
    assert fuzz.thinner_than_a_prism(vertices, faces, steeper, volume) is None
    flattened = volume.copy()
    flattened.vertices[:, 1] = 1.0  # every point on the square's plane: no volume
    assert "prism" in fuzz.thinner_than_a_prism(vertices, faces, steeper, flattened)


def test_a_slab_thinner_than_the_length_tolerance_is_no_volume():
    # Case 3496 of seed 12: a sun 1.9e-12 off the square's plane moves the
    # far cap 2.7e-10 off it, below the 1.4e-9 length tolerance (points that
    # close are the same point): no volume.
    vertices = np.array([[0, 1, 0], [1, 1, 0], [1, 1, 1], [0, 1, 1.0]])
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    direction = np.array([-0.9564962158535296, -1.9385657340094015e-12, 0.2917447326994578])
    tolerance = sg.Tolerance.for_points(vertices)
    assert tolerance.bound_length * 1.94e-12 < tolerance.length
    assert len(sg.shadow_volume((vertices, faces), sg.DirectionalLight(direction)).faces) == 0


@pytest.mark.parametrize(
    ("corner", "size", "direction"),
    [
        # geometry case 9756 of seed 12: a unit square at 1.2e8 under a sun
        # 1.07e-12 off its plane
        (
            [124423420.16514093, -66253763.86468365, 7238807.267961408],
            1.0,
            [-0.3753103555984077, -1.0663521050021641e-12, 0.9268992054050952],
        ),
        # case 13675: a 1e-12 square at 1e-4 under a sun 1.8e-11 off its plane
        (
            [0.00013304494998637762, -0.0001068722312356503, 4.09758903924179e-05],
            1e-12,
            [-0.09924232853966233, -1.830315902451896e-11, -0.9950632945828248],
        ),
    ],
)
def test_a_sweep_below_float64_spacing_casts_no_volume(corner, size, direction):
    # The sweep (100 caster diagonals) moves the square off its plane by
    # sweep x cosine, less than float64's spacing at its height: the far cap
    # rounds onto the near one, so the only honest volume is none.
    corner = np.array(corner)
    vertices = corner + size * np.array([[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1.0]])
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    direction = np.array(direction)
    sweep = 100 * size * np.sqrt(2)
    drop = sweep * abs(direction[1]) / np.linalg.norm(direction)
    assert drop < np.spacing(abs(corner[1]))
    volume = sg.shadow_volume((vertices, faces), sg.DirectionalLight(direction))
    assert len(volume.faces) == 0


def rotated_triangle_cells(n_cells: int, per_cell: int) -> list[np.ndarray]:
    """``per_cell`` equilateral triangles about each cell's centre, turned by
    15 degrees each: any two of one cell cross at 6 points (a star), and
    cells lie apart, so no edge crosses another cell's."""
    angles = np.radians(np.array([90.0, 210.0, 330.0]))
    loops = []
    for cell in range(n_cells):
        centre = np.array([3.0 * (cell % 200), 3.0 * (cell // 200)])
        for k in range(per_cell):
            turned = angles + np.radians(15.0 * k)
            loops.append(centre + np.column_stack([np.cos(turned), np.sin(turned)]))
    return loops


def test_crossings_estimate_sees_many_small_unions_side_by_side():
    # 16,000 cells of 8 stars: 384,000 edges (7e10 pairs, too many for the
    # pair sample to see the budget), each edge crossing exactly 14 others.
    one_cell = rotated_triangle_cells(1, 8)
    starts = np.concatenate(one_cell)
    ends = np.concatenate([np.roll(loop, -1, axis=0) for loop in one_cell])
    per_cell = brute_force_crossings(starts, ends)
    assert per_cell == 28 * 6  # 28 pairs of triangles, 6 crossings each
    loops = rotated_triangle_cells(16_000, 8)
    estimate, crossing_edges = plane2d.crossings_estimate(loops)
    assert estimate == pytest.approx(16_000 * per_cell)
    assert crossing_edges >= 16
    with pytest.raises(sg.GeometryError, match="MAX_UNION_CROSSINGS"):
        plane2d.unite(loops)


def test_crossings_estimate_within_cells_counts_each_cells_crossings_only():
    # The same loops with their cells named (as the faces' pieces of an
    # every-surface shadow are, in cells of one plane): pairs are sampled
    # within cells, so the estimate comes from the pair sample alone, and a
    # layout whose cells together hold fewer pairs than the budget needs no
    # sample at all.
    loops = rotated_triangle_cells(16_000, 8)
    cells = np.repeat(np.arange(16_000), 8)
    estimate, sampled = plane2d.crossings_estimate(loops, cells)
    assert estimate == pytest.approx(16_000 * 28 * 6, rel=0.02)
    assert sampled > 30_000  # most sampled pairs cross: the pairs are within cells
    with pytest.raises(sg.GeometryError, match="MAX_UNION_CROSSINGS"):
        plane2d.unite(loops, cells=cells)
    few = rotated_triangle_cells(4_000, 4)
    assert plane2d.crossings_estimate(few, np.repeat(np.arange(4_000), 4)) == (0.0, 0)
    # one cell holding a tangle past the budget, beside many quiet ones
    tangle = random_triangles(900, seed=4)
    starts = np.concatenate(tangle)
    ends = np.concatenate([np.roll(loop, -1, axis=0) for loop in tangle])
    exact = brute_force_crossings(starts, ends)
    quiet = [loop + [10.0, 0.0] for loop in rotated_triangle_cells(2_000, 2)]
    cells = np.concatenate([np.zeros(900, np.int64), 1 + np.repeat(np.arange(2_000), 2)])
    estimate, _ = plane2d.crossings_estimate(tangle + quiet, cells)
    assert abs(estimate - exact - 2_000 * 6) < 0.05 * exact


def test_many_small_unions_under_the_budget_are_united():
    loops = rotated_triangle_cells(4_000, 4)  # 144,000 crossings in all
    region = plane2d.unite(loops)
    star = shapely.union_all(shapely.polygons(np.array(loops[:4])))
    assert plane2d.parts_area(plane2d.components(region)) == pytest.approx(4_000 * star.area)


def test_a_proto_body_of_only_is_elements_is_skipped_with_a_note(tmp_path):
    # x3d mutant 3541 of seed 12: a Transform in a ProtoBody renamed to IS,
    # so connecting the IS elements left the body without a node
    # (StopIteration in the reader).
    source = tmp_path / "proto.x3d"
    source.write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<X3D profile="Immersive" version="3.3"><Scene>\n'
        '<ProtoDeclare name="anyShape"><ProtoInterface>\n'
        '<field name="xtranslation" accessType="inputOutput" type="SFVec3f" value="0 0 0"/>\n'
        "</ProtoInterface><ProtoBody><IS><IS>\n"
        '<connect nodeField="translation" protoField="xtranslation"/>\n'
        "</IS></IS></ProtoBody></ProtoDeclare>\n"
        '<ProtoInstance name="anyShape"/>\n'
        '<Shape><Box size="1 2 3"/></Shape>\n'
        "</Scene></X3D>\n"
    )
    scene = sg.load(source)
    assert [shape.n_faces for shape in scene.shapes] == [12]  # the Box alone
    assert any("anyShape' skipped" in note and "IS" in note for note in scene.warnings)


def brute_force_overlaps(first: np.ndarray, second: np.ndarray) -> set[tuple[int, int]]:
    overlap = np.all(first[:, None, :2] <= second[None, :, 2:], axis=2) & np.all(
        second[None, :, :2] <= first[:, None, 2:], axis=2
    )
    return set(zip(*np.nonzero(overlap), strict=True))


@pytest.mark.parametrize(("n_first", "n_second"), [(300, 250), (40, 900)])
def test_overlapping_boxes_finds_every_pair_within_the_budget(n_first, n_second):
    # (300, 250) goes through the STRtree in chunks, (40, 900) through the grid.
    from shadowgeo.lightframe import overlapping_boxes

    rng = np.random.default_rng(n_first)

    def boxes(count):
        low = rng.uniform(0, 10, size=(count, 2))
        return np.hstack([low, low + rng.uniform(0.1, 2, size=(count, 2))])

    first, second = boxes(n_first), boxes(n_second)
    i, j = overlapping_boxes(first, second)
    expected = brute_force_overlaps(first, second)
    assert set(zip(i.tolist(), j.tolist(), strict=True)) == expected
    with pytest.raises(sg.GeometryError, match="MAX_SURFACE_PAIRS"):
        overlapping_boxes(first, second, budget=len(expected) - 1)


def test_a_soup_of_large_overlapping_triangles_stops_at_the_pair_budget():
    # x3d mutant 6211 of seed 12: 6,666 large random triangles receiving
    # each other's shadows, 4.4e7 pairs: shapely ran out of memory
    # ("could not allocate numpy array"). 3,000 boxes over one another give
    # 9e6 pairs, past the 5e6 budget, in bounded memory.
    from shadowgeo.lightframe import overlapping_boxes

    boxes = np.tile([0.0, 0.0, 1.0, 1.0], (3000, 1))
    assert 3000 * 3000 > limits.MAX_SURFACE_PAIRS
    with pytest.raises(sg.GeometryError, match="MAX_SURFACE_PAIRS"):
        overlapping_boxes(boxes, boxes)


def test_usd_writer_refuses_a_vertex_past_float32_range(tmp_path):
    # x3d mutant 8906 of seed 12: a point at 3.5e38 (inside the 1e75
    # coordinate range) became inf in USD's float32 points and extent.
    pytest.importorskip("pxr")
    source = tmp_path / "far.x3d"
    source.write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<X3D profile="Interchange" version="3.3"><Scene>\n'
        '<Shape DEF="far"><IndexedFaceSet coordIndex="0 1 2 -1">'
        '<Coordinate point="0 0 0 1 0 0 0 3.5e38 0"/></IndexedFaceSet></Shape>\n'
        "</Scene></X3D>\n"
    )
    assert np.isinf(np.float32(3.5e38))
    scene = sg.load(source)
    target = tmp_path / "far.usda"
    with pytest.raises(sg.SceneError, match="float32"):
        sg.save(scene, target)
    assert list(tmp_path.iterdir()) == [source]


def test_gltf_material_factors_are_clipped_to_their_range(tmp_path):
    # glb mutant 685 of seed 12: a baseColorFactor of 1e155 went through as
    # a colour and became inf in USD's float32 displayColor.
    document = {
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "materials": [
            {
                "pbrMetallicRoughness": {"baseColorFactor": [1e155, -2, 0.5, 1]},
                "emissiveFactor": [1e155, 0.25, 3],
            }
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
        "accessors": [
            {
                "bufferView": 0,
                "componentType": 5126,
                "count": 3,
                "type": "VEC3",
                "min": [0, 0, 0],
                "max": [1, 1, 0],
            }
        ],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "buffers": [{"byteLength": 36, "uri": "tri.bin"}],
    }
    import json

    (tmp_path / "tri.bin").write_bytes(
        np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype="<f4").tobytes()
    )
    source = tmp_path / "tri.gltf"
    source.write_text(json.dumps(document))
    (shape,) = sg.load(source).shapes
    assert shape.material.diffuse_color == (1.0, 0.0, 0.5)
    assert shape.material.emissive_color == (1.0, 0.25, 1.0)


def test_an_extrusion_section_that_repeats_a_point_gets_no_caps(tmp_path):
    # x3dv mutant 685 of seed 12: a crossSection written 10,000 times over;
    # triangulating that "cap" ran for minutes in one C call.
    square = "1 1, 1 -1, -1 -1, -1 1, 1 1"
    source = tmp_path / "twice.x3d"
    source.write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<X3D profile="Interchange" version="3.3"><Scene>\n'
        f'<Shape><Extrusion spine="0 0 0 0 1 0" crossSection="{square}, {square}"/></Shape>\n'
        "</Scene></X3D>\n"
    )
    (shape,) = sg.load(source).shapes
    section_points = 10
    assert shape.n_faces == 2 * 1 * (section_points - 1)  # the sides alone, no caps
    assert any("crossSection repeats a point" in note for note in sg.load(source).warnings)


def test_gltf_node_matrix_that_is_no_rigid_transform_is_a_scene_error(tmp_path):
    # gltf mutant 8075 of seed 12: a node's matrix reordered (its last entry
    # -1) tripped an assert inside trimesh's scene graph (AssertionError).
    import json

    (tmp_path / "tri.bin").write_bytes(
        np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype="<f4").tobytes()
    )
    shuffled = [  # node ObX of the mutant, as the fuzzer left it
        0.9999999999999964, 0.0, 5.9116737227693505e-08, 5.911674072489603e-08,
        0.0, -0.9999999999999964, 0.0, 0.0,
        0.0, -5.9116737227693505e-08, 1.0, 5.911674072489603e-08,
        5.9116737227693505e-08, 5.911674072489603e-08, 0.0, -0.9999999999999964,
    ]  # fmt: skip
    document = {
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "matrix": shuffled}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [
            {
                "bufferView": 0,
                "componentType": 5126,
                "count": 3,
                "type": "VEC3",
                "min": [0, 0, 0],
                "max": [1, 1, 0],
            }
        ],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "buffers": [{"byteLength": 36, "uri": "tri.bin"}],
    }
    source = tmp_path / "tri.gltf"
    source.write_text(json.dumps(document))
    with pytest.raises(sg.SceneError, match="not a rotation, scale and translation"):
        sg.load(source)


# -- fuzz wrl 6519: a light copied 10,000 times ---------------------------------------------


def _lit_scene(count: int) -> sg.Scene:
    box = sg.Shape(
        [[0, 1, 0], [1, 1, 0], [0, 1, 1], [0, 2, 0]],
        [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        name="block",
    )
    floor = sg.Shape([[-5, 0, -5], [5, 0, -5], [5, 0, 5], [-5, 0, 5]], [[0, 2, 1], [0, 3, 2]])
    lights = [
        sg.SceneLight(sg.PointLight([0.1 * k, 6, 0.2]), name=f"lamp{k}") for k in range(count)
    ]
    return sg.Scene([floor, box], lights)


@pytest.mark.parametrize("suffix", [".x3d", ".x3dv", ".x3dj", ".glb", ".usda"])
def test_a_scene_with_more_lights_than_the_budget_is_refused_by_every_reader(
    tmp_path, monkeypatch, suffix
):
    path = tmp_path / f"lamps{suffix}"
    sg.save(_lit_scene(4), path)
    monkeypatch.setattr(limits, "MAX_LIGHTS", 4)
    assert len(sg.load(path).lights) == 4
    monkeypatch.setattr(limits, "MAX_LIGHTS", 3)
    with pytest.raises(sg.SceneError, match=r"more than 3 lights .*MAX_LIGHTS") as refused:
        sg.load(path)
    assert str(path) in str(refused.value)


def test_a_vrml_file_of_ten_thousand_and_one_lights_is_refused_naming_the_line(tmp_path):
    # The campaign's mutant held 30,006 DirectionalLights in 2.4 MB and took
    # 11 CPU-s to read and write; the budget stops it where it passes 10,000.
    light = "DirectionalLight { direction 0 -1 0 }\n"
    path = tmp_path / "lamps.wrl"
    path.write_text("#VRML V2.0 utf8\n" + light * (limits.MAX_LIGHTS + 1))
    with pytest.raises(sg.SceneError, match="more than 10,000 lights") as refused:
        sg.load(path)
    assert f"line {limits.MAX_LIGHTS + 2}" in str(refused.value)


def test_at_most_the_casting_budget_of_lights_cast_with_a_note(monkeypatch):
    monkeypatch.setattr(limits, "MAX_CASTING_LIGHTS", 2)
    result = sg.add_shadows(_lit_scene(3), surfaces=False)
    groups = sorted({shape.group for shape in result.shapes_with_role("shadow")})
    assert groups == ["shadows_lamp0", "shadows_lamp1"]
    assert any("3 lights would cast; the first 2" in note for note in result.warnings)
    named = sg.add_shadows(_lit_scene(3), lights=["lamp0", "lamp1", "lamp2"], surfaces=False)
    assert len({shape.group for shape in named.shapes_with_role("shadow")}) == 3


def test_a_geojson_field_name_that_is_not_utf8_is_one_line_naming_the_file(tmp_path):
    # The campaign's geojson mutant 38 at seed 34 (one byte set in a property
    # name): pyogrio raised a UnicodeDecodeError traceback from its field names.
    square = "[[[0, 0], [0, 10], [10, 10], [10, 0], [0, 0]]]"
    feature = (
        '{"type": "Feature", "properties": {"h\x80eight": 6.0, "height": 6.0}, '
        f'"geometry": {{"type": "Polygon", "coordinates": {square}}}}}'
    )
    path = tmp_path / "footprints.geojson"
    path.write_bytes(
        ('{"type": "FeatureCollection", "features": [' + feature + "]}").encode("latin-1")
    )
    assert b"\x80" in path.read_bytes()
    out = io.StringIO()
    with contextlib.redirect_stderr(out):
        code = cli_main(["info", str(path)])
    assert code == 1
    assert out.getvalue() == (
        f"shadowgeo info: {path}: a field name or text value is not UTF-8 (byte 0x80); refused\n"
    )
