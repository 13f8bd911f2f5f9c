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
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike

from .errors import GeometryError

# Units in the last place of float64 that a coordinate may carry after a few
# arithmetic operations; the length tolerance never drops below this.
_ULPS = 64.0
# No curve is cut into more pieces than this, whatever the tolerance asks.
_MAX_SEGMENTS = 1 << 16


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
        """
        chunks = [np.asarray(p, dtype=np.float64).reshape(-1, 3) for p in point_sets]
        chunks = [c for c in chunks if len(c)]
        if not chunks:
            return cls(**settings)
        points = np.concatenate(chunks)
        if not np.all(np.isfinite(points)):
            raise GeometryError("scene has NaN or infinite coordinates")
        diagonal = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
        magnitude = float(np.abs(points).max())
        if diagonal <= _ULPS * np.finfo(np.float64).eps * max(magnitude, 1e-300):
            diagonal = max(magnitude, 1.0)
        return cls(scale=diagonal, magnitude=magnitude, **settings)

    def with_settings(self, **settings: float) -> Tolerance:
        """A copy with some relative settings changed."""
        return replace(self, **settings)

    @property
    def length(self) -> float:
        """Absolute length below which two points are the same."""
        resolution = _ULPS * np.finfo(np.float64).eps * self.magnitude
        return max(self.relative * self.scale, resolution)

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
        step = 2.0 * math.acos(1.0 - ratio)  # chord sagitta = r (1 - cos(step / 2))
        return min(max(minimum, math.ceil(sweep / max(step, 1e-9))), _MAX_SEGMENTS)
