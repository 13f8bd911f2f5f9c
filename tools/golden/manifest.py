"""Running the golden cases, writing the manifest, comparing with an old one.

The manifest is JSON: ``commit`` (``git rev-parse HEAD``, and whether the
tree had changes), ``environment`` (Python, the libraries, the CPU),
``corpus`` (whether the corpus cases ran), ``nondeterministic`` (cases whose
two runs differed) and ``cases``, one record per case id, each with ``what``
it is and what it produced (see :mod:`golden.digest` and
:mod:`golden.conversions`). Two records are the same when every field but
``what`` is equal.
"""

from __future__ import annotations

import json
import subprocess
import tempfile
import time
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from . import conversions, geometry
from .digest import Digest

ROOT = Path(__file__).resolve().parents[2]


def corpus_folder(root: Path = ROOT) -> Path | None:
    """``../shared/corpus`` beside the repository, resolved; None when absent."""
    corpus = root.parent / "shared" / "corpus"
    return corpus.resolve() if corpus.is_dir() else None


def all_cases(corpus: Path | None, root: Path = ROOT) -> list[Any]:
    return [*conversions.cases(root, corpus), *geometry.cases()]


def commit(root: Path = ROOT) -> dict[str, Any]:
    """HEAD of the repository at ``root`` and whether its tree has changes
    (untracked files included); "unknown" outside a git checkout."""

    def git(*args: str) -> str:
        return subprocess.run(
            ["git", *args], cwd=root, capture_output=True, text=True, check=True
        ).stdout.strip()

    try:
        return {"head": git("rev-parse", "HEAD"), "dirty": bool(git("status", "--porcelain"))}
    except (OSError, subprocess.CalledProcessError):
        return {"head": "unknown", "dirty": True}


@dataclass
class Run:
    """The digests of the cases that ran, by id; the ids that differed between
    two runs in this process (with ``repeat``)."""

    digests: dict[str, Digest]
    unstable: list[str]
    seconds: float


def run(
    cases: Iterable[Any],
    corpus: Path | None,
    repeat: bool = False,
    keep: Path | None = None,
    progress: bool = True,
) -> Run:
    """Each case once, conversions twice (``repeat``: every case twice), each
    run in its own scratch folder; a case whose two records differ is listed
    as unstable."""
    cases = list(cases)
    checked_import()
    start = time.perf_counter()
    digests, unstable = {}, []
    with tempfile.TemporaryDirectory(prefix="golden-") as folder:
        scratches = [Path(folder) / "a", Path(folder) / "b"]
        for scratch in scratches:
            conversions.stage(ROOT, corpus, scratch)
        for index, case in enumerate(cases):
            began = time.perf_counter()
            twice = repeat or isinstance(case, conversions.Conversion)
            results = [case.run(scratch) for scratch in scratches[: 2 if twice else 1]]
            digests[case.id] = results[0]
            if any(result.record != results[0].record for result in results[1:]):
                unstable.append(case.id)
            if progress:
                print(
                    f"[{index + 1}/{len(cases)}] {case.id} ({time.perf_counter() - began:.2f} s)",
                    flush=True,
                )
            if keep is not None:
                write_kept(keep, case.id, results[0])
    return Run(digests, unstable, time.perf_counter() - start)


def write_kept(keep: Path, case_id: str, result: Digest) -> None:
    """The output files and an .npz of the arrays of one case under ``keep/<id>/``."""
    folder = keep / case_id
    folder.mkdir(parents=True, exist_ok=True)
    for name, data in result.files.items():
        (folder / name).write_bytes(data)
    if result.arrays:
        np.savez(folder / "arrays.npz", **result.arrays)
    (folder / "record.json").write_text(json.dumps(result.record, indent=1, sort_keys=True))


