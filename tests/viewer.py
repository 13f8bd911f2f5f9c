"""The viewer comparison: a scene's runtime shadows against the ones shadowgeo bakes.

For one input scene, ``shadowgeo convert IN OUT.x3d`` (no flags) is run and
X_ITE in headless Chromium (:mod:`xite`) draws, side by side from the same
Viewpoint and canvas size, with the headlight as the author set it:

(a) the input as the converter frames it, with its lights' runtime shadows
    on: the output less its baked shadow shapes (:func:`unbaked`: the added
    ground and Viewpoint stay) and with the baked lights' ``shadows`` given
    back (``shadows TRUE`` on the lights shadowgeo bakes: those with
    ``shadows TRUE``, else every light that is on), so X_ITE draws shadow
    maps (2048 pixels);
(b) the output with ``shadows FALSE`` on every light: only the baked shadows;
(c) the same file as (a) with ``shadows FALSE`` on every light: no shadow at
    all.

So the three show the same scene and differ only by their shadows. The
issue's (a) and (c) are "the input"; but the output adds a light-grey ground
under a scene with no floor when the ground plane receives (and a Viewpoint
to a scene with none), and drawing the input itself would leave the shadows
on that ground with nothing to compare to in (a) and the ground itself as a
difference between (b) and (c). The output less its baked shadows is the
input's nodes, unchanged, plus that ground and Viewpoint: the input as the
converter frames it.

The Viewpoint is the author's first (world position and orientation, as
shadowgeo reads it), else :func:`shadowgeo.scene.model.overview` of the input
(the converter's own choice), bound explicitly in all three. The scene is
drawn from a copy in which every TimeSensor has ``enabled FALSE``: the three
canvases, loaded a moment apart, all show the file's own state, the one
shadowgeo bakes, not three moments of an animation. The shadow mask
of (a) and of (b) is the pixels darker than in (c) by more than
:data:`DROP` of full scale *and* by more than :data:`RELATIVE` of their value
in (c) (Rec. 709 luminance of the sRGB values, 0..1): the absolute floor keeps
noise in dark corners out, the relative one keeps a faint second light's
shadow on a bright wall in. Their agreement is the IoU (intersection over
union) of the two masks.

Used by ``tests/test_viewer.py`` (small scenes written there) and
``benchmarks/bench_viewer.py`` (the bundled examples and the corpus).
"""

from __future__ import annotations

import math
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from xite import Canvas, Shot, View, render

ROOT = Path(__file__).resolve().parents[1]
# A pixel is in shadow when (c) - (x) > DROP and > RELATIVE * (c) (luminance 0..1).
DROP = 0.04
RELATIVE = 0.08
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


@dataclass
class Comparison:
    """What the three pictures of one scene show.

    ``shots`` are (a), (b), (c) as :class:`xite.Shot` (empty when the scene
    failed before rendering); ``masks`` the shadow masks of (a) and (b),
    (size, size) bool; ``casting`` the lights shadowgeo bakes; ``problems``
    what makes the measurement wrong or missing (a failure, a light X_ITE
    did not reach, a Viewpoint not bound); ``notes`` the converter's notes.
    """

    shots: list[Shot] = field(default_factory=list)
    masks: tuple[np.ndarray, np.ndarray] | None = None
    casting: list[str] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    @property
    def iou(self) -> float:
        """Intersection over union of the masks (nan when both are empty or missing)."""
        if self.masks is None:
            return math.nan
        runtime, baked = self.masks
        union = int(np.count_nonzero(runtime | baked))
        return np.count_nonzero(runtime & baked) / union if union else math.nan

    @property
    def brighter(self) -> int:
        """Pixels of (b) brighter than (c) by the mask's threshold: baked
        shadows only darken, so anything here is another change the
        conversion made (a material, a texture, geometry)."""
        if len(self.shots) < 3:
            return 0
        return int(np.count_nonzero(shadow_mask(self.shots[2].image, self.shots[1].image)))


def luminance(image: np.ndarray) -> np.ndarray:
    """(h, w) Rec. 709 luminance, 0..1, of an (h, w, 3) uint8 sRGB picture."""
    return np.asarray(image, dtype=np.float64) @ LUMINANCE / 255.0


