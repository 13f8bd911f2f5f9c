"""Sun studies with the sun's disc (``sun_angle``): against the circular
segment a straight shadow edge cuts from the disc, the point sun's hour-area,
and the point sun's own study, bit for bit, at angle 0."""

from __future__ import annotations

import datetime as dt
import math

import numpy as np
import pytest
import shapely
import trimesh

from shadowgeo import GeometryError, Plane
from shadowgeo.sun import sun_direction
from shadowgeo.sunstudy import sun_study, sun_study_by_day, sun_summaries_by_day

LONDON = dict(latitude=51.5, longitude=-0.12)
NOON = dt.datetime(2026, 3, 21, 12, 0, tzinfo=dt.UTC)
GROUND = Plane([0, 1, 0], 0)
SUN = math.radians(0.53)
HEIGHT, THICKNESS, LENGTH = 3.0, 0.2, 200.0
UP = np.array([0.0, 1.0, 0.0])


def wall_frame(when: dt.datetime) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The sun's direction at ``when``, its way along the ground (``across``,
    away from the sun) and the wall's length (``along``), the wall facing the sun."""
    direction = sun_direction(**LONDON, when=when)
    assert direction is not None
    across = direction - (direction @ UP) * UP
    across /= np.linalg.norm(across)
    return direction, across, np.cross(UP, across)


def wall(when: dt.datetime) -> trimesh.Trimesh:
    """A wall 3 high, 0.2 thick and 200 long standing on the ground across
    the sun's way at ``when``: its shadow's far edge is straight for 100
    either side."""
    _, across, along = wall_frame(when)
    box = trimesh.creation.box([LENGTH, HEIGHT, THICKNESS])
    box.apply_translation([0, HEIGHT / 2, 0])
    turn = np.eye(4)
    turn[:3, :3] = np.column_stack([along, UP, across])
    box.apply_transform(turn)
    return box


def edge_distance(when: dt.datetime) -> float:
    """How far from the wall's middle, along ``across``, the centre of the
    sun puts the shadow's far edge: the shade-side top edge's image."""
    direction, across, _ = wall_frame(when)
    return THICKNESS / 2 + HEIGHT * float(direction @ across) / -float(direction @ UP)


def disc_share(when: dt.datetime, distances: np.ndarray, angle: float) -> np.ndarray:
    """(p,) the share of the sun's disc seen from ground points ``distances``
    along ``across`` from the wall's middle, over the wall's shade-side top
    edge: the part of the disc (radius tan(angle / 2) in the plane tangent to
    the sky at its centre) on the far side of the line the edge makes there,
    by the circular segment's area, (acos t - t sqrt(1 - t^2)) / pi of the
    disc for a chord at t radii from the centre."""
    direction, across, along = wall_frame(when)
    centre = -direction  # towards the sun
    first = np.cross(centre, along)
    first /= np.linalg.norm(first)
    second = np.cross(centre, first)
    radius = math.tan(angle / 2)
    shares = []
    for distance in distances:
        point = distance * across
        top = (THICKNESS / 2) * across + HEIGHT * UP
        normal = np.cross(along, top - point)  # the plane of the point and the edge
        if normal @ UP < 0:
            normal = -normal  # towards the sky: the side the point sees
        # a direction centre + x first + y second clears the edge when normal . it > 0
        t = float(normal @ centre) / (radius * math.hypot(normal @ first, normal @ second))
        t = min(max(t, -1.0), 1.0)
        hidden = (math.acos(t) - t * math.sqrt(1 - t * t)) / math.pi
        shares.append(1.0 - hidden)
    return np.array(shares)


def strip(when: dt.datetime, half_width: float, reach: float) -> np.ndarray:
    """(4, 3) a region across the shadow's far edge, ``reach`` either side of
    it and ``half_width`` along the wall either side of its middle: far from
    its ends, so only the straight edge crosses it."""
    _, across, along = wall_frame(when)
    edge = edge_distance(when)
    corners = [(-half_width, edge - reach), (half_width, edge - reach),
               (half_width, edge + reach), (-half_width, edge + reach)]  # fmt: skip
    return np.array([a * along + b * across for a, b in corners])


