"""project_shadow against independent references, hard cases first."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
import trimesh
from reference import (
    along_direction,
    basis,
    hull_area_2d,
    ray_plane,
    segment_hits_mesh,
    textbook_shadow,
)

from shadowgeo import (
    DirectionalLight,
    GeometryError,
    Plane,
    PointLight,
    SpotLight,
    Tolerance,
    project_shadow,
    shadow_matrix,
)

GROUND = Plane([0, 1, 0], 0)
PYRAMID_VERTICES = np.array([[-2, 3, -1], [2, 3, -1], [0, 3, 2], [0, 5, 0]], dtype=float)
PYRAMID_FACES = np.array([[1, 0, 3], [2, 1, 3], [0, 2, 3], [0, 1, 2]])
SEED_SHADOW = np.array([[-7, 0, -6.5], [-1, 0, -6.5], [-4, 0, -2], [-10, 0, -12.5]], dtype=float)


def to_uv(plane, points):
    u, v = basis(plane.normal)
    rel = np.asarray(points) - (-plane.offset * plane.normal)
    return np.column_stack([rel @ u, rel @ v])


def region(shadow):
    return shadow.to_shapely() if shadow.polygons else shapely.MultiPolygon()


# -- the seed example ---------------------------------------------------------------------


def test_seed_pyramid_matrix_gives_the_published_coordinates():
    matrix = shadow_matrix(GROUND, PointLight([8, 9, 10]))
    image = np.column_stack([PYRAMID_VERTICES, np.ones(4)]) @ matrix.T
    np.testing.assert_allclose(image[:, :3] / image[:, 3:], SEED_SHADOW, atol=1e-12)


def test_seed_pyramid_shadow_is_the_hull_of_the_published_coordinates():
    shadow = project_shadow((PYRAMID_VERTICES, PYRAMID_FACES), PointLight([8, 9, 10]), GROUND)
    outline = shadow.polygons[0][0]
    expected = to_uv(GROUND, SEED_SHADOW)
    # Every published point is a corner of the outline, and nothing else is.
    assert len(outline) == 4
    for point in expected:
        assert np.min(np.linalg.norm(outline - point, axis=1)) < 1e-12
    assert shadow.area == pytest.approx(hull_area_2d(expected), rel=1e-12)
    np.testing.assert_allclose(shadow.mesh.vertices[:, 1], 0.0, atol=1e-12)
    assert shadow.mesh.area == pytest.approx(shadow.area, rel=1e-12)


def test_offset_lifts_the_mesh_towards_the_light():
    shadow = project_shadow(
        (PYRAMID_VERTICES, PYRAMID_FACES), PointLight([8, 9, 10]), GROUND, offset=0.01
    )
    np.testing.assert_allclose(shadow.mesh.vertices[:, 1], 0.01, atol=1e-12)
    # Wound counter-clockwise seen from the light: normals point to it.
    assert np.all(shadow.mesh.face_normals @ [0, 1, 0] > 0.999)


# -- arbitrary planes and lights against convex hulls --------------------------------------


def random_convex_caster(rng, center, size=1.0, n=30):
    points = center + size * rng.normal(size=(n, 3))
    return trimesh.convex.convex_hull(points)


@pytest.mark.parametrize("seed", range(12))
def test_tilted_planes_point_lights_match_the_hull_of_ray_intersections(seed):
    rng = np.random.default_rng(seed)
    normal = rng.normal(size=3)
    plane = Plane.from_point_normal(rng.normal(size=3), normal)
    n = plane.normal
    base = -plane.offset * n + rng.normal(size=3)
    base -= (base @ n + plane.offset) * n  # a point on the plane
    caster = random_convex_caster(rng, base + 3 * n, size=0.5)
    light = PointLight(base + 8 * n + rng.normal(size=3))
    shadow = project_shadow(caster, light, plane)
    hits = ray_plane(caster.vertices, light.position, n, plane.offset)
    assert shadow.area == pytest.approx(hull_area_2d(to_uv(plane, hits)), rel=1e-9)
    # Every outline corner is the image of a caster vertex: on the plane and
    # on the line from the light through that vertex.
    corners = plane.to_3d(shadow.polygons[0][0])
    assert np.all(np.min(np.linalg.norm(corners[:, None] - hits[None], axis=2), axis=1) < 1e-9)
    np.testing.assert_allclose(plane.signed_distance(shadow.mesh.vertices), 0, atol=1e-9)


@pytest.mark.parametrize("seed", range(8))
def test_directional_lights_on_tilted_planes_match_the_hull(seed):
    rng = np.random.default_rng(100 + seed)
    plane = Plane(rng.normal(size=3), rng.normal())
    n = plane.normal
    direction = -n + 0.7 * rng.normal(size=3)
    if direction @ n >= -0.1:
        direction = -n
    caster = random_convex_caster(rng, -plane.offset * n + 4 * n, size=0.7)
    light = DirectionalLight(direction)
    shadow = project_shadow(caster, light, plane)
    hits = along_direction(caster.vertices, light.direction, n, plane.offset)
    assert shadow.area == pytest.approx(hull_area_2d(to_uv(plane, hits)), rel=1e-9)


def test_shadow_matrix_maps_plane_points_to_themselves_and_the_light_to_zero():
    plane = Plane([1, 2, -0.5], 3)
    light = PointLight([4, 5, 6])
    matrix = shadow_matrix(plane, light)
    on_plane = plane.to_3d([[1.0, 2.0]])[0]
    image = matrix @ np.append(on_plane, 1)
    np.testing.assert_allclose(image[:3] / image[3], on_plane, atol=1e-12)
    np.testing.assert_allclose(matrix @ light.homogeneous, 0, atol=1e-12)


# -- anti-shadows and division by zero -----------------------------------------------------


def wall(x=1.0, top=4.0, half_width=1.0):
    """A quad in the plane x = const from the ground up to ``top``."""
    vertices = [
        [x, 0, -half_width],
        [x, 0, half_width],
        [x, top, half_width],
        [x, top, -half_width],
    ]
    return np.array(vertices, dtype=float), np.array([[0, 1, 2], [0, 2, 3]])


def test_anti_shadow_only_the_part_below_the_light_casts():
    # Light at height 2 beside a wall 4 high: the part below 2 casts the wedge
    # {x >= 1, |z| <= x}; the part above casts nothing.
    vertices, faces = wall()
    light = PointLight([0, 2, 0])
    square = np.array([[-10, 0, -10], [10, 0, -10], [10, 0, 10], [-10, 0, 10]], dtype=float)
    shadow = project_shadow((vertices, faces), light, GROUND, receiver=square)
    assert shadow.area == pytest.approx(10**2 - 1, rel=1e-9)  # integral of 2x from 1 to 10
    assert np.all(shadow.mesh.vertices[:, 0] >= 1 - 1e-9)  # nothing on the light's other side
    assert shadow.diagnostics.clipped["at_or_above_light"] == 2
    # The textbook method puts the top corners at x = -1: an anti-shadow.
    uv, _ = textbook_shadow(vertices, faces, light.homogeneous, GROUND.vector)
    assert np.any(uv[:, 0] < 0)


def test_unbounded_shadow_without_receiver_is_bounded_and_says_so():
    vertices, faces = wall()
    shadow = project_shadow((vertices, faces), PointLight([0, 2, 0]), GROUND)
    bound = shadow.diagnostics.bound
    assert shadow.diagnostics.bounded_artificially
    assert bound == pytest.approx(Tolerance.for_points(vertices, [[0, 2, 0]]).bound_length)
    assert shadow.area == pytest.approx(bound**2 - 1, rel=1e-9)
    assert np.all(np.isfinite(shadow.mesh.vertices))


@pytest.mark.parametrize("nudge", [0.0, 1e-15, -1e-15, 1e-300])
def test_vertex_at_the_lights_height_gives_no_nan(nudge):
    # A tetrahedron whose top corner is (almost) exactly at the light's height.
    vertices = np.array([[-1, 1, -1], [1, 1, -1], [0, 1, 1], [0.5, 3 + nudge, 0]], dtype=float)
    faces = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]])
    light = PointLight([-2, 3, 0.2])
    shadow = project_shadow((vertices, faces), light, GROUND)
    assert np.all(np.isfinite(shadow.mesh.vertices))
    assert np.all(np.isfinite(shadow.area)) and shadow.area > 0
    assert shadow.diagnostics.bounded_artificially
    for loops in shadow.polygons:
        for loop in loops:
            assert np.all(np.isfinite(loop))
    # The textbook matrix divides by zero (or by 1e-15) at that corner.
    uv, _ = textbook_shadow(vertices, faces, light.homogeneous, GROUND.vector)
    assert not np.all(np.isfinite(uv)) or np.abs(uv).max() > 1e12


def test_vertex_at_the_lights_height_is_clipped_by_a_receiver_exactly():
    # Triangle with a corner at the light's height: its shadow is the wedge
    # between the images of the lower corners, cut by the receiver square.
    vertices = np.array([[1, 0, -1], [1, 0, 1], [1, 2, 0]], dtype=float)
    light = PointLight([0, 2, 0])
    half = 5.0
    square = np.array([[-half, 0, -half], [half, 0, -half], [half, 0, half], [-half, 0, half]])
    shadow = project_shadow((vertices, [[0, 1, 2]]), light, GROUND, receiver=square)
    # The triangle's points (1, y, z) with |z| <= 1 - y/2 project to
    # x = 2/(2-y), z' = 2z/(2-y): the strip 1 <= x, |z'| <= 1 (z'<=x(1-y/2)... = 1).
    assert shadow.area == pytest.approx((half - 1) * 2, rel=1e-9)


# -- casters that pierce the receiver -----------------------------------------------------


def test_cube_through_the_ground_casts_only_its_upper_half():
    cube = trimesh.creation.box(extents=[2, 2, 2])  # [-1, 1]^3
    light = DirectionalLight([1, -1, 0])
    shadow = project_shadow(cube, light, GROUND)
    # Upper half [-1, 1] x [0, 1] x [-1, 1] along (1, -1, 0): x in [-1, 2].
    assert shadow.area == pytest.approx(3 * 2, rel=1e-12)
    assert shadow.diagnostics.clipped["below_plane"] > 0
    # The textbook method also projects the part below the ground: x in [-2, 2].
    uv, triangles = textbook_shadow(cube.vertices, cube.faces, light.homogeneous, GROUND.vector)
    assert shapely.union_all(triangles).area == pytest.approx(8)


def test_sphere_centred_on_the_plane_point_light():
    sphere = trimesh.creation.icosphere(subdivisions=4)
    light = PointLight([0, 4, 0])
    shadow = project_shadow(sphere, light, GROUND)
    upper = sphere.vertices[sphere.vertices[:, 1] >= 0]
    # Upper hemisphere: the hull of the images of its vertices (and the equator).
    hits = ray_plane(upper, light.position, GROUND.normal, 0.0)
    assert shadow.area == pytest.approx(hull_area_2d(to_uv(GROUND, hits)), rel=1e-9)


# -- finite receivers ----------------------------------------------------------------------


def test_convex_and_concave_receivers_clip_exactly():
    caster = trimesh.creation.box(extents=[2, 1, 2])
    caster.apply_translation([0, 2, 0])
    light = PointLight([0.3, 6, -0.2])
    free = project_shadow(caster, light, GROUND)
    l_shape = np.array(
        [[-3, 0, -3], [0, 0, -3], [0, 0, 0], [3, 0, 0], [3, 0, 3], [-3, 0, 3]], dtype=float
    )
    clipped = project_shadow(caster, light, GROUND, receiver=l_shape)
    expected = region(free).intersection(shapely.Polygon(to_uv(GROUND, l_shape)))
    assert clipped.area == pytest.approx(expected.area, rel=1e-9)
    assert clipped.to_shapely().symmetric_difference(expected).area < 1e-9 * expected.area
    assert clipped.diagnostics.limits == ("receiver",)
    # The receiver's orientation does not matter.
    again = project_shadow(caster, light, GROUND, receiver=l_shape[::-1])
    assert again.area == pytest.approx(clipped.area, rel=1e-12)


def test_shadow_falling_off_a_finite_receiver_is_cut_at_its_edge():
    caster = trimesh.creation.box(extents=[1, 1, 1])
    caster.apply_translation([0, 2, 0])
    light = DirectionalLight([1, -1, 0])
    small = np.array([[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]], dtype=float)
    shadow = project_shadow(caster, light, GROUND, receiver=small)
    # Unclipped shadow spans x in [1.5, 3.5]: it misses the receiver entirely.
    assert shadow.area == 0 and shadow.polygons == []
    assert not shadow.diagnostics.bounded_artificially


def test_receiver_off_the_plane_is_refused():
    receiver = np.array([[0, 0, 0], [1, 0.5, 0], [0, 0, 1]], dtype=float)
    with pytest.raises(GeometryError, match="receiver point 1"):
        project_shadow(
            (PYRAMID_VERTICES, PYRAMID_FACES), PointLight([8, 9, 10]), GROUND, receiver=receiver
        )


# -- lights the plane does not see, and lights in the wrong place --------------------------


@pytest.mark.parametrize(
    ("direction", "reason"),
    [([1, 0, 0], "parallel"), ([0, 1, 0], "back"), ([0.3, 1e-14, 1], "parallel")],
)
def test_directional_light_parallel_or_from_behind_gives_an_empty_shadow(direction, reason):
    shadow = project_shadow((PYRAMID_VERTICES, PYRAMID_FACES), DirectionalLight(direction), GROUND)
    assert shadow.area == 0 and len(shadow.mesh.faces) == 0
    assert reason in shadow.diagnostics.empty_reason


def test_grazing_directional_light_is_finite_and_bounded():
    shadow = project_shadow(
        (PYRAMID_VERTICES, PYRAMID_FACES), DirectionalLight([1, -1e-9, 0]), GROUND
    )
    assert np.all(np.isfinite(shadow.mesh.vertices))
    assert shadow.diagnostics.bounded_artificially


def test_light_on_the_plane_is_an_error():
    with pytest.raises(GeometryError, match="on the receiving plane"):
        project_shadow((PYRAMID_VERTICES, PYRAMID_FACES), PointLight([5, 0, 5]), GROUND)


def test_light_inside_a_closed_caster_is_an_error():
    box = trimesh.creation.box(extents=[2, 2, 2])
    box.apply_translation([0, 3, 0])
    with pytest.raises(GeometryError, match="inside the closed caster"):
        project_shadow(box, PointLight([0.1, 3.2, 0]), GROUND)


def test_light_touching_the_caster_is_an_error():
    with pytest.raises(GeometryError, match="touches the caster"):
        project_shadow((PYRAMID_VERTICES, PYRAMID_FACES), PointLight([0, 5, 0]), GROUND)


def test_point_light_behind_the_plane_gives_an_empty_shadow():
    shadow = project_shadow(
        (PYRAMID_VERTICES, PYRAMID_FACES), PointLight([0, 9, 0]), Plane([0, -1, 0], 0)
    )
    assert shadow.area == 0 and "behind" in shadow.diagnostics.empty_reason


@pytest.mark.parametrize(
    ("caster", "message"),
    [
        ((PYRAMID_VERTICES, [[0, 1, 7]]), "missing vertex"),
        (([[0, 0, np.inf], [1, 1, 1], [0, 1, 0]], [[0, 1, 2]]), "not finite"),
        ("not a mesh", "caster must be"),
    ],
)
def test_bad_casters_are_refused_with_a_clear_message(caster, message):
    with pytest.raises(GeometryError, match=message):
        project_shadow(caster, PointLight([8, 9, 10]), GROUND)


def test_nan_offset_is_refused():
    with pytest.raises(GeometryError, match="offset"):
        project_shadow(
            (PYRAMID_VERTICES, PYRAMID_FACES), PointLight([8, 9, 10]), GROUND, offset=math.nan
        )


# -- spot lights and range -----------------------------------------------------------------


def big_floor_quad(height=1.0, half=50.0):
    vertices = [
        [-half, height, -half],
        [half, height, -half],
        [half, height, half],
        [-half, height, half],
    ]
    return np.array(vertices, dtype=float), np.array([[0, 2, 1], [0, 3, 2]])


def test_spot_light_shadow_is_limited_to_the_lit_cone():
    # A huge quad at height 1 under a spot at height 3 pointing down: the
    # shadow is exactly the lit disc on the ground, radius 3 tan(angle).
    caster = big_floor_quad()
    angle = math.radians(30)
    shadow = project_shadow(caster, SpotLight([0, 3, 0], [0, -1, 0], angle), GROUND)
    radius = 3 * math.tan(angle)
    tol = Tolerance.for_points(caster[0], [[0, 3, 0]])
    assert shadow.area == pytest.approx(math.pi * radius**2, rel=10 * tol.chord)
    assert shadow.area <= math.pi * radius**2  # inscribed polygon
    assert np.all(np.linalg.norm(shadow.mesh.vertices[:, [0, 2]], axis=1) <= radius * (1 + 1e-9))
    assert "spot_cone" in shadow.diagnostics.limits


def test_spot_light_pointing_away_casts_nothing():
    shadow = project_shadow(big_floor_quad(), SpotLight([0, 3, 0], [0, 1, 0], 0.5), GROUND)
    assert shadow.area == 0 and "cone" in shadow.diagnostics.empty_reason


def test_light_radius_limits_the_shadow_to_the_lit_disc():
    caster = big_floor_quad()
    shadow = project_shadow(caster, PointLight([0, 3, 0], radius=5.0), GROUND)
    radius = math.sqrt(5.0**2 - 3.0**2)
    chord = Tolerance.for_points(caster[0], [[0, 3, 0]]).chord_length
    # An inscribed polygon within the chord tolerance of the true circle.
    distance = np.linalg.norm(shadow.polygons[0][0], axis=1)
    assert np.all(distance <= radius * (1 + 1e-12))
    assert math.pi * (radius - chord) ** 2 <= shadow.area <= math.pi * radius**2
    assert "range" in shadow.diagnostics.limits
    short = project_shadow(caster, PointLight([0, 3, 0], radius=2.0), GROUND)
    assert short.area == 0 and "radius" in short.diagnostics.empty_reason


def test_finer_chord_tolerance_converges_to_the_true_disc():
    caster = big_floor_quad()
    tol = Tolerance.for_points(caster[0], [[0, 3, 0]], chord=1e-9)
    shadow = project_shadow(caster, PointLight([0, 3, 0], radius=5.0), GROUND, tolerance=tol)
    assert shadow.area == pytest.approx(math.pi * 16.0, rel=1e-6)


# -- numerical scale and degenerate input --------------------------------------------------


def scene_shadow(transform_point, scale=1.0):
    rng = np.random.default_rng(7)
    caster = random_convex_caster(rng, np.array([0.0, 3.0, 0.0]), size=0.6)
    vertices = transform_point(caster.vertices)
    light = PointLight(transform_point(np.array([[1.5, 7.0, -0.5]]))[0])
    floor = transform_point(np.zeros((1, 3)))[0]
    plane = Plane.from_point_normal(floor, [0, 1, 0])
    return project_shadow((vertices, caster.faces), light, plane), scale, floor


@pytest.mark.parametrize(
    ("shift", "scale"), [(1e7, 1.0), (0.0, 1e-6), (0.0, 1e6), (1e7, 1e3), (-1e7, 10.0)]
)
def test_moving_or_scaling_the_scene_changes_nothing(shift, scale):
    reference, _, _ = scene_shadow(lambda p: p)
    moved, _, floor = scene_shadow(lambda p: p * scale + shift, scale)
    assert moved.area / scale**2 == pytest.approx(reference.area, rel=1e-9)
    plane = Plane.from_point_normal(floor, [0, 1, 0])
    ours = (plane.to_3d(moved.polygons[0][0]) - shift) / scale
    theirs = GROUND.to_3d(reference.polygons[0][0])
    distance = np.max(np.min(np.linalg.norm(ours[:, None] - theirs[None], axis=2), axis=1))
    assert distance < 1e-9 * 10


def test_degenerate_triangles_and_duplicate_vertices_change_nothing():
    caster = trimesh.creation.icosphere(subdivisions=2)
    caster.apply_translation([0, 3, 0])
    light = PointLight([0.5, 8, 0.2])
    reference = project_shadow(caster, light, GROUND)
    # Unmerge every vertex (a triangle soup) and add zero-area triangles.
    soup_vertices = caster.vertices[caster.faces].reshape(-1, 3)
    soup_faces = np.arange(len(soup_vertices)).reshape(-1, 3)
    degenerate = np.array([[0, 0, 1], [2, 2, 2], [3, 4, 4]])
    sliver_vertices = np.vstack([soup_vertices, [[0, 3, 0], [0, 3.5, 0], [0, 4, 0]]])
    sliver = np.array([[len(soup_vertices), len(soup_vertices) + 1, len(soup_vertices) + 2]])
    faces = np.vstack([soup_faces, degenerate, sliver])
    shadow = project_shadow((sliver_vertices, faces), light, GROUND)
    assert shadow.area == pytest.approx(reference.area, rel=1e-9)


# -- non-convex casters against brute-force ray tests --------------------------------------


@pytest.mark.parametrize(
    "light",
    [PointLight([0.7, 6, 0.4]), DirectionalLight([0.3, -1, 0.2])],
    ids=["point", "directional"],
)
def test_torus_shadow_agrees_with_brute_force_rays(light):
    torus = trimesh.creation.torus(
        major_radius=1.0, minor_radius=0.35, major_sections=24, minor_sections=12
    )
    torus.apply_transform(trimesh.transformations.rotation_matrix(0.4, [1, 0, 0]))
    torus.apply_translation([0, 2, 0])
    shadow = project_shadow(torus, light, GROUND)
    geometry = shadow.to_shapely()
    assert len(shadow.polygons) == 1
    rng = np.random.default_rng(3)
    minx, miny, maxx, maxy = geometry.bounds
    samples = np.column_stack(
        [rng.uniform(minx - 0.5, maxx + 0.5, 600), rng.uniform(miny - 0.5, maxy + 0.5, 600)]
    )
    margin = 1e-6
    boundary = geometry.boundary
    far = np.array([boundary.distance(shapely.Point(p)) > margin for p in samples])
    samples = samples[far]
    inside = shapely.contains_xy(geometry, samples[:, 0], samples[:, 1])
    points3d = GROUND.to_3d(samples)
    if isinstance(light, PointLight):
        hits = segment_hits_mesh(points3d, light.position, torus.triangles)
    else:
        hits = (
            segment_hits_mesh(points3d, None, torus.triangles)
            if False
            else np.array(
                [
                    segment_hits_mesh([p], p - 100 * light.direction, torus.triangles)[0]
                    for p in points3d
                ]
            )
        )
    assert np.array_equal(inside, hits)
    assert inside.any() and (~inside).any()


def test_flat_torus_under_a_central_light_has_a_hole_of_the_right_size():
    torus = trimesh.creation.torus(
        major_radius=1.0, minor_radius=0.25, major_sections=64, minor_sections=16
    )
    torus.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2, [1, 0, 0]))
    torus.apply_translation([0, 2, 0])
    light = PointLight([0, 6, 0])
    shadow = project_shadow(torus, light, GROUND)
    assert len(shadow.polygons) == 1 and len(shadow.polygons[0]) == 2
    outer, hole = shadow.polygons[0]
    # Reference: the images of the torus's vertices nearest to / farthest from the axis.
    hits = ray_plane(torus.vertices, light.position, GROUND.normal, 0.0)
    radial = np.linalg.norm(hits[:, [0, 2]], axis=1)
    assert np.linalg.norm(outer, axis=1).max() == pytest.approx(radial.max(), rel=1e-9)
    assert np.linalg.norm(hole, axis=1).min() == pytest.approx(radial.min(), rel=1e-9)


# -- the outline fast path against the triangle union --------------------------------------


def bumpy_sphere(subdivisions=3):
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions)
    direction = mesh.vertices / np.linalg.norm(mesh.vertices, axis=1, keepdims=True)
    wave = 1 + 0.2 * np.sin(5 * direction[:, 0]) * np.cos(6 * direction[:, 2])
    mesh.vertices = direction * wave[:, None]
    return mesh


@pytest.mark.parametrize("closed", [True, False], ids=["closed", "open"])
@pytest.mark.parametrize(
    ("light", "height"),
    [
        (PointLight([0.4, 5, 0.3]), 2.0),  # nothing clipped: silhouette only
        (PointLight([1.8, 2.2, 0.3]), 2.0),  # light beside the caster: anti-shadow clipping
        (DirectionalLight([0.3, -1, 0.1]), 0.5),  # caster pierces the plane
    ],
    ids=["silhouette", "anti-shadow", "pierced"],
)
def test_outline_path_matches_the_triangle_union(closed, light, height):
    mesh = bumpy_sphere()
    mesh.apply_translation([0, height, 0])
    faces = mesh.faces if closed else mesh.faces[5:]
    caster = trimesh.Trimesh(mesh.vertices, faces, process=False)
    assert caster.is_watertight == closed
    square = np.array([[-9, 0, -9], [9, 0, -9], [9, 0, 9], [-9, 0, 9]], dtype=float)
    fast = project_shadow(caster, light, GROUND, receiver=square)
    union = project_shadow(caster, light, GROUND, receiver=square, method="triangles")
    assert fast.area == pytest.approx(union.area, rel=1e-9)
    assert fast.to_shapely().symmetric_difference(union.to_shapely()).area <= 1e-9 * union.area
    # The fast path never hands more loops to the union; with nothing to
    # clip it hands over just the outline.
    assert fast.diagnostics.n_loops <= union.diagnostics.n_loops
    if not any(fast.diagnostics.clipped.values()):
        assert fast.diagnostics.n_loops < union.diagnostics.n_loops / 20


# -- casters standing on the receiver ----------------------------------------------------


def _boxes_on_the_ground(
    count: int, seed: int, sink: float = 0.0, spread: float = 8.0
) -> trimesh.Trimesh:
    """``count`` boxes standing on y = 0 (their bases lowered by ``sink``, as
    rounding in a scene's transforms would), turned at random, some overlapping."""
    rng = np.random.default_rng(seed)
    boxes = []
    for _ in range(count):
        width, height, depth = rng.uniform(1, 3), rng.uniform(1, 6), rng.uniform(1, 3)
        box = trimesh.creation.box([width, height, depth])
        box.apply_transform(trimesh.transformations.rotation_matrix(rng.uniform(0, 3), [0, 1, 0]))
        box.apply_translation(
            [*rng.uniform(-spread, spread, 1), height / 2, *rng.uniform(-spread, spread, 1)]
        )
        box.vertices[box.vertices[:, 1] < 1e-9, 1] = -sink
        boxes.append(box)
    return trimesh.util.concatenate(boxes)


def _hull_union(mesh: trimesh.Trimesh, light, count: int) -> shapely.Geometry:
    """Exact reference for directional light: each box's shadow is the hull of its
    eight projected corners."""
    corners = mesh.vertices.reshape(count, 8, 3)
    direction = light.direction
    flat = corners - (corners[..., 1:2] / direction[1]) * direction
    return shapely.union_all(shapely.convex_hull(shapely.multipoints(flat[..., [0, 2]])))


@pytest.mark.parametrize("sink", [0.0, 1e-13])
@pytest.mark.parametrize(
    "light",
    [
        DirectionalLight([0.7, -0.35, 0.2]),
        DirectionalLight([-0.3, -1, -0.5]),
        PointLight([3, 9, 2]),
    ],
)
def test_buildings_on_the_ground_take_the_outline_path_and_match_the_triangles(light, sink):
    mesh = _boxes_on_the_ground(40, seed=5, sink=sink)
    receiver = np.array([[-6.0, 0, -6], [6, 0, -6], [6, 0, 6], [-6, 0, 6]])  # shadows run past it
    fast = project_shadow(mesh, light, GROUND, receiver=receiver)
    slow = project_shadow(mesh, light, GROUND, receiver=receiver, method="triangles")
    assert fast.diagnostics.clipped["below_plane"] == 0
    assert fast.diagnostics.n_loops < len(mesh.faces) / 4  # outlines, not triangles
    assert fast.area == pytest.approx(slow.area, rel=1e-9)
    assert fast.to_shapely().symmetric_difference(slow.to_shapely()).area < 1e-9 * slow.area
    if isinstance(light, DirectionalLight):
        square = shapely.box(-6, -6, 6, 6)
        expected = _hull_union(mesh, light, 40).intersection(square)
        # plane 2-D coordinates of the ground are (z, x) or (x, z): compare areas
        assert fast.area == pytest.approx(expected.area, rel=1e-9)


# -- many lights in one call -------------------------------------------------------------


BATCH_LIGHTS = [
    PointLight([8, 9, 10]),
    PointLight([1.5, 2.5, 0.2]),  # at the height of caster vertices: clipped
    PointLight([0, 3, 0], radius=4.0),  # a range that cuts the shadow
    PointLight([0, -3, 0]),  # behind the plane: empty
    SpotLight([1, 6, 1], [0, -1, 0.2], 0.4),
    SpotLight([0, 3, 0], [0, 1, 0], 0.5),  # pointing away: empty
    DirectionalLight([0.3, -1, 0.2]),
    DirectionalLight([1, 0, 0]),  # parallel to the plane: empty
    DirectionalLight([1, -0.05, 0]),  # grazing: a long shadow past the bound
]


@pytest.mark.parametrize("with_receiver", [False, True])
@pytest.mark.parametrize("method", ["auto", "triangles"])
def test_a_sequence_of_lights_gives_each_lights_own_shadow_exactly(with_receiver, method):
    caster = trimesh.creation.icosphere(subdivisions=2)
    caster.apply_translation([0, 2, 0])  # from y = 1 to y = 3, the second light inside its span
    caster.vertices[caster.vertices[:, 1] > 2.9] += [0, -0.5, 0]  # dent: not convex
    receiver = (
        np.array([[-4.0, 0, -4], [4, 0, -4], [4, 0, 4], [-4, 0, 4]]) if with_receiver else None
    )
    batch = project_shadow(caster, BATCH_LIGHTS, GROUND, receiver=receiver, method=method)
    assert isinstance(batch, list) and len(batch) == len(BATCH_LIGHTS)
    empty = 0
    for light, shadow in zip(BATCH_LIGHTS, batch, strict=True):
        single = project_shadow(caster, light, GROUND, receiver=receiver, method=method)
        assert shadow.light is light
        assert shadow.area == single.area
        assert shadow.diagnostics == single.diagnostics
        assert len(shadow.polygons) == len(single.polygons)
        for part, other in zip(shadow.polygons, single.polygons, strict=True):
            assert all(np.array_equal(a, b) for a, b in zip(part, other, strict=True))
        np.testing.assert_array_equal(shadow.mesh.vertices, single.mesh.vertices)
        empty += shadow.is_empty
    assert 3 <= empty < len(BATCH_LIGHTS)  # the hard cases are there, and not all empty


def test_a_bad_light_in_a_sequence_is_named_by_its_index():
    caster = trimesh.creation.box()
    caster.apply_translation([0, 2, 0])
    with pytest.raises(GeometryError, match="light 1: .*on the receiving plane"):
        project_shadow(caster, [PointLight([0, 5, 0]), PointLight([3, 0, 0])], GROUND)
    assert project_shadow(caster, [], GROUND) == []


def _front_triangle_union(mesh: trimesh.Trimesh, light, plane: Plane) -> shapely.Geometry:
    """Independent reference for a closed caster wholly between the light and
    the plane: every triangle's corners taken along the light's rays to the
    plane, and all the triangles united by shapely (GEOS)."""
    if isinstance(light, DirectionalLight):
        flat = along_direction(mesh.vertices, light.direction, plane.normal, plane.offset)
    else:
        flat = ray_plane(mesh.vertices, light.position, plane.normal, plane.offset)
    uv = to_uv(plane, flat)[mesh.faces]
    triangles = shapely.polygons(uv)
    return shapely.union_all(triangles[shapely.area(triangles) > 0])


def test_a_batch_of_many_lights_matches_single_calls_and_a_triangle_union():
    # More than one 64-light word of front bits, both kinds, on a dented
    # (non-convex) sphere whose silhouettes have several loops that touch.
    mesh = trimesh.creation.icosphere(subdivisions=3)
    mesh.vertices[mesh.vertices[:, 1] > 0.6] *= [1, 0.6, 1]
    mesh.apply_translation([0, 2.5, 0])
    rng = np.random.default_rng(11)
    lights = [
        PointLight([*rng.uniform(-3, 3, 1), rng.uniform(5, 9), *rng.uniform(-3, 3, 1)])
        if k % 2
        else DirectionalLight([rng.uniform(-1, 1), -rng.uniform(0.4, 1), rng.uniform(-1, 1)])
        for k in range(150)
    ]
    batch = project_shadow(mesh, lights, GROUND)
    for index, (light, shadow) in enumerate(zip(lights, batch, strict=True)):
        single = project_shadow(mesh, light, GROUND)
        assert shadow.area == single.area
        assert shadow.diagnostics == single.diagnostics
        for part, other in zip(shadow.polygons, single.polygons, strict=True):
            assert all(np.array_equal(a, b) for a, b in zip(part, other, strict=True))
        if index % 10 == 0:  # the reference is slow: every tenth light
            expected = _front_triangle_union(mesh, light, GROUND)
            assert shadow.area == pytest.approx(expected.area, rel=1e-9)
            assert region(shadow).symmetric_difference(expected).area < 1e-9 * expected.area


def test_thousands_of_buildings_are_united_exactly():
    # Past the count where the 2-D union goes cell by cell.
    count = 2500
    mesh = _boxes_on_the_ground(count, seed=8, spread=200.0)
    light = DirectionalLight([0.45, -0.75, 0.3])
    shadow = project_shadow(mesh, light, GROUND)
    corners = along_direction(mesh.vertices, light.direction, GROUND.normal, GROUND.offset)
    hulls = shapely.convex_hull(shapely.multipoints(to_uv(GROUND, corners).reshape(count, 8, 2)))
    expected = shapely.union_all(hulls)  # each box's shadow: the hull of its corners' images
    assert shadow.diagnostics.n_loops == count  # one outline per building
    assert shadow.area == pytest.approx(expected.area, rel=1e-9)
    # the same region, holes (courtyards) and all
    assert region(shadow).symmetric_difference(expected).area < 1e-9 * expected.area
    assert len(shadow.polygons) == len(getattr(expected, "geoms", [expected]))


def test_a_box_made_of_many_triangles_casts_a_shadow_of_few():
    """A box whose faces are cut into 512 triangles each: its silhouette runs
    through many collinear corners, but the shadow's mesh is the hexagon's
    four triangles, with the exact area (the hull of the corners' images),
    while the polygons keep every corner the union gave."""
    mesh = trimesh.creation.box(extents=[2.0, 2.0, 2.0])
    for _ in range(4):
        mesh = mesh.subdivide()
    mesh.apply_translation([0.0, 2.0, 0.0])
    light = DirectionalLight([0.3, -1.0, 0.2])
    shadow = project_shadow(mesh, light, GROUND)
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (1, 3) for z in (-1, 1)], float)
    images = corners - (corners[:, 1:2] / light.direction[1]) * light.direction
    hull = shapely.MultiPoint(images[:, [0, 2]]).convex_hull
    assert len(shadow.mesh.faces) == 4
    assert shadow.mesh.area == pytest.approx(hull.area, rel=1e-14)
    assert shadow.area == pytest.approx(hull.area, rel=1e-14)
    assert sum(len(loop) for part in shadow.polygons for loop in part) > 6
