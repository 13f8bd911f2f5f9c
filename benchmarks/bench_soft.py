"""Soft shadows: shadowgeo's hidden fraction against a converged reference
and a shadow map's percentage-closer filtering, error against time.

Run from the repository root::

    python benchmarks/bench_soft.py              # writes its REPORT.md section and plot
    python benchmarks/bench_soft.py --quick      # few points, small maps, print only
    python benchmarks/bench_soft.py --no-write   # the full run, print only

A cube and an icosphere under a rectangle light and under the sun's disc
(0.53 degrees, and 5 degrees so the penumbra shows at the scene's scale).
Receiver points are drawn uniformly in the penumbra's neighbourhood: a band
round the hard shadow from the light's centre, wide enough to hold the whole
penumbra (every vertex's image moves less than the band's half-width as the
light point moves over the light). The reference (``softref.py``, which does
not import shadowgeo) is the share of ``side x side`` stratified random light
samples, fresh for each point, blocked from it, twice with independent
seeds: their mean is the reference and their difference states its noise.
"""

from __future__ import annotations

import argparse
import datetime
import math
import platform
import subprocess
import sys
import time
from collections import defaultdict
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numpy as np
import shapely
import trimesh

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

import shadowmap  # noqa: E402
import softref  # noqa: E402
from common import cpu_model, median_time, write_section  # noqa: E402

import shadowgeo as sg  # noqa: E402
from shadowgeo.lights import RectLight  # noqa: E402

TITLE = "## Soft shadows"
PLOT = HERE.parent / "docs" / "images" / "soft_shadows.png"
SWEEP_PLOT = HERE.parent / "docs" / "images" / "soft_levels.png"
# The levels swept, on the cube and icosphere under the rectangle and the 0.53 degree sun.
SWEEP_LEVELS = (2, 4, 8, 16, 32, 64)
# A sweep call taking this long (seconds) is timed once, not three times.
SWEEP_ONCE = 1.0
GROUND = sg.Plane([0, 1, 0], 0.0)
SUN_DIRECTION = np.array([0.3, -1.0, 0.2]) / np.linalg.norm([0.3, -1.0, 0.2])


@dataclass(frozen=True)
class Scene:
    """A caster under a light, as shadowgeo and the reference each take it."""

    caster_name: str
    light_name: str
    caster: trimesh.Trimesh
    light: object  # shadowgeo's
    reference: softref.Rect | softref.Sun


def casters() -> dict[str, trimesh.Trimesh]:
    cube = trimesh.creation.box([2, 2, 2])
    cube.apply_translation([0, 2, 0])
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=1.2)
    sphere.apply_translation([0, 2.2, 0])
    return {"cube": cube, "icosphere (320 faces)": sphere}


def lights() -> dict[str, tuple[object, softref.Rect | softref.Sun]]:
    centre = np.array([0.4, 6.0, 0.2])
    rect = RectLight(centre, [0, -1, 0], 1.5, 1.0, up=[0, 0, 1])
    across, up = rect.axes
    assert np.allclose(across, [1, 0, 0]) and np.allclose(up, [0, 0, 1])
    found = {
        "rect 1.5 x 1 at height 6": (
            rect,
            softref.Rect(centre, np.array([0, -1.0, 0]), across, up, 1.5, 1.0),
        )
    }
    for degrees in (0.53, 5.0):
        angle = math.radians(degrees)
        found[f"sun disc {degrees:g} deg"] = (
            sg.DirectionalLight(SUN_DIRECTION, angle=angle),
            softref.Sun(SUN_DIRECTION, angle),
        )
    return found


def swept(scene: Scene) -> bool:
    """Whether the levels are swept for ``scene``: the rectangle and the real
    sun (the 5 degree sun only shows the penumbra at the scene's scale)."""
    return not scene.light_name.startswith("sun disc 5")


def scenes() -> list[Scene]:
    return [
        Scene(caster_name, light_name, caster, light, reference)
        for caster_name, caster in casters().items()
        for light_name, (light, reference) in lights().items()
    ]


# -- where the penumbra is --------------------------------------------------------------------