def once(when: dt.datetime, **disc):
    """The study of the wall's strip at ``when`` alone, an hour's sample."""
    return sun_study(wall(when), GROUND, strip(when, 2.0, 1.0), [when], **LONDON, **disc)


TIMES = [NOON, NOON.replace(hour=9), NOON.replace(hour=15, minute=20)]


def penumbra_scan(when: dt.datetime, angle: float) -> tuple[np.ndarray, np.ndarray]:
    """(p, 2) plane points across the far edge, 0.2 either side of it, every
    0.0005, and the share of the disc each sees (:func:`disc_share`)."""
    _, across, _ = wall_frame(when)
    distances = edge_distance(when) + np.linspace(-0.2, 0.2, 801)
    return GROUND.to_2d(distances[:, None] * across), disc_share(when, distances, angle)


@pytest.mark.parametrize("when", TIMES, ids=["noon", "9:00", "15:20"])
@pytest.mark.parametrize(("samples", "worst", "mean"), [(None, 0.08, 0.025), (64, 0.04, 0.01)])
def test_hours_across_a_straight_edge_are_the_circular_segment(when, samples, worst, mean):
    # one hour's sample: the hours at a point are the share of the disc it sees
    points, share = penumbra_scan(when, SUN)
    penumbra = (share > 0) & (share < 1)
    assert penumbra.sum() > 100  # the scan crosses the whole penumbra, 0.07 to 0.15 wide
    assert share[0] == 0 and share[-1] == 1
    study = once(when, sun_angle=SUN, sun_samples=samples)
    assert study.disc_samples == (16 if samples is None else samples)
    error = np.abs(study.sunlit_hours(points) - share)
    # the samples' error (16 directions: 0.066 at most, 0.020 on average
    # over the penumbra; 64: 0.032 and 0.0085, measured here)
    assert error.max() <= worst and error[penumbra].mean() <= mean
    # and the point sun's hard edge: dark before it, an hour after it
    hard = once(when).sunlit_hours(points)
    assert set(hard[~penumbra].tolist()) <= {0.0, 1.0}
    np.testing.assert_array_equal(hard[~penumbra], share[~penumbra])


@pytest.mark.parametrize("when", TIMES, ids=["noon", "9:00", "15:20"])
def test_the_disc_keeps_the_sunlit_hour_area_of_a_straight_edge(when):
    # the penumbra takes from the lit side what it gives the shaded one: over
    # a strip across the straight edge, far from the wall's ends, the hours
    # times the area are the point sun's, but for the second-order bend of
    # the ground distance with the angle (and the samples' own mean offset)
    disc, point = once(when, sun_angle=SUN), once(when)
    totals = [sum(h * a for h, a in s.level_areas().items()) for s in (disc, point)]
    assert totals[1] == pytest.approx(4.0, abs=1e-9)  # half the 4 x 2 strip, lit an hour
    _, share = penumbra_scan(when, SUN)
    width = 0.4 * float(np.mean((share > 0) & (share < 1)))  # the penumbra's, 0.07 to 0.15
    assert abs(totals[0] - totals[1]) <= 0.005 * 4.0 * width
    # and the levels: fractional in steps of 1/16 h, tiling the strip
    assert set(disc.levels) - {0, 16} and all(0 <= k <= 16 for k in disc.levels)
    assert sum(disc.level_areas().values()) == pytest.approx(8.0, rel=1e-12)


def test_at_angle_zero_the_study_is_the_point_suns_bit_for_bit():
    cube = trimesh.creation.box([1, 1, 1])
    cube.apply_translation([0.3, 0.5, -0.2])
    plot = np.array([[-6, 0, 6], [6, 0, 6], [6, 0, -6], [-6, 0, -6]], dtype=float)
    day = [NOON.replace(hour=h, minute=30) for h in range(24)]
    before = sun_study(cube, GROUND, plot, day, **LONDON)
    after = sun_study(cube, GROUND, plot, day, **LONDON, sun_angle=0.0, sun_samples=64)
    assert (after.sun_angle, after.disc_samples) == (0.0, 1)
    assert len(after.shadows) == len(after.times) == 12
    assert before.levels.keys() == after.levels.keys()
    for k in before.levels:
        for part, again in zip(before.levels[k], after.levels[k], strict=True):
            for loop, same in zip(part, again, strict=True):
                np.testing.assert_array_equal(loop, same)
    assert before.level_areas() == after.level_areas()
    # the hours of the point sun's levels: whole samples, on the study's own shadows
    assert all(after.hours(k) == k for k in after.levels)
    points = np.random.default_rng(1).uniform(-6, 6, (200, 2))
    np.testing.assert_array_equal(before.sunlit_hours(points), after.sunlit_hours(points))


