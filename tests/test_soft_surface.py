"""Soft shadows on every surface (shadowgeo.soft_surface).

References: :func:`shadowgeo.shadow_on_surface` for a light with no size,
and an independent ray test written here (Moller-Trumbore, open segment
from the receiver point to each of 1,024 stratified random points of the
light) for the hidden fraction.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import shadowgeo as sg
from shadowgeo.lights import RectLight
from shadowgeo.soft_surface import soft_shadow_on_surface


def grid(corner, along, across, cells):
    """A quad split into cells x cells squares (two triangles each), wound so
    its front faces ``along x across``."""
    steps = np.linspace(0, 1, cells + 1)
    vertices = np.array(
        [
            np.add(corner, np.multiply(a, along) + np.multiply(b, across))
            for a in steps
            for b in steps
        ]
    )
    faces = []
    for i in range(cells):
        for j in range(cells):
            k = i * (cells + 1) + j
            faces += [[k, k + cells + 1, k + cells + 2], [k, k + cells + 2, k + 1]]
    return trimesh.Trimesh(vertices, faces, process=False)


# a floor (y = 0, facing up), a wall (x = 2.5, facing -x) and a column standing
# on the floor between them, under a 1.5 x 1 rectangle light up and to the left
FLOOR = grid([-4, 0, 4], [8, 0, 0], [0, 0, -8], 4)
WALL = grid([2.5, 0, -4], [0, 0, 8], [0, 4, 0], 3)
SURFACE = trimesh.util.concatenate([FLOOR, WALL])
COLUMN = trimesh.creation.box([1, 2.5, 1])
COLUMN.apply_translation([1.2, 1.25, 0])
LIGHT = RectLight([-2, 3.5, 0], [0.6, -0.8, 0], 1.5, 1.0, up=[0, 0, 1])


def rect_points(light, side, rng):
    """(side * side, 3) stratified random points of a rectangle light."""
    cells = np.stack(np.meshgrid(np.arange(side), np.arange(side)), axis=-1).reshape(-1, 2)
    square = (cells + rng.uniform(size=cells.shape)) / side - 0.5
    across = np.cross(light.up, light.direction)
    return (
        light.position
        + (square[:, :1] * light.width) * across
        + (square[:, 1:] * light.height) * light.up
    )


def blocked(origins, ends, triangles):
    """(p, l) bool: whether the open segment from each origin (p, 3) to each
    end (l, 3) meets one of the triangles (t, 3, 3) (Moller-Trumbore)."""
    direction = ends[None, :, None, :] - origins[:, None, None, :]  # (p, l, 1, 3)
    a, b, c = (triangles[None, None, :, k, :] for k in range(3))  # (1, 1, t, 3)
    edge1, edge2 = b - a, c - a
    p_vec = np.cross(direction, edge2)
    det = np.einsum("...i,...i", edge1, p_vec)
    with np.errstate(divide="ignore", invalid="ignore"):
        inverse = 1.0 / det
        t_vec = origins[:, None, None, :] - a
        u = np.einsum("...i,...i", t_vec, p_vec) * inverse
        q_vec = np.cross(t_vec, edge1)
        v = np.einsum("...i,...i", direction, q_vec) * inverse
        t = np.einsum("...i,...i", edge2, q_vec) * inverse
    hit = (np.abs(det) > 1e-12) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-9) & (t < 1 - 1e-9)
    return hit.any(axis=2)


def hidden_at(soft, points, faces):
    """(p,) the fraction of the level holding each of ``points`` (p, 3), each
    in the surface face ``faces`` (p,) says; 0 where no level holds it."""
    hidden = np.zeros(len(points))
    for fraction, level in soft.levels:
        triangles = level.vertices[level.faces]
        a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
        normal = np.cross(b - a, c - a)
        proper = np.linalg.norm(normal, axis=1) > 1e-12  # slivers of no area hold nothing
        for index in np.flatnonzero(np.isin(faces, level.face_index)):
            mine = (level.face_index == faces[index]) & proper
            point = points[index]
            inside = np.ones(int(mine.sum()), dtype=bool)
            for p, q in ((a, b), (b, c), (c, a)):
                turn = np.cross(q[mine] - p[mine], point - p[mine])
                inside &= np.einsum("ij,ij->i", turn, normal[mine]) >= 0
            if inside.any():
                hidden[index] = fraction
    return hidden


def random_points(rng):
    """2,500 points: 1,500 on the floor, 1,000 on the wall, with their faces."""
    floor = np.c_[rng.uniform(-4, 4, 1500), np.zeros(1500), rng.uniform(-4, 4, 1500)]
    wall = np.c_[np.full(1000, 2.5), rng.uniform(0, 4, 1000), rng.uniform(-4, 4, 1000)]
    points = np.concatenate([floor, wall])
    _, distance, faces = SURFACE.nearest.on_surface(points)
    assert distance.max() < 1e-9
    return points, faces


def test_hidden_fraction_at_2500_points_against_ray_tests():
    rng = np.random.default_rng(11)
    points, faces = random_points(rng)
    # levels = samples: each level is one count of hidden samples, no rounding
    soft = soft_shadow_on_surface(COLUMN, LIGHT, SURFACE, levels=64, samples=64)
    got = hidden_at(soft, points, faces)
    ends = rect_points(LIGHT, 32, rng)
    triangles = COLUMN.vertices[COLUMN.faces]
    reference = np.concatenate(
        [blocked(chunk, ends, triangles).mean(axis=1) for chunk in np.array_split(points, 50)]
    )
    error = np.abs(got - reference)
    penumbra = (reference > 0) & (reference < 1)
    on_wall = points[:, 0] == 2.5
    # both receivers have penumbra points to test
    assert penumbra[on_wall].sum() > 50 and penumbra[~on_wall].sum() > 50
    # shadowgeo.soft's figures for 64 samples under a rectangle (0.035 at
    # most, 0.007 on average in the penumbra) plus the reference's own noise
    # (1,024 stratified points); an edge point may fall in either level.
    # Measured: 0.035 at most, 0.0105 on average in the penumbra
    assert error.max() <= 0.08
    assert error[penumbra].mean() <= 0.015
    assert np.isfinite(soft.fraction).all()


@pytest.mark.parametrize(
    "zero",
    [
        sg.PointLight([-2, 3.5, 0], source_radius=0.0),
        sg.SpotLight([-2, 3.5, 0], [0.6, -0.8, 0], 1.2),
        sg.DirectionalLight([0.6, -0.8, 0.1], angle=0.0),
    ],
)
def test_a_light_with_no_size_gives_shadow_on_surface_exactly(zero):
    hard = sg.shadow_on_surface(COLUMN, zero, SURFACE)
    soft = soft_shadow_on_surface(COLUMN, zero, SURFACE)
    ((fraction, level),) = soft.levels
    assert fraction == 1.0 and hard.area > 0
    assert np.array_equal(level.vertices, hard.vertices)
    assert np.array_equal(level.faces, hard.faces)
    assert np.array_equal(level.face_index, hard.face_index)
    assert np.array_equal(soft.fraction, hard.fraction)


def test_one_sample_is_the_hard_shadow_of_the_light_centre():
    # the general path with one sample: one level, the hard shadow's region
    hard = sg.shadow_on_surface(COLUMN, sg.PointLight(LIGHT.position), SURFACE)
    soft = soft_shadow_on_surface(COLUMN, LIGHT, SURFACE, samples=1)
    ((fraction, level),) = soft.levels
    assert fraction == 1.0
    assert level.area == pytest.approx(hard.area, rel=1e-9)
    assert np.allclose(level.fraction, hard.fraction, atol=1e-9)


def test_levels_lie_in_their_faces_do_not_overlap_and_have_no_nan():
    soft = soft_shadow_on_surface(COLUMN, LIGHT, SURFACE, levels=8)
    assert [f for f, _ in soft.levels] == sorted(f for f, _ in soft.levels)
    corners = SURFACE.vertices[SURFACE.faces]
    normals = SURFACE.face_normals
    share = np.zeros(len(SURFACE.faces))
    for _, level in soft.levels:
        assert np.isfinite(level.vertices).all()
        triangles = level.vertices[level.faces]
        own = corners[level.face_index]
        # in the plane of its face, on its front (nothing on the wrong side)
        heights = np.einsum("tkj,tj->tk", triangles - own[:, :1], normals[level.face_index])
        assert np.abs(heights).max() < 1e-9
        # inside the face: barycentric coordinates of each corner >= 0
        for k in range(3):
            a, b = own[:, k], own[:, (k + 1) % 3]
            side = np.einsum(
                "tij,tj->ti",
                np.cross((b - a)[:, None], triangles - a[:, None]),
                normals[level.face_index],
            )
            assert side.min() > -1e-9
        share += level.fraction
    # the levels of a face add up to no more than the face
    assert share.max() <= 1 + 1e-9
    assert np.all((soft.fraction >= 0) & (soft.fraction <= 1))
