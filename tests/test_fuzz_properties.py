"""Robustness properties under random and mutated input (hypothesis, derandomized).

* readers: a mutated small X3D document gives a Scene or a SceneError, nothing else;
* converter: ``shadowgeo convert`` exits 0, 1 or 2, writes nothing when it fails,
  never touches its input and writes no NaN or inf;
* geometry: project_shadow, silhouette and shadow_volume return finite results
  that agree with independent references, or raise GeometryError;
* tools/fuzz.py itself runs end to end on a handful of inputs.

The ranges stay inside what works today; the known findings in
``../shared/findings/robustness`` (huge light radii, Extrusion with empty
fields, coordinates past ~1e100, denormal sizes, near-degenerate triangles)
are left out until their fixes land: see the ``# widen after`` notes.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import random
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest
import shapely
import trimesh
from fuzz_replay import fuzz_module
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from reference import basis

import shadowgeo as sg
from cli.main import main as cli_main

ROOT = Path(__file__).resolve().parents[1]
FUZZ = ROOT / "tools" / "fuzz.py"
SETTINGS = dict(
    derandomize=True,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)


mutate = fuzz_module("mutate").mutate
non_finite_in_output = fuzz_module("check_output").non_finite_in_output
ddmin = fuzz_module("shrink").ddmin

# -- small X3D documents -----------------------------------------------------------------------

# Numbers a field may get. Widen after the fixes land: 1e155 and 1e300 (r1, r3,
# r9, r10 in the findings), 1e-320 (r8, denormal sizes are very slow), 1e103 (r5).
NUMBERS = st.sampled_from(
    ["0", "-0", "1", "-1", "2.5", "0.001", "1000", "1e6", "-1e6", "1e-6", "1e30", "-7", "3e-5"]
)
# Hostile values reach the documents through the campaign's own mutations
# (nan, inf, 1e308, 1e-320 and huge counts, one field at a time), so that a
# document is not rejected for its first bad number every time.
INDICES = st.sampled_from(["0", "1", "2", "3", "-1", "-2", "4", "99", "2147483647", "x"])


def numbers(count: int):
    """An MF field: up to ``count`` numbers."""
    return st.lists(NUMBERS, min_size=0, max_size=count).map(" ".join)


def vector(size: int):
    """An SF field of ``size`` numbers (SFFloat, SFVec3f, SFRotation)."""
    return st.lists(NUMBERS, min_size=size, max_size=size).map(" ".join)


def geometry_nodes():
    face_set = st.builds(
        lambda index, point, solid: (
            f'<IndexedFaceSet solid="{solid}" coordIndex="{index}">'
            f'<Coordinate point="{point}"/></IndexedFaceSet>'
        ),
        st.lists(INDICES, max_size=12).map(" ".join),
        numbers(12),
        st.sampled_from(["true", "false", "maybe"]),
    )
    sizes = vector(3)
    return st.one_of(
        face_set,
        sizes.map(lambda s: f'<Box size="{s}"/>'),
        # Sphere radius: widen after r8 (denormal radii) is fixed.
        st.sampled_from(["1", "0", "-1", "nan", "inf", "0.5"]).map(
            lambda r: f'<Sphere radius="{r}"/>'
        ),
        st.builds(lambda r, h: f'<Cone bottomRadius="{r}" height="{h}"/>', vector(1), vector(1)),
        st.builds(lambda r, h: f'<Cylinder radius="{r}" height="{h}"/>', vector(1), vector(1)),
        # Extrusion without empty orientation/scale: widen after r2 is fixed.
        st.just('<Extrusion crossSection="1 1 1 -1 -1 -1 -1 1 1 1"/>'),
        st.just("<Text/>"),
    )


def shape_nodes():
    return st.builds(
        lambda name, geometry: f'<Shape DEF="{name}">{geometry}</Shape>',
        st.sampled_from(["a", "b", "ground", "a"]),
        geometry_nodes(),
    )


def light_nodes():
    return st.builds(
        lambda kind, where, shadows, on: (
            f'<{kind} location="{where}" direction="{where}" shadows="{shadows}" on="{on}"/>'
        ),
        st.sampled_from(["PointLight", "SpotLight", "DirectionalLight"]),
        vector(3),
        st.sampled_from(["true", "false"]),
        st.sampled_from(["true", "false"]),
    )


def children(depth: int):
    viewpoint = st.just('<Viewpoint position="0 1 9"/>')
    leaf = st.one_of(shape_nodes(), shape_nodes(), shape_nodes(), light_nodes(), viewpoint)
    if depth == 0:
        return leaf
    inner = st.lists(children(depth - 1), max_size=3).map("".join)
    transform = st.builds(
        lambda t, s, r, body, use: (
            f'<Transform DEF="t{use}" translation="{t}" scale="{s}" rotation="{r}">{body}'
            f'<Transform USE="t{use}"/></Transform>'
            if use
            else f'<Transform translation="{t}" scale="{s}" rotation="{r}">{body}</Transform>'
        ),
        vector(3),
        vector(3),
        vector(4),
        inner,
        st.sampled_from(["", "", "", "1"]),  # "1": a DEF/USE cycle
    )
    return st.one_of(leaf, transform, inner.map(lambda b: f"<Group>{b}</Group>"))


documents = st.lists(children(2), min_size=1, max_size=4).map(
    lambda nodes: f'<X3D version="4.0"><Scene>{"".join(nodes)}</Scene></X3D>'
)


@settings(max_examples=80, **SETTINGS)
@given(document=documents, cut=st.integers(0, 10_000), mutation=st.integers(0, 2**32 - 1))
def test_a_mutated_x3d_document_gives_a_scene_or_a_scene_error(document, cut, mutation):
    data = document.encode()
    if mutation % 4 == 1:
        data = data[: cut % (len(data) + 1)]  # truncated
    elif mutation % 4 >= 2:
        # the campaign's own structure and meaning mutations
        data, _ = mutate(data, "x3d", random.Random(mutation), [])
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "scene.x3d"
        path.write_bytes(data)
        try:
            scene = sg.load(path)
        except sg.SceneError as error:
            assert str(error)  # a message, naming what is wrong
            return
    assert isinstance(scene, sg.Scene)
    for shape in scene.shapes:
        assert shape.faces.ndim == 2 and shape.faces.shape[1] == 3
        if len(shape.faces):
            assert shape.faces.min() >= 0 and shape.faces.max() < len(shape.vertices)


# -- the converter -----------------------------------------------------------------------------

# A scene that casts: a ground, a box above it, a light. The fields vary within
# what works today. Widen after the fixes: a radius past 1e100 (r1, r9),
# translations past 1e100 (r3, r10), scales past 1e102 (r5), a Viewpoint at inf (r4).
MODEST = st.sampled_from(["0", "1", "-1", "2.5", "0.001", "1000", "-3", "1e-6", "1e6"])


@settings(max_examples=30, **SETTINGS)
@given(
    light=st.sampled_from(["PointLight", "SpotLight", "DirectionalLight"]),
    location=st.lists(MODEST, min_size=3, max_size=3).map(" ".join),
    direction=st.lists(MODEST, min_size=3, max_size=3).map(" ".join),
    radius=st.sampled_from(["1", "100", "1e6", "-1", "0", "nan", "inf"]),
    translation=st.lists(MODEST, min_size=3, max_size=3).map(" ".join),
    size=st.lists(MODEST, min_size=3, max_size=3).map(" ".join),
    output=st.sampled_from([".x3d", ".glb", ".usda"]),
    options=st.sampled_from(
        [[], ["--method", "volume"], ["--sun", "0.3,-1,0.2"], ["--plane", "0"]]
    ),
)
def test_the_converter_exits_0_1_or_2_and_writes_nothing_when_it_fails(
    light, location, direction, radius, translation, size, output, options
):
    document = (
        '<X3D version="4.0"><Scene>'
        '<Shape DEF="ground"><IndexedFaceSet solid="false" coordIndex="0 1 2 3 -1">'
        '<Coordinate point="-9 0 -9 9 0 -9 9 0 9 -9 0 9"/></IndexedFaceSet></Shape>'
        f'<Transform translation="{translation}"><Shape><Box size="{size}"/></Shape></Transform>'
        f'<{light} location="{location}" direction="{direction}" radius="{radius}" '
        'shadows="true"/></Scene></X3D>'
    )
    with tempfile.TemporaryDirectory() as folder:
        source = Path(folder) / "scene.x3d"
        source.write_text(document)
        target = Path(folder) / "out" / f"result{output}"
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            try:
                code = cli_main(["convert", str(source), str(target), *options])
            except SystemExit as error:  # argparse: bad usage
                code = error.code
        assert code in (0, 1, 2)
        assert source.read_text() == document
        if code != 0:
            assert not target.parent.exists() or not any(target.parent.iterdir())
        else:
            assert target.is_file()
            assert non_finite_in_output(target) is None


# -- the geometry API --------------------------------------------------------------------------

# Scales within what works today; widen to 1e-150..1e150 after a1-a7 (overflow,
# Clipper range, negative area of near-degenerate triangles) are fixed.
SCALES = st.sampled_from([1e-6, 1e-3, 1.0, 1.0, 1e3, 1e6])


def well_shaped(points: np.ndarray) -> bool:
    """No triangle thinner than 1e-3 of its longest edge (near-degenerate ones are a6)."""
    for a, b, c in points.reshape(-1, 3, 3):
        area = 0.5 * np.linalg.norm(np.cross(b - a, c - a))
        longest = max(np.linalg.norm(b - a), np.linalg.norm(c - b), np.linalg.norm(a - c))
        if area < 1e-3 * longest**2:
            return False
    return True


@settings(max_examples=80, **SETTINGS)
@given(
    seed=st.integers(0, 2**32 - 1),
    count=st.integers(1, 8),
    scale=SCALES,
    height=st.floats(1.5, 20.0),
    light_kind=st.sampled_from(["point", "sun"]),
)
def test_a_shadow_between_plane_and_light_is_the_union_of_projected_triangles(
    seed, count, scale, height, light_kind
):
    rng = np.random.default_rng(seed)
    normal = rng.normal(size=3)
    normal /= np.linalg.norm(normal)
    u, v = basis(normal)
    points = rng.uniform(-1, 1, size=(3 * count, 2)) @ np.array([u, v])
    points += rng.uniform(0.2, 1.0, size=(3 * count, 1)) * normal  # strictly above the plane
    if not well_shaped(points):
        return
    plane = sg.Plane(normal, -float(normal @ (scale * np.array([3.0, -2.0, 1.0]))))
    origin = scale * np.array([3.0, -2.0, 1.0])
    vertices = origin + scale * points
    faces = np.arange(3 * count).reshape(-1, 3)
    if light_kind == "point":
        light = sg.PointLight(origin + scale * (height * normal + rng.uniform(-1, 1) * u))
        light_h = np.append(light.position, 1.0)
    else:
        light = sg.DirectionalLight(-normal + 0.4 * rng.uniform(-1, 1) * u)
        light_h = np.append(-light.direction, 0.0)
    shadow = sg.project_shadow((vertices, faces), light, plane)
    expected = reference_area(vertices[faces], light_h, plane)
    assert shadow.area >= 0 and math.isfinite(shadow.area)
    assert np.all(np.isfinite(shadow.mesh.vertices))
    assert abs(shadow.area - expected) <= 1e-6 * expected
    outline = sg.silhouette((vertices, faces), light)
    for loop in outline.loops:
        assert len(loop) >= 3


def reference_area(triangles: np.ndarray, light_h: np.ndarray, plane: sg.Plane) -> float:
    """The textbook matrix, each triangle a shapely polygon, their union's area."""
    plane_vector = np.append(plane.normal, plane.offset)
    matrix = (plane_vector @ light_h) * np.eye(4) - np.outer(light_h, plane_vector)
    origin = triangles.reshape(-1, 3).mean(axis=0)
    moved = np.append(plane.normal, plane.offset + plane.normal @ origin)
    light = light_h.copy()
    if light[3]:
        light[:3] -= origin
    matrix = (moved @ light) * np.eye(4) - np.outer(light, moved)
    points = triangles.reshape(-1, 3) - origin
    projected = np.column_stack([points, np.ones(len(points))]) @ matrix.T
    projected = projected[:, :3] / projected[:, 3:]
    u, v = basis(plane.normal)
    flat = np.column_stack([projected @ u, projected @ v]).reshape(-1, 3, 2)
    return float(shapely.union_all(shapely.polygons(flat)).area)


