"""Batch conversion (``shadowgeo convert IN... OUT_DIR``): the outputs are the
bytes the single-file command writes, serially and on Dask (a LocalCluster of
2 workers, and a running cluster named by address); a bad file is named and
fails the run without stopping the others."""

from __future__ import annotations

import hashlib
import shutil
import subprocess
from pathlib import Path

import pytest
from needs import need

import shadowgeo as sg
from cli.batch import distinct_targets, jobs_for
from cli.main import main

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "examples" / "scenes"
# the bundled scenes a batch of the folder converts (soft_lights.usda among them)
EXAMPLES = sorted(path for path in SCENES.iterdir() if path.suffix in (".x3d", ".usda"))
BASIC = ROOT / "tests" / "data" / "basic.x3d"


def in_process(capsys, *args):
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return subprocess.CompletedProcess(args, code, out, err)


def digests(folder: Path) -> dict[str, str]:
    return {
        str(path.relative_to(folder)): hashlib.sha256(path.read_bytes()).hexdigest()
        for path in sorted(folder.rglob("*"))
        if path.is_file()
    }


@pytest.fixture(scope="module")
def single(tmp_path_factory):
    """Each scene converted alone by the single-file form: the reference bytes."""
    folder = tmp_path_factory.mktemp("single")
    for scene in [*EXAMPLES, BASIC]:
        assert main(["convert", str(scene), str(folder / scene.name)]) == 0
    assert main(["convert", str(BASIC), str(folder / "basic.glb")]) == 0
    return digests(folder)


def test_serial_batch_writes_what_single_conversions_write(capsys, tmp_path, single):
    out = tmp_path / "out"
    done = in_process(capsys, "convert", SCENES, BASIC, out, "--serial", "--progress")
    assert done.returncode == 0, done.stderr
    assert digests(out) == {name: d for name, d in single.items() if name != "basic.glb"}
    count = len(EXAMPLES) + 1
    assert f"{count} files [" in done.stderr and "100%" in done.stderr  # the progress bar
    assert f"converted {count} of {count} file(s)" in done.stdout
    assert "note: " + str(SCENES / "courtyard.x3d") + ": shadows:" in done.stderr
    glb = tmp_path / "glb"
    done = in_process(
        capsys, "convert", BASIC, SCENES / "pyramid.x3d", glb, "--serial", "--format", "glb"
    )
    assert done.returncode == 0, done.stderr
    assert sorted(digests(glb)) == ["basic.glb", "pyramid.glb"]
    assert digests(glb)["basic.glb"] == single["basic.glb"]


def test_two_dask_workers_write_the_same_bytes(capsys, tmp_path, single):
    need("dask")
    out = tmp_path / "out"
    missing = Path("no-such-folder") / "gone.x3d"  # relative: named as given, not as resolved
    done = in_process(
        capsys, "convert", SCENES, BASIC, missing, out, "--workers", "2", "--progress"
    )
    assert done.returncode == 1
    assert "on a Dask LocalCluster of 2 worker(s); 1 failed" in done.stdout
    assert f"shadowgeo convert: {missing}: no such file" in done.stderr.splitlines()
    assert digests(out) == {name: d for name, d in single.items() if name != "basic.glb"}


def test_a_running_cluster_named_by_address(capsys, tmp_path, single):
    need("dask")
    from dask.distributed import LocalCluster

    with LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cluster:
        out = tmp_path / "out"
        done = in_process(
            capsys,
            "convert",
            SCENES / "pyramid.x3d",
            BASIC,
            out,
            "--scheduler",
            cluster.scheduler_address,
        )
    assert done.returncode == 0, done.stderr
    assert f"on the Dask cluster at {cluster.scheduler_address}" in done.stdout
    assert digests(out) == {"pyramid.x3d": single["pyramid.x3d"], "basic.x3d": single["basic.x3d"]}


def test_a_bad_file_is_named_and_fails_the_run_but_not_the_others(capsys, tmp_path, single):
    folder = tmp_path / "in"
    (folder / "sub").mkdir(parents=True)
    shutil.copy(SCENES / "pyramid.x3d", folder / "sub" / "pyramid.x3d")
    (folder / "broken.x3d").write_text((SCENES / "pyramid.x3d").read_text()[:120])
    (folder / "readme.txt").write_text("not a scene")
    out = tmp_path / "out"
    done = in_process(capsys, "convert", folder, tmp_path / "missing.glb", out, "--serial")
    assert done.returncode == 1
    errors = [line for line in done.stderr.splitlines() if line.startswith("shadowgeo convert:")]
    assert len(errors) == 2
    assert errors[0].startswith(f"shadowgeo convert: {folder / 'broken.x3d'} line ")
    assert "malformed XML" in errors[0] and errors[0].count("broken.x3d") == 1
    assert errors[1] == f"shadowgeo convert: {tmp_path / 'missing.glb'}: no such file"
    assert "note: skipped 1 file(s) no reader takes" in done.stderr
    assert "converted 1 of 3 file(s)" in done.stdout and "2 failed" in done.stdout
    # the good file written where its folder put it, nothing left of the bad ones
    assert digests(out) == {"sub/pyramid.x3d": single["pyramid.x3d"]}


