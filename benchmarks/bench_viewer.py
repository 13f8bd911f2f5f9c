"""What the viewer shows: X_ITE's runtime shadows against the ones shadowgeo bakes.

For the bundled examples and the corpus scenes listed in :data:`SCENES`, X_ITE
in headless Chromium draws (a) the input as the converter frames it (the
output of ``shadowgeo convert IN OUT.x3d``, no flags, less its baked shadow
shapes: the input's nodes plus the ground and Viewpoint the converter adds)
with its lights' runtime shadows (shadow maps), (b) the output with runtime
shadows off and (c) the same as (a) with no shadows, from the same
Viewpoint, so the three differ only by their shadows; the shadow masks of (a)
and (b), the pixels darker than in (c), are compared by their IoU. The rules
(what (a) is and why, Viewpoint, thresholds, which lights cast) are
``tests/viewer.py``'s; the rendering is ``tests/xite.py``'s.

Run from the repository root (needs Chromium and ``npm ci --prefix
tests/node``; about 5 minutes on 2 cores)::

    python benchmarks/bench_viewer.py [--size 512] [--only NAME ...] [--no-write]

It prints the table, writes the section "What the viewer shows" of
``benchmarks/REPORT.md`` (``common.write_section``) and the gallery
``docs/images/viewer/*.png`` ((a) | (b) | masks, 256 pixels each).
"""

from __future__ import annotations

import argparse
import math
import shutil
import statistics
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests"), str(ROOT / "benchmarks")]

from common import write_section  # noqa: E402
from needs import TOOLS  # noqa: E402
from viewer import DROP, RELATIVE, Comparison, compare, gallery_image, shadow_mask  # noqa: E402
from xite import FRAMES, Canvas, render  # noqa: E402

CORPUS = ROOT.parent / "shared" / "corpus"
GALLERY = ROOT / "docs" / "images" / "viewer"
TITLE = "## What the viewer shows"
PANEL = 256  # gallery pixels per picture
# A scene counts towards the median when a mask covers this share of the picture.
SHADOW_SHARE = 0.001


@dataclass(frozen=True)
class Entry:
    """A scene measured: ``path`` under ``root`` ("examples" is
    examples/scenes, else a corpus folder), why it was chosen, and what the
    pictures show about X_ITE's own shadow map there (judged by eye)."""

    root: str
    path: str
    reason: str
    seen: str = ""
    xite_fault: bool = False  # the pictures show X_ITE's own shadow map wrong

    @property
    def folder(self) -> Path:
        return ROOT / "examples" / "scenes" if self.root == "examples" else CORPUS / self.root

    @property
    def name(self) -> str:
        return self.path if self.root == "examples" else f"{self.root}/{self.path}"


CLASSIC = "castle-demo-models-classic"
XML = "castle-demo-models"