@settings(max_examples=60, **SETTINGS)
@given(
    seed=st.integers(0, 2**32 - 1),
    points=st.integers(4, 16),
    scale=SCALES,
    light_kind=st.sampled_from(["point", "sun", "grazing", "near"]),
)
def test_a_shadow_volume_is_closed_and_outward_or_a_geometry_error(seed, points, scale, light_kind):
    rng = np.random.default_rng(seed)
    hull = trimesh.convex.convex_hull(rng.normal(size=(points, 3)))
    if hull.volume < 1e-3:
        return  # flat hulls: a caster edge-on to a grazing light is the "flat volume" finding
    vertices = hull.vertices * scale
    direction = rng.normal(size=3)
    if light_kind == "point":
        light = sg.PointLight(scale * 5 * direction / np.linalg.norm(direction))
    elif light_kind == "near":  # just outside a vertex
        vertex = vertices[int(rng.integers(len(vertices)))]
        light = sg.PointLight(vertex * (1 + 1e-3))
    elif light_kind == "grazing":
        light = sg.DirectionalLight(direction + np.array([0, 0, 1e-9]))
    else:
        light = sg.DirectionalLight(direction)
    try:
        volume = sg.shadow_volume((vertices, hull.faces), light)
    except sg.GeometryError:
        return
    assert np.all(np.isfinite(volume.vertices))
    if len(volume.faces):
        assert volume.is_watertight and volume.is_winding_consistent
        centred = volume.vertices - volume.vertices.mean(axis=0)
        unit = trimesh.Trimesh(centred / np.abs(centred).max(), volume.faces, process=False)
        assert unit.volume > 0
        # The caster's own interior is inside the volume.
        assert unit.contains(
            [(hull.centroid * scale - volume.vertices.mean(axis=0)) / np.abs(centred).max()]
        )[0]


