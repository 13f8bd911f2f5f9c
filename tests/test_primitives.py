"""Box, Sphere, Cone and Cylinder: on the true surface, within the chord,
converging to the analytic volume and area, and scaled with the scene."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

import shadowgeo as sg
from shadowgeo.io.x3d import read as x3d_read
from shadowgeo.scene import primitives


def mesh(vertices, faces) -> trimesh.Trimesh:
    return trimesh.Trimesh(vertices, faces, process=False)


def surface_points(vertices, faces, per_face=12, seed=0):
    """Points spread over every triangle, including its edge midpoints (where
    an inscribed polygon is farthest from its circle)."""
    rng = np.random.default_rng(seed)
    weights = rng.dirichlet(np.ones(3), per_face)
    weights = np.concatenate([weights, [[0.5, 0.5, 0], [0, 0.5, 0.5], [0.5, 0, 0.5]]])
    corners = vertices[faces]
    return np.einsum("kj,fjd->fkd", weights, corners).reshape(-1, 3)


def cylinder_gap(points, radius, height):
    """Distance from points inside a cylinder to its surface."""
    rho = np.hypot(points[:, 0], points[:, 2])
    return np.minimum(radius - rho, height / 2 - np.abs(points[:, 1]))


def cone_gap(points, radius, height):
    """Distance from points inside a cone to its surface (side line in the
    (rho, y) half-plane, and the base plane)."""
    rho, y = np.hypot(points[:, 0], points[:, 2]), points[:, 1]
    # side through (radius, -h/2) and (0, h/2): outward normal (h, radius) / |.|
    normal = np.array([height, radius]) / math.hypot(height, radius)
    side = -((rho - radius) * normal[0] + (y + height / 2) * normal[1])
    return np.minimum(side, y + height / 2)


def ring_count(vertices, height):
    return int(
        np.sum(
            np.isclose(vertices[:, 1], -height / 2) & (np.hypot(vertices[:, 0], vertices[:, 2]) > 0)
        )
    )


# -- box ----------------------------------------------------------------------------


def test_box_is_the_closed_box_of_its_size():
    vertices, faces = primitives.box((2.0, 4.0, 6.0))
    box = mesh(vertices, faces)
    assert box.is_watertight and box.is_winding_consistent
    assert box.volume == pytest.approx(48.0)  # positive: faces point outwards
    assert box.area == pytest.approx(2 * (8 + 12 + 24))
    np.testing.assert_array_equal(np.abs(vertices), np.tile([1.0, 2.0, 3.0], (8, 1)))


def test_box_refuses_a_non_positive_size():
    with pytest.raises(sg.GeometryError, match="Box size"):
        primitives.box((1.0, 0.0, 1.0))


# -- curved primitives ------------------------------------------------------------------


@pytest.mark.parametrize("chord", [1e-1, 1e-2, 1e-3])
def test_cylinder_segments_are_the_fewest_within_the_chord(chord):
    radius, height = 2.0, 3.0
    vertices, faces = primitives.cylinder(radius, height, chord)
    n = ring_count(vertices, height)
    # the sagitta of an n-gon inscribed in a circle of radius r is r (1 - cos(pi / n))
    assert radius * (1 - math.cos(math.pi / n)) <= chord
    assert n == 8 or radius * (1 - math.cos(math.pi / (n - 1))) > chord
    shape = mesh(vertices, faces)
    assert shape.is_watertight and shape.volume > 0
    gap = cylinder_gap(surface_points(vertices, faces), radius, height)
    assert gap.min() >= -1e-12 and gap.max() <= chord * (1 + 1e-9)


@pytest.mark.parametrize("chord", [1e-1, 1e-2, 1e-3])
def test_cone_within_the_chord_and_vertices_on_the_surface(chord):
    radius, height = 1.5, 2.0
    vertices, faces = primitives.cone(radius, height, chord)
    gap_at_vertices = cone_gap(vertices, radius, height)
    np.testing.assert_allclose(gap_at_vertices[vertices[:, 1] > -height / 2], 0, atol=1e-12)
    gap = cone_gap(surface_points(vertices, faces), radius, height)
    assert gap.min() >= -1e-12 and gap.max() <= chord * (1 + 1e-9)
    shape = mesh(vertices, faces)
    assert shape.is_watertight and shape.volume > 0


@pytest.mark.parametrize("chord", [1e-1, 1e-2, 1e-3])
def test_sphere_vertices_on_the_sphere_and_within_the_chord(chord):
    radius = 3.0
    vertices, faces = primitives.sphere(radius, chord)
    np.testing.assert_allclose(np.linalg.norm(vertices, axis=1), radius, rtol=1e-14)
    gap = radius - np.linalg.norm(surface_points(vertices, faces), axis=1)
    assert gap.min() >= -1e-12 and gap.max() <= chord * (1 + 1e-9)
    # and not needlessly fine: the worst face is at least a quarter of the way to the bound
    assert gap.max() > chord / 4
    shape = mesh(vertices, faces)
    assert shape.is_watertight and shape.is_winding_consistent and shape.volume > 0


@pytest.mark.parametrize(
    "make, volume, area",
    [
        (lambda c: primitives.sphere(1.0, c), 4 * math.pi / 3, 4 * math.pi),
        (lambda c: primitives.cylinder(1.0, 2.0, c), 2 * math.pi, 6 * math.pi),
        (lambda c: primitives.cone(1.0, 2.0, c), 2 * math.pi / 3, math.pi * (1 + math.sqrt(5))),
    ],
    ids=["sphere", "cylinder", "cone"],
)
def test_volume_and_area_converge_as_the_chord_shrinks(make, volume, area):
    errors = []
    for chord in [1e-1, 1e-2, 1e-3, 1e-4]:
        shape = mesh(*make(chord))
        # an inscribed solid lies within ``chord`` of the surface: it misses at most area * chord
        assert 0 < volume - shape.volume <= area * chord
        assert 0 < area - shape.area
        errors.append(volume - shape.volume)
    assert all(later < earlier / 5 for earlier, later in zip(errors[:-1], errors[1:], strict=True))


def test_open_primitives_drop_their_parts():
    vertices, faces = primitives.cylinder(1.0, 2.0, 1e-2, top=False, bottom=False)
    n = ring_count(vertices, 2.0)
    assert len(faces) == 2 * n and len(vertices) == 2 * n  # side only, no cap centres
    vertices, faces = primitives.cone(1.0, 2.0, 1e-2, side=False)
    assert np.allclose(vertices[:, 1], -1.0)  # the base disc alone
    n = len(vertices) - 1  # the ring and the centre
    assert mesh(vertices, faces).area == pytest.approx(n / 2 * math.sin(2 * math.pi / n))
    vertices, faces = primitives.cylinder(1.0, 2.0, 1e-2, side=False, top=False, bottom=False)
    assert len(vertices) == 0 and len(faces) == 0


@settings(max_examples=25, deadline=None)
@given(
    radius=st.floats(1e-3, 1e3),
    height=st.floats(1e-3, 1e3),
    relative=st.floats(1e-4, 0.2),
)
def test_chord_bound_holds_at_any_scale(radius, height, relative):
    chord = relative * radius
    for make, gap_of in [
        (lambda: primitives.cylinder(radius, height, chord), cylinder_gap),
        (lambda: primitives.cone(radius, height, chord), cone_gap),
    ]:
        vertices, faces = make()
        gap = gap_of(surface_points(vertices, faces, per_face=2), radius, height)
        assert gap.max() <= chord * (1 + 1e-9) and gap.min() >= -1e-9 * max(radius, height)
    vertices, faces = primitives.sphere(radius, chord)
    gap = radius - np.linalg.norm(surface_points(vertices, faces, per_face=2), axis=1)
    assert gap.max() <= chord * (1 + 1e-9)


# -- through the reader: the tolerance follows the scene ---------------------------------


def read(tmp_path, body, name="scene.x3d", **options):
    path = tmp_path / name
    path.write_text(f'<X3D version="4.0"><Scene>{body}</Scene></X3D>')
    return x3d_read.read(path, **options)


SPHERES = (
    '<Transform translation="{0} 0 0" scale="{1} {1} {1}">'
    '<Shape><Sphere radius="{2}"/></Shape></Transform>'
    '<Shape><Box size="{3} {3} {3}"/></Shape>'
)


def test_tessellation_scales_with_the_scene(tmp_path):
    small = read(tmp_path, SPHERES.format(5, 1, 1, 1), "small.x3d")
    large = read(tmp_path, SPHERES.format(5000, 1, 1000, 1000), "large.x3d")
    stretched = read(tmp_path, SPHERES.format(5000, 1000, 1, 1000), "stretched.x3d")
    assert small.shapes[0].n_faces == large.shapes[0].n_faces == stretched.shapes[0].n_faces


@pytest.mark.parametrize("chord", [1e-2, 1e-4])
def test_reader_chord_is_relative_to_the_scene_size(tmp_path, chord):
    scene = read(tmp_path, SPHERES.format(10, 2, 1.5, 4), chord=chord)
    sphere = scene.shapes[0]
    tolerance = sg.Tolerance.for_points(*[s.world_vertices for s in scene.shapes], chord=chord)
    world = surface_points(sphere.world_vertices, sphere.faces, per_face=2)
    gap = 3.0 - np.linalg.norm(world - [10, 0, 0], axis=1)
    assert gap.max() <= tolerance.chord_length * (1 + 1e-6)
    assert gap.max() > tolerance.chord_length / 4


def test_reader_takes_a_tolerance(tmp_path):
    coarse = read(
        tmp_path, SPHERES.format(0, 1, 1, 1), tolerance=sg.Tolerance(scale=1.0, chord=0.05)
    )
    fine = read(
        tmp_path, SPHERES.format(0, 1, 1, 1), tolerance=sg.Tolerance(scale=1.0, chord=0.001)
    )
    assert coarse.shapes[0].n_faces < fine.shapes[0].n_faces
    vertices, faces = fine.shapes[0].vertices, fine.shapes[0].faces
    gap = 1.0 - np.linalg.norm(surface_points(vertices, faces, per_face=2), axis=1)
    assert gap.max() <= 0.001 * (1 + 1e-9)


def test_reader_primitive_fields(tmp_path):
    body = (
        '<Shape><Cylinder radius="2" height="6" top="false" solid="false"/></Shape>'
        '<Shape><Cone bottomRadius="3" height="4" bottom="false"/></Shape>'
    )
    cylinder, cone = read(tmp_path, body).shapes
    assert cylinder.solid is False and cone.solid is True
    rho = np.hypot(cylinder.vertices[:, 0], cylinder.vertices[:, 2])
    np.testing.assert_allclose(rho[rho > 0], 2.0, rtol=1e-14)
    assert cylinder.vertices[:, 1].max() == 3.0 and cylinder.vertices[:, 1].min() == -3.0
    assert not mesh(cylinder.vertices, cylinder.faces).is_watertight  # no top
    assert cone.vertices[:, 1].max() == 2.0 and cone.vertices[:, 1].min() == -2.0
    assert not np.any(np.all(np.isclose(cone.vertices, [0, -2, 0]), axis=1))  # no base centre


def test_equal_primitives_share_a_tessellation_not_their_flags(tmp_path):
    body = '<Shape><Sphere/></Shape><Shape><Sphere solid="false"/></Shape><Shape><Sphere/></Shape>'
    first, second, third = read(tmp_path, body).shapes
    assert np.shares_memory(first.vertices, third.vertices)
    assert (first.solid, second.solid, third.solid) == (True, False, True)


def test_reader_skips_a_shape_with_a_non_positive_radius(tmp_path):
    scene = read(tmp_path, '<Shape><Sphere radius="-1"/></Shape><Shape><Box/></Shape>')
    (box,) = scene.shapes
    assert box.n_faces == 12
    (warning,) = scene.warnings
    assert "line 1, Sphere: field radius: -1.0 must be > 0; the Shape is skipped" in warning


def test_sphere_segments_are_capped_and_the_reader_says_so(tmp_path, monkeypatch):
    monkeypatch.setattr(primitives, "MAX_SPHERE_SEGMENTS", 64)
    scene = read(tmp_path, '<Shape><Sphere radius="2"/></Shape>', chord=1e-6)
    (sphere,) = scene.shapes
    assert sphere.n_faces <= 2 * 64 * 32
    (warning,) = scene.warnings
    assert "scene.x3d line 1, Sphere: Sphere tessellation capped" in warning
