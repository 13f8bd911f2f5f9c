"""The map of sunlight hours (:func:`shadowgeo.sunmap.plot_sunlight`), checked
on its pixels: each level in its ramp colour, in proportion to its area, holes
left empty, buildings grey over the levels."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from shadowgeo.scene.sunlight import ramp_colour
from shadowgeo.sunmap import plot_sunlight

plt = pytest.importorskip("matplotlib.pyplot")


def _count(image: np.ndarray, colour: tuple[float, float, float]) -> int:
    """Pixels within 2/255 of ``colour`` in each channel."""
    return int(np.all(np.abs(image[..., :3] - np.asarray(colour)) < 2.5 / 255, axis=-1).sum())


def test_levels_fill_in_their_colours_by_area_and_holes_stay_empty(tmp_path):
    # 0 h: a 10 x 10 square with a 4 x 4 hole; 12 h: a 10 x 30 strip beside it
    dark = shapely.Polygon([(0, 0), (10, 0), (10, 10), (0, 10)], [[(3, 3), (3, 7), (7, 7), (7, 3)]])
    bright = shapely.box(10, 0, 40, 10)
    target = tmp_path / "map.png"
    plot_sunlight(target, [(0.0, dark), (12.0, bright)], [], most_hours=12.0, title="t")
    image = plt.imread(target)
    purple, yellow = _count(image, ramp_colour(0.0)), _count(image, ramp_colour(1.0))
    # areas 84 and 300 (legend swatches add a few hundred pixels of each)
    assert yellow / purple == pytest.approx(300 / 84, rel=0.05)
    assert purple > 2000


def test_buildings_cover_the_levels_and_the_file_is_written_whole(tmp_path):
    level = shapely.box(0, 0, 10, 10)
    roofs = [
        shapely.Polygon([(0, 0), (10, 0), (10, 5)]),
        shapely.Polygon([(0, 0), (10, 5), (0, 5)]),
    ]
    target = tmp_path / "map.png"
    plot_sunlight(target, [(6.0, level)], roofs, most_hours=12.0, title="t")
    image = plt.imread(target)
    middle = _count(image, ramp_colour(0.5))
    grey = _count(image, (0.55, 0.55, 0.55))
    # the roofs hide the lower half of the level
    assert grey / middle == pytest.approx(1.0, rel=0.08)
    assert [path.name for path in tmp_path.iterdir()] == ["map.png"]
