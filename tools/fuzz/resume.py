"""A campaign that can stop and go on: what it is (commit, changes, seed,
sizes, seed files) kept in ``campaign.json`` beside its ``results.jsonl``, the
runs already recorded read back, and a refusal when the code or the plan
differs, so that every run in one results file is of one commit.

A run is recorded by one line of ``results.jsonl``, flushed as it ends; a
campaign killed outright loses only the runs in flight (and at most a
half-written last line, which is dropped here before appending)."""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
from pathlib import Path

from .inputs import ROOT

PLAN = "campaign.json"
RESULTS = "results.jsonl"


class ResumeRefused(Exception):
    """The output folder holds runs of another commit or another plan."""


def checkout() -> dict[str, str]:
    """The commit the runs use, and a digest of its uncommitted changes ("" when none)."""

    def git(*args: str) -> str:
        done = subprocess.run(["git", *args], capture_output=True, text=True, cwd=ROOT)
        return done.stdout

    changes = git("diff", "HEAD")
    return {
        "commit": git("rev-parse", "HEAD").strip() or "unknown",
        "changes": hashlib.sha256(changes.encode()).hexdigest()[:16] if changes else "",
    }


def plan_of(args, encodings: list[str], seeds: dict[str, list]) -> dict:
    """What must be the same for two sessions' runs to be one campaign."""
    digest = hashlib.sha256()
    for encoding in sorted(seeds):
        for name, data in seeds[encoding]:
            digest.update(f"{encoding}\0{name}\0{len(data)}\0".encode())
            digest.update(data)
    return {
        **checkout(),
        "seed": args.seed,
        "inputs": args.inputs,
        "first_index": args.first_index,
        "geometry": args.geometry,
        "encodings": sorted(encodings),
        "time_budget": args.time_budget,
        "memory_budget": args.memory_budget,
        "seed_files": digest.hexdigest()[:16],
    }


def run_key(entry: dict) -> tuple[str, int]:
    """(encoding, mutant index), or ("geometry", case index): one run of a campaign."""
    if "case" in entry:
        return ("geometry", int(entry["case"]))
    return (entry["encoding"], int(entry["index"]))


def recorded(out: Path, plan: dict) -> tuple[list[dict], float]:
    """The runs ``out`` holds of this ``plan``, and the wall-clock seconds its
    earlier sessions took; ``([], 0.0)`` for a folder with no results yet.
    A half-written last line (a kill during the write) is cut off the file.

    Raises :class:`ResumeRefused` when the folder's runs are of another plan."""
    results, saved = out / RESULTS, out / PLAN
    if not results.is_file() or not results.stat().st_size:
        return [], 0.0
    if not saved.is_file():
        raise ResumeRefused(f"{results} has runs but no {PLAN}: not a campaign to go on with")
    before = json.loads(saved.read_text())
    differ = [k for k in plan if before.get(k) != plan[k]]
    if differ:
        said = ", ".join(f"{k} {before.get(k)!r} now {plan[k]!r}" for k in differ)
        raise ResumeRefused(
            f"{out} holds runs of another campaign ({said}); "
            "give another --out, or delete that folder to start again"
        )
    return _whole_lines(results), float(before.get("wall_seconds", 0.0))


def _whole_lines(results: Path) -> list[dict]:
    """The entries of ``results``, after cutting a half-written last line off it."""
    data = results.read_bytes()
    entries, kept = [], 0
    for line in data.splitlines(keepends=True):
        try:
            entry = json.loads(line) if line.endswith(b"\n") else None
        except json.JSONDecodeError:
            entry = None
        if entry is None:
            break  # a torn line (written at a kill): it and anything after are lost runs
        entries.append(entry)
        kept += len(line)
    if kept != len(data):
        with results.open("r+b") as stream:
            stream.truncate(kept)
    return entries


def save_plan(out: Path, plan: dict, wall_seconds: float) -> None:
    """Write ``campaign.json`` (atomically: a rename) with the seconds spent so far."""
    temporary = out / f".{PLAN}.{os.getpid()}"
    temporary.write_text(json.dumps({**plan, "wall_seconds": wall_seconds}, indent=1) + "\n")
    temporary.replace(out / PLAN)
