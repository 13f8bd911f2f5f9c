"""Planning metrics (issue 33): EN 17037 at a window, BRE's amenity test, the
longest sunlit period and shadow hours per building, against sun intervals
worked out here from the sun's azimuth and elevation by the angle test."""

from __future__ import annotations

import datetime as dt
import math

import numpy as np
import pytest
import trimesh

from shadowgeo import GeometryError, Plane
from shadowgeo.metrics import (
    bre_amenity,
    day_times,
    en17037_exposure,
    en17037_level,
    longest_sunlit,
    polygon_mesh,
    shadow_hours_by_owner,
)
from shadowgeo.sun import sun_position
from shadowgeo.sunlight_surfaces import surface_sun_study
from shadowgeo.sunstudy import sun_study

SITE = dict(latitude=52.0, longitude=4.37)
MARCH = dt.date(2026, 3, 21)
FEBRUARY = dt.date(2026, 2, 20)
FIVE = dt.timedelta(minutes=5)


def box(low, high) -> trimesh.Trimesh:
    low, high = np.asarray(low, float), np.asarray(high, float)
    mesh = trimesh.creation.box(extents=high - low)
    mesh.apply_translation((low + high) / 2)
    return mesh


def _runs(flags) -> int:
    best = run = 0
    for flag in flags:
        run = run + 1 if flag else 0
        best = max(best, run)
    return best


def _positions(day, step):
    times = day_times(day, SITE["longitude"], step)
    return times, np.array([sun_position(SITE["latitude"], SITE["longitude"], t) for t in times])


def test_a_south_window_without_obstruction_has_sun_while_the_sun_is_in_front():
    # Z up, north +y: a window in the south face (y = 0, normal -y) of a
    # building. By the angle test the sun lights it while its horizontal
    # direction has a southward part: azimuth between 90 and 270 degrees.
    building = box([-10, 0, 0], [10, 12, 15])
    point, normal = [0.0, 0.0, 5.0], [0.0, -1.0, 0.0]
    for min_elevation in (0.0, 10.0, 25.0):
        exposure = en17037_exposure(
            building, point, normal, MARCH, min_elevation=min_elevation, step=FIVE, up="Z", **SITE
        )
        times, sun = _positions(MARCH, FIVE)
        counted = sun[:, 1] >= min_elevation
        in_front = (sun[:, 0] > 90) & (sun[:, 0] < 270)
        expected = in_front[counted]
        assert len(exposure.times) == int(counted.sum())
        assert exposure.sunlit.tolist() == expected.tolist()
        assert exposure.hours == pytest.approx(expected.sum() / 12.0)
        assert exposure.longest == pytest.approx(_runs(expected) / 12.0)
    assert exposure.level == en17037_level(exposure.hours)


def test_a_window_facing_a_long_wall_across_the_street_loses_the_low_sun():
    # A wall 2 km long, 10 m south of the window (y = -10), rising 3 m above it:
    # the sun clears it when its profile angle across the street,
    # atan(tan(elevation) / cos(azimuth - 180)), passes atan(3 / 10).
    building = box([-10, 0, 0], [10, 12, 15])
    opposite = box([-1000, -12, 0], [1000, -10, 8])
    point, normal = [0.0, 0.0, 5.0], [0.0, -1.0, 0.0]
    exposure = en17037_exposure(
        [building, opposite], point, normal, FEBRUARY, min_elevation=5.0, step=FIVE, up="Z", **SITE
    )
    _, sun = _positions(FEBRUARY, FIVE)
    counted = sun[:, 1] >= 5.0
    azimuth, elevation = np.radians(sun[counted, 0]), np.radians(sun[counted, 1])
    across = -np.cos(azimuth)  # the sun's horizontal direction's share towards the south
    profile = np.where(across > 0, np.tan(elevation) / np.maximum(across, 1e-300), -1.0)
    expected = profile > 3.0 / 10.0
    assert exposure.sunlit.tolist() == expected.tolist()
    assert 0 < exposure.hours < np.sum(across > 0) / 12.0  # the wall takes some sun away
    assert exposure.hours == pytest.approx(expected.sum() / 12.0)


def test_en17037_levels_follow_the_standards_hours():
    assert [en17037_level(h) for h in (0.0, 1.49, 1.5, 2.9, 3.0, 3.99, 4.0, 9.0)] == [
        "none",
        "none",
        "minimum",
        "minimum",
        "medium",
        "medium",
        "high",
        "high",
    ]


def test_longest_sunlit_counts_consecutive_samples_and_a_gap_ends_a_run():
    step = dt.timedelta(minutes=30)
    start = dt.datetime(2026, 3, 21, 6, tzinfo=dt.UTC)
    times = [start + k * step for k in range(6)] + [start + (k + 8) * step for k in range(3)]
    lit = np.array(
        [
            [1, 1, 1, 0, 1, 1, 1, 1, 1],
            [0, 1, 0, 1, 1, 0, 0, 0, 0],
        ],
        dtype=bool,
    ).T
    # point 0: three, then two before the gap and three after it (not five)
    assert longest_sunlit(lit, times, step).tolist() == [1.5, 1.0]
    with pytest.raises(GeometryError, match="samples"):
        longest_sunlit(lit[:4], times, step)


