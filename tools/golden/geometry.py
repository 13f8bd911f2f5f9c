"""Geometry cases: the benchmark scenes and the pyramid through the geometry API.

Scenes (built by the benchmarks' own builders, so they are the scenes the
benchmarks time):

- ``city``: 300 random boxes on the ground (``bench_buildings.buildings``)
  as one caster, receiving on the ground plane or a ground square;
  ``city-every-face``: the same boxes as separate casters, every face of the
  ground square and of the boxes receiving (``bench_buildings --surfaces``);
- ``terrain``: a 30 x 30 grid of hills under an icosphere
  (``bench_surface.terrain`` and ``sphere``, their quick sizes), the sphere
  casting and the terrain shadowing itself; ``terrain-open``: the terrain
  alone as a caster (an open mesh, two-sided) over the plane y = -1.5;
- ``icosphere``, ``bumpy``, ``torus``: ``benchmarks/common.meshes(quick=True)``
  over the plane y = -2 (the torus also shadowing itself);
- ``pyramid``: the seed example (``examples/pyramid.py``), its own light.

Each scene has a point, a spot and a directional light placed so that the
shadows are not trivial (the spot's cone cuts through the caster's shadow);
each light goes through ``project_shadow``, ``shadow_on_surface``,
``shadow_volume`` and ``silhouette``, and all three at once through
``project_shadow`` with a list (the many-lights path). A tiny ``sun_study``
ends the list. The hash of each caster's vertices and faces is part of its
cases' records, so a changed builder shows as a changed input, not as a
changed result.
"""

from __future__ import annotations

import datetime as dt
import math
import sys
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from . import digest
from .digest import Digest, array_hash, canonical

ROOT = Path(__file__).resolve().parents[2]


@dataclass(frozen=True)
class Scene:
    """Casters, the plane and the surface that receive, and the three lights."""

    caster: Any  # (vertices, faces) or trimesh.Trimesh: what project_shadow gets
    plane: Any
    surface: Any  # the mesh shadow_on_surface receives on
    surface_casters: Any  # what shadow_on_surface is given as casters
    lights: dict[str, Any]
    input_hash: str
    calls: tuple[str, ...] = ("project_shadow", "shadow_on_surface", "shadow_volume", "silhouette")


def benchmarks_on_path() -> None:
    for folder in (ROOT / "benchmarks", ROOT):
        if str(folder) not in sys.path:
            sys.path.insert(0, str(folder))


def _mesh_hash(*meshes: Any) -> str:
    parts = []
    for mesh in meshes:
        vertices, faces = (mesh.vertices, mesh.faces) if hasattr(mesh, "faces") else mesh
        parts.append(array_hash(canonical(vertices, "f")) + array_hash(canonical(faces, "i")))
    return digest.sha256("".join(parts).encode())


def _square(y: float, half: float) -> tuple[np.ndarray, np.ndarray]:
    """A ground square at height ``y``, facing up (+y)."""
    vertices = np.array([[-half, y, -half], [-half, y, half], [half, y, half], [half, y, -half]])
    return vertices, np.array([[0, 1, 2], [0, 2, 3]])


def _lights(point: Any, spot_at: Any, spot_to: Any, cut_off: float, sun: Any) -> dict[str, Any]:
    import shadowgeo as sg

    spot_at = np.asarray(spot_at, dtype=float)
    return {
        "point": sg.PointLight(point),
        "spot": sg.SpotLight(spot_at, np.asarray(spot_to, dtype=float) - spot_at, cut_off),
        "directional": sg.DirectionalLight(sun),
    }


@cache
def scenes() -> dict[str, Scene]:
    """Every scene by name (built once per process)."""
    import shadowgeo as sg

    benchmarks_on_path()
    import bench_buildings
    import bench_surface
    import common

    found = {}
    corners = bench_buildings.buildings(300)
    city = bench_buildings.as_mesh(corners)
    ground = _square(0.0, 300.0)
    found["city"] = Scene(
        city,
        sg.Plane([0, 1, 0], 0),
        ground,
        city,
        _lights([40, 250, -30], [-60, 180, 50], [20, 0, -10], math.pi / 8, [0.45, -0.75, 0.3]),
        _mesh_hash(city, ground),
    )
    boxes = [(box, bench_buildings._FACES) for box in corners]
    vertices = np.concatenate([ground[0], city[0]])
    every_face = (vertices, np.concatenate([ground[1], city[1] + len(ground[0])]))
    found["city-every-face"] = Scene(
        city,
        sg.Plane([0, 1, 0], 0),
        every_face,
        boxes,
        found["city"].lights,
        _mesh_hash(every_face, *boxes),
        ("shadow_on_surface",),
    )
    terrain, ball = bench_surface.terrain(30), bench_surface.sphere(3)
    found["terrain"] = Scene(
        ball,
        sg.Plane([0, 1, 0], 0),
        terrain,
        [terrain, ball],
        _lights([2, 8, 1], [-3, 7, 2], [0.5, 0, 0], 0.3, [1.0, -0.35, 0.3]),
        _mesh_hash(terrain, ball),
    )
    found["terrain-open"] = Scene(
        terrain,
        sg.Plane([0, 1, 0], 1.5),
        _square(-1.5, 12.0),
        terrain,
        found["terrain"].lights,
        _mesh_hash(terrain),
    )
    below = _square(-2.0, 6.0)
    names = ("icosphere", "bumpy", "torus")
    for name, mesh in zip(names, common.meshes(quick=True).values(), strict=True):
        found[name] = Scene(
            mesh,
            sg.Plane([0, 1, 0], 2),
            below,
            mesh,
            _lights([1.5, 4, 1], [-1, 3.5, 0.5], [0.2, -2, 0], 0.35, [0.3, -1, 0.2]),
            _mesh_hash(mesh, below),
        )
    pyramid = (
        np.array([[-2, 3, -1], [2, 3, -1], [0, 3, 2], [0, 5, 0]], dtype=float),
        np.array([[1, 0, 3], [2, 1, 3], [0, 2, 3], [0, 1, 2]]),
    )
    found["pyramid"] = Scene(
        pyramid,
        sg.Plane([0, 1, 0], 0),
        _square(0.0, 20.0),
        pyramid,
        {"point": sg.PointLight([8, 9, 10])},
        _mesh_hash(pyramid),
    )
    return found


