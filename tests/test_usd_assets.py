"""USD asset containment: no asset path of any kind reaches outside the
scene's folder, and usd-core never opens the file it names."""

from __future__ import annotations

import os
import shutil

import pytest
from needs import absent
from pxr import Sdf, Usd  # noqa: E402

import shadowgeo as sg
from shadowgeo.io.usd_assets import layer_assets  # noqa: E402

# Its points come from the value clip.
TRIANGLE = """
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [0, 1, 2]
    point3f[] points
"""

# A layer with one triangle at /Secret, time samples for value clips too.
SECRET = """#usda 1.0
def Mesh "Secret"
{
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [0, 1, 2]
    point3f[] points = [(0, 0, 0), (7, 0, 0), (0, 7, 0)]
    point3f[] points.timeSamples = { 0: [(0, 0, 0), (7, 0, 0), (0, 7, 0)] }
}
"""


def _clip(asset_paths: str) -> str:
    return f"""#usda 1.0
def Mesh "Tri" (
    clips = {{
        dictionary default = {{
            double2[] active = [(0, 0)]
            asset[] assetPaths = [{asset_paths}]
            string primPath = "/Secret"
            double2[] times = [(0, 0)]
        }}
    }}
)
{{{TRIANGLE}}}
"""


def _template(pattern: str) -> str:
    return f"""#usda 1.0
def Mesh "Tri" (
    clips = {{
        dictionary default = {{
            string templateAssetPath = "{pattern}"
            double templateStartTime = 1
            double templateEndTime = 1
            double templateStride = 1
            string primPath = "/Secret"
        }}
    }}
)
{{{TRIANGLE}}}
"""


CASES = {
    "value clip": _clip("@../outside/secret.usda@"),
    "value clip template": _template("../outside/secret.#.usda"),
    "value clip manifest": _clip("@clip.usda@").replace(
        "string primPath", "asset manifestAssetPath = @../outside/secret.usda@\n string primPath"
    ),
    "reference": '#usda 1.0\ndef Mesh "Tri" (references = @../outside/secret.usda@</S>)\n{}\n',
    "payload": '#usda 1.0\ndef Mesh "Tri" (payload = @../outside/secret.usda@</S>)\n{}\n',
    "sublayer": "#usda 1.0\n(\n subLayers = [@../outside/secret.usda@]\n)\n",
    "variant reference": """#usda 1.0
def Xform "Tri" (
    variants = {
        string v = "a"
    }
    prepend variantSets = "v"
)
{
    variantSet "v" = {
        "a" (prepend references = @../outside/secret.usda@</Secret>) {}
    }
}
""",
    "asset": '#usda 1.0\ndef Mesh "Tri"\n{\n asset inputs:file = @../outside/secret.usda@\n}\n',
    "asset time sample": (
        '#usda 1.0\ndef Mesh "Tri"\n{\n'
        " asset[] textures.timeSamples = { 0: [@ok.png@], 1: [@../outside/secret.usda@] }\n}\n"
    ),
}


def _folders(tmp_path):
    """``scene/`` for the scene, ``outside/secret.usda`` (and a clip-template
    match) beside it."""
    scene, outside = tmp_path / "scene", tmp_path / "outside"
    scene.mkdir()
    outside.mkdir()
    (outside / "secret.usda").write_text(SECRET)
    (outside / "secret.1.usda").write_text(SECRET)
    (scene / "clip.usda").write_text(SECRET)
    return scene, outside


@pytest.fixture
def opened(monkeypatch) -> list[str]:
    """The files handed to usd-core's openers during the test (a stage opens
    its layers in C++, out of sight: a refusal must come before any stage)."""
    calls: list[str] = []
    for owner, name in [
        (Usd.Stage, "Open"),
        (Sdf.Layer, "OpenAsAnonymous"),
        (Sdf.Layer, "FindOrOpen"),
    ]:
        original = getattr(owner, name)

        def spy(path, *args, _original=original, _name=name, **kwargs):
            calls.append(f"{_name} {path}")
            return _original(path, *args, **kwargs)

        monkeypatch.setattr(owner, name, staticmethod(spy))
    return calls


def _never_opened(opened: list[str], outside) -> None:
    assert not any(call.startswith("Open ") for call in opened), opened
    assert not any(str(outside) in call for call in opened), opened


# Assets that no one opens (textures): noted, and the scene still reads.
NEVER_OPENED = {"asset", "asset time sample"}


