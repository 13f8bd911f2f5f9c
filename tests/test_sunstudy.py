"""Sun positions and sun studies, against hand-derived sun angles, the exact
area of a box's shadow, and rays cast from random points to the sun."""

from __future__ import annotations

import datetime as dt
import math

import numpy as np
import pytest
import shapely
import trimesh

from shadowgeo import GeometryError, Plane
from shadowgeo.sun import frame, hourly, sun_direction, sun_lights, sun_position
from shadowgeo.sunstudy import (
    DaySummary,
    days_table,
    sun_study,
    sun_study_by_day,
    sun_summaries_by_day,
)

UTC = dt.UTC
LONDON = dict(latitude=51.5, longitude=-0.12)
GROUND = Plane([0, 1, 0], 0)
PLOT = np.array([[-20, 0, 20], [20, 0, 20], [20, 0, -20], [-20, 0, -20]], dtype=float)


def test_noon_sun_matches_the_textbook_elevation():
    # At local solar noon the sun's elevation is 90 - latitude + declination;
    # at an equinox the declination is ~0, at the June solstice ~23.44 degrees.
    for latitude, when, declination in [
        (51.48, dt.datetime(2026, 6, 21, 12, 2, tzinfo=UTC), 23.44),
        (30.0, dt.datetime(2026, 3, 20, 12, 7, tzinfo=UTC), 0.0),
    ]:
        azimuth, elevation = sun_position(latitude, 0.0, when)
        assert abs(elevation - (90 - latitude + declination)) < 0.3
        assert abs(azimuth - 180) < 2.0  # due south of a northern site


def test_direction_is_the_frame_image_of_azimuth_and_elevation():
    when = dt.datetime(2026, 3, 21, 9, 0, tzinfo=UTC)
    azimuth, elevation = sun_position(**LONDON, when=when)
    az, el = math.radians(azimuth), math.radians(elevation)
    # Y up, north -Z, east +X: the vector to the sun, negated
    expected = -np.array([math.cos(el) * math.sin(az), math.sin(el), -math.cos(el) * math.cos(az)])
    np.testing.assert_allclose(sun_direction(**LONDON, when=when), expected, atol=1e-12)
    # Z up, north +Y: the same sky, another frame
    expected_z = -np.array([math.cos(el) * math.sin(az), math.cos(el) * math.cos(az), math.sin(el)])
    np.testing.assert_allclose(sun_direction(**LONDON, when=when, up="Z"), expected_z, atol=1e-12)
    east, north, up = frame("Z")
    np.testing.assert_allclose(np.cross(east, north), up)


def test_night_and_bad_input():
    midnight = dt.datetime(2026, 3, 21, 0, 0, tzinfo=UTC)
    assert sun_direction(**LONDON, when=midnight) is None
    kept, lights = sun_lights(**LONDON, times=hourly(midnight, midnight + dt.timedelta(days=1)))
    assert 10 <= len(kept) == len(lights) <= 14  # about 12 hours of day at an equinox
    with pytest.raises(GeometryError, match="time zone"):
        sun_direction(**LONDON, when=dt.datetime(2026, 3, 21, 12))
    with pytest.raises(GeometryError, match="latitude"):
        sun_position(91.0, 0.0, midnight)
    with pytest.raises(GeometryError, match="parallel"):
        frame("Y", north=[0, 2, 0])


def _floating_box(centre, size):
    box = trimesh.creation.box(size)
    box.apply_translation(centre)
    return box


