"""The certified orientation test of 2-D points in the local window.

Shadow regions are worked in a local frame whose coordinates stay within
+-:data:`MAX_COORDINATE` (the range Clipper2 handles safely, see
:mod:`shadowgeo.plane2d`). Within it, :func:`turns` and :func:`turn_sign`
tell left from right turns beyond float64's rounding, or say that rounding
could decide it; the star-shaped certificates of :mod:`shadowgeo.plane2d`,
the sweep of :mod:`shadowgeo.sweep` and the many-lights arrays of
:mod:`shadowgeo.batchlights` rest on them.
"""

from __future__ import annotations

import numpy as np

from .limits import PRODUCT_SLACK

__all__ = ["MAX_COORDINATE", "POINT_SLACK", "turn_sign", "turns"]

# Coordinates handed to Clipper2 stay below this (it accepts about 4e10 before
# its 1e8 fixed-point scaling overflows int64's safe range).
MAX_COORDINATE = 1e8

# Coordinates of the 2-D loops stay within +-MAX_COORDINATE (the window), so
# a difference of two of them is off by at most this much (a few units in
# the last place of MAX_COORDINATE) ...
POINT_SLACK = 8 * MAX_COORDINATE * float(np.finfo(np.float64).eps)
# ... and a product of two differences by limits.PRODUCT_SLACK relative.


def turns(origin: np.ndarray, one: np.ndarray, two: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(sign, cross): +1 where ``origin -> one -> two`` certainly turns left,
    -1 certainly right, 0 when rounding could decide it; and the cross
    product ``(one - origin) x (two - origin)`` itself (rows of (n, 2)
    points within +-MAX_COORDINATE)."""
    a, b = one - origin, two - origin
    cross: np.ndarray = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    size_a = np.abs(a[:, 0]) + np.abs(a[:, 1])
    size_b = np.abs(b[:, 0]) + np.abs(b[:, 1])
    margin = 2 * POINT_SLACK * (size_a + size_b) + PRODUCT_SLACK * size_a * size_b
    sign: np.ndarray = np.where(cross > margin, 1, np.where(cross < -margin, -1, 0))
    return sign, cross


def turn_sign(ax: float, ay: float, bx: float, by: float) -> int:
    """:func:`turns` of one pair, from its two differences ``a = one -
    origin`` and ``b = two - origin``: +1, -1, or 0 when rounding could
    decide it."""
    size_a, size_b = abs(ax) + abs(ay), abs(bx) + abs(by)
    margin = 2 * POINT_SLACK * (size_a + size_b) + PRODUCT_SLACK * size_a * size_b
    cross = ax * by - ay * bx
    return 1 if cross > margin else -1 if cross < -margin else 0
