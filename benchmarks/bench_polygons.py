"""One polygon of many reflex corners: triangulated and certified simple by
shadowgeo, next to manifold3d, GEOS and Clipper2.

Run from the repository root::

    python benchmarks/bench_polygons.py            # writes its REPORT.md section
    python benchmarks/bench_polygons.py --quick    # small polygons, print only

Two families whose every sweep line crosses many edges, the inputs on
which ear clipping and scanline sweeps take time that grows with the
square of the corners:

* **star**: ``n`` corners at even angles, radii 1 and 0.5 by turns
  (star-shaped round the mean of its corners);
* **comb**: a spine and ``n / 4`` teeth, their feet in line (not
  star-shaped).

Per polygon, in the same process, the median of ``--repeat`` calls (a
method past ``--cap`` seconds once is not timed at the next size):

* shadowgeo's own triangulation (``plane2d.star_triangles``, the
  star's one-pass ears, else the sweep of ``shadowgeo.sweep``), which the
  X3D reader and the shadows' triangulation take from 4,096 corners on;
* ``manifold3d.triangulate`` (ear clipping), which the reader used before;
* ``shapely.constrained_delaunay_triangles`` (GEOS);
* shadowgeo's certificate that the outline is simple (star-shaped, else
  the sweep), which ``plane2d.whole_loop`` takes from 4,096 corners on
  to spare the shadow the Clipper2 union (``CrossSection``) beside it.

Every triangulation is checked: ``n - 2`` triangles whose areas add up to
the polygon's (the shoelace area), each counter-clockwise.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np
import shapely
from manifold3d import CrossSection, FillRule, triangulate

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from shadowgeo import plane2d  # noqa: E402
from shadowgeo.orientation import MAX_COORDINATE  # noqa: E402
from shadowgeo.sweep import simple_triangles  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import write_section  # noqa: E402

TITLE = "## One polygon of many reflex corners"


def star(n: int) -> np.ndarray:
    k = np.arange(n)
    radius = np.where(k % 2 == 0, 1.0, 0.5)
    angle = 2 * np.pi * k / n
    return np.column_stack([radius * np.cos(angle), radius * np.sin(angle)])


def comb(n: int) -> np.ndarray:
    teeth = max(n // 4, 1)
    xs = np.linspace(-3.9, 3.9, 2 * teeth)
    corners = []
    for x0, x1 in zip(xs[0::2], xs[1::2], strict=True):
        corners += [(x0, 0.5), (x0, 3.0), (x1, 3.0), (x1, 0.5)]
    return np.array([(4.0, 0.0), (4.0, 0.5), *corners[::-1], (-4.0, 0.5), (-4.0, 0.0)])


def checked(loop: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """``faces`` tile ``loop``: n - 2 counter-clockwise triangles whose
    areas add up to the loop's."""
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    a, b, c = loop[faces[:, 0]], loop[faces[:, 1]], loop[faces[:, 2]]
    cross = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0]
    x, y = loop[:, 0], loop[:, 1]
    area = np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
    assert len(faces) == len(loop) - 2, "not n - 2 triangles"
    assert np.all(cross > 0), "a triangle turned over"
    assert abs(cross.sum() - area) <= 1e-9 * abs(area), "the areas do not add up"
    return faces


def ours(loop: np.ndarray) -> np.ndarray:
    """shadowgeo's own triangulation of the loop (the reader takes it from
    ``plane2d.predicates._SPIKED_CORNERS`` corners on): the star's one-pass ears,
    else the sweep."""
    faces = plane2d.star_triangles(loop)
    if faces is None:
        faces = simple_triangles(loop)[1]
    assert faces is not None, "not triangulated"
    return checked(loop, faces)


def manifold(loop: np.ndarray) -> np.ndarray:
    return checked(loop, triangulate([loop]))


def geos(loop: np.ndarray) -> object:
    triangles = shapely.constrained_delaunay_triangles(shapely.Polygon(loop))
    assert shapely.get_num_geometries(triangles) == len(loop) - 2
    return triangles