def ground_images(reference, vertices: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """(s, v, 2) the vertices' images on the ground (x, z) from each light sample."""
    positions = softref.light_positions(reference, offsets)
    if isinstance(reference, softref.Rect):
        t = positions[:, None, 1] / (positions[:, None, 1] - vertices[None, :, 1])
        hits = positions[:, None, :] + t[..., None] * (vertices[None] - positions[:, None, :])
    else:  # along the ray away from the sun
        t = vertices[None, :, 1] / positions[:, None, 1]
        hits = vertices[None] - t[..., None] * positions[:, None, :]
    return hits[..., [0, 2]]


def neighbourhood(reference, vertices: np.ndarray):
    """The hard shadow from the light's centre (convex caster: the hull of its
    vertices' images) and the band round its outline that holds the penumbra."""
    rim = (
        np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
        * [reference.width, reference.height]
        if isinstance(reference, softref.Rect)
        else math.tan(reference.angle / 2)
        * np.column_stack(
            [np.cos(np.linspace(0, 2 * math.pi, 256)), np.sin(np.linspace(0, 2 * math.pi, 256))]
        )
        / math.cos(math.pi / 256)
    )
    centre_images = ground_images(reference, vertices, np.zeros((1, 2)))[0]
    rim_images = ground_images(reference, vertices, rim)
    reach = float(np.linalg.norm(rim_images - centre_images[None], axis=2).max())
    hard = shapely.MultiPoint(centre_images).convex_hull
    return hard, hard.boundary.buffer(1.05 * reach + 1e-9, quad_segs=32)


def swept_regions(reference, vertices: np.ndarray):
    """The umbra and penumbra by exact hard shadows (shapely): the common part
    and the union of the shadows (hulls of the vertices' images) from a dense
    set of the light's points: a 41 x 41 grid over the rectangle, edges
    included, or 17 rings of 256 points over the disc, its rim included. The
    umbra of a convex caster under a convex light is the common part of its
    rim's shadows, so exact under the rectangle (and larger by about 1e-4 of
    the disc's radius under the disc); the penumbra is a lower bound, short by
    what the grid's gaps leave out."""
    if isinstance(reference, softref.Rect):
        steps = np.linspace(-0.5, 0.5, 41)
        grid = np.stack(np.meshgrid(steps, steps), axis=-1).reshape(-1, 2)
        offsets = grid * [reference.width, reference.height]
    else:
        turn = np.linspace(0, 2 * math.pi, 256, endpoint=False)
        ring = np.column_stack([np.cos(turn), np.sin(turn)])
        radii = math.tan(reference.angle / 2) * np.linspace(0, 1, 17)
        offsets = np.concatenate([radius * ring for radius in radii])
    shadows = shapely.convex_hull(shapely.multipoints(ground_images(reference, vertices, offsets)))
    return shapely.intersection_all(shadows), shapely.union_all(shadows)


def band_points(band, count: int, rng: np.random.Generator) -> np.ndarray:
    """(count, 3) points on the ground drawn uniformly in ``band``."""
    minx, minz, maxx, maxz = band.bounds
    shapely.prepare(band)
    found = []
    while sum(len(f) for f in found) < count:
        xz = rng.uniform([minx, minz], [maxx, maxz], (4 * count, 2))
        found.append(xz[shapely.contains_xy(band, xz[:, 0], xz[:, 1])])
    xz = np.concatenate(found)[:count]
    return np.column_stack([xz[:, 0], np.zeros(count), xz[:, 1]])


# -- methods ----------------------------------------------------------------------------------


def level_values(soft, points: np.ndarray) -> np.ndarray:
    """(p,) the fraction of the level each point lies in (0 in none)."""
    flat = GROUND.to_2d(points)
    value = np.zeros(len(points))
    for fraction, shadow in soft.levels:
        region = shadow.to_shapely()
        value[shapely.contains_xy(region, flat[:, 0], flat[:, 1])] = fraction
    return value


def map_camera(scene: Scene, band, resolution: int):
    """The light's camera over the band: perspective from a rectangle's
    centre along its normal, orthographic along the sun's direction."""
    minx, minz, maxx, maxz = band.bounds
    corners = np.array([[x, 0.0, z] for x in (minx, maxx) for z in (minz, maxz)])
    reference = scene.reference
    if isinstance(reference, softref.Rect):
        target = reference.centre + reference.normal * reference.centre[1]
        camera = shadowmap.LightCamera(reference.centre, target, 1.0, resolution)
        rel = corners - target
        half = 1.05 * np.abs(np.column_stack([rel @ camera.right, rel @ camera.up])).max()
        return shadowmap.LightCamera(reference.centre, target, half, resolution)
    target = np.array([(minx + maxx) / 2, 0.0, (minz + maxz) / 2])
    camera = shadowmap.OrthographicCamera(reference.direction, target, 1.0, resolution)
    rel = corners - target
    half = 1.05 * np.abs(np.column_stack([rel @ camera.right, rel @ camera.up])).max()
    return shadowmap.OrthographicCamera(reference.direction, target, half, resolution)


def map_taps(scene: Scene, camera, offsets: np.ndarray) -> np.ndarray:
    """(k, 2) the light samples as pixel shifts per unit of PCF's spread
    (``softref.pcf_fraction``)."""
    reference = scene.reference
    if isinstance(reference, softref.Rect):
        world = offsets[:, :1] * reference.across + offsets[:, 1:] * reference.up
        per_pixel = camera.resolution / (2 * camera.half)
    else:
        first, second = softref.frame(-reference.direction)
        world = offsets[:, :1] * first + offsets[:, 1:] * second
        per_pixel = camera.resolution / (2 * camera.half)
    return per_pixel * np.column_stack([world @ camera.right, world @ camera.up])


def sweep_samples(levels: int) -> int:
    """The samples for ``levels`` levels: the default 64, or four a level
    when more (the levels' bands are 1 / levels wide, so the samples' own
    error must stay under half of that for the bands to mean anything)."""
    return max(sg.soft.DEFAULT_SAMPLES, 4 * levels)


def umbra_penumbra_values(soft, points: np.ndarray) -> np.ndarray:
    """(p,) 1 in the umbra, 1/2 in the rest of the penumbra, 0 outside: the
    hidden fraction the umbra and penumbra alone can give."""
    flat = GROUND.to_2d(points)
    value = np.zeros(len(points))
    for share, shadow in ((0.5, soft.penumbra), (1.0, soft.umbra)):
        region = shadow.to_shapely()
        value[shapely.contains_xy(region, flat[:, 0], flat[:, 1])] = share
    return value


def sweep(scene: Scene, points: np.ndarray, reference: np.ndarray, levels_swept, repeat: int):
    """Rows (levels, samples, seconds, max error, mean error) of
    ``soft_shadow`` at each of ``levels_swept`` (samples by
    :func:`sweep_samples`), first the umbra/penumbra row (levels 0). Times:
    the median of ``repeat`` calls, or one call when it takes
    :data:`SWEEP_ONCE` or more."""
    rows = []
    for levels in levels_swept:
        count = sweep_samples(levels)
        call = partial(
            sg.soft_shadow, scene.caster, scene.light, GROUND, levels=levels, samples=count
        )
        start = time.perf_counter()
        soft = call()
        seconds = time.perf_counter() - start
        if seconds < SWEEP_ONCE and repeat > 1:  # the slow calls are timed once
            seconds, soft = median_time(call, repeat)
        if not rows:
            estimate = umbra_penumbra_values(soft, points)
            rows.append((0, count, seconds, *errors(estimate, reference)))
        rows.append((levels, count, seconds, *errors(level_values(soft, points), reference)))
    return rows


def errors(estimate: np.ndarray, reference: np.ndarray) -> tuple[float, float]:
    """The largest error over all points, and the mean over the true penumbra."""
    error = np.abs(estimate - reference)
    penumbra = (reference > 0) & (reference < 1)
    return float(error.max()), float(error[penumbra].mean())


def measure(
    scene: Scene,
    n_points: int,
    side: int,
    resolutions,
    samples,
    taps: int,
    seed: int,
    levels_swept=(),
    sweep_repeat: int = 1,
):
    """Rows (method, parameters, seconds, max error, mean error) and the
    areas and reference statistics of one scene; with ``levels_swept``, the
    :func:`sweep` rows over the same points in ``stats["sweep"]``."""
    rng = np.random.default_rng(seed)
    vertices = np.asarray(scene.caster.vertices, dtype=float)
    hard, band = neighbourhood(scene.reference, vertices)
    points = band_points(band, n_points, rng)

    start = time.perf_counter()
    first = softref.hidden_fraction(scene.reference, vertices, points, side, rng)
    second = softref.hidden_fraction(scene.reference, vertices, points, side, rng)
    reference_seconds = time.perf_counter() - start
    reference = 0.5 * (first + second)
    # The mean of two draws errs by half their difference's spread.
    noise = np.abs(first - second) / 2
    check = points[rng.choice(n_points, min(200, n_points), replace=False)]
    check_offsets = softref.light_points(scene.reference, 16, rng)
    disagree = int(
        np.sum(
            softref.cone_blocked(scene.reference, vertices, check, check_offsets)
            != softref.ray_fraction(scene.reference, scene.caster.triangles, check, check_offsets)
        )
    )

    rows = []

    def add(method, parameters, seconds, estimate):
        rows.append((method, parameters, seconds, *errors(estimate, reference)))

    softs = {}
    for count in samples:
        seconds, soft = median_time(
            lambda c=count: sg.soft_shadow(scene.caster, scene.light, GROUND, levels=8, samples=c)
        )
        softs[count] = soft
        add(
            "shadowgeo levels",
            f"{len(soft.samples)} samples, 8 levels",
            seconds,
            level_values(soft, points),
        )
        lookup, fraction = median_time(lambda s=soft: s.fraction(points))
        add("shadowgeo fraction", f"{len(soft.samples)} samples", seconds + lookup, fraction)

    light_offsets = softref.light_points(scene.reference, taps, np.random.default_rng(seed + 1))
    for resolution in resolutions:
        camera = map_camera(scene, band, resolution)
        start = time.perf_counter()
        buffer = shadowmap.depth_map(camera, np.asarray(scene.caster.triangles))
        render = time.perf_counter() - start
        per_tap = map_taps(scene, camera, light_offsets)
        _, centre_depth = camera.view(scene.caster.centroid[None])
        receiver_depth = float(np.median(camera.view(points)[1]))
        nearest = float(camera.view(vertices)[1].min())
        spread = (
            (receiver_depth - nearest) / (receiver_depth * nearest)
            if isinstance(scene.reference, softref.Rect)
            else receiver_depth - nearest
        )
        lookup, pcf = median_time(
            lambda c=camera, b=buffer, t=per_tap, d=centre_depth[0]: softref.pcf_fraction(
                c, b, points, t, blocker_depth=d
            )
        )
        texel = 2 * camera.half / resolution * getattr(camera, "focal", 1.0)
        label = f"{resolution} px (texel {texel:.3f}), {taps}x{taps} taps"
        add("shadow map PCF", label, render + lookup, pcf)
        lookup, pcss = median_time(
            lambda c=camera, b=buffer, t=per_tap, s=per_tap * spread: softref.pcf_fraction(
                c, b, points, t, search=s
            )
        )
        add("shadow map PCSS", label, render + lookup, pcss)

    def area(hidden):
        inner = hard.difference(band).area
        share = hidden.mean()
        return inner + band.area * share, band.area * math.sqrt(share * (1 - share) / n_points)

    soft = softs[max(samples)]
    umbra, penumbra = swept_regions(scene.reference, vertices)
    stats = {
        "swept umbra": umbra.area,
        "swept penumbra": penumbra.area,
        "umbra": soft.umbra.area,
        "penumbra": soft.penumbra.area,
        "exact": soft.exact,
        "reference umbra": area((first == 1) & (second == 1)),
        "reference penumbra": area((first > 0) | (second > 0)),
        "noise max": float(noise.max()),
        "noise mean": float(noise[(reference > 0) & (reference < 1)].mean()),
        "reference seconds": reference_seconds,
        "ray check": (disagree, len(check) * len(check_offsets)),
        "penumbra points": int(np.sum((reference > 0) & (reference < 1))),
        "sweep": sweep(scene, points, reference, levels_swept, sweep_repeat),
    }
    return rows, stats


# -- the report -------------------------------------------------------------------------------


def table(results) -> str:
    lines = [
        "| scene | method | parameters | time (ms) | max error | mean error |",
        "|---|---|---|---:|---:|---:|",
    ]
    for scene, rows, _ in results:
        for method, parameters, seconds, worst, mean in rows:
            lines.append(
                f"| {scene.caster_name}, {scene.light_name} | {method} | {parameters} | "
                f"{seconds * 1e3:,.1f} | {worst:.3f} | {mean:.4f} |"
            )
    return "\n".join(lines)


def area_table(results) -> str:
    lines = [
        "| scene | umbra: shadowgeo | umbra: swept | umbra: sampled | penumbra: shadowgeo | "
        "penumbra: swept | penumbra: sampled | exact | reference noise: max, mean | ray check |",
        "|---|---:|---:|---:|---:|---:|---:|---|---|---|",
    ]
    for scene, _, stats in results:
        umbra, umbra_noise = stats["reference umbra"]
        penumbra, penumbra_noise = stats["reference penumbra"]
        wrong, total = stats["ray check"]
        lines.append(
            f"| {scene.caster_name}, {scene.light_name} | {stats['umbra']:.4f} | "
            f"{stats['swept umbra']:.4f} | {umbra:.3f} ± {umbra_noise:.3f} | "
            f"{stats['penumbra']:.4f} | {stats['swept penumbra']:.4f} | "
            f"{penumbra:.3f} ± {penumbra_noise:.3f} | {'yes' if stats['exact'] else 'no'} | "
            f"{stats['noise max']:.4f}, {stats['noise mean']:.5f} | {wrong} of {total:,} |"
        )
    return "\n".join(lines)


def sweep_label(levels: int) -> str:
    return "umbra / penumbra (1, 1/2, 0)" if levels == 0 else f"{levels} levels"


def map_rows(rows, finest: bool = True):
    """The scene's shadow-map rows: PCF and PCSS at the finest resolution,
    or all of them."""
    maps = [row for row in rows if row[0].startswith("shadow map")]
    if not finest or not maps:
        return maps
    last = maps[-1][1].split(" px")[0]
    return [row for row in maps if row[1].split(" px")[0] == last]


def sweep_table(results) -> str:
    lines = [
        "| scene | estimate | samples | time (ms) | max error | mean error |",
        "|---|---|---:|---:|---:|---:|",
    ]
    for scene, rows, stats in results:
        if not stats["sweep"]:
            continue
        name = f"{scene.caster_name}, {scene.light_name}"
        for levels, count, seconds, worst, mean in stats["sweep"]:
            lines.append(
                f"| {name} | {sweep_label(levels)} | {count} | {seconds * 1e3:,.1f} | "
                f"{worst:.3f} | {mean:.4f} |"
            )
        for method, parameters, seconds, worst, mean in map_rows(rows):
            label = f"{method[len('shadow map ') :]} {parameters.split(' (')[0]}"
            lines.append(
                f"| {name} | shadow map {label} | | {seconds * 1e3:,.1f} | {worst:.3f} | "
                f"{mean:.4f} |"
            )
    return "\n".join(lines)


MAP_STYLES = {"shadow map PCF": ("C3", "^", "--"), "shadow map PCSS": ("C1", "v", "-.")}


def sweep_column(top, bottom, scene: Scene, rows, sweep_rows) -> None:
    """One scene's sweep: error against levels on ``top`` (the finest maps'
    mean error as lines), against time on ``bottom`` (every map as points)."""
    levelled = [row for row in sweep_rows if row[0] > 0]
    levels = [row[0] for row in levelled]
    for ax, xs in ((top, levels), (bottom, [row[2] * 1e3 for row in levelled])):
        ax.plot(xs, [r[4] for r in levelled], "s-", color="C0", label="levels: mean")
        ax.plot(xs, [r[3] for r in levelled], "s:", color="C0", mfc="none", label="levels: max")
    top.plot(levels, [0.5 / n for n in levels], color="grey", lw=0.8, label="1 / (2 levels)")
    for method, _, seconds, worst, mean in map_rows(rows, finest=False):
        color, marker, _ = MAP_STYLES[method]
        bottom.plot(seconds * 1e3, mean, marker, color=color)
        bottom.plot(seconds * 1e3, worst, marker, color=color, mfc="none")
    for method, parameters, _, _, mean in map_rows(rows):
        color, marker, line = MAP_STYLES[method]
        px = parameters.split(" (")[0]
        top.axhline(mean, color=color, ls=line, lw=1, label=f"{method[11:]} {px}: mean")
        bottom.plot([], [], marker, color=color, label=f"{method[11:]}: mean (filled), max")
    top.set_xscale("log", base=2)
    top.set_xticks(levels, [str(n) for n in levels])
    top.set_xlabel("levels (samples: max(64, 4 x levels))")
    bottom.set_xscale("log")
    bottom.set_xlabel("time (ms)")
    for ax in (top, bottom):
        ax.set_yscale("log")
        ax.set_ylabel("hidden-fraction error")
        ax.grid(True, which="both", alpha=0.3)
    top.set_title(f"{scene.caster_name}, {scene.light_name}", fontsize=9)


def sweep_plot(results, path: Path) -> None:
    """Error against levels (top) and against time (bottom), one column a
    scene, the shadow maps as lines (top) and points (bottom)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    swept = [(scene, rows, stats) for scene, rows, stats in results if stats["sweep"]]
    figure, axes = plt.subplots(2, len(swept), figsize=(3.6 * len(swept), 6.6), squeeze=False)
    for column, (scene, rows, stats) in enumerate(swept):
        sweep_column(axes[0][column], axes[1][column], scene, rows, stats["sweep"])
    # every column draws the same kinds: the first's top, and its bottom's map points
    top_handles, top_labels = axes[0][0].get_legend_handles_labels()
    bottom_handles, bottom_labels = axes[1][0].get_legend_handles_labels()
    figure.legend(
        top_handles + bottom_handles[2:],
        top_labels + bottom_labels[2:],
        loc="lower center",
        ncol=4,
        fontsize=8,
    )
    figure.tight_layout(rect=(0, 0.1, 1, 1))
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=100)
    plt.close(figure)


def plot(results, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    columns = list(dict.fromkeys(scene.light_name for scene, _, _ in results))
    rows_of = list(dict.fromkeys(scene.caster_name for scene, _, _ in results))
    figure, axes = plt.subplots(
        len(rows_of), len(columns), figsize=(4.2 * len(columns), 3.6 * len(rows_of)), squeeze=False
    )
    styles = {
        "shadowgeo levels": ("C0", "s"),
        "shadowgeo fraction": ("C0", "o"),
        "shadow map PCF": ("C3", "^"),
        "shadow map PCSS": ("C1", "v"),
    }
    for scene, rows, stats in results:
        ax = axes[rows_of.index(scene.caster_name)][columns.index(scene.light_name)]
        for method, (color, marker) in styles.items():
            mine = [r for r in rows if r[0] == method]
            times = [r[2] * 1e3 for r in mine]
            ax.plot(
                times, [r[4] for r in mine], marker=marker, color=color, label=f"{method}: mean"
            )
            ax.plot(
                times,
                [r[3] for r in mine],
                marker=marker,
                color=color,
                linestyle=":",
                markerfacecolor="none",
                label=f"{method}: max",
            )
        ax.axhline(stats["noise mean"], color="grey", linewidth=0.8, label="reference noise (mean)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_title(f"{scene.caster_name}, {scene.light_name}", fontsize=9)
        ax.set_xlabel("time (ms)")
        ax.set_ylabel("hidden-fraction error")
        ax.grid(True, which="both", alpha=0.3)
    handles, labels = axes[0][0].get_legend_handles_labels()
    figure.legend(handles, labels, loc="lower center", ncol=5, fontsize=8)
    figure.tight_layout(rect=(0, 0.08, 1, 1))
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=110)
    plt.close(figure)


def section(results, command: str, settings: dict, elapsed: float) -> str:
    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=HERE
    ).stdout.strip()
    side = settings["side"]
    taps = settings["taps"]
    return f"""{TITLE}

`{command}` on {datetime.date.today().isoformat()} at commit {commit} ({cpu_model()},
Python {platform.python_version()}, numpy {np.__version__}; {elapsed / 60:.1f} minutes; times
are the median of 3 calls in one process, on a shared 2-core machine). Casters: a 2 x 2 x 2
cube spanning heights 1 to 3, and an icosphere of radius 1.2 (320 faces) centred at height 2.2,
over the ground y = 0. Lights: a one-sided 1.5 x 1 rectangle at height 6 facing down, and the
sun's disc along (0.3, -1, 0.2) at 0.53 degrees (the real sun) and at 5 degrees, so that its
penumbra is visible at the scene's scale.

**Points and reference.** {settings["points"]:,} receiver points per scene, uniform in a band
round the hard shadow from the light's centre that holds the whole penumbra (its half-width
is 1.05 times the largest distance a vertex's image moves as the light point moves over the
light). The reference (`benchmarks/softref.py`, which does not import shadowgeo) is, for each
point, the share of {side} x {side} = {side * side:,} stratified random light samples (one in
each cell of a grid over the rectangle, or over the sun's spherical cap by an equal-area map;
fresh for each point) blocked by the caster, drawn twice with independent seeds: the reference
is their mean, and its noise, half their difference, is in the second table (mean over the
penumbra, max over all points) — well under every error below. A sample is blocked when it lies
in the caster's central projection from the point onto the light (the hull of the vertices'
images), the same answer as a ray test for a convex caster: the "ray check" column counts the
disagreements with Moller-Trumbore ray tests of 200 of the points against 256 samples each.

