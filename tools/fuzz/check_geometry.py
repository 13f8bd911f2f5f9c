"""The checks of geometry mode: finite results, a shadow's mesh as large as
its area and as the textbook union, closed silhouette loops, a shadow
volume watertight, consistently wound, outward and not flat."""

from __future__ import annotations

import math
from collections import Counter

import numpy as np
import trimesh

import shadowgeo

from .check_area import textbook_area, triangles_area


def check_shadow(vertices, faces, light, plane):
    shadow = shadowgeo.project_shadow((vertices, faces), light, plane)
    mesh_vertices = np.asarray(shadow.mesh.vertices)
    if not math.isfinite(shadow.area) or not np.all(np.isfinite(mesh_vertices)):
        return "non-finite", f"area {shadow.area!r}"
    if any(not np.all(np.isfinite(loop)) for part in shadow.polygons for loop in part):
        return "non-finite", "polygon loops"
    if shadow.area < 0:
        return "negative-area", f"area {shadow.area!r}"
    mesh_area = triangles_area(mesh_vertices[np.asarray(shadow.mesh.faces)])
    resolution = area_resolution(vertices, shadow)
    if 1e-250 < shadow.area < 1e250 and abs(mesh_area - shadow.area) > 1e-5 * shadow.area:
        if abs(mesh_area - shadow.area) > resolution:
            return "mesh-area-mismatch", f"mesh {mesh_area!r} vs area {shadow.area!r}"
    expected = geometry_reference(vertices, faces, light, plane, shadow)
    if expected is not None:
        if abs(shadow.area - expected) > 1e-6 * expected + resolution:
            return "area-vs-reference", f"area {shadow.area!r}, textbook union {expected!r}"
    return None


def area_resolution(vertices, shadow) -> float:
    """The area float64 can resolve: a sliver as long as the shadow and a
    thousand units in the last place of the largest coordinate wide."""
    points = [np.abs(vertices).reshape(-1, 3)]
    points += [np.abs(loop) for part in shadow.polygons for loop in part]
    magnitude = max(float(p.max()) for p in points if p.size)
    extent = max(
        (float(np.ptp(loop, axis=0).max()) for p in shadow.polygons for loop in p), default=0
    )
    extent = max(extent, float(np.ptp(vertices.reshape(-1, 3), axis=0).max()))
    return 1e3 * np.finfo(np.float64).eps * max(magnitude, extent) * extent


def geometry_reference(vertices, faces, light, plane, shadow) -> float | None:
    """Textbook area where it is well conditioned: every triangle strictly
    between the plane and the light, no radius or cone, sizes far from
    overflow, the shadow not cut by the default bound."""
    if shadow.diagnostics.bounded_artificially or isinstance(light, shadowgeo.SpotLight):
        return None
    if not np.all(np.abs(vertices) < 1e100):
        return None
    used = vertices[faces]
    size = float(np.ptp(used.reshape(-1, 3), axis=0).max()) if len(used) else 0.0
    if not 1e-100 < size < 1e100 or size < 1e-9 * float(np.abs(used).max()):
        return None
    distance = used @ plane.normal + plane.offset
    if isinstance(light, shadowgeo.DirectionalLight):
        if -float(plane.normal @ light.direction) < 0.05 or distance.min() <= 1e-3 * size:
            return None
        light_h = np.append(-light.direction, 0.0)
    else:
        height = float(plane.normal @ light.position + plane.offset)
        if not math.isinf(light.radius) or height <= 0:
            return None
        if distance.min() <= 1e-3 * height or distance.max() >= (1 - 1e-3) * height:
            return None
        light_h = np.append(light.position, 1.0)
    return textbook_area(used, light_h, plane.normal, plane.offset)


def check_silhouette(vertices, faces, light):
    outline = shadowgeo.silhouette((vertices, faces), light)
    if outline.front.shape != (len(faces),):
        return "front-shape", str(outline.front.shape)
    if outline.loops:
        edges = np.concatenate([np.column_stack([lp, np.roll(lp, -1)]) for lp in outline.loops])
        leaving = Counter(edges[:, 0].tolist())
        arriving = Counter(edges[:, 1].tolist())
        if leaving != arriving:
            return "open-loop", "a loop vertex has unequal in and out edges"
    return None


def check_volume(vertices, faces, light):
    volume = shadowgeo.shadow_volume((vertices, faces), light)
    if len(volume.faces) == 0:
        return None
    points = np.asarray(volume.vertices)
    if not np.all(np.isfinite(points)):
        return "non-finite", "vertices"
    if not volume.is_watertight:
        return "not-watertight", f"{len(volume.faces)} faces"
    if not volume.is_winding_consistent:
        return "winding-inconsistent", f"{len(volume.faces)} faces"
    centred = points - points.mean(axis=0)
    largest = float(np.abs(centred).max())
    if largest > 0:
        normalised = trimesh.Trimesh(centred / largest, volume.faces, process=False)
        if isinstance(light, shadowgeo.DirectionalLight):
            problem = thinner_than_a_prism(vertices, faces, light, volume)
            if problem:
                return "flat (zero volume)", problem
        else:
            # A volume float64 cannot tell from zero at its own scale.
            resolution = 1e3 * np.finfo(np.float64).eps * float(normalised.area)
            if abs(normalised.volume) <= resolution:
                return "flat (zero volume)", (
                    f"normalised volume {float(normalised.volume)!r} <= {resolution!r}"
                )
        if not normalised.volume > 0:
            return "inside-out", f"normalised volume {float(normalised.volume)!r}"
    return None


def thinner_than_a_prism(vertices, faces, light, volume) -> str | None:
    """A sun's shadow volume holds the prism that each casting face sweeps
    (its area times the cosine with the light times the sweep length): a
    volume smaller than half the largest such prism is flat where it should
    not be. Faces within ten times the library's angle or length tolerance of
    edge-on are left out (the library may rightly drop them), and so is the
    check when no face remains. Computed in the caster's frame scaled to 1."""
    sweep = volume.metadata.get("shadowgeo", {}).get("sweep")
    triangles = np.asarray(vertices, dtype=np.float64)[np.asarray(faces).reshape(-1, 3)]
    if sweep is None or not len(triangles):
        return None
    centre = 0.5 * (triangles.reshape(-1, 3).min(axis=0) + triangles.reshape(-1, 3).max(axis=0))
    size = float(np.abs(triangles - centre).max())
    if not size > 0:
        return None
    tolerance = shadowgeo.Tolerance.for_points(triangles.reshape(-1, 3))
    unit = (triangles - centre) / size
    doubled = np.cross(unit[:, 1] - unit[:, 0], unit[:, 2] - unit[:, 0])
    longest = np.abs(unit - unit[:, [1, 2, 0]]).max(axis=(1, 2))
    direction = np.asarray(light.direction, dtype=np.float64)
    direction = direction / np.linalg.norm(direction)
    norms = np.linalg.norm(doubled, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        cosine = np.abs(doubled @ direction) / norms
    casting = (np.abs(doubled).max(axis=1) > 10 * tolerance.length / size * longest) & (
        cosine > 10 * tolerance.angle
    )
    if not casting.any():
        return None
    prism = float((0.5 * norms * cosine)[casting].max()) * float(sweep) / size
    mesh = trimesh.Trimesh(
        (np.asarray(volume.vertices) - centre) / size, volume.faces, process=False
    )
    if abs(float(mesh.volume)) < 0.5 * prism:
        return f"volume {float(mesh.volume)!r} < half the largest face prism {prism!r} (scaled)"
    return None