@settings(max_examples=60, **SETTINGS)
@given(
    values=st.lists(
        st.sampled_from([0.0, -0.0, 1.0, -1.0, 1e-9, 1e6, math.nan, math.inf]),
        min_size=9,
        max_size=9,
    ),
    light=st.lists(
        st.sampled_from([0.0, 1.0, -2.0, 5.0, math.nan, math.inf]), min_size=3, max_size=3
    ),
    normal=st.lists(st.sampled_from([0.0, 1.0, -1.0, math.nan]), min_size=3, max_size=3),
)
def test_odd_numbers_give_a_finite_shadow_or_a_geometry_error(values, light, normal):
    vertices = np.array(values).reshape(3, 3)
    try:
        shadow = sg.project_shadow(
            (vertices, [[0, 1, 2]]), sg.PointLight(light), sg.Plane(normal, 0.5)
        )
    except sg.GeometryError:
        return
    assert math.isfinite(shadow.area) and shadow.area >= 0
    assert np.all(np.isfinite(shadow.mesh.vertices))


# -- the campaign tool -------------------------------------------------------------------------


def test_ddmin_finds_the_smallest_failing_subset():
    calls = []

    def reproduces(candidates):
        calls.append(len(candidates))
        for index, candidate in enumerate(candidates):
            if 3 in candidate and 17 in candidate:
                return index
        return None

    found = ddmin(list(range(40)), reproduces, [1000])
    assert found == [3, 17]
    budget = [5]
    ddmin(list(range(40)), reproduces, budget)
    assert budget[0] <= 0  # the bound on tries holds