SCENES = [
    # the bundled examples
    Entry("examples", "courtyard.x3d", "crate, column and tent on a ground, a lamp and a sun",
          "clean shadow maps; the outlines agree"),
    Entry("examples", "pyramid.x3d", "a pyramid over a ground under a lamp", "clean"),
    Entry("examples", "terrain.x3d", "blocks and a pole on a terrain under a sun",
          "clean; the pole's thin shadow on the slope agrees"),
    # X3D XML
    Entry(XML, "blender/simple/test1.x3d", "Blender export: cubes, one lamp",
          "no floor: the converter adds a ground, and the cubes' shadows on it agree"),
    Entry(XML, "lights_materials/light_street_lights_radius.x3d",
          "8 street lamps over a road between walls",
          "X_ITE fault: on the wall right beside each lamp, its point-light shadow map "
          "darkens all around a small square of the lamp's spot, above the lamp too where "
          "nothing can cast (the red rings); the curbs' thin shadows agree",
          xite_fault=True),
    Entry(XML, "lights_materials/shading_smooth_even_on_flat_normals.x3d",
          "a capsule over a box, one lamp", "clean; the capsule's shadow on itself agrees"),
    Entry(XML, "navigation/avatar_climb_stairs_geometry.x3d",
          "three flights of stairs on a floor, 2 lamps",
          "X_ITE acne and aliasing: speckles on the right-hand flight's top riser, 1-2 pixel "
          "lines along the treads' lit edges and the flights' feet (red); the shadows on the "
          "floor and on the right-hand flight's side agree",
          xite_fault=True),
    Entry(XML, "x3d/axis.x3d", "axis bars and 3-D text crossing, 2 lamps",
          "X_ITE peter-panning: the small shadows at a contact are missing at run time and "
          "baked (blue): inside the 3-D letters (their counters, where the X's strokes "
          "cross) and beside the bars' crossing; the bars' shadows on each other agree",
          xite_fault=True),
    Entry(XML, "x3d/matrix_transform.x3d", "MatrixTransform: spheres and a box, 1 lamp",
          "the converter writes each MatrixTransform (a Castle Game Engine node, not X3D, "
          "which X_ITE does not draw) as the Transform of the same matrix, so all three "
          "spheres show; their ground shadows agree"),
    # ClassicVRML and VRML 97
    Entry(CLASSIC, "x3d/matrix_transform.x3dv", "the same scene in ClassicVRML",
          "as its XML twin"),
    Entry(CLASSIC, "lights_materials/directional_light_scope.wrl",
          "VRML 97: six spheres, two suns each scoped to its group",
          "X_ITE fault: the blue sun is non-global in a moved Transform (translation 0 -3 0), "
          "and X_ITE draws no shadow for such a light (control scene 1 below); baked: the "
          "lower-left sphere's shadow on the lit side of the spheres behind it in the sun's "
          "path (blue). The output says global FALSE on both suns: X_ITE takes a VRML 97 "
          "DirectionalLight with none as global, the standard keeps it to its group",
          xite_fault=True),
    Entry(CLASSIC, "lights_materials/light_radius.wrl",
          "VRML 97: two grids of 512 cubes, a point and a spot light with a radius",
          "X_ITE aliasing: many tiny cube shadows, a few pixels each, mostly agreeing; the "
          "rest is 1-2 pixel offsets at their edges and the spot's lit ellipse, whose rim "
          "is a staircase of shadow-map texels at run time and smooth baked (red and blue "
          "specks). The cubes (transparency 0.3) cast black at run time and 11/16 dark "
          "baked, as their opacity says",
          xite_fault=True),
    Entry(CLASSIC, "lights_materials/lights.x3dv",
          "spheres, cone and box under a lamp, a spot and a sun (three USEd groups)",
          "X_ITE fault: the sun, non-global, is USEd in the groups moved to x 20 and 40, and "
          "X_ITE draws no shadow for such a light (control scene 1 below); baked: in the "
          "group at x 20, the cone's shadow on the box's front (the sun, 1 0 -1, carries "
          "the cone at z 4 onto the box at x 4) (blue)",
          xite_fault=True),
    Entry(CLASSIC, "lights_materials/raytracer/alien_mirror.wrl",
          "VRML 97: an alien head before a wall, 2 lamps",
          "agree on the wall; baked: a few shards on the head (its own faces)"),
    Entry(CLASSIC, "lights_materials/light_location_animated.x3dv",
          "3 spheres, a lamp moved by an interpolator (stopped: at 0 0 0)",
          "the lamp is inside the yellow sphere (the file's animation moves it out): no light "
          "gets out, so X_ITE draws all dark, and shadowgeo bakes all the lamp faces outside "
          "the sphere (the ground, the outer spheres' lit sides) in its shadow"),
    Entry(CLASSIC, "lights_materials/light_transform_animated.x3dv",
          "3 spheres, a lamp under an animated Transform (stopped)",
          "the spheres' large ground shadows agree; the lamp's marker sphere (radius 0.1) "
          "round it is taken for its bulb and casts nothing, as in X_ITE (its shadow maps "
          "start 0.125 from the light)"),
    Entry(CLASSIC, "x3d/material_parameters_x3dom_xite_tests/material_parameters.x3dv",
          "11 spheres, a lamp, animated materials (stopped)",
          "the spheres' ground shadows agree (the lamp's marker sphere is its bulb, as in "
          "light_transform_animated)"),
    Entry(CLASSIC,
          "animation/simple_tests_interpolation_and_time/orientation_interpolator_aluminium.wrl",
          "VRML 97: a tube under 6 scoped suns, turned by an interpolator (stopped)",
          "no floor: the converter adds a ground inside the suns' group (their scope, so they "
          "light it in every browser), and the tube's shadows on it agree"),
    Entry(CLASSIC,
          "animation/simple_tests_interpolation_and_time/orientation_interpolator_alum_box.wrl",
          "VRML 97: the same with a box", "as the tube: the shadows on the added ground agree"),
    # corpus scenes with lights in which neither picture shows a shadow to speak of
    Entry(CLASSIC, "lights_materials/directional_light_scope_simple.x3dv",
          "a quad and a sphere, two scoped suns", "neither picture has a shadow"),
    Entry(CLASSIC, "lights_materials/house_behind_the_glass.x3dv",
          "a glass sphere mesh, 1 lamp",
          "the glass sphere's shadow on the floor agrees (X_ITE's darker)"),
    Entry(CLASSIC, "lights_materials/light_attenuation.x3dv",
          "two small spheres, a lamp and a spot", "neither picture has a shadow"),
    Entry(CLASSIC, "lights_materials/non_global_lights_test.x3dv",
          "a corner and a sphere, 2 non-global lamps", "neither picture has a shadow"),
    Entry(CLASSIC, "x3d/shininess_phong_lighting_effect.x3dv",
          "5 quads under 5 lamps", "neither picture has a shadow"),
    Entry(CLASSIC, "prototypes/proto_events_test.x3dv",
          "a sphere, a sun inside a PROTO", "neither picture has a shadow (one sphere)"),
    Entry(CLASSIC, "lights_materials/sphere.x3dv", "a sphere and a half sphere, 1 sun",
          "a few pixels only: X_ITE's acne speckles along the lit sphere's terminator"),
    Entry(CLASSIC, "lights_materials/light_color_animated.x3dv",
          "3 spheres, a lamp of animated colour (stopped)",
          "the spheres' ground shadows agree"),
]  # fmt: skip

