"""``shadowgeo sun`` on each real city file of the shared corpus, to a
GeoPackage, as a planner would run it: the date and (for the two files that
name no CRS) the site. The levels read back tile the region the command
reports, and Delft's LoD1 studies its ground (roads, land, water) with its
buildings and trees casting.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from needs import SHARED, absent

import shadowgeo as sg
from cli.main import main

gpd = pytest.importorskip("geopandas")

GIS = SHARED / "corpus" / "gis"
# The two cjio subsets name no CRS: their places, from the corpus README.
FILES = {
    "rotterdam_subset.city.json": ["--at", "51.9,4.5"],
    "denhaag_subset.city.json": ["--at", "52.08,4.31"],
    "delft_lod1.city.json": [],
    # 2,000 footprints: every 2 hours keeps the test short (the default, hourly,
    # is timed in the report)
    "suzhou_buildings.geojson": ["--every", "120"],
}


def _gis(name: str) -> Path:
    path = GIS / name
    if not path.is_file():
        absent(f"{path} is absent (it exists on the project's machines and CI, not in a clone)")
    return path


@pytest.mark.parametrize("name", sorted(FILES))
def test_each_city_file_gives_a_geopackage_of_its_levels(name, tmp_path, capsys):
    source = _gis(name)
    target = tmp_path / "out.gpkg"
    args = ["sun", str(source), str(target), "--date", "2026-03-21", "--progress"]
    assert main([*args, *FILES[name]]) == 0
    out, err = capsys.readouterr()
    region = float(re.search(r"region ([0-9.e+]+) square units", out).group(1))
    frame = gpd.read_file(target, layer="sunlight")
    scene = sg.load(source)
    if scene.site is None:
        assert frame.crs is None
        metric = frame
    else:
        assert frame.crs.equals(scene.site.source_crs, ignore_axis_order=True)
        metric = frame.to_crs(scene.site.crs)
    assert metric.area.sum() == pytest.approx(region, rel=1e-5)  # printed to 6 digits
    assert list(frame["hours"]) == sorted(frame["hours"])
    assert "day(s)" in err  # the progress bar


def test_delft_studies_its_ground_with_buildings_and_trees_casting(tmp_path, capsys):
    source = _gis("delft_lod1.city.json")
    assert main(["sun", str(source), "--date", "2026-03-21"]) == 0
    out, err = capsys.readouterr()
    assert re.search(r"sun study: \d+ flat city object\(s\)", err)
    # the region is the plan of the whole file, not one road's outline
    low, high = sg.load(source).bounds
    plan = float(np.prod(high[:2] - low[:2]))
    region = float(re.search(r"region ([0-9.e+]+) square units", out).group(1))
    assert region == pytest.approx(plan, rel=1e-5)  # printed to 6 digits