def test_mutants_are_reproducible_and_change_the_input():
    seed = b'<X3D><Scene><Shape><Box size="1 2 3"/></Shape></Scene></X3D>'
    first = [mutate(seed, "x3d", random.Random(i), [seed]) for i in range(30)]
    again = [mutate(seed, "x3d", random.Random(i), [seed]) for i in range(30)]
    assert first == again
    assert sum(data != seed for data, _ in first) >= 20  # a few operations find nothing to do


def test_the_output_check_finds_non_finite_numbers(tmp_path):
    bad = tmp_path / "bad.x3d"
    bad.write_text('<X3D><Scene><Viewpoint position="0 inf 0" description="inf"/></Scene></X3D>')
    good = tmp_path / "good.x3d"
    good.write_text('<X3D><Scene><Viewpoint position="0 1 0" description="inf"/></Scene></X3D>')
    assert "position" in non_finite_in_output(bad)
    assert non_finite_in_output(good) is None
    usda = tmp_path / "bad.usda"
    usda.write_text(
        '#usda 1.0\ndef Mesh "m" (doc = "inf") {\n  point3f[] points = [(0, nan, 0)]\n}\n'
    )
    assert non_finite_in_output(usda) is not None


def test_the_campaign_runs_end_to_end(tmp_path):
    out = tmp_path / "campaign"
    command = [sys.executable, str(FUZZ), "--inputs", "3", "--geometry", "4", "--seed", "5"]
    command += ["--out", str(out), "--encodings", "x3d,wrl", "--jobs", "1", "--no-known"]
    command += ["--time-budget", "30", "--shrink-tries", "10", "--quiet"]
    finished = subprocess.run(command, capture_output=True, text=True, timeout=240, cwd=ROOT)
    assert finished.returncode in (0, 1), finished.stderr[-2000:]
    runs = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    assert len([r for r in runs if r.get("encoding") == "x3d"]) == 3  # examples/scenes
    assert len([r for r in runs if "case" in r]) == 4
    # Each run passed with exit 0, 1 or 2 or carries a failure signature; .wrl
    # (no reader today, so exit 1 "cannot read") is mutated all the same.
    assert all(r["code"] in (0, 1, 2) if r["ok"] else r["signature"] for r in runs)
    if (ROOT.parent / "shared" / "corpus").is_dir():  # .wrl seeds come from the corpus only
        assert len([r for r in runs if r.get("encoding") == "wrl"]) == 3
    failing = {r["signature"] for r in runs if not r["ok"]}
    assert (finished.returncode == 1) == bool(failing)
    summary = (out / "summary.md").read_text()
    assert "| encoding | runs |" in summary
    for signature in failing:
        assert signature in summary
    folders = sorted((out / "failures").glob("*")) if failing else []
    assert len(folders) == len(failing)