def test_bre_amenity_matches_the_ground_study_of_the_same_garden():
    # A 20 m garden north of a 12 m block: BRE's share with 2 h on 21 March
    # is the ground's sun study's (projected shadows on the plane, another
    # algorithm) over the same samples.
    block = box([-15, -8, 0], [15, 0, 12])
    garden = [[-10, 0, 0], [10, 0, 0], [10, 20, 0], [-10, 20, 0]]
    check = bre_amenity(block, garden, year=2026, up="Z", **SITE)
    step = dt.timedelta(minutes=10)
    ground = sun_study(
        block,
        Plane([0, 0, 1], 0),
        garden,
        day_times(MARCH, SITE["longitude"], step),
        step=step,
        up="Z",
        **SITE,
    )
    assert check.fraction == pytest.approx(ground.fraction_meeting(2.0), abs=1e-9)
    assert 0 < check.fraction < 1
    assert check.passes == (check.fraction >= 0.5)


def test_bre_amenity_open_and_walled_in_gardens():
    garden = [[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0]]
    far = box([500, 500, 0], [501, 501, 1])
    open_garden = bre_amenity(far, garden[::-1], year=2026, up="Z", **SITE)  # either winding
    assert open_garden.fraction == 1.0 and open_garden.passes
    walls = [
        box([-1, -1, 0], [11, 0, 60]),
        box([-1, 10, 0], [11, 11, 60]),
        box([-1, 0, 0], [0, 10, 60]),
        box([10, 0, 0], [11, 10, 60]),
    ]
    walled = bre_amenity(walls, garden, year=2026, up="Z", **SITE)
    assert walled.fraction == 0.0 and not walled.passes


def test_polygon_mesh_keeps_the_area_and_faces_up():
    vertices, faces = polygon_mesh(
        [[0, 0, 0], [0, 4, 0], [3, 4, 0], [3, 2, 0], [1, 2, 0], [1, 0, 0]], "Z"
    )
    corners = vertices[faces]
    cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert 0.5 * cross[:, 2].sum() == pytest.approx(3 * 4 - 2 * 2)
    assert np.all(cross[:, 2] > 0)
    with pytest.raises(GeometryError, match="no area"):
        polygon_mesh([[0, 0, 0], [1, 0, 0], [2, 0, 0]])


def test_shadow_hours_per_building_against_rays_at_random_points():
    low = box([0, 0, 0], [10, 10, 6])
    tower = box([0, -14, 0], [10, -4, 40])  # south of the low block: shades it
    mesh = trimesh.util.concatenate([low, tower])
    owner = np.repeat([0, 1], [len(low.faces), len(tower.faces)])
    up = mesh.face_normals[:, 2] > -0.5  # walls and roofs
    receiver = (mesh.vertices, mesh.faces[up])
    day = day_times(MARCH, SITE["longitude"], dt.timedelta(minutes=30))
    half = dt.timedelta(minutes=30)
    result = surface_sun_study([low, tower], receiver, day, step=half, levels=False, up="Z", **SITE)
    shadow = shadow_hours_by_owner(result, owner[up])
    assert shadow.owners.tolist() == [0, 1]
    # turned away: hand-counted from the faces' normals and the sun's directions
    normals = mesh.face_normals[up]
    areas = result.face_areas
    for index in (0, 1):
        mine = owner[up] == index
        turned = sum(
            areas[mine] @ (normals[mine] @ -direction <= 0) for direction in result.directions
        )
        assert shadow.turned_hours[index] == pytest.approx(turned / areas[mine].sum() / 2)
    # cast shadow: rays from 20,000 random points (a Monte Carlo mean)
    rng = np.random.default_rng(5)
    samples = 20_000
    chosen = rng.choice(len(areas), size=samples, p=areas / areas.sum())
    a, b = rng.random(samples), rng.random(samples)
    flip = a + b > 1
    a[flip], b[flip] = 1 - a[flip], 1 - b[flip]
    corners = result.vertices[result.faces[chosen]]
    points = corners[:, 0] + a[:, None] * (corners[:, 1] - corners[:, 0])
    points += b[:, None] * (corners[:, 2] - corners[:, 0])
    intersector = trimesh.ray.ray_triangle.RayMeshIntersector(mesh)
    cast = np.zeros(samples)
    for direction in result.directions:
        facing = normals[chosen] @ -direction > 0
        origins = points + 1e-6 * normals[chosen]
        blocked = intersector.intersects_any(origins, np.tile(-direction, (samples, 1)))
        cast += facing & blocked
    cast /= 2.0  # half-hour samples
    for index in (0, 1):
        mine = owner[up][chosen] == index
        spread = cast[mine].std() / math.sqrt(mine.sum())
        assert abs(cast[mine].mean() - shadow.cast_hours[index]) < 4 * spread + 1e-9
    assert shadow.cast_hours[0] > 0.5  # the tower shades the low block
    assert shadow.sun_hours == pytest.approx(len(result.times) / 2)


def test_metric_inputs_are_checked():
    building = box([-10, 0, 0], [10, 12, 15])
    with pytest.raises(GeometryError, match="normal is zero"):
        en17037_exposure(building, [0, 0, 5], [0, 0, 0], MARCH, up="Z", **SITE)
    with pytest.raises(GeometryError, match="finite"):
        en17037_exposure(building, [0, 0, math.nan], [0, -1, 0], MARCH, up="Z", **SITE)
    result = surface_sun_study(
        building, building, day_times(MARCH, 4.37, dt.timedelta(hours=2)), up="Z", **SITE
    )
    with pytest.raises(GeometryError, match="owners"):
        shadow_hours_by_owner(result, [0, 1])
