"""Mutated ClassicVRML, VRML 97 and X3D JSON documents never give a traceback
or hang: ``shadowgeo.load`` returns a Scene or raises SceneError, and
``shadowgeo convert`` exits 0 with its output or 1 with none.

Small documents holding most of each encoding's grammar (PROTO with IS,
DEF/USE, ROUTE, strings with escapes, MF fields, Inline, comments) are
mutated by seeded, bounded hypothesis strategies: tokens dropped or
duplicated, brackets added, the text cut short, numbers made huge, not
finite or hex, nodes nested past the depth limit, and for JSON also values
replaced by others of any JSON type.
"""

from __future__ import annotations

import io
import json
import re
import signal
import tempfile
from contextlib import contextmanager, redirect_stderr, redirect_stdout
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, seed, settings
from hypothesis import strategies as st
from lxml import etree

import shadowgeo as sg
from cli.main import main
from shadowgeo.io.x3d import classic_read as x3d_classic_read

CLASSIC = """#X3D V4.0 utf8
PROFILE Immersive
COMPONENT Shape:1
UNIT length centimetre 0.01
META "title" "mutations"
PROTO Post [ inputOutput SFVec3f size 0.2 2 0.2  initializeOnly SFString label "a \\"b\\"" ] {
  Transform { children Shape { geometry Box { size IS size } } }
}
DEF light DirectionalLight { direction 0.3 -1 0.2 shadows TRUE }
DEF ground Transform {
  translation 0 -0.05 0
  children [
    Shape { appearance Appearance { material Material { diffuseColor 0.8 0.8 0.8 } }
            geometry Box { size 10 0.1 10 } }  # the floor
  ]
}
DEF post Transform { translation 1 0 0 children Post { size 0.3 2 0.3 } }
Transform { translation -1 0 0 scale 1 1 1 children USE post }
Shape { geometry IndexedFaceSet { coordIndex [ 0 1 2 -1 ] solid FALSE
        coord Coordinate { point [ 0 1 0, 1 1 0, 0 1 1 ] } } }
Switch { whichChoice 0 children [ Shape { geometry Sphere { radius 0.5 } } ] }
Inline { url [ "missing.x3dv" ] }
DEF clock TimeSensor { }
ROUTE clock.fraction_changed TO post.set_translation
"""

VRML97 = """#VRML V2.0 utf8
PROTO Post [ exposedField SFVec3f size 0.2 2 0.2 field SFColor color 1 0 0 ] {
  Shape { appearance Appearance { material Material { diffuseColor IS color } }
          geometry Box { size IS size } }
}
DEF sun DirectionalLight { direction 0.3 -1 0.2 }
Transform { translation 0 -0.05 0 children Shape { geometry Box { size 10 0.1 10 } } }
DEF post Transform { translation 1 1 0 children [ Post { size 0.3 2 0.3 } ] }
Collision { collide FALSE children [ USE post ] }
LOD { level [ Shape { geometry Cone { bottomRadius 0.5 height 1 } } ] }
Shape { geometry IndexedFaceSet { coord Coordinate { point [ 0 1 0 1 1 0 0 1 1 ] }
        coordIndex [ 0, 1, 2, -1 ] } }
Extrusion { spine [ 0 0 0, 0 1 0 ] crossSection [ 1 1, 1 -1, -1 -1, -1 1, 1 1 ] }
"""

MUTATIONS = ("drop", "duplicate", "bracket", "truncate", "number", "nest", "insert")
HUGE = ["1e999", "-1e999", "1e308", "9" * 400, "nan", "inf", "0x7FFFFFFFFFFFFFFFFF", "-0", ""]
PIECES = ["{", "}", "[", "]", '"', "#", "DEF", "USE", "IS", "PROTO", "ROUTE", "NULL", ",", "\x00"]
PIECES += ["TRUE", "1e-400", "EXTERNPROTO x [] []", "\\", "\u00e9", "\ud7ff", "\n"]
TOKEN = re.compile(r'"(?:[^"\\]|\\.)*"|[{}\[\]]|[^\s{}\[\]"]+')
NUMBER = re.compile(r"(?<![\w.])-?\d+(?:\.\d+)?(?:e-?\d+)?(?![\w.])")
# Seconds one read or conversion of a small document may take before it counts as a hang.
HANG = 20.0