def environment() -> dict[str, str]:
    """Python's and the numeric libraries' versions (the bytes may depend on them)."""
    import importlib.metadata
    import platform

    found = {"python": platform.python_version(), "machine": platform.machine(), "cpu": _cpu()}
    for name in (
        "numpy",
        "shapely",
        "trimesh",
        "manifold3d",
        "numba",
        "lxml",
        "usd-core",
        "orjson",
    ):
        try:
            found[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            found[name] = "absent"
    return found


def environment_changes(old: dict[str, Any], new: dict[str, Any]) -> list[str]:
    """``name old -> new`` for each entry of the environment that changed."""
    before, after = old.get("environment", {}), new.get("environment", {})
    return [
        f"{name} {before.get(name)} -> {after.get(name)}"
        for name in sorted(before.keys() | after.keys())
        if before.get(name) != after.get(name)
    ]


def checked_import(root: Path = ROOT) -> None:
    """Import shadowgeo and check it is the one in ``root`` (an editable
    install of another checkout would be imported first otherwise)."""
    import shadowgeo

    where = Path(shadowgeo.__file__).resolve().parent
    if where != root / "shadowgeo":
        raise SystemExit(f"golden: shadowgeo imported from {where}, not from {root}")


def manifest(cases: list[Any], done: Run, corpus: Path | None) -> dict[str, Any]:
    return {
        "tool": "tools/golden.py",
        "commit": commit(),
        "environment": environment(),
        "corpus": corpus is not None,
        "cases": {
            case.id: {"what": case.what, **done.digests[case.id].record}
            for case in cases
            if case.id in done.digests
        },
    }


def write(path: Path, data: dict[str, Any]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(path.name + ".tmp")
    temporary.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")
    temporary.replace(path)


def same(old: dict[str, Any], new: dict[str, Any]) -> bool:
    strip = {"what"}
    return {k: v for k, v in old.items() if k not in strip} == {
        k: v for k, v in new.items() if k not in strip
    }


def verdict(old: dict[str, Any] | None, new: dict[str, Any] | None) -> tuple[str, str]:
    """(status, detail) of one case: identical, different, not run or new."""
    if new is None:
        return "not run", ""
    if old is None:
        return "new", ""
    if same(old, new):
        return "identical", ""
    return "different", difference(old, new)


def difference(old: dict[str, Any], new: dict[str, Any]) -> str:
    """What differs: the input, the error, the area (with its relative change),
    counts, then the names of the arrays or files whose bytes differ."""
    notes = []
    for key in ("input_sha256", "study_input_sha256"):
        if old.get(key) != new.get(key):
            notes.append("INPUT CHANGED")
    if old.get("error") != new.get("error"):
        notes.append(f"error {old.get('error')!r} -> {new.get('error')!r}")
    if "area" in old and "area" in new and old["area"] != new["area"]:
        before, after = float(old["area"]), float(new["area"])
        relative = abs(after - before) / abs(before) if before else float("inf")
        notes.append(
            f"area {before!r} -> {after!r} (diff {after - before:.3g}, rel {relative:.3g})"
        )
    for group in ("areas", "counts", "arrays", "outputs"):
        before, after = old.get(group, {}), new.get(group, {})
        changed = sorted(
            key for key in before.keys() | after.keys() if before.get(key) != after.get(key)
        )
        if changed and group == "counts":
            notes.append(
                "counts " + ", ".join(f"{k} {before.get(k)}->{after.get(k)}" for k in changed)
            )
        elif changed:
            shown = ", ".join(changed[:6]) + (", ..." if len(changed) > 6 else "")
            notes.append(f"{group} differ: {shown}")
    rest = {k for k in old.keys() | new.keys() if old.get(k) != new.get(k)} - {
        "what",
        "input_sha256",
        "study_input_sha256",
        "error",
        "area",
        "areas",
        "counts",
        "arrays",
        "outputs",
        "sizes",
    }
    if rest:
        notes.append("also " + ", ".join(sorted(rest)))
    return "; ".join(notes)


def table(old: dict[str, Any], new: dict[str, Any]) -> tuple[list[str], dict[str, int]]:
    """Lines of the comparison and the number of cases of each status."""
    old_cases, new_cases = old["cases"], new["cases"]
    lines, tally = [], {}
    for case_id in [*old_cases, *(k for k in new_cases if k not in old_cases)]:
        status, detail = verdict(old_cases.get(case_id), new_cases.get(case_id))
        tally[status] = tally.get(status, 0) + 1
        lines.append(f"{status:<10} {case_id}" + (f"  {detail}" if detail else ""))
    return lines, tally


def _cpu() -> str:
    geometry.benchmarks_on_path()  # the benchmarks' own record of the machine
    from common import cpu_model

    return str(cpu_model())
