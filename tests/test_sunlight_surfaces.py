"""Sunlight on walls and roofs (issue 33): exact shadows on every face against
hand-projected polygons, ray casting at ten thousand facade points, pvlib's
published row-shading cases, and real city data."""

from __future__ import annotations

import datetime as dt
import math

import numpy as np
import pytest
import shapely
import trimesh
from needs import SHARED, absent

from shadowgeo import GeometryError
from shadowgeo import plane2d as poly
from shadowgeo.errors import BudgetError
from shadowgeo.sun import hourly
from shadowgeo.sunlight_surfaces import surface_sun_study, surface_sunlight

UTC = dt.UTC
DELFT = dict(latitude=52.0, longitude=4.37)


def box(low, high) -> trimesh.Trimesh:
    """A closed box, outward faces, between two corners."""
    low, high = np.asarray(low, float), np.asarray(high, float)
    mesh = trimesh.creation.box(extents=high - low)
    mesh.apply_translation((low + high) / 2)
    return mesh


def quad(corners) -> tuple[np.ndarray, np.ndarray]:
    """Four corners (counter-clockwise seen from the front) as two triangles."""
    return np.asarray(corners, float), np.array([[0, 1, 2], [0, 2, 3]])


def stacked(*meshes) -> tuple[np.ndarray, np.ndarray]:
    vertices, faces, base = [], [], 0
    for mesh in meshes:
        points, triangles = (mesh.vertices, mesh.faces) if hasattr(mesh, "faces") else mesh
        vertices.append(np.asarray(points, float))
        faces.append(np.asarray(triangles) + base)
        base += len(points)
    return np.concatenate(vertices), np.concatenate(faces)


def moller_trumbore(origins, direction, triangles, least):
    """(n,) whether each ray origins + t * direction, t > least, meets one of
    ``triangles`` (k, 3, 3): Moller and Trumbore's test, written out here."""
    hit = np.zeros(len(origins), dtype=bool)
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    edge1, edge2 = b - a, c - a
    p = np.cross(direction, edge2)  # (k, 3)
    det = np.einsum("kd,kd->k", edge1, p)
    usable = np.abs(det) > 1e-300
    edge1, edge2, a, p, det = edge1[usable], edge2[usable], a[usable], p[usable], det[usable]
    for start in range(0, len(origins), 2000):
        chunk = origins[start : start + 2000]
        s = chunk[:, None, :] - a[None]  # (n, k, 3)
        u = np.einsum("nkd,kd->nk", s, p) / det
        q = np.cross(s, edge1[None])
        v = np.einsum("d,nkd->nk", direction, q) / det
        t = np.einsum("nkd,kd->nk", q, edge2) / det
        inside = (u >= 0) & (v >= 0) & (u + v <= 1) & (t > least)
        hit[start : start + 2000] = inside.any(axis=1)
    return hit


# --- (a) a box's shadow on a wall and on a neighbour's flat roof, by hand ---------------


