"""Shadows on every surface: shadowgeo.shadow_on_surface against manifold3d, one run.

Run from the repository root::

    python benchmarks/bench_surface.py            # full size (20,000-face terrain)
    python benchmarks/bench_surface.py --quick    # small meshes, for a smoke test

The scene: a hilly terrain (a 100 x 100 grid, 20,000 faces) under an icosphere
(20,480 faces), the terrain shadowing itself too. For each light it times

* ``shadowgeo.shadow_on_surface([terrain, sphere], light, terrain)``, warm
  (the meshes' topology cached) -- the exact shadow on every terrain face;
* the peer for the *sphere's planar shadow alone* on the terrain's mean plane,
  as benchmarks/bench_planar.py times it: manifold3d's perspective ``warp`` and
  ``project()`` (mesh ingested once), and with the ingest;
* ``shadow_on_surface`` with the sphere alone as caster (no self-shadowing),
  and ``shadowgeo.project_shadow`` of the sphere on that plane, for scale.

The ratio column divides each time by manifold3d's warp + project measured in
the same run. A flat-grid row checks the result against ``project_shadow``
(relative area error). Last, a table of times for casters x surface faces
shows how the cost grows. Times are the best of several runs (see
:func:`best_time`), taken round by round (each method once per round) so that
all methods see the same spells of load: the benchmark machines are shared.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import platform
import sys
import time
from pathlib import Path

import numpy as np
import shapely
import trimesh

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench_planar import manifold_ingest, manifold_perspective  # noqa: E402

import shadowgeo  # noqa: E402
from shadowgeo import (  # noqa: E402
    DirectionalLight,
    Plane,
    PointLight,
    project_shadow,
    shadow_on_surface,
)


def best_time(function, repeat: int) -> tuple[float, float]:
    """The fastest of ``repeat`` calls: (wall seconds, CPU seconds of this
    process, all threads). On a shared machine the median still carries other
    processes' load; the minimum, and CPU time, are what the code costs."""
    walls, cpus = [], []
    for _ in range(repeat):
        start, cpu = time.perf_counter(), time.process_time()
        function()
        walls.append(time.perf_counter() - start)
        cpus.append(time.process_time() - cpu)
    return min(walls), min(cpus)


def terrain(cells: int, half: float = 5.0, flat: bool = False) -> trimesh.Trimesh:
    """A cells x cells grid (2 cells^2 faces) of rolling hills over [-half, half]^2."""
    xs = np.linspace(-half, half, cells + 1)
    x, z = np.meshgrid(xs, xs, indexing="ij")
    y = np.zeros_like(x)
    if not flat:
        y = 0.6 * np.sin(1.3 * x) * np.cos(1.1 * z) + 0.2 * np.sin(3 * x + 1)
    vertices = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    index = np.arange((cells + 1) ** 2).reshape(cells + 1, cells + 1)
    a, b = index[:-1, :-1].ravel(), index[1:, :-1].ravel()
    c, d = index[1:, 1:].ravel(), index[:-1, 1:].ravel()
    faces = np.concatenate([np.column_stack([a, d, c]), np.column_stack([a, c, b])])
    return trimesh.Trimesh(vertices, faces, process=False)


def sphere(subdivisions: int) -> trimesh.Trimesh:
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    mesh.apply_translation([0.0, 2.5, 0.0])
    return mesh


LIGHTS = {
    "point": PointLight([2.0, 8.0, 1.0]),
    "low sun": DirectionalLight([1.0, -0.35, 0.3]),
}
GROUND = Plane([0.0, 1.0, 0.0], 0.0)


def comparison(quick: bool, repeat: int) -> list[dict]:
    cells, subdivisions = (30, 3) if quick else (100, 5)
    ground, ball = terrain(cells), sphere(subdivisions)
    ingested = manifold_ingest(ball)
    rows = []
    for name, light in LIGHTS.items():
        shadow = shadow_on_surface([ground, ball], light, ground)  # warm the caches
        entries = [
            (
                "shadowgeo shadow_on_surface (terrain + sphere, self-shadowing)",
                lambda light=light: shadow_on_surface([ground, ball], light, ground),
            ),
            (
                "shadowgeo shadow_on_surface (sphere alone on the terrain)",
                lambda light=light: shadow_on_surface(ball, light, ground),
            ),
            (
                "shadowgeo project_shadow (sphere on the plane)",
                lambda light=light: project_shadow(ball, light, GROUND),
            ),
        ]
        if isinstance(light, PointLight):
            entries += [
                (
                    "manifold3d warp+project (sphere on the plane, ingested once)",
                    lambda light=light: manifold_perspective(ball, light, GROUND, ingested),
                ),
                (
                    "manifold3d ingest+warp+project",
                    lambda light=light: manifold_perspective(ball, light, GROUND),
                ),
            ]
        else:
            frame = _frame_along(light.direction)
            entries += [
                (
                    "manifold3d project along the light (sphere, ingested once)",
                    lambda frame=frame: ingested.transform(frame).project().area(),
                ),
                (
                    "manifold3d ingest+project",
                    lambda frame=frame: manifold_ingest(ball).transform(frame).project().area(),
                ),
            ]
        # Round by round, every method once per round: on a shared machine the
        # methods then see the same spells of load, and the ratios hold.
        walls = np.full((repeat, len(entries)), np.inf)
        cpus = np.full((repeat, len(entries)), np.inf)
        for round_ in range(repeat):
            for k, (_, function) in enumerate(entries):
                walls[round_, k], cpus[round_, k] = best_time(function, 1)
        for k, (method, _) in enumerate(entries):
            seconds, cpu = float(walls[:, k].min()), float(cpus[:, k].min())
            rows.append({"light": name, "method": method, "seconds": seconds, "cpu": cpu})
        rows[-5]["detail"] = (
            f"{shadow.diagnostics.n_shadowed_faces:,} faces shadowed, "
            f"{shadow.diagnostics.n_full_faces:,} wholly; "
            f"{shadow.diagnostics.n_clipped_pairs:,} triangle pairs clipped"
        )
    return rows


