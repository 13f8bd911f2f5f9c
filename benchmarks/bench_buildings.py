"""Many buildings under the sun: shadowgeo against per-building polygons + GEOS.

Run from the repository root::

    python benchmarks/bench_buildings.py                 # 1,000 and 10,000 buildings
    python benchmarks/bench_buildings.py --sizes 1000    # one size
    python benchmarks/bench_buildings.py --phases        # where shadowgeo's time goes
    python benchmarks/bench_buildings.py --surfaces --sizes 1000   # every surface receiving

The city is ``n`` random boxes (8-16 m wide, 3-40 m tall, turned at random)
standing on the ground y = 0, scattered over a square whose side grows with
``sqrt(n)`` so the density (and the overlap between shadows) stays the same.
One sun direction lights them all. Methods, on the same input, same process:

* ``shadowgeo.project_shadow`` of all boxes as one caster (its result is the
  union, holes and all);
* the method of pybdshadow (Yu et al. 2023), reproduced: each building's shadow
  is the convex hull of its base and its projected roof, then
  ``shapely.union_all`` (GEOS). pybdshadow itself is not installed: it pulls
  in geopandas and its own data stack, and its method is the few lines here.

The two methods are called in turn, ``--repeat`` rounds after one warm call
each, so a shared machine's drifting load weighs on both alike; the ratio is
of wall-clock medians, the CPU ratio of this process's CPU-time medians
(steadier on a shared machine), both from the same calls. Area error is relative to an exact
reference: the union, by shapely, of each box's exact shadow (the convex hull
of its eight projected corners, exact for a convex box standing on the
ground), computed with GEOS's ``union_all`` in float64. Times are medians of
``--repeat`` runs. The last column, CPU time / (n log n), should stay flat if
the cost grows as n log n.
``--surfaces`` times the shadow on every surface instead: the ``n`` boxes as
separate casters (each closed: each goes by its outline) over a ground
square, every face of the ground and of the boxes receiving
(``shadow_on_surface``), under the sun and under a point light high over the
city, beside ``project_shadow`` of the same boxes onto the ground and the
per-building + GEOS union (the planar shadow alone, same run); the ground's
shadowed area against the exact reference under the sun (the ground holds
every shadow, footprints included).
``--phases`` times the steps of ``project_shadow`` calls (CPU time, each
step's functions wrapped with a timer; steps nest), after one call to warm
up, and prints the median call of ``--repeat``.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

import numpy as np
import shapely

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_lights import timed_phases  # noqa: E402

from shadowgeo import (  # noqa: E402
    DirectionalLight,
    Plane,
    PointLight,
    project_shadow,
    shadow_on_surface,
)

SUN = DirectionalLight([0.45, -0.75, 0.3])
GROUND = Plane([0, 1, 0], 0)

# The eight corners and twelve triangles of the unit box [0, 1]^3, outward wound.
_CORNERS = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
_FACES = np.array(
    [
        [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5],  # x = 0, x = 1
        [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],  # y = 0, y = 1
        [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3],  # z = 0, z = 1
    ]
)  # fmt: skip


def buildings(n: int, seed: int = 7) -> np.ndarray:
    """(n, 8, 3) corners of ``n`` random boxes standing on y = 0."""
    rng = np.random.default_rng(seed)
    side = 25.0 * math.sqrt(n)
    size = np.column_stack([rng.uniform(8, 16, n), rng.uniform(3, 40, n), rng.uniform(8, 16, n)])
    angle = rng.uniform(0, math.pi, n)
    cosine, sine = np.cos(angle), np.sin(angle)
    local = (_CORNERS - [0.5, 0.0, 0.5])[None] * size[:, None]
    x = cosine[:, None] * local[..., 0] - sine[:, None] * local[..., 2]
    z = sine[:, None] * local[..., 0] + cosine[:, None] * local[..., 2]
    centre = rng.uniform(-side / 2, side / 2, (n, 2))
    return np.stack([x + centre[:, :1], local[..., 1], z + centre[:, 1:]], axis=-1)


def as_mesh(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """All boxes as one (vertices, faces) mesh."""
    n = len(corners)
    faces = (_FACES[None] + 8 * np.arange(n)[:, None, None]).reshape(-1, 3)
    return corners.reshape(-1, 3), faces


def ground_points(points: np.ndarray) -> np.ndarray:
    """Points projected along the sun onto y = 0, as plane 2-D coordinates."""
    direction = SUN.direction
    flat = points - (points[..., 1:2] / direction[1]) * direction
    return GROUND.to_2d(flat.reshape(-1, 3)).reshape(*points.shape[:-1], 2)


def per_building_union(corners: np.ndarray) -> shapely.Geometry:
    """pybdshadow's way: hull of base and projected roof per building, union_all."""
    base = GROUND.to_2d(corners[:, [0, 1, 5, 4]].reshape(-1, 3)).reshape(-1, 4, 2)
    roof = ground_points(corners[:, [2, 3, 7, 6]])
    hulls = shapely.convex_hull(shapely.multipoints(np.concatenate([base, roof], axis=1)))
    return shapely.union_all(hulls)


