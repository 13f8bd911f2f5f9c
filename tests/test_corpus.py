"""Every file of the shared corpus converts and validates no worse than its
input, or fails with the one clear message we judged right for it.

Every file converts with no flags, as ``shadowgeo convert IN OUT``. A scene
with no light (most of the corpus: test files for containerField, metadata,
prototypes, text) is lit by the default sun, with a note; whether a file
really has no light is checked by looking for light elements in the XML
directly. A scene with no receiver of its own gets the ground plane under its
lowest point, with a note. Files whose reader warnings matter (missing
textures, invalid fields) must still read.

The ClassicVRML and VRML 97 corpus (``classic_corpus_dir``) and the JSON
files of the pairs corpus (``pairs_dir``) convert with no flags to their own
encoding: at least 98 % of the X3D and VRML 97 files write an output, the rest
fail with one line naming the file (VRML 1.0 is refused so), none crashes;
every 10th output is read back and its XML translation validated, every JSON
output is valid against the X3D JSON schema, and a few files of each also go
through the Khronos glTF validator (.glb) and usd-core's validators (.usda).
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from lxml import etree
from needs import absent
from validators import gltf_problems, gltf_reports, usd_errors
from x3d_json_schema import json_schema_errors, json_validator
from x3d_schema import new_schema_errors, x3d_schema_errors

import shadowgeo as sg
from cli.main import main
from shadowgeo.io.x3d.parse import read_bytes

SAFE = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False)
LIGHTS = ("PointLight", "SpotLight", "DirectionalLight")
NCNAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_.\-]*$")
CLASSIC_SUFFIXES = (".x3dv", ".x3dvz", ".x3dv.gz", ".wrl", ".wrz", ".wrl.gz")


def lights_in_xml(path) -> int:
    root = etree.parse(str(path), SAFE).getroot()
    return sum(len(root.findall(f".//{name}")) for name in LIGHTS)


def convert(capsys, path, out):
    """``shadowgeo convert IN OUT``, no flags, in this process: (notes, result)."""
    code = main(["convert", str(path), str(out)])
    _, err = capsys.readouterr()
    assert code == 0 and "Traceback" not in err, err
    return [line for line in err.splitlines() if line.startswith("note: ")]


def check_shadows(result) -> None:
    for shape in result.shapes_with_role("shadow"):
        points = shape.world_vertices
        assert np.all(np.isfinite(points)) and len(shape.faces)
        if shape.name.endswith("_surfaces"):
            continue  # on every other surface: tests/test_surfaces_baked.py checks those
        # Flat: every planar shadow lies in one plane (its receiver's, lifted).
        centered = points - points.mean(axis=0)
        thickness = np.linalg.svd(centered, compute_uv=False)[-1] if len(points) > 3 else 0.0
        assert thickness <= 1e-9 * max(1.0, float(np.abs(points).max())) * np.sqrt(len(points))
        assert NCNAME.match(shape.name) and NCNAME.match(shape.group)
        assert shape.material.diffuse_color == (0.0, 0.0, 0.0)


def test_every_corpus_file_converts_with_no_flags(corpus_dir, x3d_schema, tmp_path, capsys):
    files = sorted(corpus_dir.rglob("*.x3d"))
    assert len(files) >= 20
    outcomes = {}
    for path in files:
        name = str(path.relative_to(corpus_dir))
        out = tmp_path / (path.stem + ".out.x3d")
        notes = convert(capsys, path, out)
        sunny = any("a default sun casts" in note for note in notes)
        assert sunny == (lights_in_xml(path) == 0), name
        result = sg.load(out)
        assert len(result.lights) == lights_in_xml(path), name  # the sun is not added
        check_shadows(result)
        before = x3d_schema_errors(path, x3d_schema)
        new = new_schema_errors(before, x3d_schema_errors(out, x3d_schema))
        assert new == [], f"{name}: {new[:3]}"
        # Nothing removed: the input's elements plus, per shadow and for the
        # ground, Shape, Appearance, Material, IndexedTriangleSet and Coordinate,
        # and a Group per light and for the ground.
        shadows = result.shapes_with_role("shadow")
        grounds = result.shapes_with_role("ground")
        original = etree.parse(str(path), SAFE).getroot()
        written = etree.parse(str(out), SAFE).getroot()
        added = 5 * len(shadows + grounds) + len({s.group for s in shadows + grounds})
        # and a Viewpoint framing the scene when it has none
        viewpoints = "//*[local-name()='Viewpoint' or local-name()='OrthoViewpoint']"
        added += 0 if original.xpath(viewpoints) else 1
        assert written.xpath(viewpoints), name
        assert len(written.xpath("//*")) == len(original.xpath("//*")) + added, name
        casters = len(result.shapes_with_role("geometry"))
        outcomes[name] = (len(shadows), sunny, any("ground plane" in n for n in notes), grounds)
        # Everything with geometry casts (a few files hold only text or metadata).
        assert len(shadows) > 0 or casters == 0, name
    assert len(outcomes) == len(files)
    # Most files are lit by the default sun; the few that have no large flat
    # surface (a lone cube, spheres) receive on the ground under them.
    assert sum(sunny for _, sunny, _, _ in outcomes.values()) >= 15
    grounded = [name for name, (_, _, ground, _) in outcomes.items() if ground]
    assert "blender/simple/test1.x3d" in grounded and "x3d/matrix_transform.x3d" in grounded
    drawn = [name for name, (_, _, _, ground) in outcomes.items() if ground]
    assert drawn == grounded  # the ground plane that receives is drawn
    assert sum(count > 0 for count, _, _, _ in outcomes.values()) >= 15, outcomes


# -- ClassicVRML, VRML 97 and JSON: the ">= 98 % write an output, 0 crash" ------------


def own_output(path: Path) -> str:
    """The output in the input's own encoding: .wrl for VRML 97, .x3dv for
    ClassicVRML, .x3dj for JSON."""
    name = path.name.lower()
    if name.endswith(".json"):
        return ".x3dj"
    return ".wrl" if name.endswith((".wrl", ".wrz", ".wrl.gz")) else ".x3dv"


def full_suffix(path: Path) -> str:
    return "".join(path.suffixes[-2:]) if path.suffix.lower() == ".gz" else path.suffix


def run_convert(capsys, path: Path, out: Path) -> tuple[int, str]:
    out.unlink(missing_ok=True)
    code = main(["convert", str(path), str(out)])
    _, err = capsys.readouterr()
    assert "Traceback" not in err and code in (0, 1), f"{path}: exit {code}: {err[-300:]}"
    if code == 0:
        assert out.is_file(), path
    else:  # one line naming the file, nothing written
        assert len(err.strip().splitlines()) == 1 and path.name in err, err
        assert not out.exists() and list(out.parent.glob(out.name + "*")) == [], path
    return code, err


def check_read_back(path: Path, out: Path, folder: Path, x3d_schema) -> None:
    """``out`` (ClassicVRML or VRML 97) reads back with the input's shapes, and
    its XML translation has no schema error the input's translation has not."""
    copy = folder / ("input" + full_suffix(path))  # beside out: both miss the same Inlines
    shutil.copyfile(path, copy)
    source, back = sg.load(copy), sg.load(out)
    assert len(back.shapes_with_role("geometry")) == len(source.shapes), path
    added = back.shapes_with_role("shadow") + back.shapes_with_role("ground")
    assert len(added) == len(back.shapes) - len(source.shapes)
    assert len(back.shapes_with_role("ground")) <= 1  # under the ground plane, when it receives
    sg.save(source, folder / "input.x3d")
    sg.save(back, folder / "back.x3d")
    before = x3d_schema_errors(folder / "input.x3d", x3d_schema)
    assert new_schema_errors(before, x3d_schema_errors(folder / "back.x3d", x3d_schema)) == []


