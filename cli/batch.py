"""``shadowgeo convert IN... OUT_DIR``: many scenes, on Dask.

The batch form of ``convert``: the inputs are folders (every scene file under
them, subfolders kept) and files; each is converted on its own, on a Dask
``LocalCluster`` started here (``--workers N``), on a running cluster
(``--scheduler ADDRESS``) or one after another in this process (``--serial``).
A thin layer over :func:`shadowgeo.batch.convert_files`.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import shadowgeo
from shadowgeo.batch import Outcome, convert_files, scene_suffix
from shadowgeo.io import WRITERS

from .common import ProgressBar, dask_failure, options_of, terminal


def jobs_for(
    inputs: list[Path], out_dir: Path, suffix: str | None
) -> tuple[list[tuple[Path, Path]], int]:
    """(source, target) pairs for the files and folders of ``inputs``, and the
    number of files skipped in folders (no reader for them). A folder's files
    keep their place below it; a file lands in ``out_dir`` itself."""
    jobs, skipped = [], 0
    out_resolved = out_dir.resolve()
    for given in inputs:
        if given.is_dir():
            for path in sorted(p for p in given.rglob("*") if p.is_file()):
                if out_resolved in path.resolve().parents:
                    continue  # an earlier run's outputs inside an input folder
                if scene_suffix(path) is None:
                    skipped += 1
                    continue
                jobs.append((path, out_dir / _renamed(path.relative_to(given), suffix)))
        else:
            jobs.append((given, out_dir / _renamed(Path(given.name), suffix)))
    return jobs, skipped


def distinct_targets(
    jobs: list[tuple[Path, Path]],
) -> tuple[list[tuple[Path, Path]], list[tuple[Path, Path]]]:
    """``jobs`` with every target its own, and the jobs renamed to make it so.

    Inputs that differ only in their scene extension (``table.x3dv``,
    ``table.x3dv.gz`` and ``table.x3dvz`` of one folder, all ``table.glb``
    under ``--format glb``) keep their whole name before the new extension
    (``table.x3dv.glb``, ...); an input already in the output's format keeps
    its plain name. Targets are compared case-folded: on a case-insensitive
    file system ``Table.glb`` and ``table.glb`` are one file. Raises
    :class:`shadowgeo.SceneError` naming the inputs when two still share a
    target (the same name in two input folders)."""

    def clashes(pairs: list[tuple[Path, Path]]) -> dict[str, list[int]]:
        seen: dict[str, list[int]] = {}
        for index, (_, target) in enumerate(pairs):
            seen.setdefault(str(target).casefold(), []).append(index)
        return {key: indices for key, indices in seen.items() if len(indices) > 1}

    result = list(jobs)
    renamed = []
    for indices in clashes(result).values():
        for index in indices:
            source, target = result[index]
            if source.name.casefold() == target.name.casefold():
                continue  # already in the output's format: the plain name stays
            chosen = target.name[len(target.name) - len(scene_suffix(target) or "") :]
            result[index] = (source, target.with_name(source.name + chosen))
            renamed.append(result[index])
    left = clashes(result)
    if left:
        indices = next(iter(left.values()))
        sources = ", ".join(str(result[index][0]) for index in indices)
        raise shadowgeo.SceneError(
            f"{sources} would be written to the same output file {result[indices[0]][1]}; "
            "convert them into different folders"
        )
    return result, renamed


def _renamed(relative: Path, suffix: str | None) -> Path:
    """``relative`` with its scene extension replaced by ``suffix`` (kept when
    None and writable, else ``.glb``)."""
    own = scene_suffix(relative)
    if own is None:
        return relative if suffix is None else relative.with_name(relative.name + suffix)
    stem = relative.name[: len(relative.name) - len(own)]
    chosen = suffix or (own if own in WRITERS else ".glb")
    return relative.with_name(stem + chosen)


def run_batch(args: argparse.Namespace, inputs: list[Path], out_dir: Path) -> int:
    if out_dir.exists() and not out_dir.is_dir():
        raise shadowgeo.SceneError(
            "OUT must be a folder when converting several files", path=str(out_dir)
        )
    jobs, skipped = jobs_for(inputs, out_dir, args.format)
    if not jobs:
        print("shadowgeo convert: no scene files in the inputs", file=sys.stderr)
        return 1
    if skipped:
        print(f"note: skipped {skipped} file(s) no reader takes", file=sys.stderr)
    jobs = _checked_targets(jobs)
    scheduler = None if args.serial else (args.scheduler or "local")
    converted = _convert(args, jobs, scheduler)
    if isinstance(converted, int):
        return converted
    outcomes, elapsed = converted
    report(outcomes)
    failed = sum(not outcome.ok for outcome in outcomes)
    print(
        f"converted {len(outcomes) - failed} of {len(outcomes)} file(s) into {out_dir} "
        f"in {elapsed:.1f} s {_where(args, scheduler)}" + (f"; {failed} failed" if failed else "")
    )
    return 1 if failed else 0


def _checked_targets(jobs: list[tuple[Path, Path]]) -> list[tuple[Path, Path]]:
    """``jobs`` with distinct targets, each output folder found writable
    before the long work, and a note for each input renamed."""
    jobs, renamed = distinct_targets(jobs)
    first_in = {target.parent: target for _, target in reversed(jobs)}
    for target in first_in.values():  # a folder that cannot be written, before the long work
        shadowgeo.io.check_writable(target)
    for source, target in renamed:
        print(
            f"note: {source} is written as {target.name}: another input has the same name "
            "but for its extension",
            file=sys.stderr,
        )
    return jobs


def _where(args: argparse.Namespace, scheduler: str | None) -> str:
    """Where the files were converted, for the closing line."""
    return (
        "in this process"
        if scheduler is None
        else f"on the Dask cluster at {scheduler}"
        if args.scheduler
        else f"on a Dask LocalCluster of {args.workers or 'one worker per core'}"
        + (" worker(s)" if args.workers else "")
    )


def _convert(
    args: argparse.Namespace, jobs: list[tuple[Path, Path]], scheduler: str | None
) -> tuple[list[Outcome], float] | int:
    """The outcomes of the jobs and the seconds they took, under a progress
    bar; an exit code when Dask cannot run."""
    options = options_of(args)
    show = args.progress or sys.stderr.isatty()
    bar = ProgressBar(f"{len(jobs)} files") if show else None
    begin = time.perf_counter()
    try:
        outcomes = convert_files(
            jobs, options, scheduler=scheduler, workers=args.workers, progress=bar
        )
    except (ImportError, OSError) as error:
        return dask_failure("convert", error)
    finally:
        if bar is not None:
            bar.close()
    return outcomes, time.perf_counter() - begin


def report(outcomes: list[Outcome]) -> None:
    """One line a file written (stdout), one a file failed (stderr), and the
    shadows' notes, named by file, in the order the files were given."""
    for outcome in outcomes:
        if not outcome.ok:
            error = str(outcome.error)
            # name the file once: most errors start with it already
            named = error if error.startswith(str(outcome.source)) else f"{outcome.source}: {error}"
            print(f"shadowgeo convert: {terminal(named)}", file=sys.stderr)
            continue
        for note in outcome.notes:
            print(f"note: {terminal(f'{outcome.source}: {note}')}", file=sys.stderr)
        groups = f": {', '.join(outcome.groups)}" if outcome.groups else ""
        print(
            f"wrote {outcome.target}: {outcome.n_shapes} shape(s), {outcome.n_triangles} "
            f"triangles, in {len(outcome.groups)} group(s){groups}"
        )