def exact_area(corners: np.ndarray) -> float:
    """Reference: union of each box's exact shadow, the hull of its eight images."""
    images = ground_points(corners)
    return float(shapely.union_all(shapely.convex_hull(shapely.multipoints(images))).area)


# (module, attribute, label) of the steps --phases times, in call order.
PHASES = [
    ("shadowgeo.projection", "as_caster", "caster checked (vertices, faces)"),
    ("shadowgeo.projection", "light_frames", "light's frame: tolerance, plane frame, window"),
    ("shadowgeo.batchlights", "front_rows", "front faces (and face normals)"),
    ("shadowgeo.batchlights", "silhouette_outlines", "silhouettes (edge keys, chaining)"),
    ("shadowgeo.batchlights", "project_outlines", "outlines projected"),
    ("shadowgeo.plane2d", "unite", "2-D union (the arrangement, else Clipper2), and parts"),
    ("shadowgeo.plane2d.union", "convex_union_flat", "  of which the arrangement (numpy)"),
    ("shadowgeo.plane2d.nesting", "FlatParts.nested", "  of which holes to their parts"),
    ("shadowgeo.plane2d.union", "_clipped", "  of which Clipper2 unions"),
    ("shadowgeo.batchlights", "vertex_components", "  of which the caster's parts"),
    ("shadowgeo.batchlights", "_array_result", "result (area, polygons)"),
]


