"""Many lights on one mesh: the batch call against a loop of single calls.

Run from the repository root::

    python benchmarks/bench_lights.py                 # 1,000 lights, 20,480 faces
    python benchmarks/bench_lights.py --lights 100    # a shorter run

The caster is an icosphere of 20,480 faces, dented so it is not convex, a metre
above the ground; the lights are random point lights above it and random sun
directions. ``project_shadow(caster, lights, plane)`` returns one shadow per
light; the table gives milliseconds per light for the batch call and for a
loop of single calls (the caster's topology cached in both), and checks that
both give the same areas bit for bit.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lights", type=int, default=1000)
    args = parser.parse_args()
    mesh = trimesh.creation.icosphere(subdivisions=5)
    mesh.vertices[mesh.vertices[:, 1] > 0.8] *= [1, 0.7, 1]
    mesh.apply_translation([0, 2, 0])
    caster = as_caster(mesh)
    ground = Plane([0, 1, 0], 0)
    project_shadow(caster, DirectionalLight([0, -1, 0]), ground)  # topology cached
    print(f"{len(mesh.faces):,} faces, {args.lights:,} lights of each kind")
    print("| lights | batch ms / light | loop ms / light | same areas |")
    print("|---|---|---|---|")
    for kind, group in lights(args.lights).items():
        start = time.perf_counter()
        batch = project_shadow(caster, group, ground)
        middle = time.perf_counter()
        loop = [project_shadow(caster, light, ground) for light in group]
        end = time.perf_counter()
        same = all(a.area == b.area for a, b in zip(batch, loop, strict=True))
        per_batch = (middle - start) / len(group) * 1e3
        per_loop = (end - middle) / len(group) * 1e3
        print(f"| {kind} | {per_batch:.2f} | {per_loop:.2f} | {same} |")


if __name__ == "__main__":
    main()
