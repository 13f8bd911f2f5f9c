"""Regression tests for the second outsider campaign (issue 34 item 2,
``../shared/findings/outsider-2``): each replays a finding's reproducer,
written here by the test (they are a few lines of text) so that nothing is
skipped when the findings folder is absent."""

from __future__ import annotations

import json
import subprocess

import pytest

from cli.main import main

LONG_NAME = "a" * 300  # one path component past every file system's 255


def run(capsys, *args):
    """The command line, in this process."""
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return subprocess.CompletedProcess(args, code, out, err)


@pytest.mark.parametrize(
    ("name", "text"),
    [
        (
            "inline.wrl",
            f'#VRML V2.0 utf8\nInline {{ url "{LONG_NAME}.wrl" }}\n'
            "Shape { geometry Box { } }\n",
        ),
        (
            "texture.x3dv",
            "#X3D V4.0 utf8\nShape { appearance Appearance { texture ImageTexture "
            f'{{ url "{LONG_NAME}" }} }} geometry Box {{ }} }}\n',
        ),
        (
            "texture.json",
            json.dumps(
                {
                    "X3D": {
                        "@version": "4.0",
                        "Scene": {
                            "-children": [
                                {
                                    "Shape": {
                                        "-appearance": {
                                            "Appearance": {
                                                "-texture": {"ImageTexture": {"@url": [LONG_NAME]}}
                                            }
                                        },
                                        "-geometry": {"Box": {}},
                                    }
                                }
                            ]
                        },
                    }
                }
            ),
        ),
    ],
)
def test_a_url_too_long_for_the_file_system_is_a_note_and_skipped(tmp_path, capsys, name, text):
    # outsider-2 traceback_OSError_ENAMETOOLONG_*: Path.is_file raised.
    scene = tmp_path / name
    scene.write_text(text)
    done = run(capsys, "info", scene)
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr
    notes = [line for line in done.stdout.splitlines() if "cannot be looked up" in line]
    assert len(notes) == 1 and "name too long" in notes[0].lower()
    assert "Box" in done.stdout  # the rest of the scene is read


def test_a_gltf_image_uri_too_long_for_the_file_system_is_a_note(tmp_path, capsys):
    # The same cause in the glTF reader's check of its external files.
    scene = tmp_path / "image.gltf"
    scene.write_text(json.dumps({"asset": {"version": "2.0"}, "images": [{"uri": LONG_NAME}]}))
    done = run(capsys, "info", scene)
    assert done.returncode == 0, done.stderr
    assert "missing texture image" in done.stdout


OVERFLOWING = "9" * 400  # past float64's range with no exponent: inf when read


@pytest.mark.parametrize(
    ("name", "text", "literal"),
    [
        (
            "spot.x3dv",
            "#X3D V4.0 utf8\nShape { geometry Box { } }\n"
            f"SpotLight {{ radius {OVERFLOWING} }}\n",
            OVERFLOWING,
        ),
        (
            "coord.wrl",
            "#VRML V2.0 utf8\nShape { geometry IndexedFaceSet { coordIndex [ 0 1 2 -1 ] "
            f"coord Coordinate {{ point [ 0 0 0 1 0 0 0 {OVERFLOWING} 0 ] }} }} }}\n",
            OVERFLOWING,
        ),
        (
            "translation.json",
            json.dumps(
                {
                    "X3D": {
                        "@version": "4.0",
                        "Scene": {
                            "-children": [
                                {"Shape": {"-geometry": {"Box": {}}}},
                                {"Transform": {"@translation": [1, 2, float(OVERFLOWING)]}},
                            ]
                        },
                    }
                }
            ).replace("Infinity", OVERFLOWING),
            OVERFLOWING,
        ),
        (
            "interpolator.x3dv",
            "#X3D V4.0 utf8\nDEF P PositionInterpolator { key [ 0 1 ] "
            "keyValue [ 0 0 0 1 1_000 Infinity ] }\nShape { geometry Box { } }\n",
            "Infinity",
        ),
    ],
)
def test_a_number_the_reader_cannot_use_is_not_copied_to_x3d(tmp_path, capsys, name, text, literal):
    # outsider-2 x3d_output_overflowing_number_literal_copied and
    # x3d_output_nan_inf_literal_copied: the writer copied the literal.
    scene = tmp_path / name
    scene.write_text(text)
    out = tmp_path / "out.x3d"
    done = run(capsys, "convert", scene, out)
    assert done.returncode == 0, done.stderr
    assert literal not in out.read_text()
    assert "is not finite; not written (the field's default applies)" in done.stderr