def test_box_shadow_on_a_wall_and_a_neighbours_roof_is_the_hand_projected_polygon():
    # Z up. The box [0, 2] x [0, 2] x [0, 4]; sunlight travels d = (0.5, 1, -0.5).
    caster = box([0, 0, 0], [2, 2, 4])
    # Wall: the plane y = 5, x in [-5, 5], z in [0, 10], its front towards -y (the box).
    # A box point (x, y, z) reaches y = 5 after t = 5 - y, at
    # (x + 0.5 (5 - y), z - 0.5 (5 - y)) in the wall's (x, z). The box's (x, z)
    # rectangle [0, 2] x [0, 4] moves by (2.5, -2.5) for its face y = 0 and by
    # (1.5, -1.5) for y = 2; the image is the hull of both: the hexagon
    # (2.5,-2.5) (4.5,-2.5) (4.5,1.5) (3.5,2.5) (1.5,2.5) (1.5,-1.5). Cut to the
    # wall (z >= 0): the pentagon below, area 3 x 2.5 - 1 x 1 / 2 = 7.
    wall = quad([[-5, 5, 0], [5, 5, 0], [5, 5, 10], [-5, 5, 10]])
    on_wall = shapely.Polygon([(1.5, 0), (4.5, 0), (4.5, 1.5), (3.5, 2.5), (1.5, 2.5)])
    # Roof of a neighbour: z = 1, x in [2.5, 6], y in [0, 4], facing up. Only the
    # box above z = 1 casts on it; a point reaches z = 1 after t = 2 (z - 1), at
    # (x + z - 1, y + 2 z - 2). The plan [0, 2]^2 swept from (0, 0) to (3, 6)
    # is the hexagon (0,0) (2,0) (5,6) (5,8) (3,8) (0,2); its edge (2,0)-(5,6) is
    # y = 2x - 4, so on the roof (x >= 2.5, y <= 4) the shadow is y >= 2x - 4:
    # the triangle (2.5,1) (4,4) (2.5,4), area 1.5 x 3 / 2 = 2.25.
    roof = quad([[2.5, 0, 1], [6, 0, 1], [6, 4, 1], [2.5, 4, 1]])
    on_roof = shapely.Polygon([(2.5, 1), (4, 4), (2.5, 4)])
    assert (on_wall.area, on_roof.area) == (7.0, 2.25)

    receiver = stacked(wall, roof)
    result = surface_sunlight(caster, receiver, [[0.5, 1.0, -0.5]])
    found = {}
    for faces, axes in (((0, 1), [0, 2]), ((2, 3), [0, 1])):
        loops = [loop for face in faces for loop in result.level_loops(face).get(0.0, [])]
        # the shadow's loops stay in their faces' planes
        for loop in loops:
            assert np.allclose(loop[:, 1 if axes == [0, 2] else 2], 5.0 if axes == [0, 2] else 1.0)
        found[faces] = shapely.union_all([shapely.Polygon(loop[:, axes]) for loop in loops])
    for faces, expected in (((0, 1), on_wall), ((2, 3), on_roof)):
        assert found[faces].symmetric_difference(expected).area < 1e-9
    # the faces' sunlit shares agree with the polygons: (1 - 7/100) and (1 - 2.25/14)
    areas = result.face_areas
    wall_sun = result.mean_hours()[:2] @ areas[:2] / areas[:2].sum()
    roof_sun = result.mean_hours()[2:] @ areas[2:] / areas[2:].sum()
    assert wall_sun == pytest.approx(1 - 7 / 100, abs=1e-12)
    assert roof_sun == pytest.approx(1 - 2.25 / 14, abs=1e-12)
    # points: the shadows' centroids are dark, points beside them lit
    points = [[3.0, 5.0, 1.2], [0.0, 5.0, 1.2], [3.0, 3.0, 1.0], [5.0, 1.0, 1.0]]
    faces = [_face_holding(receiver, point) for point in points]
    assert result.sunlit(points, faces)[0].tolist() == [False, True, False, True]


def _face_holding(mesh, point) -> int:
    vertices, faces = mesh
    for index, triangle in enumerate(vertices[faces]):
        u, v = triangle[1] - triangle[0], triangle[2] - triangle[0]
        normal = np.cross(u, v)
        if abs((np.asarray(point) - triangle[0]) @ normal) > 1e-9:
            continue
        m = np.array([u, v, normal]).T
        a, b, _ = np.linalg.solve(m, np.asarray(point) - triangle[0])
        if a >= 0 and b >= 0 and a + b <= 1:
            return index
    raise AssertionError(f"no face holds {point}")


def test_a_face_turned_from_the_sun_is_dark_whole_and_levels_tile_every_face():
    wall = quad([[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]])  # front towards -y
    far = box([50, 50, 0], [51, 51, 1])
    result = surface_sunlight(far, wall, [[0, 1, -1], [0, -1, -1], [0, 1, -2]])
    assert result.mean_hours().tolist() == [2.0, 2.0]
    assert [sorted(result.level_areas(face)) for face in (0, 1)] == [[2.0], [2.0]]
    assert result.fraction_meeting(2.0).tolist() == [1.0, 1.0]
    assert result.fraction_meeting(2.5).tolist() == [0.0, 0.0]
    assert result.sunlit([[0.5, 0, 0.5]], [0])[:, 0].tolist() == [True, False, True]