**Methods.** *shadowgeo levels*: `soft_shadow(caster, light, ground, levels=8, samples=n)`,
the fraction of the level region each point lies in (0 in none; the levels round the fraction
to the nearest 1/8, so they err by up to 1/16 by design); time: the call. *shadowgeo
fraction*: the same call's `.fraction(points)`, the fraction of its samples hidden; time: the
call and the lookup of all points. *shadow map PCF*: the caster's depth rendered from the
light's centre (perspective for the rectangle, orthographic along the sun; a numpy z-buffer
over each triangle's bounding box, `benchmarks/shadowmap.py`, caster only, so no bias is
needed), then each point compares its depth with the map at {taps} x {taps} taps (a stratified
set of the light's points, each shifted to where the ray from the point to it crosses a flat
blocker at the caster's centre depth: the filter a renderer tunes to the light's size). *shadow
map PCSS*: the same with the blocker depth found per point (the mean depth of the map's texels
nearer than the point among the same taps spread for the caster's nearest vertex). Time: render
and lookups. Errors: |estimate - reference| of the hidden fraction, max over all points, mean
over the points the reference puts strictly inside the penumbra (0 < fraction < 1).

{table(results)}

Umbra and penumbra areas. *shadowgeo*: its `umbra.area` and `penumbra.area` at
{max(settings["samples"])} samples (from the light's corners for a convex caster, so the same at
any number of samples). *swept*: exact hard shadows in shapely (each the hull of the vertices'
images) from a dense set of the light's points, their common part and their union: a 41 x 41
grid over the rectangle, its edges included, or 17 rings of 256 points over the disc, its rim
included. The umbra is exact under the rectangle (a point hidden from a convex light's rim is
hidden from all of it), larger by about 1e-4 of the disc's radius under the disc; the penumbra
is a lower bound, short by what the grid's gaps leave out. *sampled*: from the reference's
points, the hard shadow's area outside the band plus the band's area times the share of its
points hidden from all of both draws' samples (umbra) or from any (penumbra), ± one standard
deviation of that share. The sampled penumbra is biased low where the hidden fraction rises
slowly from 0 (a round caster's image reaching into a rectangle's corner covers a share that
grows with the square of the depth), so points hidden from less than one sample in 8,192 count
as lit: the icosphere under the rectangle shows it. *exact*: shadowgeo's `SoftShadow.exact` (a
convex caster under a rectangle); under a disc its umbra is conservative and its penumbra holds
the true one, by at most 0.12 % of the disc's radius (the 64-gon round the disc).