@contextmanager
def no_hang(seconds: float = HANG):
    def alarm(signum, frame):
        raise AssertionError(f"more than {seconds} s: a hang")

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def mutate(text: str, kind: str, where: float, what: int) -> str:
    """``text`` with one mutation ``kind`` at relative position ``where``;
    ``what`` picks the replacement or the count."""
    if kind == "truncate":
        return text[: int(where * len(text))]
    if kind == "insert":
        at = int(where * len(text))
        return text[:at] + PIECES[what % len(PIECES)] + text[at:]
    if kind == "nest":
        depth = (what % 4) * x3d_classic_read.MAX_DEPTH // 2 + 1
        header, _, body = text.partition("\n")
        opener = ["Group { children [ ", "Transform { children ", "PROTO P [] { "][what % 3]
        closer = {"G": "] } ", "T": "} ", "P": "} "}[opener[0]]
        return f"{header}\n{opener * depth}{body}{closer * depth}"
    matches = list((NUMBER if kind == "number" else TOKEN).finditer(text))
    if not matches:
        return text
    match = matches[min(int(where * len(matches)), len(matches) - 1)]
    if kind == "drop":
        replacement = ""
    elif kind == "duplicate":
        replacement = match.group() + " " + match.group()
    elif kind == "bracket":
        replacement = match.group() + " " + "{}[]"[what % 4] * (1 + what % 3)
    else:
        replacement = HUGE[what % len(HUGE)]
    return text[: match.start()] + replacement + text[match.end() :]


mutations = st.lists(
    st.tuples(st.sampled_from(MUTATIONS), st.floats(0, 1), st.integers(0, 10_000)),
    min_size=1,
    max_size=3,
)


def load_or_scene_error(path: Path) -> sg.Scene | None:
    """The scene, or None after a SceneError; anything else fails the test."""
    with no_hang():
        try:
            scene = sg.load(path)
        except sg.SceneError as error:
            assert str(error) and "Traceback" not in str(error)
            return None
    assert isinstance(scene, sg.Scene)
    return scene


def check_document(text: str, suffix: str, steps) -> str:
    for kind, where, what in steps:
        text = mutate(text, kind, where, what)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"mutated{suffix}"
        path.write_bytes(text.encode("utf-8", "surrogatepass"))
        load_or_scene_error(path)
    return text


@seed(20261201)
@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(steps=mutations)
def test_mutated_classic_vrml_is_a_scene_or_a_scene_error(steps):
    check_document(CLASSIC, ".x3dv", steps)


@seed(20261202)
@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(steps=mutations)
def test_mutated_vrml97_is_a_scene_or_a_scene_error(steps):
    check_document(VRML97, ".wrl", steps)


@pytest.fixture(scope="module")
def json_text(tmp_path_factory) -> str:
    """The ClassicVRML document in the X3D JSON encoding, written by shadowgeo."""
    folder = tmp_path_factory.mktemp("json")
    (folder / "seed.x3dv").write_text(CLASSIC)
    sg.save(sg.load(folder / "seed.x3dv"), folder / "seed.x3dj")
    text = (folder / "seed.x3dj").read_text()
    assert '"Transform"' in text and '"ProtoDeclare"' in text
    return text


JSON_VALUES = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(-(10**30), 10**30)
    | st.floats(allow_nan=False)
    | st.sampled_from(["", "#x", "USE", "-children", "@DEF", "1e999", "Box"]),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=8), inner),
    max_leaves=6,
)


def replace_value(document, where: float, value) -> None:
    """Replace the value at one place (chosen by ``where``) in the JSON tree."""
    places = []

    def walk(node):
        items = node.items() if isinstance(node, dict) else enumerate(node)
        for key, child in list(items):
            places.append((node, key))
            if isinstance(child, dict | list):
                walk(child)

    walk(document)
    node, key = places[min(int(where * len(places)), len(places) - 1)]
    node[key] = value