def shadow_mask(image: np.ndarray, unshadowed: np.ndarray) -> np.ndarray:
    """(h, w) bool: pixels of ``image`` darker than in ``unshadowed`` by more
    than :data:`DROP` and by more than :data:`RELATIVE` of their value there."""
    lit = luminance(unshadowed)
    drop = lit - luminance(image)
    return (drop > DROP) & (drop > RELATIVE * lit)


def casting_lights(scene) -> list[str]:
    """Names (or types) of the lights ``shadowgeo convert`` bakes: those with
    ``shadows`` set, else every light that is on."""
    chosen = [light for light in scene.lights if light.shadows] or [
        light for light in scene.lights if light.on
    ]
    return [
        light.name or f"{type(light.light).__name__} {index}" for index, light in enumerate(chosen)
    ]


def view_of(scene) -> View:
    """The author's first Viewpoint, else the converter's overview."""
    from shadowgeo.scene.model import overview

    view = scene.viewpoints[0] if scene.viewpoints else overview(scene)
    return View(
        tuple(float(v) for v in view.position),
        tuple(float(v) for v in view.orientation),
        float(view.field_of_view),
    )


def staged(source: Path, root: Path, site: Path) -> Path:
    """``source``'s place in a copy of ``root`` at ``site`` (made once): the
    scene's relative urls (``../textures/x.png`` too, within ``root``)
    resolve there as beside the original, the converter's Inline containment
    sees real folders, and the output can be written beside the scene without
    touching ``root``."""
    if not site.exists():
        shutil.copytree(root, site, symlinks=True)
    copy = site / source.relative_to(root)
    copy.write_bytes(stopped_clocks(source.read_bytes(), source.suffix.lower()))
    return copy


def stopped_clocks(text: bytes, suffix: str) -> bytes:
    """The scene ``text`` with ``enabled FALSE`` first in every TimeSensor
    (X3D XML for ``.x3d``, else ClassicVRML / VRML 97 syntax); other
    encodings (gzip) are returned as they are."""
    if suffix == ".x3d":
        return re.sub(rb"<TimeSensor\b", b'<TimeSensor enabled="false"', text)
    if suffix in (".x3dv", ".wrl"):
        return re.sub(rb"\bTimeSensor(\s*)\{", rb"TimeSensor\1{ enabled FALSE ", text)
    return text


def convert(source: Path, target: Path, timeout: float) -> tuple[str | None, list[str]]:
    """``shadowgeo convert source target`` (this checkout's CLI, no flags):
    (what went wrong or None, the notes it printed)."""
    try:
        result = subprocess.run(
            [sys.executable, "-m", "cli", "convert", str(source), str(target)],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=timeout,
            check=False,
        )
    except subprocess.TimeoutExpired:
        return f"shadowgeo convert took more than {timeout:.0f} s", []
    notes = [line[6:] for line in result.stderr.splitlines() if line.startswith("note: ")]
    if result.returncode != 0 or not target.is_file():
        return f"shadowgeo convert exit {result.returncode}: {result.stderr.strip()[-300:]}", notes
    return None, notes


def unbaked(output: Path, target: Path) -> None:
    """Write to ``target`` (beside ``output``, whose relative urls it keeps)
    the converted X3D XML ``output`` less its baked shadows: the shapes of
    role shadow or volume (class ``shadowgeo-shadows-shadow`` or
    ``-volume``) and the ``shadowgeo-shadows`` groups they leave empty go;
    the added ground (``-ground``), the added Viewpoint and every node of
    the input stay. A light marked ``shadowgeo-shadows-baked`` (its
    ``shadows TRUE`` turned off by the converter) gets ``shadows="true"``
    back, so the lights cast as in the input. The ground gets
    ``castShadow="false"``: it is only a receiver, which the converter's
    shadows do not count as a caster either (a light from below would
    otherwise have X_ITE shade the scene with the ground's shadow)."""
    from lxml import etree

    from shadowgeo.scene.model import MARK

    tree = etree.parse(str(output))

    def marks(element) -> list[str]:
        return (element.get("class") or "").split() if isinstance(element.tag, str) else []

    for element in list(tree.iter()):
        if {f"{MARK}-shadow", f"{MARK}-volume"} & set(marks(element)):
            element.getparent().remove(element)
        elif f"{MARK}-baked" in marks(element):
            element.set("shadows", "true")
        elif f"{MARK}-ground" in marks(element):
            element.set("castShadow", "false")
    for group in list(tree.iter()):
        if MARK in marks(group) and not any(isinstance(child.tag, str) for child in group):
            group.getparent().remove(group)
    tree.write(str(target), xml_declaration=True, encoding="UTF-8")


