"""A sun study of the courtyard: hours of sunlight on its ground on 21 March in London.

The same as ``shadowgeo sun examples/scenes/courtyard.x3d map.x3d --at 51.5,-0.12
--date 2026-03-21``, written out in Python: the floor found in the scene, the
sun sampled every hour, the exact area sunlit for each number of hours (the
BRE guideline asks for at least 2 hours over half of a garden on this day),
and the day's map of sunlight hours baked into the scene and drawn from above.

Run: python examples/sunlight_map.py [picture.png]
(default docs/images/sunlight_map.png)
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import sys
from pathlib import Path

import shadowgeo as sg
from shadowgeo.scene.sunlight import study_scene, sunlight_shapes

HERE = Path(__file__).resolve().parent
picture = Path(sys.argv[1]) if len(sys.argv) > 1 else HERE.parent / "docs/images/sunlight_map.png"

scene = sg.load(HERE / "scenes" / "courtyard.x3d")
day = dt.datetime(2026, 3, 21, tzinfo=dt.UTC)
times = sg.sun.hourly(day, day + dt.timedelta(days=1))
inputs, studies = study_scene(scene, times, latitude=51.5, longitude=-0.12)
(study,) = studies.days.values()
print(f"{inputs.floor}: {study.area:g} square units, {len(study.times)} hours with the sun up")
print("| sunlight (h) | area |")
print("|---:|---:|")
for hours, area in study.level_areas().items():
    if area > 1e-9 * study.area:
        print(f"| {hours:g} | {area:.4f} |")
print(f"{study.fraction_meeting(2.0):.1%} of the ground has at least 2 hours of sun")

mapped = dataclasses.replace(scene, shapes=[*scene.shapes, *sunlight_shapes(study, inputs.scale)])
sg.plot(mapped, screenshot=picture, window_size=(640, 480), view="top")
print(f"wrote {picture}")
