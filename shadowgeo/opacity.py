"""Translucent casters in sunlight: opaque studies added up, one per opacity.

The converter's rule (:mod:`shadowgeo.scene.opacity`, :mod:`shadowgeo.scene.shadows`):
a shape casts with opacity ``1 - Material.transparency``, rounded to the
nearest multiple of :data:`STEP` (1/16), and a point takes the darkness of
the most opaque caster that hides it from the light. For sunlight: at a sun
sample a point gets ``(1 - a) * step`` of sun, ``a`` the largest opacity
among the casters hiding it (0 when none does).

With the distinct opacities ``a_1 < a_2 < ... < a_n`` (``a_0 = 0``),

    1 - a = 1 - sum_k (a_k - a_(k-1)) * [hidden by a caster of opacity >= a_k]

so a point's sunlight is a weighted sum of opaque studies, one per
threshold ``a_k``, of the casters at least that opaque (:class:`Layers`).
Every weight is a whole number of sixteenths; divided by their greatest
common divisor with 16 they are small whole numbers, so each threshold's
shadow can enter a winding-number cover that many times and the levels stay
exact, counted in ``units`` parts of a sample. All casters opaque is one
threshold of weight 1 in 1 unit: the opaque study itself.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import GeometryError

__all__ = ["LEVELS", "STEP", "Layers", "layers", "rounded"]

# Opacities are rounded to multiples of STEP: 16 levels above zero.
LEVELS = 16
STEP = 1.0 / LEVELS


def rounded(opacity: ArrayLike) -> NDArray[np.float64]:
    """Opacities clipped to [0, 1] and rounded to the nearest multiple of
    :data:`STEP` (halves up), as :func:`shadowgeo.scene.opacity.casting_opacity`
    rounds a shape's; NaN (unset) is opaque.

    >>> rounded([0.2, 0.25, 1.7, -1, float("nan")]).tolist()
    [0.1875, 0.25, 1.0, 0.0, 1.0]
    """
    values = np.asarray(opacity, dtype=np.float64)
    values = np.where(np.isnan(values), 1.0, np.clip(values, 0.0, 1.0))
    result: NDArray[np.float64] = np.floor(values * LEVELS + 0.5) / LEVELS
    return result


@dataclass(frozen=True)
class Layers:
    """The opaque studies a study with translucent casters adds up.

    Attributes
    ----------
    faces : tuple of (m,) bool
        One mask over the caster's faces per threshold, lowest first: the
        faces at least that opaque.
    weights : tuple of int
        How many times each threshold's shadow counts, in ``units``.
    units : int
        The parts a sample's sunlight is counted in (1 when every caster is
        opaque; 16 at most).
    """

    faces: tuple[NDArray[np.bool_], ...]
    weights: tuple[int, ...]
    units: int

    @property
    def opaque(self) -> bool:
        """One threshold of all the faces in one unit: the opaque study."""
        return self.units == 1 and len(self.faces) == 1 and bool(self.faces[0].all())


def layers(opacity: ArrayLike | None, n_faces: int) -> Layers:
    """The thresholds of the (m,) per-face ``opacity`` (rounded by
    :func:`rounded`; None: every face opaque), as the module notes derive.

    Raises
    ------
    GeometryError
        When ``opacity`` does not give one value per face, or no face has an
        opacity that rounds above 0 (nothing casts).

    Examples
    --------
    Faces of opacity 0.5 and 1: a shadow of all the faces counts 1 of 2
    units, that of the opaque ones 1 more.

    >>> found = layers([0.5, 1.0, 1.0], 3)
    >>> [mask.tolist() for mask in found.faces], found.weights, found.units
    ([[True, True, True], [False, True, True]], (1, 1), 2)
    >>> layers(None, 2).opaque
    True
    """
    if opacity is None:
        return Layers((np.ones(n_faces, dtype=bool),), (1,), 1)
    values = rounded(opacity).reshape(-1)
    if len(values) != n_faces:
        raise GeometryError(f"opacity gives {len(values)} values for {n_faces} caster faces")
    sixteenths = np.rint(values * LEVELS).astype(np.int64)
    thresholds = np.unique(sixteenths[sixteenths > 0])
    if not len(thresholds):
        raise GeometryError("no caster face is opaque enough to cast (every opacity < 1/32)")
    steps = np.diff(thresholds, prepend=0)
    common = math.gcd(LEVELS, *(int(s) for s in steps))
    return Layers(
        tuple(sixteenths >= level for level in thresholds),
        tuple(int(s) // common for s in steps),
        LEVELS // common,
    )
