"""add_shadows: lights, receivers and casters chosen, shadows checked against
hand-derived regions and shapely references built in the test."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st
from reference import along_direction, ray_plane

import shadowgeo as sg
from shadowgeo import GeometryError, SceneError

QUAD = [[0, 2, 1], [0, 3, 2]]  # counter-clockwise seen from +y for the corners below


def ground(half=5.0, name="ground", y=0.0):
    corners = [[-half, y, -half], [half, y, -half], [half, y, half], [-half, y, half]]
    return sg.Shape(corners, QUAD, name=name)


def box(low, high, name):
    mesh = trimesh.creation.box(bounds=[low, high])
    return sg.Shape(mesh.vertices, mesh.faces, name=name)


def light(position, name="lamp", **fields):
    return sg.SceneLight(sg.PointLight(position), name=name, **fields)


def shadows(scene):
    return scene.shapes_with_role("shadow")


def xz_union(shape):
    """The shadow's triangles as a shapely region in the (x, z) plane, and the
    sum of the triangle areas (equal to the union's area iff they do not overlap)."""
    triangles = shape.world_vertices[shape.faces][:, :, [0, 2]]
    polygons = [shapely.Polygon(t) for t in triangles]
    return shapely.union_all(polygons), sum(p.area for p in polygons)


def hull_xz(points):
    return shapely.MultiPoint(np.asarray(points)[:, [0, 2]]).convex_hull


def box_corners(low, high):
    return np.array([[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1])
                     for z in (low[2], high[2])], dtype=float)  # fmt: skip


def test_cube_under_point_light_hand_computed():
    # Cube [-0.5, 0.5] x [1, 2] x [-0.5, 0.5], light at (0, 4, 0): the top face
    # (y = 2) projects with scale 4 / (4 - 2) = 2, a square of half-width 1.
    scene = sg.Scene([ground(), box([-0.5, 1, -0.5], [0.5, 2, 0.5], "cube")], [light([0, 4, 0])])
    result = sg.add_shadows(scene)
    (shadow,) = shadows(result)
    region, triangle_sum = xz_union(shadow)
    assert region.area == pytest.approx(4.0, rel=1e-9)
    assert triangle_sum == pytest.approx(4.0, rel=1e-9)  # no overlapping triangles
    assert region.symmetric_difference(shapely.box(-1, -1, 1, 1)).area < 1e-9
    lift = 1e-3 * math.sqrt(10**2 + 4**2 + 10**2)  # the diagonal of geometry and light
    assert np.allclose(shadow.world_vertices[:, 1], lift, rtol=1e-12)
    assert shadow.material.diffuse_color == (0.0, 0.0, 0.0)
    assert shadow.material.transparency == 0.0  # shadow_intensity defaults to 1
    assert not shadow.solid and shadow.group == "shadows_lamp" and shadow.name
    assert len(scene.shapes) == 2  # the input scene is not modified
    assert len(result.shapes) == 3 and result.shapes[:2] == scene.shapes


def test_directional_light_shifts_the_shadow():
    direction = np.array([1.0, -2.0, 0.5])
    cube = ([1, 1, 1], [2, 2, 2])
    sun = sg.SceneLight(sg.DirectionalLight(direction), name="sun", shadows=True)
    result = sg.add_shadows(sg.Scene([ground(10), box(*cube, "cube")], [sun]))
    (shadow,) = shadows(result)
    expected = hull_xz(along_direction(box_corners(*cube), direction, np.array([0, 1, 0]), 0.0))
    region, triangle_sum = xz_union(shadow)
    assert region.symmetric_difference(expected).area < 1e-9 * expected.area
    assert triangle_sum == pytest.approx(expected.area, rel=1e-9)


def test_overlapping_casters_are_united_and_cut_to_a_concave_receiver():
    # An L-shaped floor: [0, 4] x [0, 2] plus [0, 2] x [2, 4] (x, z), 4 triangles.
    points = [[0, 0, 0], [4, 0, 0], [4, 0, 2], [0, 0, 2], [2, 0, 2], [2, 0, 4], [0, 0, 4]]
    floor = sg.Shape(points, [[0, 3, 1], [1, 3, 2], [3, 6, 4], [4, 6, 5]], name="floor")
    cubes = [([1, 1, 1], [2, 2, 2]), ([1.5, 0.5, 1.5], [3, 1.5, 3])]
    lamp = [1.0, 5.0, 1.0]
    scene = sg.Scene([floor, *(box(*c, f"c{i}") for i, c in enumerate(cubes))], [light(lamp)])
    result = sg.add_shadows(scene, receivers=["floor"], offset=0.0)
    (shadow,) = shadows(result)
    hulls = [
        hull_xz(ray_plane(box_corners(*c), np.array(lamp), np.array([0, 1, 0]), 0.0)) for c in cubes
    ]
    l_shape = shapely.Polygon([(0, 0), (4, 0), (4, 2), (2, 2), (2, 4), (0, 4)])
    expected = shapely.union_all(hulls).intersection(l_shape)
    region, triangle_sum = xz_union(shadow)
    assert region.symmetric_difference(expected).area < 1e-9 * expected.area
    assert triangle_sum == pytest.approx(expected.area, rel=1e-9)
    assert np.all(shadow.world_vertices[:, 1] == 0.0)