def compare(
    source: Path,
    root: Path,
    work: Path,
    *,
    size: int,
    browser: Path | str,
    timeout: float = 120.0,
) -> Comparison:
    """Draw (a), (b), (c) of ``source`` (a scene file under ``root``) in
    ``work`` and measure their shadow masks; never raises for a bad scene."""
    import shadowgeo as sg

    result = Comparison()
    try:
        scene = sg.load(source)
    except (sg.SceneError, OSError) as error:
        result.problems.append(f"shadowgeo cannot read it: {error}")
        return result
    result.casting = casting_lights(scene)
    site = work / "site"
    copy = staged(source, root, site)
    output = copy.with_name(copy.stem + ".shadowgeo.x3d")
    failure, result.notes = convert(copy, output, timeout)
    if failure:
        result.problems.append(failure)
        return result
    bare = copy.with_name(copy.stem + ".unbaked.x3d")
    try:
        unbaked(output, bare)
    except (OSError, SyntaxError) as error:  # lxml's XMLSyntaxError is a SyntaxError
        result.problems.append(f"cannot strip the baked shadows from the output: {error}")
        return result
    view = view_of(scene)
    url = bare.relative_to(site).as_posix()
    converted = output.relative_to(site).as_posix()
    canvases = [
        Canvas(url, shadows="cast", view=view),
        Canvas(converted, shadows="off", view=view),
        Canvas(url, shadows="off", view=view),
    ]
    result.shots = render(site, canvases, size, browser, timeout)
    for label, shot in zip("abc", result.shots, strict=True):
        if shot.status != "ok":
            result.problems.append(f"({label}): {shot.status}")
    if result.problems:
        return result
    # X_ITE reports each light node once; shadowgeo each instance (USE) of it.
    drawn = sum(light["shadows"] for light in result.shots[0].lights)
    baked = len(set(result.casting))
    if drawn != baked:
        result.problems.append(f"X_ITE casts {drawn} light(s), shadowgeo bakes {baked}")
    runtime, baked, plain = (shot.image for shot in result.shots)
    result.masks = (shadow_mask(runtime, plain), shadow_mask(baked, plain))
    return result


def gallery_image(comparison: Comparison, panel: int):
    """A PIL image: (a) and (b) side by side, ``panel`` pixels each, and the
    masks over (c) in grey: green where both shadow, red where only (a)
    (runtime) does, blue where only (b) (baked) does."""
    from PIL import Image

    runtime, baked, plain = (shot.image for shot in comparison.shots)
    grey = (luminance(plain)[..., None] * 160).astype(np.uint8).repeat(3, axis=2)
    if comparison.masks is not None:
        only_runtime = comparison.masks[0] & ~comparison.masks[1]
        only_baked = comparison.masks[1] & ~comparison.masks[0]
        grey[comparison.masks[0] & comparison.masks[1]] = (40, 200, 40)
        grey[only_runtime] = (230, 40, 40)
        grey[only_baked] = (60, 90, 255)
    panels = [
        Image.fromarray(runtime).resize((panel, panel), Image.LANCZOS),
        Image.fromarray(baked).resize((panel, panel), Image.LANCZOS),
        Image.fromarray(grey).resize((panel, panel), Image.NEAREST),
    ]
    strip = Image.new("RGB", (3 * panel, panel))
    for index, image in enumerate(panels):
        strip.paste(image, (index * panel, 0))
    return strip.quantize(colors=128, method=Image.Quantize.MEDIANCUT)
