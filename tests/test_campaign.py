"""The fuzz campaign over every encoding (issue 34 item 1): the city encodings'
seeds and mutants, and ``tools/fuzz.py campaign`` writing its table into a
report."""

from __future__ import annotations

import contextlib
import json
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from fuzz_replay import fuzz_module
from needs import SHARED, absent

import shadowgeo as sg

ROOT = Path(__file__).resolve().parents[1]
GIS = SHARED / "corpus" / "gis"


def corpus_file(name: str) -> Path:
    path = GIS / name
    if not path.is_file():
        absent(f"{path} is missing")
    return path


def test_every_reader_encoding_is_fuzzed():
    inputs = fuzz_module("inputs")
    wanted = {"x3d", "x3dz", "x3dv", "wrl", "x3dj", "gltf", "glb", "usda", "usdc"}
    wanted |= {"cityjson", "geojson"}
    assert wanted <= set(inputs.ENCODINGS)
    assert inputs.ENCODINGS["cityjson"] == ".city.json"
    for encoding in inputs.ENCODINGS:  # each suffix has a reader: a mutant reaches it
        assert sg.io.reader_name(f"scene{inputs.ENCODINGS[encoding]}")


def test_a_big_cityjson_file_is_cut_to_its_first_objects_with_their_own_points(tmp_path):
    source = corpus_file("delft_lod1.city.json")
    whole = json.loads(source.read_bytes())
    cut = fuzz_module("mutate_city").subset(source.read_bytes(), "cityjson", 5)
    small = json.loads(cut)
    assert len(cut) < len(source.read_bytes()) / 20
    assert list(small["CityObjects"]) == list(whole["CityObjects"])[:5]

    def points(document, name):
        """The object's boundary points, in order: the reference, read by hand."""
        found = []

        def walk(value):
            if isinstance(value, list):
                for item in value:
                    walk(item)
            elif isinstance(value, int):
                found.append(tuple(document["vertices"][value]))

        for geometry in document["CityObjects"][name].get("geometry", []):
            walk(geometry["boundaries"])
        return found

    for name in small["CityObjects"]:
        assert points(small, name) == points(whole, name)
    assert len(small["vertices"]) == len(
        {i for n in small["CityObjects"] for i in points(small, n)}
    )
    path = tmp_path / "cut.city.json"
    path.write_bytes(cut)
    sg.load(path)  # a file the reader takes


@pytest.mark.parametrize("encoding", ["cityjson", "geojson"])
def test_city_mutants_are_reproducible_json_that_changes(encoding):
    name = "rotterdam_subset.city.json" if encoding == "cityjson" else "suzhou_buildings.geojson"
    data = corpus_file(name).read_bytes()
    mutate_city = fuzz_module("mutate_city")
    seed = mutate_city.subset(data, encoding, 12) if len(data) > 64 << 10 else data
    made = [mutate_city.mutate_city(seed, encoding, random.Random(i)) for i in range(40)]
    again = [mutate_city.mutate_city(seed, encoding, random.Random(i)) for i in range(40)]
    assert made == again
    done = [m for m in made if m is not None]
    assert len(done) >= 30
    assert all(data != seed for data, _ in done)
    kinds = {op.split("-")[1] for _, op in done}
    assert len(kinds) >= 5  # the operations are all reached
    for data, _ in done:
        json.loads(data)  # whole JSON: the reader's own checks are what is tried


def test_the_campaign_command_writes_its_table_into_the_report(tmp_path):
    report = tmp_path / "REPORT.md"
    report.write_text("# report\n\n## Fuzz campaign\n\nold table\n\n## Next section\n\nkept\n")
    out = tmp_path / "campaign"
    command = [sys.executable, str(ROOT / "tools" / "fuzz.py"), "campaign", "--per-encoding", "2"]
    command += ["--geometry", "3", "--seed", "4", "--jobs", "1", "--out", str(out)]
    command += ["--encodings", "x3d,cityjson,geojson", "--report", str(report)]
    done = subprocess.run(command, capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert done.returncode in (0, 1), done.stderr[-2000:]
    text = report.read_text()
    assert "old table" not in text and text.endswith("## Next section\n\nkept\n")
    runs = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    for group in ("x3d", "cityjson", "geojson", "geometry"):
        count = sum(1 for r in runs if r.get("encoding", "geometry") == group)
        failures = sum(1 for r in runs if r.get("encoding", "geometry") == group and not r["ok"])
        assert f"| {group} | {count:,} | {failures:,} |" in text
        assert count == (3 if group == "geometry" else 2)
    head = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=ROOT
    ).stdout.strip()
    assert f"at commit {head}" in text and "seed 4, 1 workers: 9 runs" in text
    assert "`python tools/fuzz.py campaign --per-encoding 2 --geometry 3 --seed 4" in text
    assert "would take about" in text


# -- stopped and resumed ------------------------------------------------------------------------