def test_lights_with_shadows_true_cast_and_the_others_do_not():
    lights = [light([0, 4, 0], "a", shadows=True), light([1, 5, 0], "b"), light([0, 6, 1], "c")]
    scene = sg.Scene([ground(), box([-0.5, 1, -0.5], [0.5, 2, 0.5], "cube")], lights)
    result = sg.add_shadows(scene)
    assert [s.group for s in shadows(result)] == ["shadows_a"]
    assert not any("no light has shadows" in w for w in result.warnings)


def test_no_light_with_shadows_uses_every_light_that_is_on_and_says_so():
    lights = [light([0, 4, 0], "a"), light([1, 5, 0], "b", on=False), light([0, 6, 1], "c")]
    scene = sg.Scene([ground(), box([-0.5, 1, -0.5], [0.5, 2, 0.5], "cube")], lights)
    result = sg.add_shadows(scene, offset=0.01)
    assert [s.group for s in shadows(result)] == ["shadows_a", "shadows_c"]
    assert any('no light has shadows="true"' in w and "a, c" in w for w in result.warnings)
    # The second light's shadows sit higher, so the two never z-fight.
    heights = [float(s.world_vertices[0, 1]) for s in shadows(result)]
    assert heights == pytest.approx([0.01, 0.015])


def test_lights_picked_by_name():
    lights = [light([0, 4, 0], "a", shadows=True), light([1, 5, 0], "b")]
    scene = sg.Scene([ground(), box([-0.5, 1, -0.5], [0.5, 2, 0.5], "cube")], lights)
    assert [s.group for s in shadows(sg.add_shadows(scene, lights=["b"]))] == ["shadows_b"]
    with pytest.raises(SceneError, match="no light named 'x'.*a, b"):
        sg.add_shadows(scene, lights=["x"])


def test_a_scene_without_lights_gets_the_default_sun():
    # Sun along (0.3, -1, 0.2): a point at height h lands (0.3 h, 0.2 h) away in
    # (x, z). The cube [0, 1] x [1, 2] x [0, 1] throws the hull of its bottom
    # square moved (0.3, 0.2) and its top square moved (0.6, 0.4): area
    # 1 + 0.3 + 0.2 (a unit square swept by (a, b) covers 1 + |a| + |b|).
    cube = box([0, 1, 0], [1, 2, 1], "cube")
    for lights in ([], [light([0, 4, 0], on=False)]):
        result = sg.add_shadows(sg.Scene([ground(), cube], lights), offset=0.0)
        (shadow,) = shadows(result)
        assert shadow.group == "shadows_sun" and not result.lights[1:]
        region, _ = xz_union(shadow)
        moved = [[0.3, 0.2], [0.6, 0.4]]
        squares = [shapely.box(dx, dz, 1 + dx, 1 + dz) for dx, dz in moved]
        expected = shapely.union_all(squares).convex_hull
        assert expected.area == pytest.approx(1.5)
        assert region.symmetric_difference(expected).area < 1e-9
        what = "no lights" if not lights else "no light that is on"
        assert any(f"has {what}; a default sun casts" in w for w in result.warnings)
    # Given lights replace it; its direction is the documented one.
    direction = sg.scene.shadows.default_sun().light.direction
    np.testing.assert_allclose(direction, np.array([0.3, -1, 0.2]) / math.sqrt(1.13))
    z_up = sg.scene.shadows.default_sun("Z").light.direction
    np.testing.assert_allclose(z_up, np.array([0.3, -0.2, -1]) / math.sqrt(1.13))
    top = sg.SceneLight(sg.DirectionalLight([0, -1, 0]), name="top")
    result = sg.add_shadows(sg.Scene([ground(), cube], []), extra_lights=[top], offset=0.0)
    region, _ = xz_union(shadows(result)[0])
    assert region.symmetric_difference(shapely.box(0, 0, 1, 1)).area < 1e-9
    assert not any("default sun" in w for w in result.warnings)
    # An empty scene: nothing to do, and it says so.
    empty = sg.add_shadows(sg.Scene([], []))
    assert empty.shapes == [] and "no geometry, so nothing casts" in empty.warnings[-1]