def check_gltf_and_usd(capsys, paths: list[Path], folder: Path) -> None:
    """Each of ``paths`` converts to .usda (no usd-core validator error) and to
    .glb (no Khronos glTF validator error)."""
    glbs = []
    for index, path in enumerate(paths):
        for suffix in (".glb", ".usda"):
            code, err = run_convert(capsys, path, folder / f"sample{index}{suffix}")
            assert code == 0, err
        assert usd_errors(folder / f"sample{index}.usda") == [], path
        glbs.append(folder / f"sample{index}.glb")
    for path, report in zip(paths, gltf_reports(glbs), strict=True):
        assert gltf_problems(report, warnings=False) == [], path


def test_classic_corpus_converts_with_no_flags(classic_corpus_dir, x3d_schema, tmp_path, capsys):
    files = sorted(
        p
        for p in classic_corpus_dir.rglob("*")
        if p.is_file() and p.name.lower().endswith(CLASSIC_SUFFIXES)
    )
    assert len(files) >= 200
    wrote, errors, vrml1 = [], {}, []
    for path in files:
        out = tmp_path / ("out" + own_output(path))
        code, err = run_convert(capsys, path, out)
        if read_bytes(path).startswith(b"#VRML V1."):
            assert code == 1 and "VRML 1.0 is not supported" in err, path
            vrml1.append(path)
        elif code == 1:
            errors[str(path.relative_to(classic_corpus_dir))] = err
        else:
            wrote.append(path)
            if len(wrote) % 10 == 1:  # every 10th output validated
                check_read_back(path, out, tmp_path, x3d_schema)
    # VRML 1.0 is another language: refused, and not counted.
    assert len(vrml1) >= 20
    assert len(wrote) >= 0.98 * (len(files) - len(vrml1)), errors
    check_gltf_and_usd(capsys, wrote[5::40], tmp_path)