TINY = ["--inputs", "3", "--geometry", "6", "--seed", "5", "--jobs", "1", "--no-known"]
TINY += ["--encodings", "x3d,geojson", "--shrink-tries", "2", "--quiet"]
TINY_RUNS = 3 * 2 + 6


def fuzz(out: Path, *extra: str) -> subprocess.CompletedProcess:
    command = [sys.executable, str(ROOT / "tools" / "fuzz.py"), *TINY, "--out", str(out), *extra]
    return subprocess.run(command, capture_output=True, text=True, timeout=600, cwd=ROOT)


def runs_of(out: Path) -> list[tuple]:
    """Each recorded run: which one it is and how it ended (not its timing)."""
    runs = []
    for line in (out / "results.jsonl").read_text().splitlines():
        entry = json.loads(line)
        which = (
            ("geometry", entry["case"]) if "case" in entry else (entry["encoding"], entry["index"])
        )
        runs.append((which, entry["ok"], entry["signature"], entry.get("code")))
    return runs


def workers_left(out: Path, wait: float = 10.0) -> list[int]:
    """The processes still running whose command line names ``out`` (the
    campaign's forked workers have its command line), after up to ``wait`` s."""
    deadline = time.monotonic() + wait
    while True:
        left = []
        for entry in Path("/proc").iterdir():
            with contextlib.suppress(OSError):
                if entry.name.isdigit() and str(out).encode() in (entry / "cmdline").read_bytes():
                    state = (entry / "stat").read_text().rsplit(")", 1)[1].split()[0]
                    if state != "Z":  # (a zombie is dead, waiting for its reaper)
                        left.append(int(entry.name))
        if not left or time.monotonic() > deadline:
            return left
        time.sleep(0.1)


def stopped_part_way(out: Path, signum: int) -> subprocess.Popen:
    """A campaign sent ``signum`` as soon as it has recorded a run."""
    command = [sys.executable, str(ROOT / "tools" / "fuzz.py"), *TINY, "--out", str(out)]
    process = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    results = out / "results.jsonl"
    deadline = time.monotonic() + 300
    while not (results.is_file() and results.read_bytes().count(b"\n")):
        assert process.poll() is None and time.monotonic() < deadline
        time.sleep(0.01)
    os.kill(process.pid, signum)
    process.communicate(timeout=120)
    return process


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGKILL])
def test_a_campaign_stopped_part_way_and_resumed_records_the_runs_of_an_uninterrupted_one(
    tmp_path, signum
):
    whole = fuzz(tmp_path / "whole")
    assert whole.returncode in (0, 1), whole.stderr[-2000:]
    expected = runs_of(tmp_path / "whole")
    assert len(expected) == TINY_RUNS

    out = tmp_path / "stopped"
    process = stopped_part_way(out, signum)
    assert process.returncode == (143 if signum == signal.SIGTERM else -signal.SIGKILL)
    assert not workers_left(out)  # even SIGKILL, which the campaign cannot see, ends them
    kept = runs_of(out)  # whole lines only, each run's as it ended
    assert 1 <= len(kept) < TINY_RUNS and set(kept) <= set(expected)
    with (out / "results.jsonl").open("a") as stream:
        stream.write('{"encoding": "x3d", "ind')  # a line torn by a kill during the write

    resumed = fuzz(out, "--resume")
    assert resumed.returncode == whole.returncode, resumed.stderr[-2000:]
    runs = runs_of(out)
    assert sorted(runs) == sorted(expected)  # each run once: none lost, none run twice
    assert runs[: len(kept)] == kept

    def table(text: str) -> list[str]:  # the runs and exits per encoding, of every session
        return [line for line in text.splitlines() if line.startswith("| ")]

    assert table((out / "summary.md").read_text()) == table(
        (tmp_path / "whole" / "summary.md").read_text()
    )


def test_resuming_is_refused_when_the_seed_or_the_commit_differ(tmp_path):
    out = tmp_path / "campaign"
    first = fuzz(out)
    assert first.returncode in (0, 1), first.stderr[-2000:]
    results = (out / "results.jsonl").read_bytes()
    other_seed = [sys.executable, str(ROOT / "tools" / "fuzz.py"), *TINY, "--out", str(out)]
    other_seed[other_seed.index("--seed") + 1] = "6"
    done = subprocess.run(other_seed, capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert done.returncode == 2 and "seed 5 now 6" in done.stderr
    plan = json.loads((out / "campaign.json").read_text())
    (out / "campaign.json").write_text(json.dumps(dict(plan, commit="0" * 40)))
    done = fuzz(out)
    assert done.returncode == 2 and "commit '" + "0" * 40 in done.stderr
    assert (out / "results.jsonl").read_bytes() == results  # nothing run, nothing lost
    empty = tmp_path / "empty"
    done = fuzz(empty, "--resume")
    assert done.returncode == 2 and "nothing to resume" in done.stderr