@pytest.mark.parametrize("case", sorted(NEVER_OPENED))
def test_a_texture_outside_the_folder_is_noted_and_never_opened(tmp_path, opened, case):
    scene, outside = _folders(tmp_path)
    path = scene / "main.usda"
    path.write_text(CASES[case])
    loaded = sg.load(path)
    notes = [note for note in loaded.warnings if "../outside/secret.usda" in note]
    assert notes and "it leaves the file's folder" in notes[0] and "not read" in notes[0]
    assert not any(str(outside) in call for call in opened), opened


@pytest.mark.parametrize("case", sorted(set(CASES) - NEVER_OPENED))
def test_an_asset_path_outside_the_folder_is_refused_before_usd_opens_it(tmp_path, opened, case):
    scene, outside = _folders(tmp_path)
    path = scene / "main.usda"
    path.write_text(CASES[case])
    kind = case.replace("variant ", "").replace(" time sample", "")
    asset = (
        "../outside/secret.#.usda" if kind == "value clip template" else "../outside/secret.usda"
    )
    with pytest.raises(sg.SceneError, match="leaves the file's folder") as caught:
        sg.load(path)
    message = str(caught.value)
    assert str(path) in message and f"{kind} '{asset}'" in message
    _never_opened(opened, outside)


def test_the_value_clip_finding_is_refused(shared_dir):
    path = shared_dir / "findings/robustness/hostile/scene/usd_valueclip_outside.usda"
    if not path.is_file():
        absent(f"{path} is absent")
    with pytest.raises(sg.SceneError) as caught:
        sg.load(path)
    message = str(caught.value)
    assert "usd_valueclip_outside.usda" in message
    assert "value clip '../outside/secret_ts.usda'" in message
    assert "leaves the file's folder" in message


@pytest.mark.parametrize(
    "asset, reason",
    [
        ("/etc/hosts", "not a relative path"),
        ("file:///etc/hosts", "not a relative path"),
        ("https://example.com/clip.usda", "not a relative path"),
        ('`"../outside/secret.usda"`', "a variable expression"),
        ("missing.usda", "missing layer"),
    ],
)
def test_clip_asset_paths_must_be_plain_relative_files(tmp_path, opened, asset, reason):
    scene, outside = _folders(tmp_path)
    path = scene / "main.usda"
    path.write_text(_clip(f"@{asset}@"))
    with pytest.raises(sg.SceneError, match=reason) as caught:
        sg.load(path)
    assert f"value clip {asset!r}" in str(caught.value)
    _never_opened(opened, outside)


def test_a_layer_inside_the_folder_is_checked_in_turn(tmp_path, opened):
    scene, outside = _folders(tmp_path)
    (scene / "parts").mkdir()
    (scene / "parts" / "part.usda").write_text(_clip("@../../outside/secret.usda@"))
    path = scene / "main.usda"
    path.write_text("#usda 1.0\n(\n subLayers = [@parts/part.usda@]\n)\n")
    with pytest.raises(sg.SceneError, match="leaves the file's folder") as caught:
        sg.load(path)
    assert "value clip '../../outside/secret.usda' in parts/part.usda" in str(caught.value)
    _never_opened(opened, outside)


def test_a_template_match_that_links_outside_is_refused(tmp_path, opened):
    scene, outside = _folders(tmp_path)
    try:
        os.symlink(outside / "secret.1.usda", scene / "clip.1.usda")
    except OSError:
        absent("symbolic links are not available")
    path = scene / "main.usda"
    path.write_text(_template("clip.#.usda"))
    with pytest.raises(sg.SceneError, match="clip.1.usda leaves the file's folder"):
        sg.load(path)
    _never_opened(opened, outside)


def test_value_clips_inside_the_folder_are_read(tmp_path, opened):
    scene, _ = _folders(tmp_path)
    path = scene / "main.usda"
    path.write_text(_clip("@clip.usda@"))
    (shape,) = sg.load(path).shapes
    assert f"Open {path}" in opened  # the spy sees a stage open
    # The clip's points (the 7-unit triangle), not the prim's own.
    assert shape.vertices.max() == 7.0
    shutil.copy(scene / "clip.usda", scene / "frame.1.usda")
    path.write_text(_template("frame.#.usda"))
    (shape,) = sg.load(path).shapes
    assert shape.vertices.max() == 7.0


