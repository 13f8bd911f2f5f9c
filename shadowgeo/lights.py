"""Light sources as small immutable values.

Each light gives its homogeneous 4-vector ``L`` for the shadow matrix: a point
``(x, y, z, 1)`` for positional lights and ``(-direction, 0)`` for a
directional light, i.e. the point at infinity the light comes from.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import GeometryError
from .plane import finite_vector

if TYPE_CHECKING:  # annotations only: no runtime dependency on typing_extensions
    from typing_extensions import TypeIs


def _unit(vector: ArrayLike, name: str) -> NDArray[np.float64]:
    vector = finite_vector(vector, name)
    length = float(np.linalg.norm(vector))
    if length == 0.0 or not math.isfinite(length):
        raise GeometryError(f"{name} must be a non-zero vector, got {vector.tolist()}")
    unit = vector / length
    unit.setflags(write=False)
    return unit


def _radius(radius: float) -> float:
    radius = float(radius)
    if math.isnan(radius) or radius <= 0:
        raise GeometryError(f"light radius must be > 0 (or inf), got {radius!r}")
    return radius


@dataclass(frozen=True, eq=False)
class PointLight:
    """A light at ``position`` shining in every direction, up to ``radius``
    (X3D's range; ``inf`` for no limit)."""

    position: NDArray[np.float64]
    radius: float = math.inf

    def __init__(self, position: ArrayLike, radius: float = math.inf) -> None:
        object.__setattr__(self, "position", finite_vector(position, "light position"))
        object.__setattr__(self, "radius", _radius(radius))

    @property
    def homogeneous(self) -> NDArray[np.float64]:
        """``(x, y, z, 1)``."""
        return np.append(self.position, 1.0)

    def __repr__(self) -> str:
        return f"PointLight(position={self.position.tolist()}, radius={self.radius!r})"


@dataclass(frozen=True, eq=False)
class DirectionalLight:
    """A light infinitely far away whose rays travel along ``direction``
    (X3D's convention: the way the light goes, not where it comes from)."""

    direction: NDArray[np.float64]

    def __init__(self, direction: ArrayLike) -> None:
        object.__setattr__(self, "direction", _unit(direction, "light direction"))

    @property
    def homogeneous(self) -> NDArray[np.float64]:
        """``(-direction, 0)``: the point at infinity the light comes from."""
        return np.append(-self.direction, 0.0)

    def __repr__(self) -> str:
        return f"DirectionalLight(direction={self.direction.tolist()})"


@dataclass(frozen=True, eq=False)
class SpotLight:
    """A light at ``position`` lighting the cone of half-angle ``cut_off_angle``
    (radians, in (0, pi/2]) around ``direction``, up to ``radius``."""

    position: NDArray[np.float64]
    direction: NDArray[np.float64]
    cut_off_angle: float = math.pi / 4
    radius: float = math.inf

    def __init__(
        self,
        position: ArrayLike,
        direction: ArrayLike,
        cut_off_angle: float = math.pi / 4,
        radius: float = math.inf,
    ) -> None:
        cut_off_angle = float(cut_off_angle)
        if not 0 < cut_off_angle <= math.pi / 2:
            raise GeometryError(
                f"spot light cut_off_angle must be in (0, pi/2], got {cut_off_angle!r}"
            )
        object.__setattr__(self, "position", finite_vector(position, "light position"))
        object.__setattr__(self, "direction", _unit(direction, "light direction"))
        object.__setattr__(self, "cut_off_angle", cut_off_angle)
        object.__setattr__(self, "radius", _radius(radius))

    @property
    def homogeneous(self) -> NDArray[np.float64]:
        """``(x, y, z, 1)``."""
        return np.append(self.position, 1.0)

    def __repr__(self) -> str:
        return (
            f"SpotLight(position={self.position.tolist()}, direction={self.direction.tolist()}, "
            f"cut_off_angle={self.cut_off_angle!r}, radius={self.radius!r})"
        )


Light = PointLight | DirectionalLight | SpotLight


def is_positional(light: Light) -> TypeIs[PointLight | SpotLight]:
    """True for lights with a position (point and spot lights)."""
    return not isinstance(light, DirectionalLight)


def require_light(light: object) -> Light:
    """``light`` itself, or :class:`GeometryError` when it is not a light."""
    if not isinstance(light, PointLight | DirectionalLight | SpotLight):
        raise GeometryError(
            f"light must be a PointLight, SpotLight or DirectionalLight, got {light!r}"
        )
    return light