# Corpus files with a light node that are not in the table, and why (none skipped silently).
EXCLUDED = [
    (f"{CLASSIC}/lights_materials/specular_demo.wrl",
     "X_ITE draws this VRML 97 input all black, even untouched (the converted X3D draws)"),
    (f"{CLASSIC}/lights_materials/raytracer/bowl_of_soup_final.x3dv",
     "its geometry is Inlined from a VRML 1.0 file, which shadowgeo does not read"),
    (f"{CLASSIC}/lights_materials/raytracer/office_final.x3dv",
     "its geometry is Inlined from a VRML 1.0 file, which shadowgeo does not read"),
    (f"{CLASSIC}/lights_materials/raytracer/graz_final.x3dv",
     "its geometry, graz.wrl, is not in the corpus"),
    (f"{CLASSIC}/x3d/dynamic_world.x3dv", "its geometry is made by a Script at run time"),
    (f"{CLASSIC}/background/background_sunset.x3dv", "no geometry: a Background and a light"),
    (f"{CLASSIC}/x3d/are_set_changed_optional.x3dv",
     "its only light is off: X_ITE draws no shadow to compare with (shadowgeo bakes its "
     "default sun's, as documented; --sun or --light choose another)"),
    (f"{CLASSIC}/prototypes/proto_events_test_2.x3dv",
     "the sphere and sun of proto_events_test.x3dv; only the events differ"),
    (f"{CLASSIC}/prototypes/proto_events_test_3.x3dv",
     "the sphere and sun of proto_events_test.x3dv; only the events differ"),
    (f"{CLASSIC}/lights_materials/headlight_anim.x3dv",
     "its only light is a NavigationInfo headlightNode (Castle extension)"),
    (f"{CLASSIC}/lights_materials/headlight_custom.wrl",
     "its only lights are NavigationInfo headlightNodes (Castle extension)"),
    (f"{CLASSIC}/x3d/kings_head.x3dv", "its only light sits in a Switch choice not shown"),
    (f"{CLASSIC}/prototypes/extern_proto_built_in_kings_head.wrl",
     "its only light sits in a Switch choice not shown"),
    (f"{CLASSIC}/lights_materials/raytracer/raytracer_simple_shadow.wrl", "VRML 1.0"),
    (f"{CLASSIC}/lights_materials/raytracer/raytracer_spot_on_square.wrl", "VRML 1.0"),
    (f"{CLASSIC}/lights_materials/raytracer/raytracer_very_specular.wrl", "VRML 1.0"),
    (f"{CLASSIC}/lights_materials/vrml_1/forest-fog/forest-final.wrl", "VRML 1.0"),
    (f"{CLASSIC}/lights_materials/vrml_1/lights.wrl", "VRML 1.0"),
    (f"{CLASSIC}/lights_materials/vrml_1/materials.wrl", "VRML 1.0"),
]  # fmt: skip