def test_receivers_found_automatically_skip_small_planar_shapes():
    sign = sg.Shape([[3, 1, 3], [3.5, 1, 3], [3.5, 1, 3.5], [3, 1, 3.5]], QUAD, name="sign")
    cube = box([-0.5, 1, -0.5], [0.5, 2, 0.5], "cube")
    result = sg.add_shadows(sg.Scene([ground(), sign, cube], [light([0, 4, 0])]))
    assert [s.name for s in shadows(result)] == ["shadow_lamp_ground"]
    # The small planar sign is a caster: its shadow is in the ground's.
    region, _ = xz_union(shadows(result)[0])
    sign_shadow = hull_xz(ray_plane(sign.vertices, np.array([0, 4, 0]), np.array([0, 1, 0]), 0))
    assert region.intersection(sign_shadow).area == pytest.approx(sign_shadow.area, rel=1e-9)
    assert "receivers found: ground" in " ".join(result.warnings)


def test_named_receiver_must_exist_and_be_planar():
    ball = trimesh.creation.icosphere(subdivisions=2)
    ball.apply_translation([3, 1.5, 3])
    scene = sg.Scene(
        [
            ground(),
            box([0, 1, 0], [1, 2, 1], "cube"),
            sg.Shape(ball.vertices, ball.faces, name="ball"),
        ],
        [light([0, 4, 0])],
    )
    with pytest.raises(GeometryError, match="'ball' is not planar"):
        sg.add_shadows(scene, receivers=["ball"])
    with pytest.raises(SceneError, match="no shape named 'floor'"):
        sg.add_shadows(scene, receivers=["floor"])
    with pytest.raises(GeometryError, match="not both"):
        sg.add_shadows(scene, receivers=["ground"], plane=(0, 1, 0, 0))


def test_no_receiver_gives_the_ground_under_the_lowest_point():
    # The cube's bottom (y = 1) is the lowest point: the ground is y = 1. Its top
    # (1 above it) seen from the lamp 3 above it projects scaled 3 / (3 - 1):
    # a square of half-width 0.75, area 2.25.
    scene = sg.Scene([box([-0.5, 1, -0.5], [0.5, 2, 0.5], "cube")], [light([0, 4, 0])])
    result = sg.add_shadows(scene, offset=0.0)
    (shadow,) = shadows(result)
    region, _ = xz_union(shadow)
    assert region.symmetric_difference(shapely.box(-0.75, -0.75, 0.75, 0.75)).area < 1e-9
    assert np.all(shadow.world_vertices[:, 1] == 1.0)
    assert shadow.name == "shadow_lamp_ground"
    assert any("ground plane y = 1 under the scene's lowest point" in w for w in result.warnings)
    # Z up: the same scene turned, the ground is z = 1.
    turned = box([-0.5, -0.5, 1], [0.5, 0.5, 2], "cube")
    scene = sg.Scene([turned], [light([0, 0, 4])], up_axis="Z")
    (shadow,) = shadows(sg.add_shadows(scene, offset=0.0))
    assert np.all(shadow.world_vertices[:, 2] == 1.0)
    triangles = shadow.world_vertices[shadow.faces][:, :, :2]
    region = shapely.union_all([shapely.Polygon(t) for t in triangles])
    assert region.symmetric_difference(shapely.box(-0.75, -0.75, 0.75, 0.75)).area < 1e-9
    # A lamp under the ground lights nothing on it.
    scene = sg.Scene([box([-0.5, 1, -0.5], [0.5, 2, 0.5], "cube")], [light([0, -4, 0])])
    assert shadows(sg.add_shadows(scene)) == []
    # A plane given instead receives the whole shadow.
    scene = sg.Scene([box([-0.5, 1, -0.5], [0.5, 2, 0.5], "cube")], [light([0, 4, 0])])
    (shadow,) = shadows(sg.add_shadows(scene, plane=(0, 2, 0, 0), offset=0.0))
    region, _ = xz_union(shadow)
    assert region.area == pytest.approx(4.0, rel=1e-9)  # unbounded plane: the whole shadow


