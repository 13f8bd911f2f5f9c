"""Geometry mode: random casters, planes and lights (plain numbers, so a
case pickles and prints), run through ``project_shadow``, ``silhouette`` and
``shadow_volume`` with the checks of :mod:`fuzz.check_geometry`, and the
script that reproduces a case."""

from __future__ import annotations

import traceback

import numpy as np
import trimesh

import shadowgeo

from .check_geometry import check_shadow, check_silhouette, check_volume
from .results import BudgetExceeded, failure, signature_of


def geometry_case(seed: int, index: int) -> dict:
    """A random caster, plane and light: plain numbers, so it pickles and prints."""
    rng = np.random.default_rng([seed, index])
    scale = 10.0 ** rng.choice([0] * 8 + [-300, -150, -12, -6, 3, 6, 12, 50, 100, 150, 300])
    kind = rng.choice(["soup", "hull", "box", "sphere", "degenerate", "grid", "duplicate"])
    if kind == "hull" or kind == "duplicate":
        mesh = trimesh.convex.convex_hull(rng.normal(size=(int(rng.integers(4, 20)), 3)))
        vertices, faces = mesh.vertices, mesh.faces
        if kind == "duplicate":
            faces = np.concatenate([faces, faces[: int(rng.integers(1, len(faces) + 1))]])
    elif kind == "box":
        mesh = trimesh.creation.box(extents=rng.uniform(0.01, 2, size=3))
        vertices, faces = mesh.vertices, mesh.faces
    elif kind == "sphere":
        # most with a dent (not convex: its folds cast outline loops inside
        # the outline, the many-loop certificate's case); drawn apart so the
        # other kinds' cases stay as they were
        dent = np.random.default_rng([seed, index, 7])
        mesh = trimesh.creation.icosphere(subdivisions=int(dent.integers(1, 4)))
        vertices, faces = mesh.vertices.copy(), mesh.faces
        if dent.random() < 0.7:  # the cap above a level pressed in: a crater, still embedded
            axis = dent.normal(size=3)
            axis /= np.linalg.norm(axis)
            level, depth = dent.uniform(0.2, 0.9), dent.uniform(0.3, 0.95)
            height = vertices @ axis
            above = height > level
            vertices[above] -= ((1 - depth) * height[above])[:, None] * axis
    elif kind == "grid":
        vertices = np.array([[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1.0]]) + rng.normal(size=3)
        faces = np.array([[0, 1, 2], [0, 2, 3]])
    else:
        count = int(rng.integers(1, 12))
        vertices = rng.normal(size=(3 * count, 3))
        faces = np.arange(3 * count).reshape(-1, 3)
        if kind == "degenerate":
            for face in faces[: int(rng.integers(1, count + 1))]:
                if rng.random() < 0.5:
                    vertices[face[2]] = vertices[face[0]]  # a repeated vertex
                else:
                    vertices[face[2]] = 2 * vertices[face[1]] - vertices[face[0]]  # collinear
    vertices = np.asarray(vertices, dtype=np.float64)
    normal = np.array([0.0, 1.0, 0.0]) if rng.random() < 0.5 else rng.normal(size=3)
    normal /= np.linalg.norm(normal)
    # Place the caster above the plane (mostly), across it, or below it.
    heights = vertices @ normal
    lift = rng.choice([2.0, 2.0, 2.0, 0.0, -3.0]) - heights.min()
    vertices = vertices + lift * normal
    heights = vertices @ normal
    top = float(heights.max())
    light_kind = rng.choice(
        ["point", "point", "near-vertex", "on-plane", "between", "spot", "sun", "grazing"]
    )
    light: dict = {"kind": "point"}
    tangent = np.cross(normal, rng.normal(size=3))
    if light_kind in ("point", "spot"):
        position = (top + rng.uniform(0.5, 10)) * normal + rng.normal(size=3)
        light = {"kind": light_kind, "position": position}
        if light_kind == "spot":
            light.update(direction=-normal + 0.3 * rng.normal(size=3), angle=rng.uniform(0.05, 1.5))
    elif light_kind == "near-vertex":
        vertex = vertices[int(rng.integers(len(vertices)))]
        gap = 10.0 ** rng.uniform(-15, -1)
        light = {"kind": "point", "position": vertex + gap * (normal + 0.1 * tangent)}
    elif light_kind == "on-plane":
        tiny = rng.choice([0.0, 1e-15, 1e-12, -1e-15])
        light = {"kind": "point", "position": 3 * tangent + tiny * normal}
    elif light_kind == "between":
        light = {"kind": "point", "position": rng.uniform(0.1, max(top, 0.2)) * normal + tangent}
    elif light_kind == "sun":
        light = {"kind": "sun", "direction": -normal + 0.5 * rng.normal(size=3)}
    else:
        cosine = 10.0 ** -rng.uniform(1, 16)
        direction = -cosine * normal + tangent / np.linalg.norm(tangent)
        light = {"kind": "sun", "direction": direction}
    if light["kind"] != "sun" and rng.random() < 0.25:
        light["radius"] = float(10.0 ** rng.uniform(-1, 200))
    shift = rng.normal(size=3) * (10.0 ** rng.choice([0, 0, 0, 3, 8, 15]))
    if not np.all(np.isfinite(shift * scale * 100)):
        shift = np.zeros(3)  # keep every generated number finite
    for name in ("position",):
        if name in light:
            light[name] = (np.asarray(light[name]) + shift) * scale
    vertices = (vertices + shift) * scale
    offset = float(-float(normal @ shift) * scale)
    return {
        "seed": seed,
        "index": index,
        "kind": str(kind),
        "light_kind": str(light_kind),
        "vertices": vertices.tolist(),
        "faces": np.asarray(faces).tolist(),
        "normal": normal.tolist(),
        "scale": float(scale),
        "offset": offset,
        "light": {k: (np.asarray(v).tolist() if k != "kind" else str(v)) for k, v in light.items()},
    }