def test_bad_input_is_refused_with_a_message():
    wall = quad([[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]])
    far = box([50, 50, 0], [51, 51, 1])
    result = surface_sunlight(far, wall, [[0, 1, -1]], levels=False)
    with pytest.raises(GeometryError, match="without levels"):
        result.fraction_meeting(1.0)
    with pytest.raises(GeometryError, match="2 points but 1 faces"):
        result.sunlit([[0, 0, 0], [1, 0, 0]], [0])
    with pytest.raises(GeometryError, match="face indices"):
        result.sunlit([[0, 0, 0]], [7])
    with pytest.raises(GeometryError, match="step must be positive"):
        surface_sunlight(far, wall, [[0, 1, -1]], step=dt.timedelta(0))


# --- (b) ten thousand facade points against rays cast to the sun ----------------------


def _town():
    """Five boxes of different heights, close enough to shade each other."""
    return [
        box([0, 0, 0], [10, 8, 12]),
        box([14, -2, 0], [22, 6, 30]),
        box([-6, 12, 0], [8, 20, 18]),
        box([12, 10, 0], [20, 16, 6]),
        box([26, 4, 0], [32, 14, 20]),
    ]


def _random_points(vertices, faces, count, rng):
    """Points spread uniformly over the faces' area, and each one's face."""
    corners = vertices[faces]
    areas = 0.5 * np.linalg.norm(
        np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
    )
    chosen = rng.choice(len(faces), size=count, p=areas / areas.sum())
    a, b = rng.random(count), rng.random(count)
    flip = a + b > 1
    a[flip], b[flip] = 1 - a[flip], 1 - b[flip]
    triangle = corners[chosen]
    points = triangle[:, 0] + a[:, None] * (triangle[:, 1] - triangle[:, 0])
    points += b[:, None] * (triangle[:, 2] - triangle[:, 0])
    return points, chosen


def test_ten_thousand_facade_points_agree_with_rays_cast_to_the_sun_all_day():
    town = _town()
    vertices, faces = stacked(*town)
    normals = np.cross(
        vertices[faces[:, 1]] - vertices[faces[:, 0]], vertices[faces[:, 2]] - vertices[faces[:, 0]]
    )
    receiving = normals[:, 2] > -0.5  # walls and roofs, not the bottoms
    receiver = (vertices, faces[receiving])
    day = hourly(dt.datetime(2026, 4, 20, tzinfo=UTC), dt.datetime(2026, 4, 21, tzinfo=UTC))
    result = surface_sun_study(town, receiver, day, up="Z", **DELFT)
    assert len(result.times) >= 12
    rng = np.random.default_rng(33)
    points, on = _random_points(vertices, faces[receiving], 10_000, rng)
    exact = result.sunlit(points, on)

    triangles = vertices[faces]
    scale = float(np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0)))
    least, jitter = 1e-9 * scale, 1e-5 * scale
    frame_u, frame_v = result.u[on], result.v[on]
    disagreements = near_edge = 0
    for sample, direction in enumerate(result.directions):
        to_sun = -direction
        rays = ~moller_trumbore(points, to_sun, triangles, least)
        around = [
            ~moller_trumbore(points + sign * jitter * axis, to_sun, triangles, least)
            for axis in (frame_u, frame_v)
            for sign in (1, -1)
        ]
        settled = np.all([lit == rays for lit in around], axis=0)
        near_edge += int((~settled).sum())
        disagreements += int(((exact[sample] != rays) & settled).sum())
    assert disagreements == 0
    assert near_edge < 0.01 * exact.size  # only points within the jitter of an edge
    # hours at points from the levels' polygons: the level holding each point
    hours = result.sunlit_hours(points, on)
    from_levels = _hours_from_levels(result, points, on)
    assert np.array_equal(np.isnan(from_levels), np.zeros(len(points), bool))
    assert np.mean(from_levels == hours) > 0.99  # the rest lie on a level's edge
    # each face's levels tile it, and their mean is the shadows' areas' mean
    areas = result.face_areas
    for face in range(len(areas)):
        levels = result.level_areas(face)
        assert sum(levels.values()) == pytest.approx(areas[face], rel=1e-9)
        mean = sum(h * a for h, a in levels.items()) / areas[face]
        assert mean == pytest.approx(result.mean_hours()[face], abs=1e-9)