def phases(sizes: list[int], repeat: int) -> None:
    """Print where shadowgeo's time goes, per step, for each size: the steps
    of the median of ``repeat`` calls (by whole-call CPU time)."""
    print("| step | " + " | ".join(f"{n:,} buildings: CPU ms" for n in sizes) + " |")
    print("|---|" + "---|" * len(sizes))
    results = []
    for n in sizes:
        mesh = as_mesh(buildings(n))
        call = partial(project_shadow, mesh, SUN, GROUND)
        call()  # warm: first-touch memory and imports are no step's cost
        runs = [timed_phases(call, PHASES) for _ in range(repeat)]
        results.append(sorted(runs, key=lambda run: run[0])[len(runs) // 2])  # the median call
    print("| whole call | " + " | ".join(f"{total * 1e3:.1f}" for total, _ in results) + " |")
    for _, _, label in PHASES:
        print(f"| {label} | " + " | ".join(f"{s[label] * 1e3:.1f}" for _, s in results) + " |")


def surfaces(sizes: list[int], repeat: int) -> None:
    """Print the every-surface table (see the module's docstring)."""
    print(
        "| buildings | light | shadow_on_surface CPU s | project_shadow CPU s "
        "| per-building + GEOS CPU s | shadow triangles | ground rel. area error |"
    )
    print("|---|---|---|---|---|---|---|")
    for n in sizes:
        corners = buildings(n)
        boxes = [(box, _FACES) for box in corners]
        half = 15.0 * math.sqrt(n)  # the city is 25 sqrt(n) across, shadows reach ~30 m out
        square = np.array([[-half, 0, half], [half, 0, half], [half, 0, -half], [-half, 0, -half]])
        mesh = as_mesh(corners)
        vertices = np.concatenate([square, mesh[0]])
        faces = np.concatenate([[[0, 1, 2], [0, 2, 3]], mesh[1] + 4])
        lights = [("sun", SUN), ("point", PointLight([30.0, 300.0, -50.0]))]
        for name, light in lights:
            every = partial(shadow_on_surface, boxes, light, (vertices, faces))
            planar = partial(project_shadow, mesh, light, GROUND)
            runs: dict[str, list[float]] = {"every": [], "planar": [], "geos": []}
            every(), planar()
            for _ in range(repeat):  # in turn, so that all see the same load
                runs["every"].append(timed(every)[1])
                runs["planar"].append(timed(planar)[1])
                if light is SUN:
                    runs["geos"].append(timed(partial(per_building_union, corners))[1])
            shadow = every()
            # the ground's two triangles, each (2 half)^2 / 2
            ground = float(shadow.fraction[:2].sum()) * 2.0 * half * half
            error = "—"
            if light is SUN:
                reference = exact_area(corners)
                error = f"{abs(ground - reference) / reference:.1e}"
            geos = f"{statistics.median(runs['geos']):.3f}" if runs["geos"] else "—"
            print(
                f"| {n:,} | {name} | {statistics.median(runs['every']):.3f} "
                f"| {statistics.median(runs['planar']):.3f} | {geos} | {len(shadow.faces):,} "
                f"| {error} |"
            )


def timed(function: Callable[[], object]) -> tuple[float, float, object]:
    """Wall-clock and process-CPU seconds of one call, and its result."""
    wall, cpu = time.perf_counter(), time.process_time()
    result = function()
    return time.perf_counter() - wall, time.process_time() - cpu, result


def interleaved(
    ours: Callable[[], object], theirs: Callable[[], object], repeat: int
) -> tuple[list[tuple[float, float, object]], list[tuple[float, float, object]]]:
    """``repeat`` rounds of one call each way, alternating (after one warm
    call each): on a shared machine whose load drifts, both sides see the
    same drift."""
    ours(), theirs()
    mine, peer = [], []
    for _ in range(repeat):
        mine.append(timed(ours))
        peer.append(timed(theirs))
    return mine, peer


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1000, 10000])
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--phases", action="store_true", help="time shadowgeo's steps")
    parser.add_argument(
        "--surfaces", action="store_true", help="every surface receiving (shadow_on_surface)"
    )
    args = parser.parse_args()
    if args.phases:
        phases(args.sizes, args.repeat)
        return
    if args.surfaces:
        surfaces(args.sizes, args.repeat)
        return
    print(
        "| buildings | shadowgeo s | per-building + GEOS s | ratio | shadowgeo CPU s "
        "| per-building + GEOS CPU s | CPU ratio | rel. area error shadowgeo "
        "| rel. area error GEOS | shadowgeo CPU s / (n log n) x 1e6 |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for n in args.sizes:
        corners = buildings(n)
        mesh = as_mesh(corners)
        mine, peer = interleaved(
            partial(project_shadow, mesh, SUN, GROUND),
            partial(per_building_union, corners),
            args.repeat,
        )
        ours = statistics.median(run[0] for run in mine)
        theirs = statistics.median(run[0] for run in peer)
        our_cpu = statistics.median(run[1] for run in mine)
        their_cpu = statistics.median(run[1] for run in peer)
        shadow, union = mine[-1][2], peer[-1][2]
        reference = exact_area(corners)
        error = abs(shadow.area - reference) / reference  # type: ignore[attr-defined]
        geos_error = abs(union.area - reference) / reference  # type: ignore[attr-defined]
        per = our_cpu / (n * math.log(n)) * 1e6
        print(
            f"| {n:,} | {ours:.3f} | {theirs:.3f} | {ours / theirs:.2f} "
            f"| {our_cpu:.3f} | {their_cpu:.3f} | {our_cpu / their_cpu:.2f} | {error:.1e} "
            f"| {geos_error:.1e} | {per:.2f} |"
        )


if __name__ == "__main__":
    main()