def _ray_hits_box(points, towards_sun, low, high):
    """Slab test: does the ray from each point towards the sun cross the box."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t0 = (low - points) / towards_sun
        t1 = (high - points) / towards_sun
    near = np.nanmax(np.minimum(t0, t1), axis=1)
    far = np.nanmin(np.maximum(t0, t1), axis=1)
    return (far >= np.maximum(near, 0.0)) & (far > 0)


@pytest.fixture(scope="module")
def equinox_study():
    box = _floating_box([1.0, 2.0, -0.5], [2.0, 2.0, 1.0])  # x 0..2, y 1..3, z -1..0
    day = hourly(dt.datetime(2026, 3, 21, tzinfo=UTC), dt.datetime(2026, 3, 22, tzinfo=UTC))
    # keep the sun high enough that every shadow stays on the plot
    day = [when for when in day if sun_position(**LONDON, when=when)[1] > 12.0]
    return box, day, sun_study(box, GROUND, PLOT, day, **LONDON)


def test_levels_tile_the_region_and_add_up_to_the_box_shadows(equinox_study):
    box, day, study = equinox_study
    assert len(study.times) == len(day) >= 8
    areas = study.level_areas()
    assert math.isclose(sum(areas.values()), 1600.0, rel_tol=1e-9)
    # Exact shadow of a floating w x d x h box along (dx, dy, dz): the Minkowski
    # sum of its w x d footprint and the segment h * (dx, dz) / |dy|.
    expected_shadowed = 0.0
    for when in day:
        direction = sun_direction(**LONDON, when=when)
        a, b = 2.0 * direction[0] / -direction[1], 2.0 * direction[2] / -direction[1]
        expected_shadowed += 2.0 * 1.0 + abs(a) * 1.0 + abs(b) * 2.0
    shadowed = sum(
        (len(study.times) - k)
        * shapely.MultiPolygon([shapely.Polygon(p[0], p[1:]) for p in parts]).area
        for k, parts in study.levels.items()
    )
    assert math.isclose(shadowed, expected_shadowed, rel_tol=1e-9)
    assert study.fraction_meeting(0.0) == pytest.approx(1.0)
    assert 0.95 < study.fraction_meeting(len(day)) < 1.0  # the box's shadows cover a little


def test_levels_agree_with_rays_to_the_sun(equinox_study):
    box, day, study = equinox_study
    rng = np.random.default_rng(7)
    # sample near the box, where the levels change
    uv = rng.uniform([-8, -2], [10, 12], size=(3000, 2))
    points = GROUND.to_3d(uv)
    low, high = box.bounds
    lit = np.zeros(len(points))
    for when in day:
        lit += ~_ray_hits_box(points, -sun_direction(**LONDON, when=when), low, high)
    boundaries = shapely.union_all(
        [
            shapely.LinearRing(loop)
            for parts in study.levels.values()
            for part in parts
            for loop in part
        ]
    )
    far_from_edges = shapely.distance(shapely.points(uv), boundaries) > 1e-6
    level_of = np.full(len(uv), -1)
    for k, parts in study.levels.items():
        region = shapely.MultiPolygon([shapely.Polygon(part[0], part[1:]) for part in parts])
        level_of[shapely.contains_xy(region, uv[:, 0], uv[:, 1])] = k
    assert far_from_edges.sum() > 2900
    np.testing.assert_array_equal(level_of[far_from_edges], lit[far_from_edges])
    np.testing.assert_array_equal(study.sunlit_hours(uv)[far_from_edges], lit[far_from_edges])
    assert len(set(lit[far_from_edges])) >= 3  # the sample really crosses several levels


def test_days_on_dask_equal_the_serial_run():
    box = _floating_box([0.0, 1.5, 0.0], [1.0, 1.0, 1.0])
    times = hourly(dt.datetime(2026, 6, 20, tzinfo=UTC), dt.datetime(2026, 6, 22, tzinfo=UTC))
    serial = sun_study_by_day(box, GROUND, PLOT, times, **LONDON)
    seen = []
    parallel = sun_study_by_day(
        box,
        GROUND,
        PLOT,
        times,
        **LONDON,
        scheduler="local",
        progress=lambda d, t: seen.append((d, t)),
    )
    assert list(serial.days) == list(parallel.days) == [dt.date(2026, 6, 20), dt.date(2026, 6, 21)]
    assert seen[-1] == (2, 2)
    for day, study in serial.days.items():
        other = parallel.days[day]
        assert study.times == other.times
        assert study.levels.keys() == other.levels.keys()
        for k in study.levels:
            for part, other_part in zip(study.levels[k], other.levels[k], strict=True):
                for loop, other_loop in zip(part, other_part, strict=True):
                    np.testing.assert_array_equal(loop, other_loop)
    assert serial.fraction_meeting(10.0) == parallel.fraction_meeting(10.0)


def test_day_summaries_are_the_studies_figures_here_and_on_dask():
    """sun_summaries_by_day keeps a few numbers a day, from the levels' areas
    alone: the full studies' figures to rounding, identical in this process
    and on Dask; the durations' areas add up to the plot's."""
    box = _floating_box([0.0, 1.5, 0.0], [1.0, 1.0, 1.0])
    times = hourly(dt.datetime(2026, 12, 20, tzinfo=UTC), dt.datetime(2026, 12, 23, tzinfo=UTC))
    full = sun_study_by_day(box, GROUND, PLOT, times, **LONDON)
    serial = sun_summaries_by_day(box, GROUND, PLOT, times, **LONDON)
    assert list(serial) == list(full.days)
    assert all(isinstance(summary, DaySummary) for summary in serial.values())
    for day, summary in serial.items():
        study, of_study = full.days[day], full.summaries()[day]
        assert summary.samples == of_study.samples == len(study.times) > 0
        assert summary.area == of_study.area == study.area
        assert sum(summary.level_areas.values()) == pytest.approx(1600.0, rel=1e-12)
        big = {h: a for h, a in summary.level_areas.items() if a > 1e-9 * summary.area}
        assert big.keys() == {h for h, a in of_study.level_areas.items() if a > 1e-9 * study.area}
        for hours, area in big.items():
            assert area == pytest.approx(of_study.level_areas[hours], rel=1e-12)
        for hours in (0.0, 2.0, 4.5, 8.0):
            assert summary.fraction_meeting(hours) == pytest.approx(
                study.fraction_meeting(hours), rel=1e-12, abs=1e-15
            )
    parallel = sun_summaries_by_day(box, GROUND, PLOT, times, **LONDON, scheduler="local")
    assert parallel == serial
    table = days_table(serial, 2.0)
    assert table.count("\n| 2026-12-") == 3
    assert table.splitlines()[0] == full.table(2.0).splitlines()[0]


def test_a_block_of_boxes_cut_into_tiles_agrees_with_rays():
    # 64 boxes: enough shadow vertices that the levels are computed tile by tile
    boxes = [
        _floating_box([x, 1.0 + 0.2 * (i % 3), z], [1.2, 1.6 + 0.3 * (i % 4), 0.9])
        for i, (x, z) in enumerate((x, z) for x in range(-14, 14, 4) for z in range(-14, 14, 4))
    ]
    day = hourly(dt.datetime(2026, 6, 21, tzinfo=UTC), dt.datetime(2026, 6, 22, tzinfo=UTC))
    study = sun_study(boxes, GROUND, PLOT, day, **LONDON)
    assert sum(len(loop) for s in study.shadows for part in s for loop in part) > 4000
    assert math.isclose(sum(study.level_areas().values()), 1600.0, rel_tol=1e-9)
    rng = np.random.default_rng(5)
    uv = rng.uniform(-20, 20, size=(3000, 2))
    points = GROUND.to_3d(uv)
    lit = np.full(len(points), len(study.times))
    for when in study.times:
        towards_sun = -sun_direction(**LONDON, when=when)
        hit = np.zeros(len(points), dtype=bool)
        for box in boxes:
            hit |= _ray_hits_box(points, towards_sun, *box.bounds)
        lit -= hit
    boundaries = shapely.union_all(
        [shapely.LinearRing(loop) for s in study.shadows for part in s for loop in part]
    )
    clear = shapely.distance(shapely.points(uv), boundaries) > 1e-6
    level_of = np.full(len(uv), -1)
    for k, parts in study.levels.items():
        region = shapely.MultiPolygon([shapely.Polygon(part[0], part[1:]) for part in parts])
        level_of[shapely.contains_xy(region, uv[:, 0], uv[:, 1])] = k
    assert clear.sum() > 2900
    np.testing.assert_array_equal(level_of[clear], lit[clear])
    assert len(set(lit[clear])) >= 6
