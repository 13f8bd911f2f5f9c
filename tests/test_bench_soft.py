"""benchmarks/bench_soft.py and its reference (benchmarks/softref.py) on a tiny setting:
the reference's own consistency, not speed."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import bench_soft  # noqa: E402
import softref  # noqa: E402


def scene(caster: str, light: str) -> bench_soft.Scene:
    (found,) = [
        s for s in bench_soft.scenes() if s.caster_name.startswith(caster) and light in s.light_name
    ]
    return found


def test_sun_samples_cover_the_disc_evenly():
    # every direction within the cap, the cap's centre their mean, and half
    # of them within the half-area circle (an equal-area map)
    sun = softref.Sun(np.array([0.0, -1.0, 0.0]), math.radians(5))
    offsets = softref.light_points(sun, 32, np.random.default_rng(1))
    radius = np.hypot(offsets[:, 0], offsets[:, 1])
    edge = math.tan(sun.angle / 2)
    assert radius.max() <= edge * (1 + 1e-12)
    assert np.allclose(offsets.mean(axis=0), 0, atol=0.02 * edge)
    for quadrant in ((1, 1), (1, -1), (-1, 1), (-1, -1)):
        share = np.mean((np.sign(offsets) == quadrant).all(axis=1))
        assert share == pytest.approx(0.25, abs=0.02)
    assert np.mean(radius <= edge / math.sqrt(2)) == pytest.approx(0.5, abs=0.02)


@pytest.mark.parametrize("light", ["rect", "sun disc 5"])
def test_reference_is_one_deep_in_the_umbra_and_zero_past_the_penumbra(light):
    found = scene("cube", light)
    vertices = np.asarray(found.caster.vertices, dtype=float)
    hard, band = bench_soft.neighbourhood(found.reference, vertices)
    rng = np.random.default_rng(2)
    deep = hard.difference(band)
    assert deep.area > 0
    inner = bench_soft.band_points(deep, 50, rng)
    ring = band.buffer(0.1).difference(hard.union(band))
    outer = bench_soft.band_points(ring, 50, rng)
    assert np.all(softref.hidden_fraction(found.reference, vertices, inner, 16, rng) == 1)
    assert np.all(softref.hidden_fraction(found.reference, vertices, outer, 16, rng) == 0)
    # and in the band, the cone test is the ray test, sample by sample
    points = bench_soft.band_points(band, 40, rng)
    offsets = softref.light_points(found.reference, 8, rng)
    cone = softref.cone_blocked(found.reference, vertices, points, offsets)
    rays = softref.ray_fraction(found.reference, found.caster.triangles, points, offsets)
    assert np.array_equal(cone, rays)
    assert 0 < cone.mean() < 1


def test_tiny_run_reference_noise_areas_and_shadow_map_resolution():
    found = scene("cube", "sun disc 0.53")
    rows, stats = bench_soft.measure(
        found, n_points=400, side=16, resolutions=(64, 1024), samples=(16,), taps=8, seed=3
    )
    methods = [row[0] for row in rows]
    assert methods == [
        "shadowgeo levels",
        "shadowgeo fraction",
        "shadow map PCF",
        "shadow map PCSS",
        "shadow map PCF",
        "shadow map PCSS",
    ]
    for _, _, seconds, worst, mean in rows:
        assert seconds > 0 and 0 <= mean <= worst <= 1
    # two draws of 256 stratified samples: their mean errs by far less than
    # a plain random draw's 0.5 / sqrt(512) = 0.022
    assert stats["noise mean"] < 0.01 and stats["noise max"] < 0.05
    assert stats["ray check"][0] == 0
    assert stats["penumbra points"] > 100
    # the disc's bounds: a conservative umbra, a penumbra that holds the true one
    umbra, umbra_noise = stats["reference umbra"]
    penumbra, penumbra_noise = stats["reference penumbra"]
    assert stats["umbra"] <= umbra + 4 * umbra_noise
    assert stats["penumbra"] >= penumbra - 4 * penumbra_noise
    # and against exact hard shadows from a dense set of the light's points
    assert stats["umbra"] <= stats["swept umbra"] + 1e-9
    assert stats["penumbra"] >= stats["swept penumbra"] - 1e-9
    assert stats["swept umbra"] == pytest.approx(umbra, abs=4 * umbra_noise)
    # the finest map is closer to the reference than the coarsest
    coarse, fine = (row for row in rows if row[0] == "shadow map PCF")
    assert fine[4] < coarse[4]


def test_section_writes_the_table_and_links_the_plot():
    found = scene("icosphere", "rect")
    rows, stats = bench_soft.measure(
        found, n_points=100, side=8, resolutions=(32,), samples=(16,), taps=4, seed=4
    )
    settings = {"points": 100, "side": 8, "resolutions": (32,), "samples": (16,), "taps": 4}
    text = bench_soft.section([(found, rows, stats)], "tiny", settings, 1.0)
    assert text.startswith(bench_soft.TITLE + "\n")
    assert "| icosphere (320 faces), rect 1.5 x 1 at height 6 | shadow map PCSS |" in text
    assert f"../docs/images/{bench_soft.PLOT.name}" in text


def test_levels_sweep_rows_table_and_section():
    found = scene("cube", "rect")
    rows, stats = bench_soft.measure(
        found, 300, 8, (32,), (16,), 4, seed=5, levels_swept=(2, 16), sweep_repeat=1
    )
    levels = [row[0] for row in stats["sweep"]]
    samples = [row[1] for row in stats["sweep"]]
    assert levels == [0, 2, 16] and samples == [64, 64, 64]
    assert bench_soft.sweep_samples(32) == 128 and bench_soft.sweep_samples(64) == 256
    # finer levels round the fraction less: 16 levels err by far less on average than 2
    (_, _, _, _, mean_two), (_, _, _, worst, mean_sixteen) = stats["sweep"][1:]
    assert mean_sixteen < mean_two / 3 and worst < 0.25
    settings = {
        "points": 300,
        "side": 8,
        "resolutions": (32,),
        "samples": (16,),
        "taps": 4,
        "levels": (2, 16),
        "sweep repeat": 1,
    }
    text = bench_soft.section([(found, rows, stats)], "tiny", settings, 1.0)
    assert "### Levels 2 to 16" in text
    assert "| cube, rect 1.5 x 1 at height 6 | 16 levels | 64 |" in text
    assert "| cube, rect 1.5 x 1 at height 6 | shadow map PCSS 32 px | |" in text
    assert f"../docs/images/{bench_soft.SWEEP_PLOT.name}" in text
