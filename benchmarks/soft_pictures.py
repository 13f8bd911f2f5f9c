"""Pictures of soft shadows baked by the converter: the bundled example
``examples/scenes/soft_lights.usda`` (a sun of 0.53 degrees and a 2 x 1
rectangle light over a floor, a box and a column) converted to X3D, drawn by
X_ITE in headless Chromium, and by ``shadowgeo render`` (pyvista)::

    python benchmarks/soft_pictures.py      # writes docs/images/soft/*.png

The report's subsection "Soft shadows in the converter" (in
``bench_soft.py``'s template) shows them.
"""

from __future__ import annotations

import math
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

from needs import TOOLS  # noqa: E402
from xite import Canvas, View, render  # noqa: E402

import shadowgeo as sg  # noqa: E402

EXAMPLE = ROOT / "examples" / "scenes" / "soft_lights.usda"
FOLDER = ROOT / "docs" / "images" / "soft"
# The camera: up and to the front right of the box and column, looking at them.
EYE = np.array([3.5, 7.5, 9.5])
TARGET = np.array([-1.2, 0.0, 0.2])


def orientation(eye: np.ndarray, target: np.ndarray) -> tuple[float, float, float, float]:
    """X3D's (axis, angle) turning the default view (down -z, y up) to look
    from ``eye`` at ``target`` with y up."""
    forward = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(forward, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    rotation = np.column_stack([right, up, -forward])  # columns: where x, y, z go
    angle = math.acos(max(-1.0, min(1.0, (np.trace(rotation) - 1) / 2)))
    axis = np.array(
        [
            rotation[2, 1] - rotation[1, 2],
            rotation[0, 2] - rotation[2, 0],
            rotation[1, 0] - rotation[0, 1],
        ]
    )
    axis /= np.linalg.norm(axis)
    return (*axis.tolist(), angle)


def main() -> None:
    from PIL import Image

    browser = TOOLS["chromium"][0]()
    if browser is None or TOOLS["x_ite"][0]() is None:
        sys.exit("needs Chromium and X_ITE (npm ci --prefix tests/node)")
    FOLDER.mkdir(parents=True, exist_ok=True)
    baked = sg.add_shadows(sg.load(EXAMPLE))
    with tempfile.TemporaryDirectory(prefix="soft-pictures-") as scratch:
        folder = Path(scratch)
        sg.save(baked, folder / "soft_lights.x3d")
        view = View(tuple(EYE.tolist()), orientation(EYE, TARGET), 0.7)
        (shot,) = render(folder, [Canvas("soft_lights.x3d", view=view)], 640, browser, 120.0)
    if shot.status != "ok":
        sys.exit(f"X_ITE: {shot.status}")
    Image.fromarray(shot.image).save(FOLDER / "soft_lights_xite.png")
    # the same camera (what shadowgeo render --viewpoint draws)
    camera = sg.Viewpoint(view.position, view.orientation, view.field_of_view)
    sg.plot(
        baked, screenshot=FOLDER / "soft_lights_render.png", window_size=(640, 640), view=camera
    )
    print(f"wrote {FOLDER / 'soft_lights_xite.png'} and {FOLDER / 'soft_lights_render.png'}")


if __name__ == "__main__":
    main()