@seed(20261203)
@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(steps=mutations, where=st.floats(0, 1), value=JSON_VALUES, text_level=st.booleans())
def test_mutated_x3d_json_is_a_scene_or_a_scene_error(json_text, steps, where, value, text_level):
    if text_level:
        check_document(json_text, ".x3dj", [s for s in steps if s[0] != "nest"])
        return
    document = json.loads(json_text)
    replace_value(document, where, value)
    check_document(json.dumps(document), ".x3dj", [])


@seed(20261204)
@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    steps=mutations,
    source=st.sampled_from([(CLASSIC, ".x3dv"), (VRML97, ".wrl")]),
    target=st.sampled_from([".x3d", ".x3dv", ".wrl", ".x3dj", ".glb"]),
)
def test_convert_of_a_mutated_file_exits_0_or_1_and_leaves_no_partial_output(steps, source, target):
    text, suffix = source
    for kind, where, what in steps:
        text = mutate(text, kind, where, what)
    with tempfile.TemporaryDirectory() as folder:
        path, out = Path(folder) / f"in{suffix}", Path(folder) / f"out{target}"
        path.write_bytes(text.encode("utf-8", "surrogatepass"))
        stderr = io.StringIO()
        with no_hang(), redirect_stderr(stderr), redirect_stdout(io.StringIO()):
            code = main(["convert", str(path), str(out)])
        err = stderr.getvalue()
        assert "Traceback" not in err
        assert code in (0, 1), err
        files = sorted(p.name for p in Path(folder).iterdir())
        if code == 1:
            # One line naming the input; nothing written, not even a temporary file.
            errors = [line for line in err.splitlines() if not line.startswith("note: ")]
            assert len(errors) == 1 and path.name in errors[0], err
            assert files == [path.name], files
        else:
            assert files == sorted([path.name, out.name]), files
            assert isinstance(sg.load(out), sg.Scene)


def test_the_mutations_reach_the_recovery_and_the_refusals(tmp_path):
    """The strategies above are not vacuous: a mutation is recovered with a
    note, a nest past the limit is refused, a cut is kept up to the cut."""
    path = tmp_path / "m.x3dv"
    path.write_text(mutate(CLASSIC, "insert", 0.6, PIECES.index("}")))
    scene = sg.load(path)
    assert any("skipped" in note for note in scene.warnings) and scene.shapes
    path.write_text(mutate(CLASSIC, "nest", 0, 3))
    with pytest.raises(sg.SceneError, match="nested more than"):
        sg.load(path)
    # Cut inside the Transform that uses the post: the floor and the post stay.
    path.write_text(CLASSIC[: CLASSIC.index("scale 1 1 1")])
    scene = sg.load(path)
    assert len(scene.shapes) == 2 and any("the file ends" in note for note in scene.warnings)


def test_characters_xml_cannot_hold_in_a_comment_are_replaced(tmp_path):
    # Found by a longer run of the mutations above: a NUL inside a comment.
    path = tmp_path / "nul.x3dv"
    path.write_bytes(b"#X3D V4.0 utf8\n# a \x00 and \x1f comment\nShape { geometry Box { } }\n")
    scene = sg.load(path)
    assert len(scene.shapes) == 1
    comments = [c.text for c in scene.document.getroot().iter(etree.Comment)]
    assert " a \ufffd and \ufffd comment" in comments
    # In a name (a field holding a node, a DEF): that field or node is skipped with a note.
    path.write_bytes(
        b"#X3D V4.0 utf8\nTransform { child\x00ren Shape { geometry Box { } } }\n"
        b"DEF a\x01b Shape { geometry Box { } }\nShape { geometry Sphere { } }\n"
    )
    scene = sg.load(path)
    assert [shape.n_faces for shape in scene.shapes] == [scene.shapes[0].n_faces]
    assert scene.shapes[0].n_faces > 12  # the sphere alone
    assert sum("skipped" in note for note in scene.warnings) == 2
