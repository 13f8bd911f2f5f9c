import math

import numpy as np
import pytest

from shadowgeo import DirectionalLight, GeometryError, Plane, PointLight, SpotLight, Tolerance


def test_plane_normalises_and_keeps_the_same_points():
    plane = Plane([0, 2, 0], -4)  # 2y - 4 = 0  <=>  y = 2
    assert plane.coefficients == (0.0, 1.0, 0.0, -2.0)
    assert plane.signed_distance([[5, 2, 7]])[0] == 0.0
    assert plane.signed_distance([[0, 5, 0]])[0] == pytest.approx(3.0)


def test_plane_from_point_normal_and_coefficients_agree():
    point, normal = np.array([1.0, 2.0, 3.0]), np.array([1.0, -1.0, 2.0])
    a = Plane.from_point_normal(point, normal)
    b = Plane.from_coefficients([*normal, -normal @ point])
    np.testing.assert_allclose(a.vector, b.vector)
    assert abs(a.signed_distance([point])[0]) < 1e-15


@pytest.mark.parametrize(
    "normal", [[0, 1, 0], [0, -1, 0], [1, 0, 0], [0, 0, 1], [1, 2, 3], [-3, 0.1, 1e-9]]
)
def test_plane_basis_is_orthonormal_and_right_handed(normal):
    plane = Plane(normal, 0.7)
    u, v = plane.basis
    np.testing.assert_allclose([u @ u, v @ v, u @ v, u @ plane.normal], [1, 1, 0, 0], atol=1e-15)
    np.testing.assert_allclose(np.cross(u, v), plane.normal, atol=1e-15)
    uv = np.random.default_rng(1).normal(size=(20, 2))
    points = plane.to_3d(uv)
    np.testing.assert_allclose(plane.signed_distance(points), 0, atol=1e-14)
    np.testing.assert_allclose(plane.to_2d(points), uv, atol=1e-14)


def test_ground_plane_basis_is_documented():
    u, v = Plane([0, 1, 0], 0).basis
    np.testing.assert_array_equal(u, [1, 0, 0])
    np.testing.assert_array_equal(v, [0, 0, -1])


@pytest.mark.parametrize("normal", [[0, 0, 0], [np.nan, 1, 0], [np.inf, 0, 0]])
def test_bad_plane_normals_are_refused(normal):
    with pytest.raises(GeometryError, match="normal"):
        Plane(normal, 0)


def test_light_homogeneous_vectors():
    np.testing.assert_array_equal(PointLight([8, 9, 10]).homogeneous, [8, 9, 10, 1])
    directional = DirectionalLight([0, -2, 0])
    np.testing.assert_array_equal(directional.direction, [0, -1, 0])
    np.testing.assert_array_equal(directional.homogeneous, [0, 1, 0, 0])
    spot = SpotLight([0, 5, 0], [0, -1, 0], math.pi / 6)
    np.testing.assert_array_equal(spot.homogeneous, [0, 5, 0, 1])


@pytest.mark.parametrize(
    "make",
    [
        lambda: PointLight([0, np.nan, 0]),
        lambda: PointLight([0, 1, 0], radius=0),
        lambda: DirectionalLight([0, 0, 0]),
        lambda: SpotLight([0, 1, 0], [0, -1, 0], 0.0),
        lambda: SpotLight([0, 1, 0], [0, -1, 0], 2.0),
    ],
)
def test_bad_lights_are_refused(make):
    with pytest.raises(GeometryError):
        make()


def test_tolerance_scales_with_the_scene():
    small = Tolerance.for_points([[0, 0, 0], [1e-6, 0, 0]])
    large = Tolerance.for_points([[0, 0, 0], [1e6, 0, 0]])
    assert small.length == pytest.approx(1e-15)
    assert large.length == pytest.approx(1e-3)
    far = Tolerance.for_points([[1e7, 0, 0], [1e7 + 1, 0, 0]])
    assert far.length >= 1e7 * 2.2e-16  # never below what float64 resolves there
    assert small.segments(1e-6) == large.segments(1e6)
