"""Where numba's walks repay their import: the figures behind
``shadowgeo.compiled.WALK_ITEMS``.

Run from the repository root (prints only)::

    python benchmarks/bench_compiled.py           # walks of 2**12 .. 2**20 items
    python benchmarks/bench_compiled.py --large   # .. 2**22 (about a minute)

It times, in a fresh process, ``import shadowgeo.kernels`` (numba and the
cached machine code; the first run after installing also compiles them),
then an outline's two walks -- the successor matching of
``shadowgeo.silhouette`` and :func:`shadowgeo.topology.cycle_walk` -- over
random outlines of k edges in loops of 64, the numpy way and the compiled way
(``compiled_loops("never")`` / ``("always")``; the arrays are checked equal).
A job of k items is worth the import where the saving in the last column
exceeds the import time.
"""

from __future__ import annotations

import argparse
import importlib
import math
import subprocess
import sys
import time

import numpy as np

# shadowgeo itself first: the kernels' own cost is what a job pays.
IMPORT = (
    "import time, shadowgeo; t = time.perf_counter(); import shadowgeo.kernels; "
    "print(time.perf_counter() - t)"
)


def outline(count: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """(starts, ends) of ``count`` edges in loops of 64 over shuffled vertices."""
    vertices = rng.permutation(count)
    ends = np.empty(count, dtype=np.int64)
    for first in range(0, count, 64):
        loop = vertices[first : first + 64]
        ends[loop] = np.roll(loop, -1)
    return np.arange(count, dtype=np.int64), ends


def walk(starts: np.ndarray, ends: np.ndarray, mode: str) -> tuple[float, np.ndarray]:
    from shadowgeo.compiled import compiled_loops
    from shadowgeo.topology import cycle_walk

    silhouette = importlib.import_module("shadowgeo.silhouette")
    with compiled_loops(mode):  # type: ignore[arg-type]
        began = time.perf_counter()
        successor = silhouette._successors(starts, ends)
        order, _ = cycle_walk(successor)
        return time.perf_counter() - began, order


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--large", action="store_true", help="up to 2**22 items")
    parser.add_argument("--repeat", type=int, default=1, help="runs per size; the least time")
    args = parser.parse_args()
    seconds = subprocess.run(
        [sys.executable, "-c", IMPORT], capture_output=True, text=True, check=True
    ).stdout
    print(f"import shadowgeo.kernels after shadowgeo, fresh process: {float(seconds):.2f} s")
    rng = np.random.default_rng(0)
    walk(*outline(64, rng), "always")  # machine code loaded
    print(f"{'items':>10} {'numpy s':>9} {'compiled s':>11} {'saved s':>8}")
    for power in range(12, 23 if args.large else 21, 2):
        starts, ends = outline(1 << power, rng)
        plain, fast = math.inf, math.inf
        for _ in range(args.repeat):  # (a walk of a few ms varies tenfold run to run)
            seconds, expected = walk(starts, ends, "never")
            plain = min(plain, seconds)
            seconds, order = walk(starts, ends, "always")
            fast = min(fast, seconds)
            assert np.array_equal(order, expected)
        print(f"{1 << power:>10,} {plain:>9.3f} {fast:>11.3f} {plain - fast:>8.3f}")


if __name__ == "__main__":
    main()