def test_a_two_sided_wall_receives_on_the_lit_side_and_a_solid_one_only_in_front():
    # The wall x = 0 (normal -x as wound); the light at x = 4 is on its back.
    corners = [[0, 0, -3], [0, 3, -3], [0, 3, 3], [0, 0, 3]]
    cube = box([1, 1, -0.5], [2, 2, 0.5], "cube")
    lamp = np.array([4.0, 1.5, 0.0])
    solid = sg.Shape(corners, QUAD, name="wall", solid=True)
    assert shadows(sg.add_shadows(sg.Scene([solid, cube], [light(lamp)]), receivers=["wall"])) == []
    wall = sg.Shape(corners, QUAD, name="wall", solid=False)
    result = sg.add_shadows(sg.Scene([wall, cube], [light(lamp)]), offset=0.0)
    # the wall is a side of the scene's box, turned in: a floor, whichever
    # axis is up, so no ground plane is added under the scene
    (shadow,) = shadows(result)
    assert np.all(shadow.world_vertices[:, 0] == 0.0)
    corners = ray_plane(box_corners([1, 1, -0.5], [2, 2, 0.5]), lamp, np.array([1, 0, 0]), 0.0)
    expected = shapely.MultiPoint(corners[:, 1:]).convex_hull.intersection(shapely.box(0, -3, 3, 3))
    triangles = shadow.world_vertices[shadow.faces][:, :, 1:]
    region = shapely.union_all([shapely.Polygon(t) for t in triangles])
    assert region.symmetric_difference(expected).area < 1e-9 * expected.area
    # Wound counter-clockwise seen from the light (+x).
    a, b, c = (shadow.world_vertices[shadow.faces[:, i]] for i in range(3))
    assert np.all(np.cross(b - a, c - a)[:, 0] > 0)


def test_casters_that_cannot_shadow_are_skipped():
    below = box([-0.5, -3, -0.5], [0.5, -1, 0.5], "below")
    above = box([-0.5, 5, -0.5], [0.5, 6, 0.5], "above")  # beyond the light's height
    far = box([20, 1, 20], [21, 2, 21], "far")  # its shadow misses the ground
    scene = sg.Scene([ground(), below, above, far], [light([0, 4, 0])])
    # planar receivers only: with every surface receiving, the buried box's
    # top is rightly in the ground's shadow
    result = sg.add_shadows(scene, surfaces=False)
    assert shadows(result) == []
    assert any("no shadow falls on the receivers (ground)" in note for note in result.warnings)