def test_a_day_with_the_disc_nests_its_levels_and_agrees_with_its_summary():
    cube = trimesh.creation.box([1, 1, 1])
    cube.apply_translation([0.3, 0.5, -0.2])
    plot = np.array([[-4, 0, 4], [4, 0, 4], [4, 0, -4], [-4, 0, -4]], dtype=float)
    day = [NOON.replace(hour=h, minute=30) for h in range(24)]
    disc = dict(sun_angle=math.radians(5.0), sun_samples=4)  # wide: a penumbra to see
    study = sun_study(cube, GROUND, plot, day, **LONDON, **disc)
    point = sun_study(cube, GROUND, plot, day, **LONDON)
    assert len(study.shadows) == 4 * len(study.times) == 4 * len(point.times)
    areas = study.level_areas()
    assert sum(areas.values()) == pytest.approx(64.0, rel=1e-12)
    assert any(hours % 1 for hours in areas)  # quarters of an hour near the edges
    # at least h hours: a region shrinking as h grows
    at_least = [study.area_with_at_least(h) for h in sorted(areas)]
    assert all(a >= b for a, b in zip(at_least, at_least[1:], strict=False))
    # each point's hours are those of the level it lies in
    points = np.random.default_rng(2).uniform(-4, 4, (300, 2))
    hours = study.sunlit_hours(points)
    for k, parts in study.levels.items():
        region = shapely.MultiPolygon([(part[0], part[1:]) for part in parts])
        inside = shapely.contains_xy(region, points[:, 0], points[:, 1])
        np.testing.assert_allclose(hours[inside], study.hours(k), rtol=0, atol=1e-12)
    # the same day by day, in full and as areas only
    (whole,) = sun_study_by_day(cube, GROUND, plot, day, **LONDON, **disc).days.values()
    assert whole.level_areas() == areas
    (summary,) = sun_summaries_by_day(cube, GROUND, plot, day, **LONDON, **disc).values()
    assert summary.level_areas.keys() == areas.keys()
    for hours_key, area in areas.items():
        assert summary.level_areas[hours_key] == pytest.approx(area, abs=1e-9)


def test_the_sun_low_on_the_horizon_darkens_the_directions_below_it():
    # a sample whose sun's centre is up, but under a wide disc half of whose
    # directions are under the horizon: those are dark everywhere
    cube = trimesh.creation.box([1, 1, 1])
    plot = np.array([[50, 0, 50], [60, 0, 50], [60, 0, 40], [50, 0, 40]], dtype=float)
    dawn = dt.datetime(2026, 6, 21, 3, 50, tzinfo=dt.UTC)  # London, the sun 0.4 degrees up
    direction = sun_direction(**LONDON, when=dawn)
    assert direction is not None and 0 < -direction[1] < math.radians(1)
    study = sun_study(
        cube, GROUND, plot, [dawn], **LONDON, sun_angle=math.radians(20), sun_samples=16
    )
    hours = study.sunlit_hours(np.array([[55.0, -45.0]]))
    # far from the cube's shadow: lit by the directions over the horizon only,
    # about the half of the disc above its centre's 0.4 degrees
    assert 0.3 < hours[0] < 0.7


def test_bad_disc():
    for angle in (-0.1, math.pi / 2, float("nan")):
        with pytest.raises(GeometryError, match="sun_angle"):
            once(NOON, sun_angle=angle)
    with pytest.raises(GeometryError, match="sun_samples"):
        once(NOON, sun_angle=SUN, sun_samples=0)