def test_outputs_are_named_after_their_inputs(tmp_path):
    folder = tmp_path / "in"
    (folder / "a" / "b").mkdir(parents=True)
    for name in ("a/b/one.x3dv.gz", "two.obj", "three.x3d", "notes.md"):
        (folder / name).write_bytes(b"")
    out = folder / "out"  # inside the input folder: earlier outputs are not inputs
    (out).mkdir()
    (out / "three.x3d").write_bytes(b"")
    jobs, skipped = jobs_for([folder, tmp_path / "x.usda"], out, None)
    assert skipped == 1
    assert [(s.relative_to(tmp_path), t.relative_to(out)) for s, t in jobs] == [
        (Path("in/a/b/one.x3dv.gz"), Path("a/b/one.x3dv.gz")),
        (Path("in/three.x3d"), Path("three.x3d")),
        (Path("in/two.obj"), Path("two.glb")),  # no writer for .obj
        (Path("x.usda"), Path("x.usda")),
    ]
    jobs, _ = jobs_for([folder], out, ".usda")
    assert [t.name for _, t in jobs] == ["one.usda", "three.usda", "two.usda"]


def test_inputs_differing_only_in_extension_keep_it_in_their_outputs_name(tmp_path):
    """A folder holding one scene in three encodings (as the corpus's
    IkeaTable.x3dv, .x3dv.gz and .x3dvz) and a glb twin, under --format glb:
    each written, the glb under its own name, the others under their whole
    names; names compared case-folded. The same name in two input folders
    cannot be told apart by a rename and is refused, both inputs named."""
    folder = tmp_path / "in"
    folder.mkdir()
    for name in ("table.x3dv", "table.x3dv.gz", "Table.x3dvz", "table.glb", "chair.x3d"):
        (folder / name).write_bytes(b"")
    out = tmp_path / "out"
    jobs, renamed = distinct_targets(jobs_for([folder], out, ".glb")[0])
    names = {source.name: target.relative_to(out).as_posix() for source, target in jobs}
    assert names == {
        "Table.x3dvz": "Table.x3dvz.glb",
        "chair.x3d": "chair.glb",  # no twin: the plain name
        "table.glb": "table.glb",
        "table.x3dv": "table.x3dv.glb",
        "table.x3dv.gz": "table.x3dv.gz.glb",
    }
    assert sorted(source.name for source, _ in renamed) == [
        "Table.x3dvz",
        "table.x3dv",
        "table.x3dv.gz",
    ]
    assert len({str(target).casefold() for _, target in jobs}) == len(jobs)
    # without twins nothing is renamed
    assert distinct_targets(jobs_for([folder / "chair.x3d"], out, None)[0])[1] == []
    other = tmp_path / "other"
    other.mkdir()
    (other / "chair.x3d").write_bytes(b"")
    with pytest.raises(sg.SceneError) as error:
        distinct_targets(jobs_for([folder / "chair.x3d", other / "chair.x3d"], out, None)[0])
    assert str(folder / "chair.x3d") in str(error.value)
    assert str(other / "chair.x3d") in str(error.value)
    assert "same output file" in str(error.value)


def test_usage_errors(capsys, tmp_path):
    for args in (
        ["convert", str(BASIC)],  # no OUT
        ["convert", str(BASIC), str(tmp_path / "o.x3d"), "--workers", "2"],  # batch-only flag
        ["convert", str(SCENES), str(tmp_path / "o"), "--format", "obj"],  # no writer
        ["convert", str(SCENES), str(tmp_path / "o"), "--workers", "0"],
        ["convert", str(SCENES), str(tmp_path / "o"), "--serial", "--scheduler", "tcp://x:1"],
    ):
        with pytest.raises(SystemExit) as exit_:
            main(args)
        assert exit_.value.code == 2, args
    capsys.readouterr()
    # two inputs that would land on one output
    twin = tmp_path / "twin"
    twin.mkdir()
    shutil.copy(BASIC, twin / "basic.x3d")
    done = in_process(capsys, "convert", BASIC, twin / "basic.x3d", tmp_path / "o", "--serial")
    assert done.returncode == 1 and "same output file" in done.stderr
    assert str(BASIC) in done.stderr and str(twin / "basic.x3d") in done.stderr
