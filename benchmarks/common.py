"""What the benchmarks share: the timing rule and the test meshes.

Every benchmark times a method as the median of ``repeat`` calls in the same
process, and uses the same meshes, so figures from different scripts compare.
"""

from __future__ import annotations

import platform
import statistics
import time
from pathlib import Path

import numpy as np
import trimesh

REPORT = Path(__file__).resolve().parent / "REPORT.md"


def write_section(title: str, text: str) -> None:
    """Put ``text`` in REPORT.md in place of the section headed ``title``
    (up to the next ``## `` heading), or at the end."""
    report = REPORT.read_text()
    start = report.find(title)
    if start < 0:
        report = report.rstrip("\n") + "\n\n" + text
    else:
        end = report.find("\n## ", start + len(title))
        report = report[:start] + text + ("" if end < 0 else report[end:])
    REPORT.write_text(report)


def median_time(function, repeat: int = 3) -> tuple[float, object]:
    """Median seconds of ``repeat`` calls of ``function()``, and its last result."""
    times, result = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def meshes(quick: bool) -> dict[str, trimesh.Trimesh]:
    """An icosphere (convex), a bumpy sphere and a tilted torus (non-convex):
    81,920 faces each, or about 1,300 with ``quick``."""
    subdivisions = 3 if quick else 6
    sphere = trimesh.creation.icosphere(subdivisions=subdivisions)
    bumpy = trimesh.creation.icosphere(subdivisions=subdivisions)
    direction = bumpy.vertices / np.linalg.norm(bumpy.vertices, axis=1, keepdims=True)
    wave = 1 + 0.15 * np.sin(5 * direction[:, 0]) * np.sin(4 * direction[:, 1] + 1) * np.cos(
        6 * direction[:, 2]
    )
    bumpy.vertices = direction * wave[:, None]
    sections = (40, 16) if quick else (320, 128)
    torus = trimesh.creation.torus(
        major_radius=1.0,
        minor_radius=0.3,
        major_sections=sections[0],
        minor_sections=sections[1],
    )
    torus.apply_transform(trimesh.transformations.rotation_matrix(0.5, [1, 0, 0]))
    return {"icosphere": sphere, "bumpy sphere (non-convex)": bumpy, "torus (non-convex)": torus}


def cpu_model() -> str:
    """The processor's model name (Linux's /proc/cpuinfo), which picks
    OpenBLAS's kernels; else what ``platform`` knows."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()