def _hours_from_levels(result, points, on):
    found = np.full(len(points), np.nan)
    relative = points - result.origin[on]
    uv = np.column_stack(
        [
            np.einsum("ij,ij->i", relative, result.u[on]),
            np.einsum("ij,ij->i", relative, result.v[on]),
        ]
    )
    for face in np.unique(on):
        mine = np.flatnonzero(on == face)
        for k, parts in result.levels[face].items():
            inside = poly.points_in_parts(uv[mine], parts)
            found[mine[inside]] = k * result.hours_per_sample
    return found


# --- (c) pvlib's shaded fraction of rows (Anderson and Jensen 2024) ---------------------

# pvlib 0.16.1, tests/test_shading.py, fixture sf1d_premises_and_expected: rows
# (x_L, z_L, theta_L, x_R, z_R, theta_R, z_0, l, theta_s, f_s), test data from
# doi:10.5281/zenodo.10513987. The row facing away from the sun is shaded;
# f_s is its shaded share of the collector width. Only the first eight rows
# are used: in the other eight the shading row lies nearly flat, its shadow is
# a band across the middle of the shaded row (0.451 of it, by the exact
# geometry) and pvlib's 1-D model counts from the shadow's upper edge down to
# the row's lower edge (0.832).
PVLIB_ROWS = [
    (1, 0.2, 50, 0, 0, 25, 0, 0.5, 80, 1),
    (1, 0.1, 50, 0, 0, 25, 0.05, 0.5, 80, 0.937191),
    (1, 0, 50, 0, 0.1, 25, 0, 0.5, 80, 0.30605),
    (1, 0, 50, 0, 0.2, 25, 0, 0.5, 80, 0),
    (1, 0.2, -25, 0, 0, -50, 0, 0.5, -80, 0),
    (1, 0.1, -25, 0, 0, -50, 0, 0.5, -80, 0.30605),
    (1, 0, -25, 0, 0.1, -50, 0.1, 0.5, -80, 0.881549),
    (1, 0, -25, 0, 0.2, -50, 0, 0.5, -80, 1),
]
ROW_LENGTH = 40.0
THICKNESS = 1e-6  # of the rows as slabs behind their collector surface


def _collector(across, height, rotation, offset, width, length):
    """The collector surface of a row along the x axis (east): its axis at
    ``across`` (the horizontal coordinate, + towards the south, where a
    positive right-handed rotation about east tilts the row) and ``height``;
    the surface ``offset`` from the axis along its normal. Returns the four
    corners (counter-clockwise seen from the front) and the unit normal."""
    theta = math.radians(rotation)
    normal_2d = np.array([math.sin(theta), math.cos(theta)])
    along_2d = np.array([math.cos(theta), -math.sin(theta)])
    centre = np.array([across, height]) + offset * normal_2d
    ends = [centre - along_2d * width / 2, centre + along_2d * width / 2]

    def lift(point, x):  # (south, up) and east -> (east, north, up)
        return [x, -point[0], point[1]]

    corners = np.array(
        [
            lift(ends[0], -length / 2),
            lift(ends[1], -length / 2),
            lift(ends[1], length / 2),
            lift(ends[0], length / 2),
        ]
    )
    normal = np.array([0.0, -normal_2d[0], normal_2d[1]])
    first = np.cross(corners[1] - corners[0], corners[2] - corners[0])
    if first @ normal < 0:
        corners = corners[::-1]
    return corners, normal


