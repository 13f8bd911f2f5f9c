"""Invariants of project_shadow over random casters, planes and lights (hypothesis)."""

from __future__ import annotations

import numpy as np
import shapely
import trimesh
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st
from reference import basis, hull_area_2d, ray_plane, segment_hits_mesh

from shadowgeo import GeometryError, Plane, PointLight, project_shadow

unit = st.floats(-1, 1, allow_nan=False)
vectors = st.tuples(unit, unit, unit).filter(lambda v: np.linalg.norm(v) > 0.2)
seeds = st.integers(0, 2**32 - 1)


def frame(normal):
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    u, v = basis(n)
    return n, u, v


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(normal=vectors, seed=seeds, light_height=st.floats(4.0, 20.0))
def test_light_above_a_convex_caster_gives_the_hull_of_its_vertex_images(
    normal, seed, light_height
):
    n, u, v = frame(normal)
    rng = np.random.default_rng(seed)
    plane = Plane(n, rng.uniform(-3, 3))
    foot = -plane.offset * plane.normal
    caster = trimesh.convex.convex_hull(foot + 2 * n + 0.5 * rng.normal(size=(12, 3)))
    caster_height = plane.signed_distance(caster.vertices)
    light = PointLight(foot + light_height * n + rng.uniform(-2, 2) * u + rng.uniform(-2, 2) * v)
    # Casters touching the plane or near the light are the next test's cases.
    assume(caster_height.min() > 0 and caster_height.max() < light_height - 0.5)
    shadow = project_shadow(caster, light, plane)
    images = ray_plane(caster.vertices, light.position, plane.normal, plane.offset)
    expected = hull_area_2d(plane.to_2d(images))
    assert abs(shadow.area - expected) <= 1e-9 * expected
    assert np.all(np.isfinite(shadow.mesh.vertices))
    assert np.abs(plane.signed_distance(shadow.mesh.vertices)).max() <= 1e-9 * 10


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(normal=vectors, seed=seeds, light_height=st.floats(-1.0, 6.0))
@example(normal=(0.0, 1.0, 0.0), seed=1, light_height=2.0)  # light at the caster's centre height
@example(normal=(0.0, 1.0, 0.0), seed=2, light_height=0.0)  # light on the plane
def test_any_light_position_gives_a_finite_shadow_inside_the_receiver_or_an_error(
    normal, seed, light_height
):
    n, u, v = frame(normal)
    rng = np.random.default_rng(seed)
    plane = Plane(n, rng.uniform(-3, 3))
    foot = -plane.offset * plane.normal
    # Casters anywhere around the plane, piercing it or not; light anywhere.
    caster = trimesh.convex.convex_hull(foot + rng.uniform(-1, 3) * n + rng.normal(size=(10, 3)))
    light = PointLight(foot + light_height * n + rng.normal(size=3) * [1, 1, 1])
    corners = np.array([[-6, -6], [6, -6], [6, 6], [-6, 6]], dtype=float) + rng.normal(size=2)
    receiver = plane.to_3d(corners)
    try:
        shadow = project_shadow(caster, light, plane, receiver=receiver)
    except GeometryError as error:
        message = str(error)
        assert "on the receiving plane" in message or "caster" in message
        return
    assert np.all(np.isfinite(shadow.mesh.vertices))
    assert np.isfinite(shadow.area)
    square = shapely.Polygon(corners)
    assert shadow.area <= square.area * (1 + 1e-9)
    if shadow.polygons:
        assert shadow.to_shapely().difference(square.buffer(1e-9)).area <= 1e-12
        # Non-overlapping triangles: the mesh area equals the region's area.
        assert abs(shadow.mesh.area - shadow.area) <= 1e-9 * max(shadow.area, 1.0)
    # Independent check: sample points of the receiver away from the outline;
    # shadowed exactly when the segment to the light hits the caster.
    if plane.signed_distance(light.position[None])[0] > 0:
        samples = corners.min(axis=0) + rng.uniform(0, 12, size=(60, 2))
        region = shadow.to_shapely()
        keep = [region.boundary.distance(shapely.Point(p)) > 1e-7 for p in samples]
        samples = samples[np.array(keep, dtype=bool)]
        inside = shapely.contains_xy(region, samples[:, 0], samples[:, 1])
        hits = segment_hits_mesh(plane.to_3d(samples), light.position, caster.triangles)
        assert np.array_equal(inside, hits)
