"""The command line, run as a user runs it (a subprocess): the bundled example
converted to X3D, glTF and USD and checked by independent validators; the
added shadow against a shapely reference; bad input gives one line, no traceback."""

from __future__ import annotations

import hashlib
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import shapely
from lxml import etree
from reference import ray_plane
from validators import gltf_problems, gltf_report, usd_errors
from x3d_schema import x3d_schema_errors

import shadowgeo as sg
from cli.main import main

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "scenes" / "courtyard.x3d"
LAMP = np.array([3.0, 8.0, 4.0])  # the example's PointLight DEF="lamp"
SAFE = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False)


def shadowgeo_cli(*args, cwd=ROOT):
    return subprocess.run(
        [sys.executable, "-m", "cli", *map(str, args)],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=300,
    )


def in_process(capsys, *args):
    """The same command run in this process (faster than a subprocess)."""
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return subprocess.CompletedProcess(args, code, out, err)


def digest(path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


@pytest.fixture(scope="module")
def converted(tmp_path_factory):
    """The example converted once to each format through the command line."""
    folder = tmp_path_factory.mktemp("converted")
    before = digest(EXAMPLE)
    outputs = {}
    for suffix in (".x3d", ".glb", ".usda"):
        out = folder / f"courtyard{suffix}"
        done = shadowgeo_cli("convert", EXAMPLE, out)
        assert done.returncode == 0, done.stderr
        assert "wrote" in done.stdout and "Traceback" not in done.stderr
        outputs[suffix] = out
    assert digest(EXAMPLE) == before  # the input is never modified
    return outputs


def test_converting_an_x3d_or_plain_gltf_scene_imports_no_mesh_library(tmp_path):
    # trimesh (with scipy and networkx) takes about 1.4 s to import and
    # numba 0.8 s: an X3D or plain glTF scene converted to X3D or glTF needs
    # neither, nor does ``import shadowgeo``. They load when a caller asks for
    # a mesh (Shadow.mesh, shadow_volume, an OBJ input, a glTF trimesh decodes).
    script = f"""
import sys
import shadowgeo
assert "trimesh" not in sys.modules, "import shadowgeo imported trimesh"
from cli.main import main
for suffix in (".x3d", ".glb"):
    assert main(["convert", {str(EXAMPLE)!r}, {str(tmp_path)!r} + "/out" + suffix]) == 0
# a plain glTF in (as shadowgeo and most tools write it) is decoded without trimesh too
assert main(["convert", {str(tmp_path)!r} + "/out.glb", {str(tmp_path)!r} + "/again.x3d"]) == 0
# empty shadows (a light below the ground, a sun shining up), on either path
corners = [[0, 2, 0], [1, 2, 0], [0, 3, 0], [0, 2, 1]]
tetrahedron = (corners, [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
ground, square = shadowgeo.Plane([0, 1, 0], 0), [[-9, 0, -9], [9, 0, -9], [9, 0, 9], [-9, 0, 9]]
for light in (shadowgeo.PointLight([0, -5, 0]), shadowgeo.DirectionalLight([0, 1, 0])):
    for receiver in (None, square):
        assert shadowgeo.project_shadow(tetrahedron, light, ground, receiver=receiver).is_empty
print(sorted(name for name in ("trimesh", "scipy", "numba", "pyvista") if name in sys.modules))
"""
    done = subprocess.run(
        [sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().splitlines()[-1] == "[]"


def test_help_lists_examples(capsys):
    for command in ("convert", "info"):
        with pytest.raises(SystemExit) as exit_:
            main([command, "--help"])
        assert exit_.value.code == 0
        assert "examples:" in capsys.readouterr().out


def test_example_to_x3d_is_schema_valid_and_keeps_the_document(converted, x3d_schema):
    out = converted[".x3d"]
    assert x3d_schema_errors(out, x3d_schema) == []
    text = out.read_text()
    for kept in (
        "<!-- shadowgeo convert keeps this comment",
        'DEF="overview"',
        "<ROUTE",
        "TimeSensor",
    ):
        assert kept in text
    assert 'DEF="shadows_lamp"' in text and 'DEF="shadows_fill"' not in text


def test_example_to_glb_passes_the_khronos_validator(converted, node_tools):
    assert gltf_problems(gltf_report(converted[".glb"]), warnings=False) == []


def test_example_to_usda_passes_usd_validators(converted):
    assert usd_errors(converted[".usda"]) == []


def test_the_shadow_matches_a_union_of_projected_triangles(converted):
    """Reference: every caster triangle projected from the lamp onto y = 0 (all
    caster vertices lie below the lamp), united by shapely, cut to the ground."""
    scene = sg.load(EXAMPLE)
    triangles = []
    for shape in scene.shapes:
        if shape.name == "ground":
            continue
        world = shape.world_vertices
        assert world[:, 1].max() < LAMP[1]
        flat = ray_plane(world, LAMP, np.array([0.0, 1.0, 0.0]), 0.0)[:, [0, 2]]
        triangles += [shapely.Polygon(flat[f]) for f in shape.faces]
    triangles = [t for t in triangles if t.area > 0]
    expected = shapely.union_all(triangles).intersection(shapely.box(-6, -6, 6, 6))

    root = etree.parse(str(converted[".x3d"]), SAFE).getroot()
    (group,) = root.findall("Scene/Group[@DEF='shadows_lamp']")
    (shape,) = group.findall("Shape")
    geometry = shape.find("IndexedTriangleSet")
    points = np.array(geometry.find("Coordinate").get("point").replace(",", " ").split(), float)
    points = points.reshape(-1, 3)
    faces = np.array(geometry.get("index").split(), int).reshape(-1, 3)
    written = [shapely.Polygon(points[f][:, [0, 2]]) for f in faces]
    region = shapely.union_all(written)
    assert region.symmetric_difference(expected).area < 1e-9 * expected.area
    assert sum(p.area for p in written) == pytest.approx(expected.area, rel=1e-9)  # no overlaps
    # Lifted off the ground by 1e-3 of the scene's size, towards the lamp.
    assert np.ptp(points[:, 1]) == 0 and 0 < points[0, 1] < 0.1
    # shadowIntensity 0.7, but the fill light and the headlight still light the
    # ground in the lamp's shadow: drawn lighter (tests/test_darkness.py has the values)
    assert 0.3 < float(shape.find("Appearance/Material").get("transparency")) < 1.0


def test_info_prints_shapes_lights_and_what_was_skipped(capsys):
    done = in_process(capsys, "info", EXAMPLE)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    row = {
        line.split()[0]: line.split() for line in lines if line.startswith("  ") and line.split()
    }
    # Triangle counts: a quad is 2, the square pyramid 2 + 4, a box 12.
    assert row["ground"][1] == "2" and row["tent"][1] == "6" and row["crate"][1] == "12"
    assert row["lamp"][1:4] == ["PointLight", "on", "yes"] and row["fill"][3] == "no"
    assert "bounds: min -6 0 -6  max 6 3 6" in done.stdout
    # The Viewpoint: position 0 9 14, about +x by -0.571: looks along (0, -sin, -cos).
    assert row["overview"][1:4] == ["0", "9", "14"]
    assert "  0.000 -0.540 -0.841  45 deg " in done.stdout
    assert any("ROUTE" in line for line in lines)


def one_line_error(done, *fragments):
    assert done.returncode == 1, (done.returncode, done.stdout, done.stderr)
    assert "Traceback" not in done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


def test_malformed_xml_is_one_line_with_the_line_number(tmp_path):
    bad = tmp_path / "bad.x3d"
    bad.write_text('<?xml version="1.0"?>\n<X3D version="4.0">\n<Scene>\n<Shape>\n</Scene>\n')
    before = digest(bad)
    done = shadowgeo_cli("convert", bad, tmp_path / "out.x3d")
    one_line_error(done, "bad.x3d", "line")
    assert digest(bad) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.x3d"]  # nothing written


def test_missing_file_and_unknown_format(tmp_path):
    one_line_error(shadowgeo_cli("convert", tmp_path / "nope.x3d", tmp_path / "o.x3d"), "nope.x3d")
    one_line_error(shadowgeo_cli("info", tmp_path / "nope.x3d"), "nope.x3d")
    one_line_error(shadowgeo_cli("convert", EXAMPLE, tmp_path / "out.xyz"), "out.xyz", ".xyz")


@pytest.mark.parametrize("plane", ["1,2", "0,0,0,0"])
def test_bad_plane_is_bad_usage(tmp_path, plane):
    done = shadowgeo_cli("convert", EXAMPLE, tmp_path / "out.x3d", f"--plane={plane}")
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert "--plane" in done.stderr


@pytest.mark.parametrize("plane", ["a,b,c,d", "0,1,0,nan", "0,1,0,inf"])
def test_more_bad_planes(capsys, tmp_path, plane):
    with pytest.raises(SystemExit) as exit_:
        main(["convert", str(EXAMPLE), str(tmp_path / "out.x3d"), f"--plane={plane}"])
    assert exit_.value.code == 2 and "--plane" in capsys.readouterr().err


def test_receiver_and_plane_together_are_bad_usage(capsys, tmp_path):
    with pytest.raises(SystemExit) as exit_:
        main(["convert", str(EXAMPLE), str(tmp_path / "o.x3d"), "--receiver", "ground",
              "--plane", "0,1,0,0"])  # fmt: skip
    assert exit_.value.code == 2 and "not allowed with" in capsys.readouterr().err


def unlit_box(tmp_path) -> Path:
    """An X3D scene of one box and no light."""
    dark = tmp_path / "dark.x3d"
    dark.write_text(
        '<?xml version="1.0"?>\n<X3D version="4.0" profile="Interchange"><Scene>'
        "<Shape><Box/></Shape></Scene></X3D>\n"
    )
    return dark


def test_scene_without_lights_or_receiver_converts_with_no_flags(capsys, tmp_path):
    dark = unlit_box(tmp_path)
    out = tmp_path / "out.x3d"
    done = in_process(capsys, "convert", dark, out)
    assert done.returncode == 0, done.stderr
    assert "note: shadows: the scene has no lights; a default sun casts" in done.stderr
    assert "note: shadows: no receiver found" in done.stderr
    # By hand: the default sun along (0.3, -1, 0.2) onto the ground y = -1 under
    # the box [-1, 1]^3 moves its top face (2 above) by (0.6, 0.4) in (x, z):
    # the hull of the two squares, area 4 + 2 * 0.6 + 2 * 0.4 = 6.
    (shadow,) = sg.load(out).shapes_with_role("shadow")
    points = shadow.world_vertices
    region = shapely.union_all([shapely.Polygon(t) for t in points[shadow.faces][:, :, [0, 2]]])
    expected = shapely.union_all([shapely.box(-1, -1, 1, 1), shapely.box(-0.4, -0.6, 1.6, 1.4)])
    assert region.symmetric_difference(expected.convex_hull).area < 1e-9
    assert np.all(points[:, 1] > -1.0) and np.all(points[:, 1] < -0.99)  # lifted, not buried


def test_sun_lights_a_scene_without_lights(capsys, tmp_path):
    dark = unlit_box(tmp_path)
    out = tmp_path / "out.x3d"
    done = in_process(
        capsys, "convert", dark, out, "--plane", "0,1,0,3", "--sun", "1,-2,0", "--progress"
    )
    assert done.returncode == 0, done.stderr
    # By hand: the box [-1, 1]^3 under rays along (1, -2, 0) onto y = -3 moves
    # its top face by 2 in x and its bottom face by 1: x in [0, 3], z in [-1, 1].
    written = sg.load(out)
    shadows = [s for s in written.shapes if (s.name or "").startswith("shadow_sun")]
    assert len(shadows) == 1 and not written.lights  # the sun is not added to the scene
    points = shadows[0].world_vertices
    triangles = points[shadows[0].faces]
    area = (
        0.5
        * np.linalg.norm(
            np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]), axis=1
        ).sum()
    )
    assert area == pytest.approx(6.0, rel=1e-9)
    assert points[:, 0].min() == pytest.approx(0.0, abs=1e-9)
    assert points[:, 0].max() == pytest.approx(3.0, abs=1e-9)
    assert np.all(points[:, 1] > -3.0) and np.all(points[:, 1] < -2.9)  # lifted, not buried


@pytest.mark.parametrize("sun", ["0,0,0", "1,2", "a,b,c"])
def test_bad_sun_is_bad_usage(capsys, tmp_path, sun):
    with pytest.raises(SystemExit) as stop:
        main(["convert", str(EXAMPLE), str(tmp_path / "o.x3d"), "--sun", sun])
    assert stop.value.code == 2
    assert "--sun" in capsys.readouterr().err


def test_unknown_light_or_receiver_names_the_known_ones(capsys, tmp_path):
    done = in_process(capsys, "convert", EXAMPLE, tmp_path / "o.x3d", "--light", "sun")
    one_line_error(done, "no light named 'sun'", "fill, lamp")
    done = in_process(capsys, "convert", EXAMPLE, tmp_path / "o.x3d", "--receiver", "column")
    one_line_error(done, "'column' is not planar")


def test_output_onto_the_input_is_refused(capsys, tmp_path):
    copy = tmp_path / "scene.x3d"
    copy.write_bytes(EXAMPLE.read_bytes())
    one_line_error(in_process(capsys, "convert", copy, copy), "never overwritten")
    assert copy.read_bytes() == EXAMPLE.read_bytes()


def test_options_reach_the_library(capsys, tmp_path):
    out = tmp_path / "o.x3d"
    done = in_process(
        capsys, "convert", EXAMPLE, out, "--light", "fill", "--plane", "0,1,0,0", "--progress"
    )
    assert done.returncode == 0, done.stderr
    assert "100%" in done.stderr  # the bar, forced on although stderr is a pipe
    root = etree.parse(str(out), SAFE).getroot()
    assert [g.get("DEF") for g in root.findall("Scene/Group")] == ["shadows_fill"]
    quiet = in_process(capsys, "convert", EXAMPLE, tmp_path / "q.x3d")
    assert "%" not in quiet.stderr  # no bar when stderr is not a terminal


def test_glb_input_gives_a_fresh_valid_x3d_4_document(capsys, converted, tmp_path, x3d_schema):
    out = tmp_path / "from_glb.x3d"
    done = in_process(capsys, "convert", converted[".glb"], out, "--light", "lamp")
    assert done.returncode == 0, done.stderr
    assert x3d_schema_errors(out, x3d_schema) == []
    root = etree.parse(str(out), SAFE).getroot()
    assert root.get("version") == "4.0"
    assert root.find("Scene/PointLight[@DEF='lamp']") is not None
    assert len(root.findall("Scene/Group[@class='shadowgeo-shadows']/Shape")) == 1
    assert "earlier run are replaced" in done.stderr  # the .glb's own shadow is not doubled


def test_tolerance_reaches_the_tessellation(capsys, tmp_path):
    counts = []
    for tolerance in ("0.05", "0.0005"):
        out = tmp_path / f"t{tolerance}.x3d"
        done = in_process(capsys, "convert", EXAMPLE, out, "--tolerance", tolerance)
        assert done.returncode == 0, done.stderr
        counts.append(int(done.stdout.split(" triangles")[0].rsplit(" ", 1)[1]))
    assert counts[0] < counts[1]  # a finer column outline, a finer shadow
    with pytest.raises(SystemExit):
        main(["convert", str(EXAMPLE), str(tmp_path / "x.x3d"), "--tolerance", "2"])


def test_lenient_x3d_converts_with_notes_and_a_truncated_one_fails_in_one_line(capsys, tmp_path):
    scene = tmp_path / "lenient.x3d"
    scene.write_text(
        '<X3D version="4.0"><Scene>\n'
        '<Transform DEF="T" translation="0 abc 0"><Shape DEF="crate"><Box/></Shape></Transform>\n'
        '<Shape><Sphere USE="T"/></Shape>\n'
        '<Inline url=\'"../elsewhere.x3d" "https://example.com/a.x3d" "gone.x3d"\'/>\n'
        "<FancyNode/>\n"
        "</Scene></X3D>\n"
    )
    out = tmp_path / "out.x3d"
    done = in_process(capsys, "convert", scene, out)
    assert done.returncode == 0, done.stderr
    notes = done.stderr
    assert "lenient.x3d line 2, Transform DEF='T': field translation: '0 abc 0'" in notes
    assert "line 3, Sphere USE='T': USE='T' names a Transform (line 2), not a Sphere" in notes
    assert "line 4, Inline: Inline skipped: '../elsewhere.x3d' leaves the scene's folder" in notes
    assert "'https://example.com/a.x3d' is remote" in notes and "'gone.x3d' not found" in notes
    assert "line 5, FancyNode: skipped" in notes
    (crate,) = sg.load(out).shapes_with_role("geometry")
    assert crate.name == "crate"
    np.testing.assert_array_equal(crate.world_vertices.min(axis=0), [-1, -1, -1])  # not moved
    truncated = tmp_path / "truncated.x3d"
    truncated.write_text(scene.read_text()[:80])
    one_line_error(in_process(capsys, "convert", truncated, out), "truncated.x3d", "malformed XML")


def test_values_that_start_with_a_minus_sign_follow_their_flag(capsys, tmp_path):
    """A sun travelling west (-x), a site south of the equator, plan corners
    left of the origin: lists of numbers that start with "-" are values, as a
    user types them, not options argparse does not know."""
    from cli.main import negative_values_joined

    assert negative_values_joined(["--sun", "-0.3,-1,0.2", "--at", "-33.9,151.2", "-h"]) == [
        "--sun=-0.3,-1,0.2",
        "--at=-33.9,151.2",
        "-h",
    ]
    assert negative_values_joined(["--plane=0,1,0,-2", "-1e-3,2"]) == [
        "--plane=0,1,0,-2",
        "-1e-3,2",
    ]
    assert negative_values_joined(["--", "-1,2"]) == ["--", "-1,2"]
    out = tmp_path / "west.x3d"
    done = in_process(capsys, "convert", EXAMPLE, out, "--sun", "-0.3,-1,0.2", "--plane", "0,1,0,0")
    assert done.returncode == 0, done.stderr
    (shadow,) = [s for s in sg.load(out).shapes if s.role == "shadow"]
    other = tmp_path / "east.x3d"
    east = in_process(
        capsys, "convert", EXAMPLE, other, "--sun", "0.3,-1,0.2", "--plane", "0,1,0,0"
    )
    assert east.returncode == 0
    (mirror,) = [s for s in sg.load(other).shapes if s.role == "shadow"]
    # the sun from the east throws the shadows the other way along x
    assert shadow.world_vertices[:, 0].mean() < mirror.world_vertices[:, 0].mean()
    done = in_process(capsys, "sun", EXAMPLE, "--at", "-33.9,151.2", "--date", "2026-06-21")
    assert done.returncode == 0, done.stderr
    assert "at -33.9, 151.2" in done.stdout