def make_light(spec: dict):
    extra = {"radius": spec["radius"]} if "radius" in spec else {}
    if spec["kind"] == "sun":
        return shadowgeo.DirectionalLight(spec["direction"])
    if spec["kind"] == "spot":
        return shadowgeo.SpotLight(spec["position"], spec["direction"], spec["angle"], **extra)
    return shadowgeo.PointLight(spec["position"], **extra)


def run_geometry(case: dict) -> dict:
    """project_shadow, silhouette and shadow_volume on one case, checked."""
    vertices = np.asarray(case["vertices"], dtype=np.float64)
    faces = np.asarray(case["faces"], dtype=np.int64).reshape(-1, 3)
    step = "setup"
    try:
        light = make_light(case["light"])
        plane = shadowgeo.Plane(case["normal"], case["offset"])
        step = "project_shadow"
        problem = check_shadow(vertices, faces, light, plane)
        if problem:
            return failure(f"check:project_shadow:{problem[0]}", problem[1])
        step = "silhouette"
        problem = check_silhouette(vertices, faces, light)
        if problem:
            return failure(f"check:silhouette:{problem[0]}", problem[1])
        step = "shadow_volume"
        problem = check_volume(vertices, faces, light)
        if problem:
            return failure(f"check:shadow_volume:{problem[0]}", problem[1])
    except shadowgeo.GeometryError as error:
        detail = f"{step}: GeometryError: {error}"[:300]
        return {"ok": True, "signature": None, "detail": detail, "code": 1}
    except (BudgetExceeded, MemoryError):
        raise
    except Exception as error:  # noqa: BLE001 - any other exception is the finding
        return failure(signature_of(error), traceback.format_exc(limit=-8))
    return {"ok": True, "signature": None, "detail": "", "code": 0}


def geometry_reproducer(case: dict) -> str:
    return (
        f"# found by tools/fuzz.py --geometry (seed {case['seed']}, case {case['index']})\n"
        "from shadowgeo import *\n"
        f"vertices = {case['vertices']!r}\nfaces = {case['faces']!r}\n"
        f"light = {case['light']!r}\nplane = Plane({case['normal']!r}, {case['offset']!r})\n"
        "kind = light.pop('kind'); radius = light.pop('radius', float('inf'))\n"
        "L = (DirectionalLight(light['direction']) if kind == 'sun' else SpotLight("
        "light['position'], light['direction'], light['angle'], radius) if kind == 'spot' "
        "else PointLight(light['position'], radius))\n"
        "print('area', project_shadow((vertices, faces), L, plane).area)\n"
        "print('loops', [len(loop) for loop in silhouette((vertices, faces), L).loops])\n"
        "volume = shadow_volume((vertices, faces), L)\n"
        "import trimesh\n"
        "if len(volume.faces):\n"
        "    centred = volume.vertices - volume.vertices.mean(axis=0)\n"
        "    unit = trimesh.Trimesh(centred / abs(centred).max(), volume.faces, process=False)\n"
        "    print('watertight', volume.is_watertight, 'normalised volume', unit.volume)\n"
    )