def certificate(loop: np.ndarray) -> bool:
    """shadowgeo's certificate that the loop is simple (``whole_loop``
    takes it from ``plane2d.predicates._SPIKED_CORNERS`` corners on): star-shaped
    round its corners' mean, else the sweep."""
    local = loop * (MAX_COORDINATE / float(np.abs(loop).max()))
    starts, lengths = np.zeros(1, dtype=np.int64), np.array([len(local)])
    certain = bool(plane2d.star_shaped_flat(local, starts, lengths)[0])
    certain = certain or simple_triangles(local, triangles=False)[0]
    assert certain, "not certified"
    return certain


def clipper(loop: np.ndarray) -> object:
    local = loop * (MAX_COORDINATE / float(np.abs(loop).max()))
    return CrossSection([local], FillRule.Positive)


METHODS = {
    "shadowgeo triangulation": ours,
    "manifold3d ear clipping": manifold,
    "GEOS constrained Delaunay": geos,
    "shadowgeo certificate (no union)": certificate,
    "Clipper2 union": clipper,
}


def median_seconds(function, loop: np.ndarray, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        function(loop)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def measure(sizes: list[int], repeat: int, cap: float) -> list[dict]:
    rows = []
    for family, make in (("star", star), ("comb", comb)):
        slow: set[str] = set()
        for n in sizes:
            loop = make(n)
            row = {"polygon": family, "corners": len(loop)}
            for name, method in METHODS.items():
                if name in slow:
                    row[name] = None
                    continue
                seconds = median_seconds(method, loop, 1 if n == sizes[-1] else repeat)
                row[name] = seconds
                if seconds > cap:
                    slow.add(name)
            rows.append(row)
            print(family, len(loop), {k: v for k, v in row.items() if k in METHODS}, flush=True)
    return rows


def table(rows: list[dict]) -> str:
    names = list(METHODS)
    head = "| polygon | corners | " + " | ".join(f"{name} (s)" for name in names)
    head += " | manifold3d / shadowgeo | Clipper2 / certificate |"
    lines = [head, "|---|---:|" + "---:|" * (len(names) + 2)]
    for row in rows:
        cells = [f"{row[name]:.4f}" if row[name] is not None else "—" for name in names]

        def ratio(top: str, bottom: str, row: dict = row) -> str:
            if row[top] is None or row[bottom] is None:
                return "—"
            return f"{row[top] / row[bottom]:.1f}"

        cells += [
            ratio("manifold3d ear clipping", "shadowgeo triangulation"),
            ratio("Clipper2 union", "shadowgeo certificate (no union)"),
        ]
        lines.append(f"| {row['polygon']} | {row['corners']:,} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def section(rows: list[dict], command: str, cap: float) -> str:
    return f"""{TITLE}

`{command}` (Python {platform.python_version()}, numpy {np.__version__}, shapely
{shapely.__version__}, GEOS {".".join(map(str, shapely.geos_version))}; seconds of wall time,
the median of the calls in one process; a method past {cap:g} s at one size is not timed at the
next, "—"). A star of radii 1 and 0.5 by turns and a comb whose teeth's feet are in line: one
X3D polygon each, the inputs on which ear clipping and scanline sweeps do work that grows with
the square of the corners. *shadowgeo triangulation*: the star's one-pass ears
(`plane2d.star_triangles`), the comb's sweep (`shadowgeo/sweep.py`); *certificate*: that the
outline is simple, by the same two, which spares the shadow the Clipper2 union beside it. The
reader, the shadows' triangulation and `plane2d.whole_loop` take them from 4,096 corners on
(`plane2d._SPIKED_CORNERS`), where the table shows them faster than manifold3d and Clipper2;
below, those two. Every triangulation is checked (n - 2 counter-clockwise triangles whose areas
add up).

{table(rows)}
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small polygons; print only")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--cap", type=float, default=20.0, help="seconds past which to stop")
    args = parser.parse_args()
    sizes = [256, 1024] if args.quick else [1000, 4000, 16000, 48000]
    rows = measure(sizes, args.repeat, args.cap)
    command = "python benchmarks/bench_polygons.py" + (" --quick" if args.quick else "")
    text = section(rows, command, args.cap)
    print(text)
    if not args.quick:
        write_section(TITLE, text)


if __name__ == "__main__":
    main()
