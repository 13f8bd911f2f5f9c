"""Oriented planes and their 2-D coordinate frames."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import GeometryError

__all__ = ["Plane", "finite_vector"]


def finite_vector(value: ArrayLike, name: str, size: int = 3) -> NDArray[np.float64]:
    """``value`` as a read-only float64 vector of ``size`` finite components;
    a GeometryError naming ``name`` otherwise (the check planes and lights
    make on what they are given).

    >>> finite_vector([0, 1, 0], "normal").tolist()
    [0.0, 1.0, 0.0]
    """
    array = np.asarray(value, dtype=np.float64).reshape(-1)
    if array.shape != (size,):
        raise GeometryError(f"{name} must have {size} components, got {np.shape(value)}")
    if not np.all(np.isfinite(array)):
        raise GeometryError(f"{name} has NaN or infinite components: {array.tolist()}")
    array.setflags(write=False)
    return array


@dataclass(frozen=True, eq=False)
class Plane:
    """The oriented plane of points ``x`` with ``normal . x + offset = 0``.

    The normal is stored with unit length (``offset`` is scaled with it), and it
    points to the plane's front: the side a receiver is lit from.

    Parameters
    ----------
    normal : (3,) array_like
        Any non-zero vector; it is normalised.
    offset : float
        The ``d`` of ``a x + b y + c z + d = 0`` for the given (unnormalised) normal.

    Notes
    -----
    2-D coordinates (:meth:`to_2d`, :meth:`to_3d`) use the origin
    ``-offset * normal`` (the point of the plane closest to the world origin)
    and the right-handed basis ``(u, v, normal)``: ``u`` is the world axis least
    aligned with the normal (x before y before z on ties) made orthogonal to it,
    and ``v = normal x u``, so ``u x v = normal`` and areas measured in 2-D are
    positive for polygons counter-clockwise seen from the front. For the ground
    plane y = 0 with normal +y this gives ``u = +x`` and ``v = -z``.

    Examples
    --------
    >>> ground = Plane([0, 2, 0], 0)
    >>> ground.coefficients
    (0.0, 1.0, 0.0, 0.0)
    >>> ground.to_2d([[3.0, 0.0, 4.0]]).tolist()
    [[3.0, -4.0]]
    """

    normal: NDArray[np.float64]
    offset: float

    def __init__(self, normal: ArrayLike, offset: float = 0.0) -> None:
        normal = finite_vector(normal, "plane normal")
        length = float(np.linalg.norm(normal))
        if not np.isfinite(offset):
            raise GeometryError(f"plane offset must be finite, got {offset!r}")
        if length == 0.0 or not np.isfinite(length):
            raise GeometryError(f"plane normal must be a non-zero vector, got {normal.tolist()}")
        unit = normal / length
        unit.setflags(write=False)
        object.__setattr__(self, "normal", unit)
        object.__setattr__(self, "offset", float(offset) / length)

    @classmethod
    def from_point_normal(cls, point: ArrayLike, normal: ArrayLike) -> Plane:
        """The plane through ``point`` with ``normal``."""
        point = finite_vector(point, "plane point")
        normal = finite_vector(normal, "plane normal")
        return cls(normal, -float(np.dot(normal, point)))

    @classmethod
    def from_coefficients(cls, coefficients: ArrayLike) -> Plane:
        """The plane ``a x + b y + c z + d = 0`` from ``(a, b, c, d)``."""
        a, b, c, d = finite_vector(coefficients, "plane coefficients", 4)
        return cls([a, b, c], d)

    def __repr__(self) -> str:
        return f"Plane(normal={self.normal.tolist()}, offset={self.offset!r})"

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Plane):
            return NotImplemented
        return bool(np.array_equal(self.normal, other.normal)) and self.offset == other.offset

    def __hash__(self) -> int:
        return hash((tuple(self.normal), self.offset))

    @property
    def coefficients(self) -> tuple[float, float, float, float]:
        """``(a, b, c, d)`` with ``(a, b, c)`` unit length."""
        a, b, c = (float(x) for x in self.normal)
        return (a, b, c, self.offset)

    @property
    def vector(self) -> NDArray[np.float64]:
        """The plane as a homogeneous 4-vector ``(a, b, c, d)``, for ``P . X = 0``."""
        return np.array(self.coefficients)

    @property
    def origin(self) -> NDArray[np.float64]:
        """The point of the plane closest to the world origin."""
        return -self.offset * self.normal

    @property
    def basis(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The in-plane unit vectors ``(u, v)`` with ``u x v = normal``."""
        axis = np.zeros(3)
        axis[int(np.argmin(np.abs(self.normal)))] = 1.0
        u = axis - np.dot(axis, self.normal) * self.normal
        u /= np.linalg.norm(u)
        # np.cross's numbers, written out (its checks and reshaping cost more
        # than the product, once per light and plane)
        (n0, n1, n2), (u0, u1, u2) = self.normal.tolist(), u.tolist()
        v = np.array([n1 * u2 - n2 * u1, n2 * u0 - n0 * u2, n0 * u1 - n1 * u0])
        return u, v

    def flipped(self) -> Plane:
        """The same plane facing the other way."""
        return Plane(-self.normal, -self.offset)

    def signed_distance(self, points: ArrayLike) -> NDArray[np.float64]:
        """Signed distances of (n, 3) points, positive in front."""
        points = np.asarray(points, dtype=np.float64)
        return points @ self.normal + self.offset

    def project(self, points: ArrayLike) -> NDArray[np.float64]:
        """Orthogonal projection of (n, 3) points onto the plane."""
        points = np.asarray(points, dtype=np.float64)
        return points - np.outer(self.signed_distance(points), self.normal)

    def to_2d(self, points: ArrayLike) -> NDArray[np.float64]:
        """(n, 3) points to (n, 2) plane coordinates (points off the plane are
        projected orthogonally)."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        u, v = self.basis
        relative = points - self.origin
        return np.column_stack([relative @ u, relative @ v])

    def to_3d(self, uv: ArrayLike) -> NDArray[np.float64]:
        """(n, 2) plane coordinates to (n, 3) points on the plane."""
        uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
        u, v = self.basis
        return self.origin + np.outer(uv[:, 0], u) + np.outer(uv[:, 1], v)
