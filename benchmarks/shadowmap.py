"""A shadow map and ray sampling, written plainly in numpy, for the report.

The shadow map is the real thing a renderer does, on the CPU: a depth buffer
rendered from the light (a perspective camera at the light looking at the
shadow's region; caster *and* receiver drawn into it, as an engine does), then
each receiver point is in shadow when the depth stored at its texel is nearer
than its own depth minus a bias. Without bias the receiver shadows itself
("shadow acne"); with too much, the shadow detaches.
"""

from __future__ import annotations

import numpy as np


class LightCamera:
    """A perspective camera at a point light looking at ``target``, whose
    square image covers ``half_width`` around the target on the plane
    perpendicular to the view axis."""

    def __init__(self, position, target, half_width: float, resolution: int) -> None:
        self.position = np.asarray(position, dtype=float)
        forward = np.asarray(target, dtype=float) - self.position
        self.focal = float(np.linalg.norm(forward))
        self.forward = forward / self.focal
        helper = np.array([0.0, 0.0, 1.0]) if abs(self.forward[2]) < 0.9 else np.array([1.0, 0, 0])
        self.right = np.cross(self.forward, helper)
        self.right /= np.linalg.norm(self.right)
        self.up = np.cross(self.right, self.forward)
        self.half = half_width / self.focal  # tan of the half field of view
        self.resolution = resolution

    def view(self, points):
        """(n, 3) -> pixel coordinates (n, 2) (float, pixel centres at i + 0.5)
        and view depth (n,)."""
        rel = np.asarray(points, dtype=float) - self.position
        depth = rel @ self.forward
        x = (rel @ self.right) / depth
        y = (rel @ self.up) / depth
        scale = self.resolution / (2 * self.half)
        pixels = np.column_stack([(x + self.half) * scale, (y + self.half) * scale])
        return pixels, depth


class OrthographicCamera:
    """A camera looking along ``direction`` (a directional light) at ``target``,
    its square image ``half_width`` either side of the target; depth is measured
    from ``position``, which the caller puts behind everything drawn."""

    orthographic = True

    def __init__(self, direction, target, half_width: float, resolution: int) -> None:
        forward = np.asarray(direction, dtype=float)
        self.forward = forward / np.linalg.norm(forward)
        self.position = np.asarray(target, dtype=float) - self.forward * half_width * 10
        helper = np.array([0.0, 0.0, 1.0]) if abs(self.forward[2]) < 0.9 else np.array([1.0, 0, 0])
        self.right = np.cross(self.forward, helper)
        self.right /= np.linalg.norm(self.right)
        self.up = np.cross(self.right, self.forward)
        self.target = np.asarray(target, dtype=float)
        self.half = half_width
        self.resolution = resolution

    def view(self, points):
        """(n, 3) -> pixel coordinates (n, 2) and depth along the light (n,)."""
        points = np.asarray(points, dtype=float)
        depth = (points - self.position) @ self.forward
        rel = points - self.target
        scale = self.resolution / (2 * self.half)
        pixels = np.column_stack(
            [(rel @ self.right + self.half) * scale, (rel @ self.up + self.half) * scale]
        )
        return pixels, depth


def depth_map(camera, triangles: np.ndarray) -> np.ndarray:
    """Z-buffer of (m, 3, 3) triangles: nearest view depth per pixel (inf where empty).

    Depth is interpolated perspective-correctly (1 / depth is linear in screen
    space), or linearly for an orthographic camera.
    """
    perspective = not getattr(camera, "orthographic", False)
    size = camera.resolution
    buffer = np.full((size, size), np.inf)
    pixels, depth = camera.view(triangles.reshape(-1, 3))
    pixels = pixels.reshape(-1, 3, 2)
    inverse_depth = (1.0 / depth if perspective else depth).reshape(-1, 3)
    in_front = np.all(depth.reshape(-1, 3) > 0, axis=1)
    for corners, inv in zip(pixels[in_front], inverse_depth[in_front], strict=True):
        low = np.maximum(np.floor(corners.min(axis=0) - 0.5).astype(int), 0)
        high = np.minimum(np.ceil(corners.max(axis=0) - 0.5).astype(int), size - 1)
        if np.any(high < low):
            continue
        xs = np.arange(low[0], high[0] + 1) + 0.5
        ys = np.arange(low[1], high[1] + 1) + 0.5
        gx, gy = np.meshgrid(xs, ys)
        (ax, ay), (bx, by), (cx, cy) = corners
        area = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
        if area == 0:
            continue
        w0 = ((bx - gx) * (cy - gy) - (by - gy) * (cx - gx)) / area
        w1 = ((cx - gx) * (ay - gy) - (cy - gy) * (ax - gx)) / area
        w2 = 1.0 - w0 - w1
        inside = (w0 >= 0) & (w1 >= 0) & (w2 >= 0)
        if not inside.any():
            continue
        z = w0 * inv[0] + w1 * inv[1] + w2 * inv[2]
        if perspective:
            z = 1.0 / z
        rows = (gy[inside] - 0.5).astype(int)
        cols = (gx[inside] - 0.5).astype(int)
        np.minimum.at(buffer, (rows, cols), z[inside])
    return buffer


def shadow_map_test(camera: LightCamera, buffer: np.ndarray, points, bias: float) -> np.ndarray:
    """(n,) bool: in shadow by the depth map (nearest texel, depth - bias)."""
    pixels, depth = camera.view(points)
    cols = np.clip(np.floor(pixels[:, 0]).astype(int), 0, camera.resolution - 1)
    rows = np.clip(np.floor(pixels[:, 1]).astype(int), 0, camera.resolution - 1)
    return buffer[rows, cols] < depth - bias


def ray_test(mesh, points, light_position) -> np.ndarray:
    """(n,) bool: does the segment from each point to the light hit the mesh
    (trimesh's ray queries)."""
    points = np.asarray(points, dtype=float)
    directions = light_position - points
    lengths = np.linalg.norm(directions, axis=1)
    directions = directions / lengths[:, None]
    origins = points + directions * 1e-9 * lengths[:, None]
    locations, ray_index, _ = mesh.ray.intersects_location(origins, directions, multiple_hits=False)
    hit = np.zeros(len(points), dtype=bool)
    if len(ray_index):
        distance = np.linalg.norm(locations - origins[ray_index], axis=1)
        hit[ray_index[distance < lengths[ray_index]]] = True
    return hit