# Control scenes for X_ITE faults named in the table: the same two unit
# spheres on the x axis under a blue sun travelling +x (the left one shadows
# the right one's lit side), the sun non-global (its shadow then reaches only
# the spheres of its group), a red sun from above lighting all. The scenes
# differ only in where that group lies.
_CONTROL = """<X3D profile="Immersive" version="4.0"><Scene>
<NavigationInfo headlight="false"/><Viewpoint position="0 {y} 12"/>
<DirectionalLight color="1 0 0" direction="0 -1 -1"/>
<{group}><DirectionalLight color="0 0 1" direction="1 0 0" global="false" shadows="true"/>
<Transform translation="-3 0 0"><Shape><Appearance><Material/></Appearance><Sphere/></Shape>
</Transform><Transform translation="3 0 0"><Shape><Appearance><Material/></Appearance>
<Sphere/></Shape></Transform></{tag}></Scene></X3D>
"""
CONTROLS = [
    ("1a: the sun's group is a Group", "Group", "Group", 0),
    ("1b: the sun's group is a Transform, translation 0 0 0", 'Transform translation="0 0 0"',
     "Transform", 0),
    ("1c: the sun's group is a Transform, translation 0 -3 0 (directional_light_scope.wrl's)",
     'Transform translation="0 -3 0"', "Transform", -3),
]  # fmt: skip


def controls(work: Path, size: int, browser: str, timeout: float) -> list[tuple[str, int]]:
    """Each control scene with the shadow pixels X_ITE draws (its picture with
    runtime shadows against the same with none, the table's mask rule)."""
    work.mkdir(parents=True, exist_ok=True)
    canvases = []
    for index, (_, group, tag, y) in enumerate(CONTROLS):
        (work / f"control{index}.x3d").write_text(_CONTROL.format(group=group, tag=tag, y=y))
        canvases += [Canvas(f"control{index}.x3d"), Canvas(f"control{index}.x3d", shadows="off")]
    shots = render(work, canvases, size, browser, timeout)
    found = []
    for index, (title, *_) in enumerate(CONTROLS):
        lit, plain = shots[2 * index], shots[2 * index + 1]
        ok = lit.status == "ok" and plain.status == "ok"
        found.append((title, int(shadow_mask(lit.image, plain.image).sum()) if ok else -1))
    return found


def row(entry: Entry, result: Comparison | None, seconds: float, failure: str = "") -> dict:
    runtime, baked = result.masks if result and result.masks is not None else (None, None)
    problems = ([failure] if failure else []) + (result.problems if result else [])
    return {
        "scene": entry.name,
        "lights": len(set(result.casting)) if result else 0,
        "runtime": None if runtime is None else int(runtime.sum()),
        "baked": None if baked is None else int(baked.sum()),
        "iou": result.iou if result else math.nan,
        "brighter": result.brighter if result else 0,
        "notes": "; ".join(filter(None, [*problems, entry.seen])),
        "xite_fault": entry.xite_fault,
        "seconds": seconds,
        "image": None,
    }