def test_a_named_receiver_used_twice_receives_in_both_places():
    tiles = [ground(1, "tile"), ground(1, "tile")]
    tiles[1].transform = np.array([[1, 0, 0, 3.0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    cube = box([0.5, 1, -0.5], [2.5, 2, 0.5], "cube")  # over both tiles
    result = sg.add_shadows(sg.Scene([*tiles, cube], [light([1.5, 5, 0])]), receivers=["tile"])
    assert [s.name for s in shadows(result)] == ["shadow_lamp_tile", "shadow_lamp_tile_2"]
    centres = [float(s.world_vertices[:, 0].mean()) for s in shadows(result)]
    assert centres[0] < 1 < 2 < centres[1]


def test_spot_cone_and_radius_limit_the_shadow():
    cube = box([-0.5, 1, -0.5], [0.5, 2, 0.5], "cube")
    aside = box([3, 1, 3], [4, 2, 4], "aside")
    spot = sg.SceneLight(sg.SpotLight([0, 4, 0], [0, -1, 0], math.radians(10)), name="spot")
    (shadow,) = shadows(sg.add_shadows(sg.Scene([ground(), cube, aside], [spot]), offset=0))
    region, _ = xz_union(shadow)
    # Only the lit disc of radius 4 tan(10 deg) < 1 around the foot is shadowed:
    # the cube's shadow (half-width 1) covers it, the aside cube is out of the cone.
    disc_radius = 4 * math.tan(math.radians(10))
    assert region.area < math.pi * disc_radius**2
    assert region.area > 0.99 * math.pi * disc_radius**2
    # An inscribed polygon within the chord tolerance (1e-3 of the scene's size).
    bounds = [-disc_radius, -disc_radius, disc_radius, disc_radius]
    assert region.bounds == pytest.approx(bounds, abs=0.02)
    short = sg.SceneLight(sg.PointLight([0, 4, 0], radius=1.5), name="short")
    assert shadows(sg.add_shadows(sg.Scene([ground(), cube], [short]))) == []


def test_a_light_inside_a_caster_skips_that_caster_with_a_note():
    bulb = box([-0.2, 3.8, -0.2], [0.2, 4.2, 0.2], "bulb")
    cube = box([-0.5, 1, -0.5], [0.5, 2, 0.5], "cube")
    result = sg.add_shadows(sg.Scene([ground(), bulb, cube], [light([0, 4, 0])]))
    region, _ = xz_union(shadows(result)[0])
    assert region.area == pytest.approx(4.0, rel=1e-9)
    assert any("bulb does not cast" in w and "inside" in w for w in result.warnings)


def test_shadow_intensity_sets_transparency_and_names_are_unique_and_def_safe():
    lamp = light([0, 4, 0], "my lamp", shadows=True, shadow_intensity=0.3)
    taken = ground(name="shadow_my_lamp_ground")  # collides with the natural name
    floor = ground(name="ground", y=0.0)
    scene = sg.Scene([taken, floor, box([-0.5, 1, -0.5], [0.5, 2, 0.5], "cube")], [lamp])
    result = sg.add_shadows(scene, receivers=["ground"])
    (shadow,) = shadows(result)
    assert shadow.material.transparency == pytest.approx(0.7)
    assert shadow.group == "shadows_my_lamp"
    assert shadow.name == "shadow_my_lamp_ground_2"


def test_volume_method_adds_a_closed_volume_per_shape_and_light():
    scene = sg.Scene([ground(), box([-0.5, 1, -0.5], [0.5, 2, 0.5], "cube")], [light([0, 4, 0])])
    result = sg.add_shadows(scene, method="volume")
    volumes = result.shapes_with_role("volume")
    assert [v.group for v in volumes] == ["shadows_lamp", "shadows_lamp"]
    # The cube's volume holds the points the cube hides from the light: the
    # segment from the point to the light crosses the cube (tested by hand).
    cube = next(v for v in volumes if "cube" in v.name)
    mesh = trimesh.Trimesh(cube.vertices, cube.faces, process=False)
    assert mesh.is_watertight and mesh.volume > 0
    triangles = mesh.vertices[mesh.faces]
    assert ray_crossings([0.0, 0.5, 0.0], triangles) % 2 == 1  # hidden
    assert ray_crossings([3.0, 0.5, 0.0], triangles) % 2 == 0  # lit
    # Out of a light's reach, a shape has no volume.
    short = sg.SceneLight(sg.PointLight([0, 4, 0], radius=2.5), name="short")
    reach = sg.add_shadows(sg.Scene(scene.shapes, [short]), method="volume")
    assert [v.name for v in reach.shapes_with_role("volume")] == ["volume_short_cube"]


def ray_crossings(point, triangles, direction=(0.3141, 0.2718, 0.9127)):
    """How many triangles the ray from ``point`` crosses (Moller-Trumbore, brute force)."""
    direction = np.asarray(direction) / np.linalg.norm(direction)
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    e1, e2 = b - a, c - a
    p = np.cross(direction, e2)
    det = np.einsum("ij,ij->i", e1, p)
    ok = np.abs(det) > 1e-12
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = np.asarray(point) - a
    u = np.einsum("ij,ij->i", s, p) * inv
    q = np.cross(s, e1)
    v = (q @ direction) * inv
    t = np.einsum("ij,ij->i", e2, q) * inv
    return int(np.sum(ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)))


@settings(max_examples=25, deadline=None)
@given(
    st.tuples(*(st.floats(-2, 2) for _ in range(2))),
    st.floats(0.2, 2),
    st.tuples(st.floats(-3, 3), st.floats(3.5, 8), st.floats(-3, 3)),
)
def test_random_cube_and_light_match_the_hull_of_projected_corners(corner, height, lamp):
    low = [corner[0], 0.5, corner[1]]
    high = [corner[0] + 1, 0.5 + height, corner[1] + 1]
    scene = sg.Scene([ground(4), box(low, high, "cube")], [light(lamp)])
    expected = hull_xz(ray_plane(box_corners(low, high), np.array(lamp), np.array([0, 1, 0]), 0))
    expected = expected.intersection(shapely.box(-4, -4, 4, 4))
    found = shadows(sg.add_shadows(scene))
    if expected.area < 1e-9:
        assert not found
        return
    region, triangle_sum = xz_union(found[0])
    assert region.symmetric_difference(expected).area < 1e-7 * expected.area
    assert triangle_sum == pytest.approx(expected.area, rel=1e-7)


def test_a_ground_slab_receives_on_its_top_and_a_rug_on_it_casts_nothing():
    # Real grounds are boxes: its top patch receives, its bottom (facing down,
    # lit from behind) does not, and a rug lying in the top's plane casts nothing.
    slab = box([-5, -0.2, -5], [5, 0, 5], "slab")
    rug = sg.Shape([[1, 0, 1], [3, 0, 1], [3, 0, 3], [1, 0, 3]], QUAD, name="rug")
    cube = box([-0.5, 1, -0.5], [0.5, 2, 0.5], "cube")
    result = sg.add_shadows(sg.Scene([slab, rug, cube], [light([0, 4, 0])]), offset=0.0)
    (shadow,) = shadows(result)
    assert shadow.name == "shadow_lamp_slab"
    assert np.all(shadow.world_vertices[:, 1] == 0.0)
    region, triangle_sum = xz_union(shadow)
    assert region.symmetric_difference(shapely.box(-1, -1, 1, 1)).area < 1e-9
    assert triangle_sum == pytest.approx(4.0, rel=1e-9)


def test_progress_counts_up_to_the_total():
    cubes = [box([x, 1, -0.5], [x + 0.5, 2, 0.5], f"c{x}") for x in (-2, 0, 2)]
    lights = [light([0, 4, 0], "a", shadows=True), light([1, 5, 0], "b", shadows=True)]
    calls = []
    sg.add_shadows(sg.Scene([ground(), *cubes], lights), progress=lambda *a: calls.append(a))
    done = [d for d, _ in calls]
    assert done == sorted(done) and {4, 8} <= set(done)  # after each light's receiver
    assert calls[-1][0] == calls[-1][1] == 2 * 1 * 4  # lights x receivers x shapes


def test_progress_counts_each_light_after_the_ones_before():
    # 2 lights x 1 receiver (the ground plane) x 4 shapes: each light's
    # receiver reports once its casters are chosen, counting on from the
    # lights before it (4 of 8, then 8 of 8), then the run's end (8 of 8)
    cubes = [box([x, 1, -0.5], [x + 0.5, 2, 0.5], f"c{x}") for x in (-2, 0, 2)]
    lights = [light([0, 4, 0], "a", shadows=True), light([1, 5, 0], "b", shadows=True)]
    calls = []
    sg.add_shadows(sg.Scene([ground(), *cubes], lights), progress=lambda *a: calls.append(a))
    assert calls == [(4, 8), (8, 8), (8, 8)]


def test_volume_progress_counts_each_light_after_the_ones_before():
    # method="volume": one step per light, each counting its 4 shapes (the
    # ground and three cubes) on from the lights before it: 1..4, then 5..8
    cubes = [box([x, 1, -0.5], [x + 0.5, 2, 0.5], f"c{x}") for x in (-2, 0, 2)]
    lights = [light([0, 4, 0], "a", shadows=True), light([1, 5, 0], "b", shadows=True)]
    calls = []
    scene = sg.Scene([ground(), *cubes], lights)
    sg.add_shadows(scene, method="volume", progress=lambda *a: calls.append(a))
    assert calls == [(done, 8) for done in range(1, 9)]


def test_notes_come_in_the_order_of_the_steps():
    # shapes (earlier shadows, repeats), then the lights chosen, then the
    # receivers, then the runtime shadows; a second run keeps the first's notes
    cube = box([-0.5, 1, -0.5], [0.5, 2, 0.5], "cube")
    lights = [light([0, 4, 0], "a"), light([2, 4, 0], "b")]
    twin = box([-0.5, 1, -0.5], [0.5, 2, 0.5], "twin")
    once = sg.add_shadows(sg.Scene([ground(), cube, twin], lights))
    twice = sg.add_shadows(once)
    steps = [
        "shadows: 1 shapes repeat another's geometry exactly",
        'shadows: no light has shadows="true"; all 2 lights that are on cast shadows (a, b)',
        "shadows: receivers found: ground",
        "shadows: no light draws runtime shadows over the baked ones",
    ]
    replaced = "shadows: 2 shadow shapes added by an earlier run are replaced"  # a and b's
    expected = [*steps, replaced, *steps]
    assert len(twice.warnings) == len(expected)
    assert all(w.startswith(e) for w, e in zip(twice.warnings, expected, strict=True))


def test_running_twice_replaces_the_first_shadows():
    scene = sg.Scene([ground(), box([-0.5, 1, -0.5], [0.5, 2, 0.5], "cube")], [light([0, 4, 0])])
    once = sg.add_shadows(scene)
    twice = sg.add_shadows(once)
    assert [s.name for s in twice.shapes] == [s.name for s in once.shapes]
    assert np.array_equal(twice.shapes[-1].vertices, once.shapes[-1].vertices)


def test_receiver_search_never_looks_inside_shapes_smaller_than_a_receiver(monkeypatch):
    from shadowgeo.scene import receivers

    looked_at = []
    original = receivers.patches

    def spy(shape, tolerance, world_vertices=None):
        looked_at.append(shape.name)
        return original(shape, tolerance, world_vertices)

    monkeypatch.setattr(receivers, "patches", spy)
    boxes = [
        box([x, 0, z], [x + 0.5, 0.5, z + 0.5], f"b{x}_{z}") for x in (-3, 0, 3) for z in (-3, 3)
    ]
    result = sg.add_shadows(sg.Scene([ground(), *boxes], [light([0, 4, 0])]))
    assert looked_at == ["ground"]  # the boxes' diagonals are far below a quarter of the scene's
    # the found receiver is the ground, and each box shadow is the hand-derived hull
    (shadow,) = shadows(result)
    region, _ = xz_union(shadow)
    lamp = np.array([0, 4, 0])
    expected = shapely.union_all(
        [
            hull_xz(
                ray_plane(
                    box_corners(b.vertices.min(0), b.vertices.max(0)), lamp, np.array([0, 1, 0]), 0
                )
            )
            for b in boxes
        ]
    )
    assert region.area == pytest.approx(expected.area, rel=1e-9)


def _hills(n: int = 12, size: float = 10.0) -> sg.Shape:
    """An open heightfield spanning the scene, its lowest point at a valley."""
    x, z = np.meshgrid(np.linspace(-size, size, n), np.linspace(-size, size, n))
    y = 0.8 * np.sin(x / 3.0) * np.cos(z / 4.0)
    vertices = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    faces = []
    for i in range(n - 1):
        for j in range(n - 1):
            a, b, c, d = i * n + j, i * n + j + 1, (i + 1) * n + j, (i + 1) * n + j + 1
            faces += [[a, c, b], [b, c, d]]
    return sg.Shape(vertices, faces, name="hills", solid=False)


def test_a_terrain_spanning_the_scene_receives_instead_of_a_ground_plane_under_it():
    tower = box([-1, 1.5, -1], [1, 4, 1], "tower")
    sun = sg.SceneLight(sg.DirectionalLight([0.4, -1, 0.3]), name="sun", shadows=True)
    result = sg.add_shadows(sg.Scene([_hills(), tower], [sun]))
    shadows = result.shapes_with_role("shadow")
    assert [s.name for s in shadows] == ["shadow_sun_surfaces"]  # no plane under the hills
    assert any("hills spans the scene" in note for note in result.warnings)
    # Every shadow triangle lies on the hills (none on a plane below them).
    lowest = float(_hills().vertices[:, 1].min())
    assert shadows[0].vertices[:, 1].min() > lowest - 0.1


def test_a_lone_closed_caster_still_gets_the_ground_plane():
    ball = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
    ball.apply_translation([0, 2, 0])
    sun = sg.SceneLight(sg.DirectionalLight([0.4, -1, 0.3]), name="sun", shadows=True)
    result = sg.add_shadows(sg.Scene([sg.Shape(ball.vertices, ball.faces, name="ball")], [sun]))
    names = [s.name for s in result.shapes_with_role("shadow")]
    assert "shadow_sun_ground" in names


def test_a_table_top_is_no_floor_so_the_ground_plane_receives_too():
    # The top (y 1..1.1) is found as a receiver (a vase stands on it), but it
    # is no floor under the scene: the ground plane under the legs receives
    # too, and a sun straight down darkens exactly the top's 4 x 4 footprint.
    top = box([-2, 1, -2], [2, 1.1, 2], "top")
    legs = [
        box([x, 0, z], [x + 0.1, 1, z + 0.1], f"leg{k}")
        for k, (x, z) in enumerate([(-2, -2), (1.9, -2), (-2, 1.9), (1.9, 1.9)])
    ]
    vase = box([-0.2, 1.1, -0.2], [0.2, 1.6, 0.2], "vase")
    sun = sg.SceneLight(sg.DirectionalLight([0, -1, 0]), name="sun", shadows=True)
    result = sg.add_shadows(sg.Scene([top, *legs, vase], [sun]), surfaces=False)
    by_name = {s.name: s for s in result.shapes_with_role("shadow")}
    (on_top,) = [name for name in by_name if name.startswith("shadow_sun_top")]
    assert set(by_name) == {on_top, "shadow_sun_ground"}
    assert any("none of the receivers found is a floor" in n for n in result.warnings)
    ground_shadow = by_name["shadow_sun_ground"]
    assert np.all(ground_shadow.world_vertices[:, 1] > 0)  # lifted off y = 0, barely
    assert np.all(ground_shadow.world_vertices[:, 1] < 0.01)
    for name, area in ((on_top, 0.16), ("shadow_sun_ground", 16.0)):
        region, summed = xz_union(by_name[name])
        assert region.area == pytest.approx(area, rel=1e-12)
        assert summed == pytest.approx(area, rel=1e-12)  # no triangle overlaps another


def test_a_ground_slab_that_a_sunken_post_reaches_under_is_the_floor():
    # The slab's top (y = 0) is found; a post sunk 1 below it makes the scene's
    # lowest point lie under the slab, where the ground plane would be hidden.
    slab = box([-10, -1, -10], [10, 0, 10], "slab")
    post = box([-0.5, -1, -0.5], [0.5, 3, 0.5], "post")
    sun = sg.SceneLight(sg.DirectionalLight([0.4, -1, 0.3]), name="sun", shadows=True)
    result = sg.add_shadows(sg.Scene([slab, post], [sun]), surfaces=False)
    assert [s.name for s in result.shapes_with_role("shadow")] == ["shadow_sun_slab"]
    assert not any("floor" in note for note in result.warnings)


def test_an_open_shell_over_the_scene_is_no_terrain():
    # A box without its +x side (a car's body, seen from outside) spans the
    # scene like a terrain, but its faces cover its plan twice (top and
    # bottom): it is a shell, so the ground plane under it receives, where
    # the hills take the shadows themselves.
    shell = trimesh.creation.box(bounds=[[-3, 0.5, -3], [3, 2, 3]])
    keep = shell.face_normals[:, 0] < 0.5
    shell = sg.Shape(shell.vertices, shell.faces[keep], name="shell", solid=True)
    sun = sg.SceneLight(sg.DirectionalLight([0.4, -1, 0.3]), name="sun", shadows=True)
    result = sg.add_shadows(sg.Scene([shell], [sun]))
    names = [s.name for s in result.shapes_with_role("shadow")]
    assert "shadow_sun_ground" in names
    assert not any("spans the scene" in note for note in result.warnings)


def test_every_surface_sees_only_the_casters_a_light_reaches(monkeypatch):
    """A point light of radius 6 over a ground with steps: a box far past the
    radius is not handed to the every-surface shadow (it can shadow no lit
    point: a ray to one runs inside the radius), one straddling it is, and
    the shadows are those of the scene without the far box."""
    import shadowgeo.scene.surfaces as surfaces_module

    def box(centre, size):
        mesh = trimesh.creation.box(extents=size)
        mesh.apply_translation(centre)
        return sg.Shape(mesh.vertices, mesh.faces, name=f"box{centre[0]:g}")

    ground = box([0.0, -0.5, 0.0], [60.0, 1.0, 60.0])
    step = box([-1.0, 0.25, 0.0], [1.0, 0.5, 4.0])  # a surface the near box shades
    near = box([0.0, 1.0, 0.0], [0.6, 2.0, 0.6])
    edge = box([5.8, 1.0, 0.0], [1.0, 2.0, 1.0])  # its box meets the light's sphere
    far = box([25.0, 1.0, 0.0], [1.0, 2.0, 1.0])  # inside the scene's box: the same lift
    lamp = sg.SceneLight(sg.PointLight([0.5, 4.0, 0.0], radius=6.0), name="lamp")
    handed: list[int] = []
    original = surfaces_module.shadow_layers_on_surface

    def counting(groups, *args, **kwargs):
        handed.append(sum(len(casters) for casters in groups))
        return original(groups, *args, **kwargs)

    monkeypatch.setattr(surfaces_module, "shadow_layers_on_surface", counting)
    with_far = sg.add_shadows(sg.Scene(shapes=[ground, step, near, edge, far], lights=[lamp]))
    assert handed == [4]  # ground, step, near box and the one on the edge
    without = sg.add_shadows(sg.Scene(shapes=[ground, step, near, edge], lights=[lamp]))
    shadows = [
        {s.name: (s.world_vertices, s.faces) for s in result.shapes_with_role("shadow")}
        for result in (with_far, without)
    ]
    assert shadows[0].keys() == shadows[1].keys() and any("surfaces" in k for k in shadows[0])
    for name, (vertices, faces) in shadows[0].items():
        assert np.array_equal(vertices, shadows[1][name][0]), name
        assert np.array_equal(faces, shadows[1][name][1]), name