{area_table(results)}

![hidden-fraction error against time](../docs/images/{PLOT.name})

Reading the tables: shadowgeo's levels round the fraction to the nearest 1/8, so at worst they
err by 1/16 on top of their samples' error, and their mean error stays near 0.03 however many
samples; the fraction's error falls with the samples. A shadow map's error has two sources the
rows separate: its texels (a texel's width across the light at the ground is in the
parameters, to set against the penumbra's width, about 0.03 under the 0.53 degree sun here)
and the filter's blocker depth. PCF's one depth is right only where the silhouette lies at the
caster's centre depth, so past some resolution its error stops falling. PCSS finds a depth per
point, the mean of the blocking texels it sees: right for the cube, whose penumbra is cast by
the edges of its flat faces (under the rectangle about as close as shadowgeo's 64 samples, in
ten to fifteen times their time), wrong for the sphere, whose silhouette lies deeper than the
texels in front of it.
{sweep_section(results, settings)}

### Soft shadows in the converter

`shadowgeo convert` bakes a light with a size (a sun's angle, a source radius, a UsdLux
`RectLight` or `DiskLight`) as graded layers: one shape per level of the hidden fraction k/8,
as dark as the hard shadow times k/8 (the material's transparency, or glTF's and USD's alpha),
from `soft_shadow` on the planar receivers and `soft_shadow_on_surface` on every other face
(64 samples of the light each). The bundled example `examples/scenes/soft_lights.usda` (a
`DistantLight` of angle 0.53 degrees and a 2 x 1 `RectLight` 3.5 above a floor, a box and a
column) converted to X3D, drawn by X_ITE in headless Chromium (left) and by `shadowgeo
render` (right) from the same camera; made by `python benchmarks/soft_pictures.py`. The
rectangle's layers fan out from the column's foot and round the box; the 0.53 degree sun's
penumbra is a few hundredths of a unit wide at this scale. `tests/test_softbake.py` converts
the example to .x3d, .glb and .usda and checks that the X3D 4.0 schema, the Khronos glTF
validator and usd-core's validators pass and that each light's levels darken level by level.
X3D and glTF hold neither a light's size nor a rectangle light: the rectangle is written as
the spot light at its centre (cut-off 90 degrees), with a note; USD keeps both.

![soft_lights.usda converted to X3D, drawn by X_ITE](../docs/images/soft/soft_lights_xite.png)
![the same scene and camera, drawn by shadowgeo render](../docs/images/soft/soft_lights_render.png)
"""


def spread(values, form: str) -> str:
    """The range of ``values`` formatted by ``form`` ("low to high", or one value)."""
    low, high = format(min(values), form), format(max(values), form)
    return low if low == high else f"{low} to {high}"


def map_match(scene: Scene, rows, sweep_rows) -> str:
    """The fewest levels whose mean error is at most the finest shadow map's
    (the better of PCF and PCSS), with both errors and times."""
    name = f"{scene.caster_name.split(' ')[0]} under the {scene.light_name.split(' 1')[0]}"
    best = min(map_rows(rows), key=lambda row: row[4])
    close = [row for row in sweep_rows if row[0] > 0 and row[4] <= best[4]]
    if not close:
        return f"{name}, none (the map's {best[4]:.4f})"
    levels, _, seconds, _, mean = close[0]
    return (
        f"{name}, {levels} levels ({mean:.4f} against {best[4]:.4f}; "
        f"{seconds * 1e3:,.0f} against {best[2] * 1e3:,.0f} ms)"
    )


def level_figures(sweep_rows) -> dict[str, str]:
    """For each number of levels in ``sweep_rows`` (all scenes' rows), the
    range over the scenes of its mean error, max error and time."""
    figures = {}
    for levels in sorted({row[0] for row in sweep_rows}):
        chosen = [row for row in sweep_rows if row[0] == levels]
        figures[f"mean {levels}"] = spread([row[4] for row in chosen], ".4f")
        figures[f"max {levels}"] = spread([row[3] for row in chosen], ".3f")
        figures[f"ms {levels}"] = spread([row[2] * 1e3 for row in chosen], ",.0f")
    return figures


def fraction_figures(swept) -> dict[str, str]:
    """``.fraction``'s mean error at the most samples and its time as a share
    of the most levels' time, as ranges over the scenes."""
    pairs = []
    for _, rows, sweep_rows in swept:
        fractions = [row for row in rows if row[0] == "shadowgeo fraction"]
        if fractions:
            pairs.append((fractions[-1], sweep_rows[-1]))
    if not pairs:
        return {}
    return {
        "fraction mean": spread([fraction[4] for fraction, _ in pairs], ".4f"),
        "fraction share": spread([fraction[2] / most[2] for fraction, most in pairs], ".2f"),
    }


def sweep_figures(results) -> dict[str, str]:
    """The sweep's figures the reading quotes (:func:`level_figures`,
    :func:`map_match`, :func:`fraction_figures`); "n/a" for any other key
    (a level not swept in a short run)."""
    swept = [(scene, rows, stats["sweep"]) for scene, rows, stats in results if stats["sweep"]]
    figures: dict[str, str] = defaultdict(lambda: "n/a")
    figures.update(level_figures([row for _, _, sweep_rows in swept for row in sweep_rows]))
    matches = [map_match(*found) for found in swept if map_rows(found[1])]
    figures["match"] = "; ".join(matches) or "n/a"
    figures.update(fraction_figures(swept))
    return figures


def sweep_section(results, settings: dict) -> str:
    if not any(stats["sweep"] for _, _, stats in results):
        return ""
    levels = settings["levels"]
    f = sweep_figures(results)
    first, last = min(levels), max(levels)
    return f"""
### Levels {first} to {last}

The same points and reference, `soft_shadow(caster, light, ground, levels=n, samples=s)` for
n = {", ".join(str(n) for n in levels)} on the two casters under the rectangle and the
0.53 degree sun, with s = max(64, 4 n) samples: the default 64 up to 16 levels, then four a
level (128 at 32, 256 at 64), so that the samples' own error (about 0.02 at most with 256,
above) stays near the half-band 1 / (2 n) the levels round to. The estimate is the fraction of
the level each point lies in, as above. The first row of each scene is what the umbra and
penumbra alone say: 1 in the umbra, 1/2 in the rest of the penumbra, 0 outside (its time: the
call at {first} levels, which makes them). Last in each scene, the shadow maps at the finest
resolution of the table above. Times: the median of {settings["sweep repeat"]} calls, or one call
when it takes {SWEEP_ONCE:g} s or more.

{sweep_table(results)}

![hidden-fraction error against levels and time](../docs/images/{SWEEP_PLOT.name})

Reading the sweep: the levels' error is their rounding and their samples' error together.
Rounding to the nearest 1/n errs by at most 1/(2n) and, over a penumbra where the fraction
runs evenly, by 1/(4n) on average, so the mean error halves with each doubling of the levels:
{f[f"mean {first}"]} at {first} levels, {f["mean 8"]} at 8, {f["mean 16"]} at 16,
{f[f"mean {last}"]} at {last}, close to 1/(4n) and a little over it from 16 levels on, where
the samples add theirs. The largest error is about 1/(2n) plus the samples' own (0.04 to 0.06
at 64 samples, table above): {f[f"max {first}"]} at {first} levels, {f["max 16"]} at 16,
{f[f"max {last}"]} at {last} with 256 samples. The umbra and penumbra alone err by
{f["mean 0"]} on average. Against the finest shadow map (the better of PCF and PCSS by mean
error), the fewest levels as close on average, and their time against the map's: {f["match"]}.
Past 16 levels the time grows fast ({f[f"ms {last}"]} ms at {last}): each level is one more
threshold cut from the samples' cover, whose arrangement grows with the square of the samples
(doubled at 32 and again at 64), and the icosphere's many silhouette edges make that cover
large. Levels are for baking graded transparency, where a few bands do; for the fraction at
points, `.fraction` at {max(settings["samples"])} samples (table above) errs by
{f["fraction mean"]} on average, under {last} levels' {f[f"mean {last}"]}, in
{f["fraction share"]} of their time.
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="few points, small maps; print only")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()
    settings = (
        {
            "points": 1000,
            "side": 24,
            "resolutions": (128, 512),
            "samples": (16, 64),
            "taps": 8,
            "levels": (2, 8),
            "sweep repeat": 1,
        }
        if args.quick
        else {
            "points": 20000,
            "side": 64,
            "resolutions": (256, 1024, 2048),
            "samples": (16, 64, 256),
            "taps": 16,
            "levels": SWEEP_LEVELS,
            "sweep repeat": 3,
        }
    )
    begin = time.perf_counter()
    results = []
    for index, scene in enumerate(scenes()):
        rows, stats = measure(
            scene,
            settings["points"],
            settings["side"],
            settings["resolutions"],
            settings["samples"],
            settings["taps"],
            seed=index,
            levels_swept=settings["levels"] if swept(scene) else (),
            sweep_repeat=settings["sweep repeat"],
        )
        results.append((scene, rows, stats))
        print(f"{scene.caster_name}, {scene.light_name}: {stats}", flush=True)
    elapsed = time.perf_counter() - begin
    command = "python benchmarks/bench_soft.py" + (" --quick" if args.quick else "")
    text = section(results, command, settings, elapsed)
    print(text)
    if args.quick or args.no_write:
        return
    plot(results, PLOT)
    sweep_plot(results, SWEEP_PLOT)
    write_section(TITLE, text)
    print(f"wrote {PLOT}, {SWEEP_PLOT} and the section {TITLE[3:]!r} of benchmarks/REPORT.md")


if __name__ == "__main__":
    main()
