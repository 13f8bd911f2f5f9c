"""Many lights on one mesh: the batch call against a loop of single calls.

Run from the repository root::

    python benchmarks/bench_lights.py                 # 1,000 lights, 20,480 faces
    python benchmarks/bench_lights.py --lights 100    # a shorter run
    python benchmarks/bench_lights.py --phases        # where a batch's time goes

The caster is an icosphere of 20,480 faces, dented so it is not convex, a metre
above the ground; the lights are random point lights above it and random sun
directions. ``project_shadow(caster, lights, plane)`` returns one shadow per
light; the table gives milliseconds per light for the batch call (wall clock
and this process's CPU time: on a shared machine the wall clock also counts
time spent waiting for a core) and for a loop of single calls (the caster's
topology cached in both), and checks that both give the same areas bit for
bit. The first batch call is timed on its own (it also pays for memory the
process touches for the first time), then the median of ``--repeat`` more.
``--phases`` times the steps of the batch call (CPU time, each step's own
functions wrapped with a timer; what the steps leave of the whole is Python
between them: the loop over lights, the general path's few lights).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import trimesh

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from shadowgeo import DirectionalLight, Plane, PointLight, as_caster, project_shadow  # noqa: E402


def lights(count: int, seed: int = 3) -> dict[str, list[PointLight] | list[DirectionalLight]]:
    rng = np.random.default_rng(seed)
    above = np.column_stack(
        [rng.uniform(-4, 4, count), rng.uniform(5, 12, count), rng.uniform(-4, 4, count)]
    )
    suns = np.column_stack(
        [rng.uniform(-1, 1, count), -rng.uniform(0.3, 1, count), rng.uniform(-1, 1, count)]
    )
    return {
        "point": [PointLight(p) for p in above],
        "directional": [DirectionalLight(d) for d in suns],
    }


# (module, attribute, label) of the steps --phases times, in call order.
PHASES = [
    ("shadowgeo.projection", "light_frames", "frames: tolerance, plane frame, window (arrays)"),
    ("shadowgeo.projection", "settle", "frame verdicts (lights that need one)"),
    ("shadowgeo.batchlights", "front_rows", "front faces (one matrix-vector product each)"),
    ("shadowgeo.batchlights", "silhouette_outlines", "silhouettes, all lights together"),
    ("shadowgeo.batchlights", "project_outlines", "silhouettes projected to 2-D, together"),
    ("shadowgeo.batchlights", "whole_outlines", "one loop the whole: certificate"),
    ("shadowgeo.plane2d", "unite", "2-D union (Clipper2, per light)"),
    ("shadowgeo.batchlights", "_array_result", "result: area, polygons (per light)"),
]


def timed_phases(
    run: Callable[[], Any], phases: list[tuple[str, str, str]]
) -> tuple[float, Counter[str]]:
    """CPU seconds of ``run()`` and of each step of ``phases`` ((module,
    attribute, label) triples) within it."""
    import importlib

    spent: Counter[str] = Counter()
    restore = []
    for module_name, attribute, label in phases:
        owner: Any = importlib.import_module(module_name)
        *path, name = attribute.split(".")
        for part in path:
            owner = getattr(owner, part)
        original = getattr(owner, name)

        def wrapper(*args: Any, _f: Any = original, _label: str = label, **kw: Any) -> Any:
            start = time.process_time()
            try:
                return _f(*args, **kw)
            finally:
                spent[_label] += time.process_time() - start

        setattr(owner, name, wrapper)
        restore.append((owner, name, original))
    try:
        start = time.process_time()
        run()
        total = time.process_time() - start
    finally:
        for owner, name, original in restore:
            setattr(owner, name, original)
    return total, spent


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lights", type=int, default=1000)
    parser.add_argument("--phases", action="store_true", help="time the batch call's steps")
    parser.add_argument(
        "--repeat", type=int, default=7, help="batch calls timed after the first (default 7)"
    )
    args = parser.parse_args()
    mesh = trimesh.creation.icosphere(subdivisions=5)
    mesh.vertices[mesh.vertices[:, 1] > 0.8] *= [1, 0.7, 1]
    mesh.apply_translation([0, 2, 0])
    caster = as_caster(mesh)
    ground = Plane([0, 1, 0], 0)
    project_shadow(caster, DirectionalLight([0, -1, 0]), ground)  # topology cached
    print(f"{len(mesh.faces):,} faces, {args.lights:,} lights of each kind")
    groups = lights(args.lights)
    if args.phases:
        print("| step | point: CPU ms / light | directional: CPU ms / light |")
        print("|---|---|---|")
        results = {
            kind: timed_phases(lambda group=group: project_shadow(caster, group, ground), PHASES)
            for kind, group in groups.items()
        }
        per = {kind: 1e3 / len(groups[kind]) for kind in groups}
        cells = " | ".join(f"{results[k][0] * per[k]:.3f}" for k in groups)
        print(f"| whole batch call | {cells} |")
        for _, _, label in PHASES:
            cells = " | ".join(f"{results[k][1][label] * per[k]:.3f}" for k in groups)
            print(f"| {label} | {cells} |")
        return
    print(
        "| lights | batch CPU ms / light, first call | batch CPU ms / light, median of the next "
        f"{args.repeat} | batch ms / light (wall), median | loop ms / light | same areas |"
    )
    print("|---|---|---|---|---|---|")
    for kind, group in groups.items():
        cpu, wall = [], []
        for _ in range(1 + args.repeat):
            start, started = time.perf_counter(), time.process_time()
            batch = project_shadow(caster, group, ground)
            cpu.append((time.process_time() - started) / len(group) * 1e3)
            wall.append((time.perf_counter() - start) / len(group) * 1e3)
        middle = time.perf_counter()
        loop = [project_shadow(caster, light, ground) for light in group]
        per_loop = (time.perf_counter() - middle) / len(group) * 1e3
        same = all(a.area == b.area for a, b in zip(batch, loop, strict=True))
        print(
            f"| {kind} | {cpu[0]:.2f} | {statistics.median(cpu[1:]):.2f} | "
            f"{statistics.median(wall[1:]):.2f} | {per_loop:.2f} | {same} |"
        )


if __name__ == "__main__":
    main()