def _slab(corners, normal):
    points = np.concatenate([corners, corners - THICKNESS * normal])
    return trimesh.convex.convex_hull(points)


def _shaded_fraction(shader, shaded, to_sun):
    """Shaded share of the middle tenth of the shaded row's collector."""
    corners, normal = shaded
    middle = corners.copy()
    middle[:, 0] *= 0.1
    caster = _slab(*shader)
    result = surface_sunlight(caster, quad(middle), [-np.asarray(to_sun)], levels=False)
    areas = result.face_areas
    return float(result.shadows[0].fraction @ areas / areas.sum())


@pytest.mark.parametrize("row", PVLIB_ROWS)
def test_pvlib_shaded_fraction_of_tilted_rows(row):
    x_l, z_l, theta_l, x_r, z_r, theta_r, offset, width, zenith, expected = row
    theta = math.radians(zenith)
    to_sun = [0.0, -math.sin(theta), math.cos(theta)]  # in the plane across the rows
    left = _collector(x_l, z_l, theta_l, offset, width, ROW_LENGTH)
    right = _collector(x_r, z_r, theta_r, offset, width, ROW_LENGTH)
    # the row nearer the sun (across, + south) shades the other
    shader, shaded = (left, right) if (zenith > 0) == (x_l > x_r) else (right, left)
    assert _shaded_fraction(shader, shaded, to_sun) == pytest.approx(expected, abs=1e-5)


def test_pvlib_fixed_tilt_example_with_the_sun_off_the_rows_plane():
    # pvlib 0.16.1 shaded_fraction1d docstring, "Fixed-tilt south-facing array
    # on flat terrain": zenith 80, azimuth 135, axis azimuth 90, rotations 30,
    # collector width 2, pitch 3, offset 0.05 -> 0.47755694708090535.
    zenith, azimuth = math.radians(80), math.radians(135)
    to_sun = [
        math.sin(zenith) * math.sin(azimuth),
        math.sin(zenith) * math.cos(azimuth),
        math.cos(zenith),
    ]
    shader = _collector(3.0, 0.0, 30, 0.05, 2.0, ROW_LENGTH)
    shaded = _collector(0.0, 0.0, 30, 0.05, 2.0, ROW_LENGTH)
    assert _shaded_fraction(shader, shaded, to_sun) == pytest.approx(0.47755694708090535, abs=1e-5)


# --- real city data ----------------------------------------------------------------------


def test_rotterdam_walls_and_roofs_agree_with_rays_at_random_points():
    import shadowgeo as sg
    from shadowgeo.scene.facades import city_casters, study_city_surfaces

    path = SHARED / "corpus" / "gis" / "rotterdam_subset.city.json"
    if not path.exists():
        absent(f"{path} is not there")
    scene = sg.load(path)
    day = [dt.datetime(2026, 3, 21, hour, 30, tzinfo=UTC) for hour in range(24)]
    surfaces, result = study_city_surfaces(scene, day, latitude=51.92, longitude=4.48)
    kinds = {surfaces.kinds[k] for k in np.unique(surfaces.kind)}
    assert kinds == {"WallSurface", "RoofSurface"}
    assert len(surfaces.faces) == sum(
        len(s.semantics.faces("WallSurface")) + len(s.semantics.faces("RoofSurface"))
        for s in scene.shapes
        if s.semantics is not None
    )
    areas = result.face_areas
    tiled = np.array([sum(result.level_areas(face).values()) for face in range(len(areas))])
    assert np.allclose(tiled, areas, rtol=1e-9, atol=1e-9)
    rng = np.random.default_rng(7)
    proper = np.flatnonzero(areas > 1e-6)
    points, chosen = _random_points(surfaces.vertices, surfaces.faces[proper], 2000, rng)
    on = proper[chosen]
    exact = result.sunlit(points, on)
    vertices, faces = city_casters(scene)
    triangles = vertices[faces]
    scale = float(np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0)))
    corners = surfaces.vertices[surfaces.faces[on]]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    unsettled = wrong = 0
    for sample, direction in enumerate(result.directions):
        # The file's buildings are not closed (rays leave through their open
        # sides), so a face's back counts dark by the angle test: a surface
        # takes direct sun on its front only.
        front = normals @ -direction > 0
        rays = front & ~moller_trumbore(points, -direction, triangles, 1e-9 * scale)
        around = [
            front
            & ~moller_trumbore(points + s * 1e-5 * scale * ax, -direction, triangles, 1e-9 * scale)
            for ax in (result.u[on], result.v[on])
            for s in (1, -1)
        ]
        settled = np.all([lit == rays for lit in around], axis=0)
        unsettled += int((~settled).sum())
        wrong += int(((exact[sample] != rays) & settled).sum())
    assert wrong == 0
    assert unsettled < 0.02 * exact.size


