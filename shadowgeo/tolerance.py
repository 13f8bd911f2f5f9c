"""Every epsilon shadowgeo uses, in one place, scaled by the size of the scene.

A tolerance is never an absolute number: a scene in millimetres and the same
scene in kilometres must give the same shadow. :class:`Tolerance` is built from
the points that matter for one computation (caster, light, receiver) and
derives every threshold from two lengths:

``scale``
    The characteristic size of the scene: the diagonal of the bounding box of
    those points.
``magnitude``
    The largest absolute coordinate. Float64 cannot resolve lengths below about
    ``magnitude * 2.2e-16``, so a scene far from the origin gets a tolerance no
    smaller than a few units in the last place of its coordinates.

The thresholds are

=================  =====================================================  =========
name               meaning                                                default
=================  =====================================================  =========
``length``         two points closer than this are the same point;        1e-9
                   a light this close to a plane or caster touches it     x scale
``angle``          a direction whose cosine with a plane's normal is      1e-12
                   below this is parallel to the plane
``coplanar``       a receiver point this far from its plane is still on   1e-6
                   it (receivers often come from float32 files)           x scale
``chord``          largest deviation of a tessellated curve (spot cone,   1e-3
                   light range, primitives) from the true curve           x scale
``bound``          half-width of the square that bounds a shadow which     100
                   truly runs off to infinity, when no receiver bounds it  x scale
=================  =====================================================  =========

The range of coordinates and sizes these scale over (1e-75 to 1e75) is stated
in :mod:`shadowgeo.limits`; :meth:`Tolerance.for_points` refuses a scene
outside it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike

from .boxes import bounding_box
from .errors import GeometryError
from .limits import MAX_CURVE_SEGMENTS, SMALLEST_LENGTH, check_coordinates

__all__ = ["Tolerance", "below_resolution", "resolution", "scene_scales"]

# Units in the last place of float64 that a coordinate may carry after a few
# arithmetic operations; the length tolerance never drops below this.
_ULPS = 64.0
_EPSILON = float(np.finfo(np.float64).eps)


@dataclass(frozen=True)
class Tolerance:
    """Scene-scaled tolerances.

    Parameters
    ----------
    scale : float
        Characteristic length of the scene (bounding-box diagonal), > 0.
    magnitude : float
        Largest absolute coordinate in the scene, >= 0.
    relative : float
        Length tolerance relative to ``scale``.
    angle : float
        Cosine below which a direction counts as parallel to a plane.
    coplanar : float
        Largest distance, relative to ``scale``, of a point that is on a plane.
    chord : float
        Tessellation tolerance relative to ``scale``.
    bound : float
        Default shadow bound (half-width) relative to ``scale``.

    Examples
    --------
    >>> tol = Tolerance.for_points([[0, 0, 0], [3, 4, 0]])
    >>> tol.scale, tol.length
    (5.0, 5e-09)
    """

    scale: float = 1.0
    magnitude: float = 0.0
    relative: float = 1e-9
    angle: float = 1e-12
    coplanar: float = 1e-6
    chord: float = 1e-3
    bound: float = 100.0

    def __post_init__(self) -> None:
        for name in ("scale", "magnitude", "relative", "angle", "coplanar", "chord", "bound"):
            value = getattr(self, name)
            if not math.isfinite(value) or value < 0:
                raise GeometryError(f"tolerance {name}={value!r} must be finite and >= 0")
        if self.scale <= 0:
            raise GeometryError(f"tolerance scale={self.scale!r} must be > 0")

    @classmethod
    def for_points(cls, *point_sets: ArrayLike, **settings: float) -> Tolerance:
        """Tolerance for a scene made of these point sets ((n, 3) arrays).

        Empty sets are ignored; a scene of one point gets scale 1.
        ``settings`` override the relative defaults (``relative``, ``chord``, ...).

        Raises
        ------
        GeometryError
            A coordinate outside ``+-limits.LARGEST_COORDINATE`` or a scene
            smaller than ``limits.SMALLEST_LENGTH`` (see :mod:`shadowgeo.limits`).
        """
        chunks = [np.asarray(p, dtype=np.float64).reshape(-1, 3) for p in point_sets]
        chunks = [c for c in chunks if len(c)]
        if not chunks:
            return cls(**settings)
        points = np.concatenate(chunks)
        check_coordinates(points, "scene")
        lower, upper = bounding_box(points)
        # Normalised before squaring: the diagonal of a box near the range's
        # ends neither overflows nor underflows.
        side = upper - lower
        largest = float(side.max())
        diagonal = largest * float(np.linalg.norm(side / largest)) if largest > 0 else 0.0
        magnitude = float(np.abs(points).max())
        if diagonal <= _ULPS * np.finfo(np.float64).eps * magnitude or diagonal == 0.0:
            diagonal = max(magnitude, 1.0)  # one point: no size of its own
        elif diagonal < SMALLEST_LENGTH:
            raise GeometryError(
                f"the scene is {diagonal:g} across, below the smallest supported size "
                f"{SMALLEST_LENGTH:g}"
            )
        return cls(scale=diagonal, magnitude=magnitude, **settings)

    def with_settings(self, **settings: float) -> Tolerance:
        """A copy with some relative settings changed."""
        return replace(self, **settings)

    @property
    def length(self) -> float:
        """Absolute length below which two points are the same."""
        return max(self.relative * self.scale, float(resolution(self.magnitude)))

    @property
    def coplanar_length(self) -> float:
        """Absolute largest distance of a point that counts as on a plane."""
        return max(self.coplanar * self.scale, self.length)

    @property
    def chord_length(self) -> float:
        """Absolute largest deviation of a tessellated curve from the true one."""
        return max(self.chord * self.scale, self.length)

    @property
    def bound_length(self) -> float:
        """Absolute half-width of the default shadow bound."""
        return self.bound * self.scale

    def segments(self, radius: float, sweep: float = 2 * math.pi, minimum: int = 8) -> int:
        """Number of segments for an arc of ``radius`` and angle ``sweep`` whose
        inscribed polygon stays within ``chord_length`` of the true arc."""
        if radius <= 0 or not math.isfinite(radius):
            return minimum
        ratio = min(self.chord_length / radius, 1.0)
        # chord sagitta = r (1 - cos(step / 2)) = 2 r sin(step / 4)^2: the sine
        # form keeps its precision when ``ratio`` is far below float64's epsilon
        step = 4.0 * math.asin(math.sqrt(ratio / 2.0))
        if step <= 0.0 or sweep / step >= MAX_CURVE_SEGMENTS:
            return max(minimum, MAX_CURVE_SEGMENTS)
        return max(minimum, math.ceil(sweep / step))


def resolution(magnitude: float | np.ndarray) -> float | np.ndarray:
    """The shortest length float64 resolves among coordinates as large as
    ``magnitude`` (a float, or an array of them): ``_ULPS`` units in the
    last place. :attr:`Tolerance.length` never drops below it."""
    return _ULPS * _EPSILON * magnitude


def scene_scales(lower: np.ndarray, upper: np.ndarray, magnitude: np.ndarray) -> np.ndarray:
    """(k,) the ``scale`` that :meth:`Tolerance.for_points` gives each of k
    scenes, from their boxes ``lower``, ``upper`` (k, 3) and their largest
    absolute coordinates ``magnitude`` (k,): many lights' tolerances at once.

    The diagonal is summed element by element (it may differ from
    ``for_points``'s in the last bit).

    Raises
    ------
    GeometryError
        A scene smaller than ``limits.SMALLEST_LENGTH``.
    """
    side = upper - lower
    largest = np.maximum(np.maximum(side[:, 0], side[:, 1]), side[:, 2])
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = side / largest[:, None]
    norm = np.sqrt(
        ratio[:, 0] * ratio[:, 0] + ratio[:, 1] * ratio[:, 1] + ratio[:, 2] * ratio[:, 2]
    )
    diagonal = np.where(largest > 0, largest * norm, 0.0)
    point = (diagonal <= resolution(magnitude)) | (diagonal == 0.0)
    small = ~point & (diagonal < SMALLEST_LENGTH)
    if np.any(small):
        raise GeometryError(
            f"the scene is {float(diagonal[small][0]):g} across, below the smallest supported "
            f"size {SMALLEST_LENGTH:g}"
        )
    scale: np.ndarray = np.where(point, np.maximum(magnitude, 1.0), diagonal)
    return scale


def below_resolution(bounds: np.ndarray) -> bool:
    """True when a box ``bounds`` ((2, 3): low, high) is no larger than
    float64's resolution where it sits (``_ULPS`` units in the last place of
    its largest coordinate): its points differ by rounding alone, and
    nothing computed from their differences (normals, volumes) has meaning.

    >>> below_resolution(np.array([[1e9, 0, 0], [1e9 + 1e-6, 1e-6, 0]]))
    True
    >>> below_resolution(np.array([[1e9, 0, 0], [1e9 + 1.0, 1.0, 0]]))
    False
    """
    bounds = np.asarray(bounds, dtype=np.float64)
    side = bounds[1] - bounds[0]
    largest = float(np.abs(side).max())
    diagonal = largest * float(np.linalg.norm(side / largest)) if largest > 0 else 0.0
    magnitude = float(np.abs(bounds).max())
    return diagonal <= _ULPS * float(np.finfo(np.float64).eps) * magnitude
