"""The fuzz findings' worst inputs (issue 12), timed: each must stay cheap.

Run from the repository root::

    python benchmarks/bench_robustness.py

Before the fixes: 300,000 copies of one triangle ran past 90 s (the 2-D
union was quadratic in the copies), four Spheres of radius 1e-320 took 95 s
and 1.6 GB (the tessellation search never converged), and a radius far
larger than the scene raised a Clipper2 range error. Times are medians of
three runs, in this process (no import cost).
"""

from __future__ import annotations

import statistics
import time

import numpy as np
import trimesh

import shadowgeo as sg
from shadowgeo.scene import primitives


def median_time(call, runs: int = 3) -> float:
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> None:
    floor = sg.Plane([0, 1, 0], 0)
    triangle = np.array([[0, 2, 0], [1, 2, 0], [0, 2, 1]], dtype=float)
    light = sg.PointLight([1, 8, 1])
    box = trimesh.creation.box()
    box.apply_translation([0, 2, 0])
    cases = {
        "1 triangle": lambda: sg.project_shadow((triangle, [[0, 1, 2]]), light, floor),
        "300,000 copies of it": lambda: sg.project_shadow(
            (triangle, np.tile([[0, 1, 2]], (300_000, 1))), light, floor
        ),
        "Sphere r = 1, chord 1e-3": lambda: primitives.sphere(1.0, chord=1e-3),
        "Sphere r = 1e-70, chord 1e-73": lambda: primitives.sphere(1e-70, chord=1e-73),
        "box, light radius inf": lambda: sg.project_shadow(box, sg.PointLight([0, 5, 0]), floor),
        "box, light radius 1e70": lambda: sg.project_shadow(
            box, sg.PointLight([0, 5, 0], radius=1e70), floor
        ),
    }
    print(f"{'case':<34} {'median s':>10}")
    for name, call in cases.items():
        print(f"{name:<34} {median_time(call):>10.4f}")


if __name__ == "__main__":
    main()