@pytest.mark.parametrize("number", range(1, 6))
def test_castle_invalid_statements_are_omitted_as_castle_does(classic_corpus_dir, number):
    path = classic_corpus_dir / "x3d" / "warnings" / f"invalid_statement_omitted_{number}.x3dv"
    scene = sg.load(path)
    # "when parsed by Castle Game Engine, SimpleBox should still be visible"
    assert [shape.n_faces for shape in scene.shapes] == [12]
    skipped = [note for note in scene.warnings if "skipped" in note]
    assert len(skipped) == 1 and re.match(rf"{re.escape(str(path))} line 1[56]: ", skipped[0])


def test_a_use_of_a_def_outside_its_proto_is_skipped(classic_corpus_dir):
    path = (
        classic_corpus_dir / "prototypes" / "warnings" / "errors" / "proto_separate_namespace.wrl"
    )
    scene = sg.load(path)
    # The blue sphere outside the PROTO is read; the USE inside its body is not.
    assert len(scene.shapes) == 1 and scene.shapes[0].material.diffuse_color == (0.0, 0.0, 1.0)
    assert any("USE 'MySphere' names no DEF" in note for note in scene.warnings)


def test_json_corpus_converts_with_no_flags(pairs_dir, shared_dir, tmp_path, capsys):
    files = sorted(pairs_dir.glob("*.json"))
    assert len(files) >= 10
    schema = shared_dir / "schemas" / "x3d" / "x3d-4.0-JSONSchema.json"
    written = []
    for path in files:
        out = tmp_path / f"{path.stem}.x3dj"
        code, err = run_convert(capsys, path, out)
        assert code == 0, err
        written.append(out)
    if not schema.is_file():
        absent(f"{schema} is absent")
    validator = json_validator(str(schema))
    for path, out in zip(files, written, strict=True):
        before = json_schema_errors(validator, path)
        assert new_schema_errors(before, json_schema_errors(validator, out)) == [], path
    check_gltf_and_usd(capsys, files[::5], tmp_path)