def _frame_along(direction) -> np.ndarray:
    """(3, 4) rotation taking ``direction`` to -z (manifold3d projects along z)."""
    plane = Plane(-np.asarray(direction), 0.0)
    u, v = plane.basis
    return np.column_stack([np.vstack([u, v, plane.normal]), np.zeros(3)])


def flat_check(quick: bool) -> dict:
    ground = terrain(30 if quick else 100, flat=True)
    ball = sphere(3 if quick else 5)
    light = LIGHTS["point"]
    square = [[-5, 0, -5], [5, 0, -5], [5, 0, 5], [-5, 0, 5]]
    ours = shadow_on_surface(ball, light, ground).area
    planar = project_shadow(ball, light, GROUND, receiver=square).area
    return {"faces": len(ground.faces), "ours": ours, "planar": planar}


def scaling(quick: bool) -> tuple[list[int], list[int], np.ndarray]:
    cells = [10, 20, 40] if quick else [25, 50, 100]
    subdivisions = [2, 3] if quick else [3, 4, 5]
    light = LIGHTS["point"]
    times = np.zeros((len(subdivisions), len(cells)))
    for i, level in enumerate(subdivisions):
        ball = sphere(level)
        for j, size in enumerate(cells):
            ground = terrain(size)
            shadow_on_surface([ground, ball], light, ground)
            times[i, j] = best_time(
                lambda g=ground, b=ball: shadow_on_surface([g, b], light, g), 5
            )[1]
    faces = [2 * c * c for c in cells]
    casters = [len(sphere(level).faces) for level in subdivisions]
    return casters, faces, times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small meshes, fewer repeats")
    parser.add_argument("--repeat", type=int, default=9, help="runs per method (best)")
    args = parser.parse_args()
    repeat = 3 if args.quick else args.repeat
    print(
        f"shadowgeo {shadowgeo.__version__}, numpy {np.__version__}, "
        f"trimesh {trimesh.__version__}, "
        f"manifold3d {importlib.metadata.version('manifold3d')}, shapely {shapely.__version__}, "
        f"Python {platform.python_version()}, {platform.machine()}"
    )
    rows = comparison(args.quick, repeat)
    print(
        "\n| light | method | wall (ms) | CPU (ms) | wall / manifold3d warm "
        "| CPU / manifold3d warm | notes |"
    )
    print("|---|---|---:|---:|---:|---:|---|")
    for name in LIGHTS:
        mine = [row for row in rows if row["light"] == name]
        peer = next(row for row in mine if "manifold3d" in row["method"])
        for row in mine:
            print(
                f"| {name} | {row['method']} | {1e3 * row['seconds']:.1f} | {1e3 * row['cpu']:.1f} "
                f"| {row['seconds'] / peer['seconds']:.1f}x | {row['cpu'] / peer['cpu']:.1f}x "
                f"| {row.get('detail', '')} |"
            )
    check = flat_check(args.quick)
    error = abs(check["ours"] - check["planar"]) / check["planar"]
    print(
        f"\nflat grid of {check['faces']:,} faces: shadow_on_surface area {check['ours']:.12f}, "
        f"project_shadow {check['planar']:.12f}, relative difference {error:.1e}"
    )
    casters, faces, times = scaling(args.quick)
    print("\nshadow_on_surface CPU time (ms), point light, terrain shadowing itself:")
    print("| sphere faces \\ terrain faces | " + " | ".join(f"{f:,}" for f in faces) + " |")
    print("|---|" + "---:|" * len(faces))
    for count, line in zip(casters, times, strict=True):
        print(f"| {count:,} | " + " | ".join(f"{1e3 * t:.0f}" for t in line) + " |")


if __name__ == "__main__":
    main()