def test_a_receiver_too_big_for_one_call_is_cast_in_halves_with_the_same_result(monkeypatch):
    # A low sun over a city can pass shadow_on_surface's union budget for all
    # faces at once; the faces are then cast in halves. Here a stand-in refuses
    # more than 7 faces, as the budget would.
    import shadowgeo.sunlight_surfaces as module

    town = _town()
    vertices, faces = stacked(*town)
    directions = [[0.3, 0.8, -0.5], [-0.6, 0.2, -0.3]]
    whole = surface_sunlight(town, (vertices, faces), directions)
    real = module.shadow_on_surface

    def refusing(casters, light, surface, **options):
        if len(surface[1]) > 7:
            raise BudgetError("past a budget (shadowgeo.limits.MAX_UNION_CROSSINGS)")
        return real(casters, light, surface, **options)

    monkeypatch.setattr(module, "shadow_on_surface", refusing)
    halves = surface_sunlight(town, (vertices, faces), directions)
    for one, other in zip(whole.shadows, halves.shadows, strict=True):
        assert np.array_equal(one.dark, other.dark)
        assert np.allclose(one.fraction, other.fraction, rtol=0, atol=1e-12)
    for face in range(len(faces)):
        assert whole.level_areas(face).keys() == halves.level_areas(face).keys()

    calls = []

    def bad_input(casters, light, surface, **options):
        calls.append(len(surface[1]))
        raise GeometryError("a bad caster: not worth halving for")

    monkeypatch.setattr(module, "shadow_on_surface", bad_input)
    with pytest.raises(GeometryError, match="not worth halving"):
        surface_sunlight(town, (vertices, faces), directions)
    assert calls == [len(faces)]  # refused once, not halved down to single faces
    # a scattered (vertices, faces) comes back from Dask as a list: one mesh
    monkeypatch.setattr(module, "shadow_on_surface", real)
    listed = surface_sunlight([vertices, faces], (vertices, faces), directions, levels=False)
    tupled = surface_sunlight((vertices, faces), (vertices, faces), directions, levels=False)
    assert np.array_equal(listed.shadows[0].fraction, tupled.shadows[0].fraction)


def test_city_files_without_semantics_or_a_site_are_refused_with_the_file_named():
    import shadowgeo as sg
    from shadowgeo import SceneError
    from shadowgeo.scene.facades import city_surfaces, study_city_surfaces

    delft = SHARED / "corpus" / "gis" / "delft_lod1.city.json"
    rotterdam = SHARED / "corpus" / "gis" / "rotterdam_subset.city.json"
    for path in (delft, rotterdam):
        if not path.exists():
            absent(f"{path} is not there")
    # LoD1 blocks: no RoofSurface or WallSurface to study
    with pytest.raises(SceneError, match="delft_lod1.*no face of the scene is a WallSurface"):
        city_surfaces(sg.load(delft))
    # no CRS: no site, so the place must be given
    day = [dt.datetime(2026, 3, 21, 12, tzinfo=UTC)]
    with pytest.raises(SceneError, match="rotterdam_subset.*latitude and longitude"):
        study_city_surfaces(sg.load(rotterdam), day)
