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

__all__ = [
    "AreaLight",
    "DirectionalLight",
    "DiskLight",
    "Light",
    "PointLight",
    "RectLight",
    "SpotLight",
    "centre_light",
    "is_positional",
    "require_light",
]


def _unit(vector: ArrayLike, name: str) -> NDArray[np.float64]:
    vector = finite_vector(vector, name)
    length = float(np.linalg.norm(vector))
    if length == 0.0 or not math.isfinite(length):
        raise GeometryError(f"{name} must be a non-zero vector, got {vector.tolist()}")
    unit = vector / length
    unit.setflags(write=False)
    return unit


def _size(value: float, name: str, upper: float = math.inf) -> float:
    """A light's size (a source radius, an angle): finite, >= 0, below ``upper``."""
    value = float(value)
    if not 0 <= value < upper:
        raise GeometryError(f"{name} must be in [0, {upper:g}), got {value!r}")
    return value


def _radius(radius: float) -> float:
    radius = float(radius)
    if math.isnan(radius) or radius <= 0:
        raise GeometryError(f"light radius must be > 0 (or inf), got {radius!r}")
    return radius


@dataclass(frozen=True, eq=False)
class PointLight:
    """A light at ``position`` shining in every direction, up to ``radius``
    (X3D's range; ``inf`` for no limit). ``source_radius``: the radius of the
    glowing sphere (UsdLux ``SphereLight.radius``); 0, a point, is all the
    hard-shadow functions see (they cast from ``position``), and
    :func:`shadowgeo.soft_shadow` gives its umbra and penumbra."""

    position: NDArray[np.float64]
    radius: float = math.inf
    source_radius: float = 0.0

    def __init__(
        self, position: ArrayLike, radius: float = math.inf, source_radius: float = 0.0
    ) -> None:
        object.__setattr__(self, "position", finite_vector(position, "light position"))
        object.__setattr__(self, "radius", _radius(radius))
        object.__setattr__(self, "source_radius", _size(source_radius, "source_radius"))

    @property
    def homogeneous(self) -> NDArray[np.float64]:
        """``(x, y, z, 1)``."""
        return np.append(self.position, 1.0)

    def __repr__(self) -> str:
        size = f", source_radius={self.source_radius!r}" if self.source_radius else ""
        return f"PointLight(position={self.position.tolist()}, radius={self.radius!r}{size})"


@dataclass(frozen=True, eq=False)
class DirectionalLight:
    """A light infinitely far away whose rays travel along ``direction``
    (X3D's convention: the way the light goes, not where it comes from).
    ``angle``: the angular diameter of its disc in radians (UsdLux
    ``DistantLight.angle``, in degrees there: the sun's is 0.53 degrees); 0
    is all the hard-shadow functions see, :func:`shadowgeo.soft_shadow`
    gives its umbra and penumbra."""

    direction: NDArray[np.float64]
    angle: float = 0.0

    def __init__(self, direction: ArrayLike, angle: float = 0.0) -> None:
        object.__setattr__(self, "direction", _unit(direction, "light direction"))
        object.__setattr__(self, "angle", _size(angle, "angle", math.pi))

    @property
    def homogeneous(self) -> NDArray[np.float64]:
        """``(-direction, 0)``: the point at infinity the light comes from."""
        return np.append(-self.direction, 0.0)

    def __repr__(self) -> str:
        size = f", angle={self.angle!r}" if self.angle else ""
        return f"DirectionalLight(direction={self.direction.tolist()}{size})"


