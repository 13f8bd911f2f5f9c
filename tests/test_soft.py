"""Soft shadows of lights with a size (shadowgeo.soft).

References: hand-derived polygons (a box under a square light), dense
sampling of the light with exact hard shadows, and an independent ray test
(Moller-Trumbore: ``benchmarks/softref.py``, which does not import shadowgeo)
of many random points of each light.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh

import shadowgeo as sg
from shadowgeo.lights import DiskLight, RectLight
from shadowgeo.plane2d import points_in_parts
from shadowgeo.soft import light_samples, soft_shadow

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from softref import ray_blocked  # noqa: E402

GROUND = sg.Plane([0, 1, 0], 0.0)


def box(size, centre):
    mesh = trimesh.creation.box(size)
    mesh.apply_translation(centre)
    return mesh


def corners_of(shadow):
    (part,) = shadow.polygons
    (outer,) = part
    return sorted(map(tuple, np.round(outer, 9).tolist()))


def test_a_box_under_a_square_light_against_hand_derived_polygons():
    # The 2 x 2 x 2 box spans y 1..3; from a point (px, 6, pz) its shadow is
    # the top face (y = 3) scaled by 6 / (6 - 3) = 2 about the point's foot:
    # x -> 2 x - px. From the corners px, pz = +-0.5 the squares
    # [-2.5, 1.5] and [-1.5, 2.5] (each way): the umbra is their common
    # [-1.5, 1.5]^2 (area 9), the penumbra their hull [-2.5, 2.5]^2 (25).
    light = RectLight([0, 6, 0], [0, -1, 0], 1, 1, up=[0, 0, 1])
    soft = soft_shadow(box([2, 2, 2], [0, 2, 0]), light, GROUND)
    assert soft.exact
    assert soft.umbra.area == pytest.approx(9, abs=1e-9)
    assert soft.penumbra.area == pytest.approx(25, abs=1e-9)
    square = lambda h: sorted((x, y) for x in (-h, h) for y in (-h, h))  # noqa: E731
    assert corners_of(soft.umbra) == square(1.5)
    assert corners_of(soft.penumbra) == square(2.5)
    # the levels tile the samples' penumbra (inside the exact one) and do not
    # overlap; the top one holds the umbra
    # (each level's area against the share of a fine grid of points whose
    # fraction rounds to it)
    grid = np.random.default_rng(3).uniform(-3, 3, (160_000, 2))  # 4 sigma: 0.1
    rounded = np.floor(soft.fraction(np.c_[grid[:, 0], np.zeros(len(grid)), grid[:, 1]]) * 8 + 0.5)
    for fraction, shadow in soft.levels:
        share = np.mean(rounded == round(fraction * 8)) * 36
        assert shadow.area == pytest.approx(share, abs=0.1)
    assert sum(s.area for _, s in soft.levels) < 25
    assert [f for f, _ in soft.levels] == [k / 8 for k in range(1, 9)]
    assert soft.levels[-1][1].area >= 9 - 1e-9
    # the fraction: the middle is hidden from all, a point past the rim from none
    fraction = soft.fraction([[0, 0, 0], [2.0, 0, 0], [2.6, 0, 0]])
    assert fraction[0] == 1 and fraction[2] == 0 and 0.4 < fraction[1] < 0.6


def test_two_boxes_under_a_long_light_corners_overstate_the_umbra():
    # Two unit boxes with a gap of 1 under a 6 x 0.2 light 4 up along x. The
    # ground under the gap is hidden from each end of the light (by the far
    # box) but sees the light's middle through the gap: inside the common
    # region of the four corner shadows, outside the umbra.
    boxes = trimesh.util.concatenate([box([1, 1, 1], [-1, 1.5, 0]), box([1, 1, 1], [1, 1.5, 0])])
    light = RectLight([0, 4, 0], [0, -1, 0], 6, 0.2, up=[0, 0, 1])
    corners = [sg.PointLight([x, 4, z]) for x in (-3, 3) for z in (-0.1, 0.1)]
    corner_shadows = sg.project_shadow(boxes, corners, GROUND)
    gap = np.array([[0.0, 0.0]])
    assert all(
        points_in_parts(GROUND.to_2d(np.array([[0.0, 0, 0]])), s.polygons)[0]
        for s in corner_shadows
    )
    soft = soft_shadow(boxes, light, GROUND, samples=256)
    assert not soft.exact
    assert soft.fraction(gap)[0] < 0.75  # the middle of the light shines through
    assert not points_in_parts(GROUND.to_2d(np.array([[0.0, 0, 0]])), soft.umbra.polygons)[0]
    # against dense sampling: 4,096 samples' exact hard shadows, and the
    # points of a fine random set hidden from all of them (the umbra) or from
    # any (the penumbra), by point-in-polygon tests
    dense = sg.project_shadow(boxes, light_samples(light, 4096, [0, 1.5, 0]), GROUND)
    xz = np.random.default_rng(5).uniform([-7, -2], [7, 2], (20_000, 2))
    points = GROUND.to_2d(np.c_[xz[:, 0], np.zeros(len(xz)), xz[:, 1]])
    hidden = np.zeros(len(points))
    for shadow in dense:
        hidden += points_in_parts(points, shadow.polygons)
    box_area = 14 * 4
    for region, share in ((soft.umbra, hidden == len(dense)), (soft.penumbra, hidden > 0)):
        inside = points_in_parts(points, region.polygons)
        assert np.mean(inside != share) * box_area < 0.06 * max(region.area, 1)
        assert region.area == pytest.approx(share.mean() * box_area, rel=0.05)


@pytest.mark.parametrize("kind", ["rect", "disk"])
def test_hidden_fraction_at_10000_points_against_ray_tests(kind):
    caster = box([2, 2, 2], [0, 2, 0])
    rng = np.random.default_rng(7)
    if kind == "rect":
        light = RectLight([0, 6, 0], [0, -1, 0], 1.5, 1.0, up=[0, 0, 1])
        u, v = rng.uniform(-0.5, 0.5, (2, 1024))
        points = np.stack([u * 1.5, np.full(1024, 6.0), v * 1.0], axis=1)
    else:
        light = DiskLight([0.3, 6, 0], [0, -1, 0], 0.8)
        r, phi = np.sqrt(rng.uniform(0, 1, 1024)) * 0.8, rng.uniform(0, 2 * math.pi, 1024)
        points = np.stack([0.3 + r * np.cos(phi), np.full(1024, 6.0), r * np.sin(phi)], axis=1)
    soft = soft_shadow(caster, light, GROUND)
    targets = np.c_[
        rng.uniform(-3.5, 3.5, 10_000), np.zeros(10_000), rng.uniform(-3.5, 3.5, 10_000)
    ]
    triangles = caster.vertices[caster.faces]
    reference = np.concatenate(
        [
            ray_blocked(
                chunk, np.broadcast_to(points, (len(chunk), *points.shape)), triangles
            ).mean(axis=1)
            for chunk in np.array_split(targets, 20)
        ]
    )
    error = np.abs(soft.fraction(targets) - reference)
    # the module's figures for 64 Hammersley samples (0.035 and 0.007 under
    # the rectangle, 0.065 and 0.010 under the disc), plus the reference's own
    # noise (1,024 random points: about 0.016, some 0.06 at the worst of
    # 10,000); a grid of 64 errs by 0.10 and 0.03 on average
    assert error.max() <= 0.13
    penumbra = (reference > 0) & (reference < 1)
    assert error[penumbra].mean() <= 0.02
    assert np.isfinite(soft.fraction(targets)).all()


def test_the_sun_disc_softens_a_pole_shadow():
    pole = box([0.2, 10, 0.2], [0, 5, 0])
    sun = sg.DirectionalLight([0.3, -1, 0.2], angle=math.radians(0.53))
    soft = soft_shadow(pole, sun, GROUND)
    hard = sg.project_shadow(pole, sg.DirectionalLight([0.3, -1, 0.2]), GROUND)
    # the penumbra holds the hard shadow, the umbra lies in it
    assert soft.umbra.area < hard.area < soft.penumbra.area
    assert not soft.exact  # a disc: bounds, not exact
    # the umbra of a 0.2 pole thins out 0.2 / tan(0.53 deg) = 21.6 along the
    # ray from the top: the pole is 10 tall, so some umbra is left
    assert soft.umbra.area > 0


@pytest.mark.parametrize(
    "zero",
    [
        sg.PointLight([1, 6, 0.5], source_radius=0.0),
        sg.SpotLight([1, 6, 0.5], [0, -1, 0], 1.2, source_radius=0.0),
        sg.DirectionalLight([0.2, -1, 0.1], angle=0.0),
    ],
)
def test_a_light_with_no_size_gives_todays_shadow_bit_for_bit(zero):
    caster = trimesh.creation.icosphere(subdivisions=2)
    caster.apply_translation([0, 2, 0])
    hard = sg.project_shadow(caster, zero, GROUND)
    soft = soft_shadow(caster, zero, GROUND)
    assert soft.umbra is soft.penumbra and len(soft.levels) == 1
    for got, want in zip(soft.umbra.polygons, hard.polygons, strict=True):
        for a, b in zip(got, want, strict=True):
            assert np.array_equal(a, b)
    assert soft.umbra.area == hard.area


def test_hard_cases_give_no_nan_and_nothing_on_the_wrong_side():
    # a square light 2 x 2 centred at the caster's top height (half of it
    # level with or below the top: anti-shadows for those samples), and a
    # light reaching below the plane (its lower half lights nothing)
    caster = box([1, 1, 1], [0, 1.5, 0])
    for light in (
        RectLight([0, 2, 2], [0, 0, -1], 2, 2, up=[0, 1, 0]),
        RectLight([3, 0.5, 0], [-1, 0, 0], 2, 2, up=[0, 1, 0]),
    ):
        soft = soft_shadow(caster, light, GROUND)
        for shadow in (soft.umbra, soft.penumbra, *(s for _, s in soft.levels)):
            for part in shadow.polygons:
                for loop in part:
                    assert np.isfinite(loop).all()
            if shadow.area:
                vertices = shadow.mesh.vertices
                assert np.isfinite(vertices).all() and np.all(vertices[:, 1] >= -1e-9)
        fraction = soft.fraction(np.array([[0.0, 0, 0], [0, 0, -3], [5, 0, 5]]))
        assert np.all((fraction >= 0) & (fraction <= 1))
    with pytest.raises(sg.GeometryError, match="behind the plane"):
        soft_shadow(caster, RectLight([0, -1, 0], [0, 1, 0], 1, 1, up=[0, 0, 1]), GROUND)