@dataclass(frozen=True)
class GeometryCase:
    """One call of the geometry API on one scene; ``light``: a key of the
    scene's lights, or "all" for the list of them."""

    id: str
    what: str
    scene: str
    light: str
    call: Callable[[Scene, Any], Digest]
    needs_corpus: bool = False

    def run(self, scratch: Path) -> Digest:
        scene = scenes()[self.scene]
        light = list(scene.lights.values()) if self.light == "all" else scene.lights[self.light]
        try:
            result = self.call(scene, light)
        except Exception as exception:  # the error is the golden result of this case
            result = digest.error(exception)
        result.record["input_sha256"] = scene.input_hash
        return result


def _project(scene: Scene, light: Any) -> Digest:
    import shadowgeo as sg

    return digest.shadow(sg.project_shadow(scene.caster, light, scene.plane))


def _project_many(scene: Scene, lights: Any) -> Digest:
    import shadowgeo as sg

    return digest.shadows(sg.project_shadow(scene.caster, lights, scene.plane))


def _surface(scene: Scene, light: Any) -> Digest:
    import shadowgeo as sg

    return digest.surface_shadow(sg.shadow_on_surface(scene.surface_casters, light, scene.surface))


def _self_surface(scene: Scene, light: Any) -> Digest:
    import shadowgeo as sg

    return digest.surface_shadow(sg.shadow_on_surface(scene.caster, light, scene.caster))


def _volume(scene: Scene, light: Any) -> Digest:
    import shadowgeo as sg

    return digest.volume(sg.shadow_volume(scene.caster, light))


def _silhouette(scene: Scene, light: Any) -> Digest:
    import shadowgeo as sg

    return digest.silhouette(sg.silhouette(scene.caster, light))


def _pyramid(scene: Scene, light: Any) -> Digest:
    import shadowgeo as sg

    # as examples/pyramid.py calls it
    return digest.shadow(sg.project_shadow(scene.caster, light, scene.plane, offset=0.001))


def _sun_study(scene: Scene, light: Any) -> Digest:
    import shadowgeo as sg

    benchmarks_on_path()
    import bench_sunstudy

    vertices, faces, half = bench_sunstudy.city(4)
    region = [[-half, 0, half], [half, 0, half], [half, 0, -half], [-half, 0, -half]]
    day = [dt.datetime(2026, 6, 21, hour, 30, tzinfo=dt.UTC) for hour in range(3, 20, 2)]
    study = sg.sun_study(
        (vertices, faces), sg.Plane([0, 1, 0]), region, day, latitude=48.85, longitude=2.35
    )
    result = digest.sun_study(study)
    result.record["study_input_sha256"] = _mesh_hash((vertices, faces))
    return result


CALLS = {
    "project_shadow": (_project, "project_shadow onto the plane"),
    "shadow_on_surface": (_surface, "shadow_on_surface"),
    "shadow_volume": (_volume, "shadow_volume of the caster"),
    "silhouette": (_silhouette, "silhouette of the caster"),
}


def cases() -> list[GeometryCase]:
    """Every geometry case, in a fixed order."""
    found = [
        GeometryCase(
            "shadow/pyramid/point/project_shadow",
            "examples/pyramid.py: project_shadow, offset 0.001",
            "pyramid",
            "point",
            _pyramid,
        )
    ]
    for scene, built in scenes().items():
        if scene == "pyramid":
            continue
        for light in ("point", "spot", "directional"):
            for call in built.calls:
                function, what = CALLS[call]
                found.append(
                    GeometryCase(
                        f"shadow/{scene}/{light}/{call}", f"{what}, {scene}", scene, light, function
                    )
                )
            if scene == "torus":
                found.append(
                    GeometryCase(
                        f"shadow/{scene}/{light}/self_shadow",
                        "shadow_on_surface of the torus on itself",
                        scene,
                        light,
                        _self_surface,
                    )
                )
        if "project_shadow" not in built.calls:
            continue
        found.append(
            GeometryCase(
                f"shadow/{scene}/all/project_shadow",
                f"project_shadow with the list of three lights, {scene}",
                scene,
                "all",
                _project_many,
            )
        )
    found.append(
        GeometryCase(
            "shadow/sun_study/city4",
            "sun_study of 4 buildings (bench_sunstudy.city), midsummer in Paris",
            "pyramid",
            "point",
            _sun_study,
        )
    )
    return found