@pytest.fixture(autouse=True)
def _quiet_numpy():
    with np.errstate(all="ignore"):
        yield


def _copied_out_reference(text: str) -> str | None:
    """The check as it was, copying the text out (strings, then comments,
    dropped): the reference for the scan in place."""
    import re

    text = re.sub(r'"(?:[^"\\]|\\.)*"', '""', text)
    text = re.sub(r"#[^\n]*", "", text)
    match = re.search(r"(?<![\w\"])[-+]?(nan|inf|infinity)(?![\w\"])", text, re.IGNORECASE)
    return None if match is None else match.group(0)


def test_the_output_check_scans_in_place_as_the_copying_check_did(tmp_path, monkeypatch):
    # The seed-42 campaign's x3dv mutant 5761 (1,000 copies) wrote a 546 MB
    # USDA; copying its text out took the check past the worker's memory
    # budget. The check now scans the file in place, lowered a chunk at a
    # time: chunks of 7 bytes here, so that words straddle them.
    check_output = fuzz_module("check_output")
    monkeypatch.setattr(check_output, "_CHUNK", 7)
    rng = random.Random(42)
    words = ["nan", "NaN", "-inf", "+Infinity", "info:id", "infinite", "0.5", "1e3", "x_nan"]
    words += ['"nan"', '"a b"', "# inf here\n", "\n", " ", ",", "(", ")", "[", "=", "nanx"]
    for case in range(300):
        text = "#usda 1.0\n" + "".join(rng.choice(words) + rng.choice(" \n,") for _ in range(12))
        path = tmp_path / f"case{case}.usda"
        path.write_text(text)
        expected = _copied_out_reference(text)
        found = check_output.non_finite_in_output(path)
        assert (found is None) == (expected is None), (text, found, expected)
