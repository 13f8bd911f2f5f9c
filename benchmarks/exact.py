"""Exact references for the report, in rational arithmetic (fractions.Fraction).

Every float is a rational number, so the shadow of a convex caster on a square
receiver can be computed with no rounding at all: clip each triangle to the
receiving plane and the pyramid joining the light to the receiver, project the
pieces, take the convex hull. The result is the exact area for the float
input as given, whatever the light's height or the distance from the origin.
"""

from __future__ import annotations

from fractions import Fraction


def _frac(values):
    return [Fraction(float(v)) for v in values]


def _clip(polygon, plane):
    out = []
    count = len(polygon)
    side = [sum(p * q for p, q in zip(point, plane, strict=True)) for point in polygon]
    for i in range(count):
        j = (i + 1) % count
        if side[i] >= 0:
            out.append(polygon[i])
        if (side[i] >= 0) != (side[j] >= 0):
            t = side[i] / (side[i] - side[j])
            out.append([a + t * (b - a) for a, b in zip(polygon[i], polygon[j], strict=True)])
    return out


def _hull(points):
    points = sorted(set(points))
    if len(points) < 3:
        return points

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower, upper = [], []
    for p in points:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(points):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return lower[:-1] + upper[:-1]


def convex_shadow_area_on_ground(triangles, light, square_low, square_high, directional=False):
    """Exact area of the shadow of a convex caster (its (m, 3, 3) triangles) on
    the ground y = 0 (normal +y) within the square [low, high]^2 in x and z.

    ``light`` is a position, or with ``directional`` the travel direction.
    """
    lx, ly, lz = _frac(light)
    lo, hi = Fraction(float(square_low)), Fraction(float(square_high))
    if directional:
        # Homogeneous (x, y, z, 1) -> ground (x - y dx/dy, z - y dz/dy): a parallel map.
        def project(point):
            x, y, z, _ = point
            return (x - y * lx / ly, z - y * lz / ly)

        planes = [[0, 1, 0, 0]]
        # Receiver prism sides: x' >= lo etc. with x' = x - y lx/ly (linear).
        planes += [
            [1, -lx / ly, 0, -lo],
            [-1, lx / ly, 0, hi],
            [0, -lz / ly, 1, -lo],
            [0, lz / ly, -1, hi],
        ]
    else:
        # Point light: x' = (lx y - x ly) / (y - ly), w = ly - y > 0 below the light.
        def project(point):
            x, y, z, _ = point
            w = ly - y
            return ((ly * x - lx * y) / w, (ly * z - lz * y) / w)

        # x' >= lo  <=>  ly x - lx y - lo (ly - y) >= 0 (for w > 0; the pyramid
        # over a bounded square has w > 0 everywhere but at the light).
        planes = [
            [0, 1, 0, 0],
            [ly, -lx + lo, 0, -lo * ly],
            [-ly, lx - hi, 0, hi * ly],
            [0, -lz + lo, ly, -lo * ly],
            [0, lz - hi, -ly, hi * ly],
        ]
    points = []
    for triangle in triangles:
        polygon = [_frac(corner) + [Fraction(1)] for corner in triangle]
        for plane in planes:
            if not polygon:
                break
            polygon = _clip(polygon, plane)
        points.extend(project(p) for p in polygon)
    hull = _hull(points)
    if len(hull) < 3:
        return Fraction(0)
    twice = sum(a[0] * b[1] - b[0] * a[1] for a, b in zip(hull, hull[1:] + hull[:1], strict=True))
    return abs(twice) / 2