def test_every_kind_of_asset_path_is_listed(tmp_path):
    scene, _ = _folders(tmp_path)
    path = scene / "kinds.usda"
    path.write_text(
        """#usda 1.0
(
    subLayers = [@sub.usda@]
    customLayerData = { asset note = @note.txt@ }
)
def Xform "A" (
    references = [@ref.usda@</X>, </Internal>]
    payload = @payload.usda@
    assetInfo = { asset identifier = @identifier.usda@ }
    clips = { dictionary default = {
        asset[] assetPaths = [@clip.usda@]
        asset manifestAssetPath = @manifest.usda@
        string templateAssetPath = "frame.###.usda"
    } }
)
{
    asset inputs:file = @texture.png@
}
"""
    )
    found = set(layer_assets(Sdf.Layer.OpenAsAnonymous(str(path))))
    assert found == {
        ("sublayer", "sub.usda"),
        ("asset", "note.txt"),
        ("reference", "ref.usda"),
        ("reference", ""),
        ("payload", "payload.usda"),
        ("asset", "identifier.usda"),
        ("value clip", "clip.usda"),
        ("value clip manifest", "manifest.usda"),
        ("value clip template", "frame.###.usda"),
        ("asset", "texture.png"),
    }


def test_a_template_with_digits_in_its_folder_is_refused(tmp_path, opened):
    scene, outside = _folders(tmp_path)
    path = scene / "main.usda"
    path.write_text(_template("clips.#/../../outside/secret.usda"))
    with pytest.raises(sg.SceneError, match="'#' outside the file name"):
        sg.load(path)
    _never_opened(opened, outside)


def test_expression_variables_are_refused(tmp_path, opened):
    scene, outside = _folders(tmp_path)
    path = scene / "main.usda"
    path.write_text(
        '#usda 1.0\n(\n expressionVariables = { string DIR = "." }\n)\n'
        'def Mesh "Tri"\n{\n asset inputs:file = @`"${DIR}/secret.usda"`@\n}\n'
    )
    with pytest.raises(sg.SceneError, match="expressionVariables") as caught:
        sg.load(path)
    assert str(path) in str(caught.value)
    _never_opened(opened, outside)


def test_an_expression_in_a_texture_path_is_checked_as_it_evaluates(tmp_path, opened):
    scene, outside = _folders(tmp_path)
    path = scene / "main.usda"
    path.write_text('#usda 1.0\ndef Mesh "Tri"\n{\n asset t = @`"../outside/secret.usda"`@\n}\n')
    notes = sg.load(path).warnings
    assert any("leaves the file's folder" in note or "expression" in note for note in notes), notes
    assert not any(str(outside) in call for call in opened), opened


def test_a_text_layer_is_parsed_within_a_budget_first(tmp_path, monkeypatch):
    """Found by the fuzzing campaign (usda mutant 3327): a few bytes inserted
    into a 725 KB .usda made usd-core's parser take 7.8 GB and 71 CPU seconds
    before its error. Each text layer is parsed first in a child process held
    to a memory and CPU budget; here the budget is shrunk below what any parse
    needs, so the same file that reads with the default budget is refused."""
    import trimesh

    from shadowgeo import limits

    ball = trimesh.creation.icosphere(subdivisions=5)  # 10,242 points: MBs to parse
    scene = sg.Scene([sg.Shape(ball.vertices, ball.faces, name="ball")])
    path = tmp_path / "scene.usda"
    sg.save(scene, path)
    assert len(sg.load(path).shapes) == 1  # within the default budget
    monkeypatch.setattr(limits, "USD_TEXT_MEMORY", 1)
    monkeypatch.setattr(limits, "USD_TEXT_MEMORY_PER_BYTE", 0)
    refusal = r"(needs more than|not a USD file|stopped with signal)"
    with pytest.raises(sg.SceneError, match=r"scene\.usda.*" + refusal):
        sg.load(path)
    crate = tmp_path / "scene.usdc"  # a crate is checked whatever its size (it can abort)
    sg.save(scene, crate)
    with pytest.raises(sg.SceneError, match=r"scene\.usdc.*" + refusal):
        sg.load(crate)
    monkeypatch.undo()
    assert len(sg.load(crate).shapes) == 1
    monkeypatch.setattr(limits, "USD_TEXT_MEMORY", 1)
    monkeypatch.setattr(limits, "USD_TEXT_MEMORY_PER_BYTE", 0)
    # nor is a small text layer (the child would cost more than the parse)
    small = tmp_path / "small.usda"
    sg.save(sg.Scene([sg.Shape([[0, 0, 0], [1, 0, 0], [0, 0, 1]], [[0, 2, 1]])]), small)
    assert path.stat().st_size > limits.USD_TEXT_CHECK_BYTES >= small.stat().st_size
    assert len(sg.load(small).shapes) == 1