@dataclass(frozen=True, eq=False)
class SpotLight:
    """A light at ``position`` lighting the cone of half-angle ``cut_off_angle``
    (radians, in (0, pi/2]) around ``direction``, up to ``radius``;
    ``source_radius`` as :class:`PointLight`'s."""

    position: NDArray[np.float64]
    direction: NDArray[np.float64]
    cut_off_angle: float = math.pi / 4
    radius: float = math.inf
    source_radius: float = 0.0

    def __init__(
        self,
        position: ArrayLike,
        direction: ArrayLike,
        cut_off_angle: float = math.pi / 4,
        radius: float = math.inf,
        source_radius: float = 0.0,
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
        object.__setattr__(self, "source_radius", _size(source_radius, "source_radius"))

    @property
    def homogeneous(self) -> NDArray[np.float64]:
        """``(x, y, z, 1)``."""
        return np.append(self.position, 1.0)

    def __repr__(self) -> str:
        return (
            f"SpotLight(position={self.position.tolist()}, direction={self.direction.tolist()}, "
            f"cut_off_angle={self.cut_off_angle!r}, radius={self.radius!r}"
            + (f", source_radius={self.source_radius!r})" if self.source_radius else ")")
        )


@dataclass(frozen=True, eq=False)
class RectLight:
    """A one-sided rectangle of ``width`` x ``height`` centred on ``position``,
    emitting towards ``direction`` (its normal; UsdLux ``RectLight``), its
    ``width`` along ``up`` x ``direction`` and its ``height`` along the part of
    ``up`` across ``direction``. For :func:`shadowgeo.soft_shadow`."""

    position: NDArray[np.float64]
    direction: NDArray[np.float64]
    width: float
    height: float
    up: NDArray[np.float64]

    def __init__(
        self,
        position: ArrayLike,
        direction: ArrayLike,
        width: float,
        height: float,
        up: ArrayLike = (0.0, 1.0, 0.0),
    ) -> None:
        normal = _unit(direction, "light direction")
        toward = finite_vector(up, "light up")
        across = toward - (toward @ normal) * normal
        if not float(np.linalg.norm(across)) > 0:  # up along the normal: any across it
            toward = np.eye(3)[int(np.argmin(np.abs(normal)))]
            across = toward - (toward @ normal) * normal
        object.__setattr__(self, "position", finite_vector(position, "light position"))
        object.__setattr__(self, "direction", normal)
        object.__setattr__(self, "width", _size(width, "width"))
        object.__setattr__(self, "height", _size(height, "height"))
        object.__setattr__(self, "up", _unit(across, "light up"))

    @property
    def axes(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Unit vectors along its width and its height."""
        return np.cross(self.up, self.direction), self.up

    def __repr__(self) -> str:
        return (
            f"RectLight(position={self.position.tolist()}, direction={self.direction.tolist()}, "
            f"width={self.width!r}, height={self.height!r}, up={self.up.tolist()})"
        )


@dataclass(frozen=True, eq=False)
class DiskLight:
    """A one-sided disc of ``radius`` centred on ``position``, emitting
    towards ``direction`` (its normal; UsdLux ``DiskLight``). For
    :func:`shadowgeo.soft_shadow`."""

    position: NDArray[np.float64]
    direction: NDArray[np.float64]
    radius: float

    def __init__(self, position: ArrayLike, direction: ArrayLike, radius: float) -> None:
        object.__setattr__(self, "position", finite_vector(position, "light position"))
        object.__setattr__(self, "direction", _unit(direction, "light direction"))
        object.__setattr__(self, "radius", _size(radius, "radius"))

    def __repr__(self) -> str:
        return (
            f"DiskLight(position={self.position.tolist()}, direction={self.direction.tolist()}, "
            f"radius={self.radius!r})"
        )


Light = PointLight | DirectionalLight | SpotLight
AreaLight = RectLight | DiskLight

# The widest spot cone X3D holds: its schema's largest cutOffAngle (just
# under pi / 2, by 3e-7).
HALF_SPACE_CUT_OFF = 1.570796


def centre_light(light: AreaLight) -> SpotLight:
    """The light with no size that stands for a rectangle or disc light
    where only a point, spot or directional light fits (the hard-shadow
    functions, X3D's and glTF's lights): a spot light at its centre, facing
    the same way, lighting the half-space in front of it as the one-sided
    rectangle or disc does (cut-off angle :data:`HALF_SPACE_CUT_OFF`)."""
    return SpotLight(light.position, light.direction, HALF_SPACE_CUT_OFF)


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