def measure(entry: Entry, work: Path, size: int, browser: str, timeout: float) -> dict:
    """One table row (and the gallery image, kept in the row) for ``entry``."""
    begin = time.perf_counter()
    source = entry.folder / entry.path
    if not source.is_file():
        return row(entry, None, 0.0, f"missing: {source}")
    try:
        result = compare(source, entry.folder, work, size=size, browser=browser, timeout=timeout)
    except Exception as error:  # noqa: BLE001 - the row says why, the others still run
        return row(entry, None, time.perf_counter() - begin, f"{type(error).__name__}: {error}")
    found = row(entry, result, time.perf_counter() - begin)
    if len(result.shots) == 3:
        found["image"] = gallery_image(result, PANEL)
    return found


def fmt_iou(value: float) -> str:
    return "n/a" if math.isnan(value) else f"{value:.2f}"


def table(rows: list[dict], gallery: bool) -> str:
    lines = [
        "| scene | lights | runtime mask (a) | baked mask (b) | IoU | (b) lighter than (c) "
        "| notes |",
        "|---|---:|---:|---:|---:|---:|---|",
    ]
    for r in rows:
        name = r["scene"]
        if gallery and r["image"] is not None:
            name = f"[{name}](../docs/images/viewer/{slug(r['scene'])}.png)"
        counts = [("—" if r[k] is None else f"{r[k]:,}") for k in ("runtime", "baked")]
        lines.append(
            f"| {name} | {r['lights']} | {counts[0]} | {counts[1]} | {fmt_iou(r['iou'])} "
            f"| {r['brighter']:,} | {r['notes'].replace('|', '/')} |"
        )
    return "\n".join(lines)


def slug(name: str) -> str:
    return name.replace("/", "_").rsplit(".", 1)[0]


def counted(r: dict, size: int) -> bool:
    """Whether a row has a shadow to compare: a mask of at least
    :data:`SHADOW_SHARE` of the picture."""
    return max(r["runtime"] or 0, r["baked"] or 0) >= SHADOW_SHARE * size**2


def summary(rows: list[dict], size: int) -> str:
    measured = [r["iou"] for r in rows if counted(r, size)]
    failed = sum(r["runtime"] is None for r in rows)
    if not measured:
        return f"No scene has a shadow to compare ({failed} failed)."
    low = [r for r in rows if counted(r, size) and r["iou"] < 0.7]
    excused = sum(r["xite_fault"] for r in low)
    return (
        f"{len(measured)} of {len(rows)} scenes have a shadow to compare (a mask of at least "
        f"{SHADOW_SHARE:.1%} of the picture; {failed} failed to render): median IoU "
        f"{statistics.median(measured):.2f} (target 0.9), lowest {min(measured):.2f}; "
        f"{len(low)} under 0.7 (target: none), {excused} of them where X_ITE's own shadow "
        "map is wrong."
    )


def section(rows: list[dict], size: int, elapsed: float, checks: list[tuple[str, int]]) -> str:
    excluded = "\n".join(f"- `{path}`: {why}" for path, why in EXCLUDED)
    checked = "\n".join(
        f"| {title} | {'failed to render' if count < 0 else f'{count:,}'} |"
        for title, count in checks
    )
    return f"""{TITLE}

Generated by `python benchmarks/bench_viewer.py` ({elapsed / 60:.1f} minutes). For each scene,
X_ITE (the npm package in `tests/node`) in headless Chromium (SwiftShader) draws, on {size} x
{size} canvases from the same Viewpoint (the author's first, else the converter's overview,
bound in all three) with the headlight as the author set it: (a) the input as the converter
frames it, with runtime shadows on the lights shadowgeo bakes (`shadows TRUE` on those with
it, else on every light that is on; `shadowMapSize` 2048), (b) the output of `shadowgeo
convert IN OUT.x3d` (no flags) with `shadows FALSE` on every light, (c) the same as (a) with
`shadows FALSE` on every light; {FRAMES} frames after the set-up. "The input as the converter
frames it" is the output less its baked shadow shapes (the shapes of class
`shadowgeo-shadows-shadow`), the baked lights' `shadows TRUE` given back: the input's nodes,
plus the light-grey ground the converter adds under a scene with no floor when the ground
plane receives (and the Viewpoint it adds to a scene with none). Drawn from the input itself,
(a) would have nothing to cast onto where the baked shadows lie on that ground, and (b) would
differ from (c) by the ground as well as the shadows; this way the three pictures show the
same scene and differ only by their shadows (the ground has `castShadow FALSE` there: it
only receives, as in the converter's own shadows). The scene is drawn from a copy of its folder in
which every TimeSensor has `enabled FALSE`, so all three show the file's own state, the one
shadowgeo bakes. A pixel is in a shadow mask when it is darker than in (c) by more than {DROP}
of full scale and by more than {RELATIVE:.0%} of its value in (c) (Rec. 709 luminance). IoU is
|a and b| / |a or b| of the two masks (n/a: both empty); the median and the targets count the
scenes with a mask of at least {SHADOW_SHARE:.1%} of the picture. "(b) lighter than (c)"
counts pixels the conversion made lighter by the same threshold: baked shadows only darken, so
anything there is a change besides the shadows (it should be none, now that (c) is the output
less its shadows). "lights" are the lights shadowgeo bakes (each node once). Notes give what
kept a scene from being measured, and what the pictures show (judged by eye), X_ITE's own
shadow-map faults (acne, light leaking, peter-panning) named as such.

{summary(rows, size)}

{table(rows, gallery=True)}

Each scene name links to its gallery picture: (a) runtime, (b) baked, and the masks over
(c) in grey: green where both shadow, red where only X_ITE's runtime shadow does, blue where
only the baked one does.

Control scenes for the X_ITE fault named "control scene 1" above (written by the benchmark,
drawn the same way, shadow pixels by the same mask rule): two unit spheres on the x axis at
x = -3 and 3 under a blue sun travelling +x with `global FALSE` and `shadows TRUE`, both
spheres in its group, so the left one shadows the right one's lit side. X_ITE draws that
shadow when the group is a Group or an unmoved Transform, and none when the same Transform is
moved:

| control scene | shadow pixels X_ITE draws |
|---|---:|
{checked}

Corpus files with a light that are not in the table, and why:

{excluded}
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=512, help="canvas pixels (default 512)")
    parser.add_argument("--timeout", type=float, default=90.0, help="seconds per scene step")
    parser.add_argument("--only", nargs="+", help="scenes whose name contains one of these")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()
    browser = TOOLS["chromium"][0]()
    if browser is None or TOOLS["x_ite"][0]() is None:
        sys.exit("needs Chromium and X_ITE (npm ci --prefix tests/node)")
    entries = [e for e in SCENES if not args.only or any(word in e.name for word in args.only)]
    begin = time.perf_counter()
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench-viewer-") as scratch:
        for index, entry in enumerate(entries):
            work = Path(scratch) / str(index)
            found = measure(entry, work, args.size, str(browser), args.timeout)
            shutil.rmtree(work, ignore_errors=True)
            rows.append(found)
            print(
                f"{entry.name}: IoU {fmt_iou(found['iou'])} ({found['seconds']:.0f} s) "
                f"{found['notes']}",
                flush=True,
            )
        checks = controls(Path(scratch) / "controls", args.size, str(browser), args.timeout)
    for title, count in checks:
        print(f"control {title}: {count:,} shadow pixels")
    elapsed = time.perf_counter() - begin
    print()
    print(summary(rows, args.size))
    print(table(rows, gallery=False))
    if args.no_write:
        return
    GALLERY.mkdir(parents=True, exist_ok=True)
    if args.only is None:  # a full run replaces the whole gallery
        for old in GALLERY.glob("*.png"):
            old.unlink()
    for r in rows:
        if r["image"] is not None:
            r["image"].save(GALLERY / f"{slug(r['scene'])}.png", optimize=True)
    if args.only is None:
        write_section(TITLE, section(rows, args.size, elapsed, checks))
        print(f"wrote {GALLERY} and the section {TITLE[3:]!r} of benchmarks/REPORT.md")


if __name__ == "__main__":
    main()
