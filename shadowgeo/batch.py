"""Batch conversion: many scenes read, shadowed and written, here or on Dask.

Each file is one independent job (:func:`convert_file`: load, add the shadows,
save atomically). :func:`convert_files` runs the jobs one after another in
this process, or hands them to Dask (``scheduler``), one task a file; either
way a file's output is byte for byte the same, and a file that fails is
reported with its name while the others go on. Dask only schedules: nothing
here queues, retries or balances work itself. A task whose worker dies is run
again on another by Dask (``distributed.scheduler.allowed-failures`` times, 3
by default), then reported as failed; as every output is written atomically,
a file is whole or not there (the hidden temporary files of workers killed
mid-write are removed when the batch ends: :func:`~shadowgeo.io.atomic.remove_stale`).

On a cluster every worker must see the input and output paths under the same
names (a shared file system) and have shadowgeo installed.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from .errors import GeometryError, SceneError
from .io import READERS, load, reader_name, save
from .io.atomic import remove_stale
from .lights import DirectionalLight
from .plane import Plane
from .scene import Scene, SceneLight
from .scene.shadows import Progress, add_shadows
from .scene.softbake import with_light_sizes

__all__ = [
    "ConvertOptions",
    "Outcome",
    "convert_file",
    "convert_files",
    "save_output",
    "scene_suffix",
    "shadowed",
]


@dataclass(frozen=True)
class ConvertOptions:
    """What :func:`add_shadows` is asked for every file (see its parameters);
    ``sun``: a directional light that casts instead of the scene's own
    (unless named in ``lights``), not written into the scene;
    ``max_triangles``: the reader's budget (:func:`shadowgeo.load`);
    ``keep_runtime_shadows``, ``soft_levels``, ``soft_samples``: see
    :func:`add_shadows`; ``sun_angle`` (radians) and ``light_sizes`` ((name,
    source radius) pairs): sizes given to the scene's lights and ``sun``
    (:func:`~shadowgeo.scene.softbake.with_light_sizes`)."""

    method: Literal["planar", "volume"] = "planar"
    lights: tuple[str, ...] | None = None
    receivers: tuple[str, ...] | None = None
    plane: Plane | None = None
    tolerance: float | None = None
    sun: DirectionalLight | None = None
    max_triangles: int | None = None
    keep_runtime_shadows: bool = False
    sun_angle: float | None = None
    light_sizes: tuple[tuple[str, float], ...] = ()
    soft_levels: int = 8
    soft_samples: int | None = None


@dataclass(frozen=True)
class Outcome:
    """How one file went: ``error`` is None when it was written."""

    source: Path
    target: Path
    error: str | None = None
    notes: tuple[str, ...] = field(default=(), repr=False)
    n_shapes: int = 0
    n_triangles: int = 0
    groups: tuple[str, ...] = ()

    @property
    def ok(self) -> bool:
        return self.error is None


def scene_suffix(path: Path) -> str | None:
    """The reader extension ``path`` ends with (``.x3dv.gz`` before ``.gz``),
    or None when no reader takes it."""
    name = path.name.lower()
    matches = [suffix for suffix in READERS if name.endswith(suffix)]
    return max(matches, key=len) if matches else None


def shadowed(
    source: Path, options: ConvertOptions, progress: Progress | None = None
) -> tuple[Scene, Scene]:
    """The scene read from ``source`` and the same with the shadows
    ``options`` ask for (see :func:`add_shadows`; ``progress`` is passed on)."""
    # the chord only matters for X3D's curved primitives; other readers take no options
    curved = options.tolerance is not None and reader_name(source) == "x3d.read"
    scene = load(
        source,
        max_triangles=options.max_triangles,
        **({"chord": options.tolerance} if curved else {}),
    )
    if options.sun_angle is not None or options.light_sizes:
        scene = with_light_sizes(
            scene, sun_angle=options.sun_angle, light_sizes=options.light_sizes
        )
    sun = options.sun
    if sun is not None and options.sun_angle is not None:
        sun = DirectionalLight(sun.direction, options.sun_angle)
    extra = [] if sun is None else [SceneLight(sun, name="sun", shadows=True)]
    result = add_shadows(
        scene,
        method=options.method,
        lights=options.lights,
        receivers=options.receivers,
        plane=options.plane,
        tolerance=options.tolerance,
        progress=progress,
        extra_lights=extra,
        keep_runtime_shadows=options.keep_runtime_shadows,
        soft_levels=options.soft_levels,
        soft_samples=options.soft_samples,
    )
    return scene, result


def convert_file(source: Path, target: Path, options: ConvertOptions) -> Outcome:
    """Read ``source``, add its shadows, write ``target`` atomically.

    Never raises for a bad file: a :class:`SceneError`, :class:`GeometryError`
    or an error of the file system comes back as ``Outcome.error``; so does
    any other exception, named by its type, so that one file cannot stop a
    batch.
    """
    try:
        if target.exists() and source.exists() and os.path.samefile(source, target):
            raise SceneError("OUT is the input file; it is never overwritten", path=str(target))
        scene, result = shadowed(source, options)
        known = len(scene.warnings)
        save_output(result, target)
    except (SceneError, GeometryError) as error:
        return Outcome(source, target, error=str(error))
    except OSError as error:
        return Outcome(source, target, error=f"{error.strerror or error}")
    except Exception as error:  # a bug met on one file must not stop the batch
        return Outcome(source, target, error=f"{type(error).__name__}: {error}")
    added = [shape for shape in result.shapes if shape.role in ("shadow", "volume")]
    return Outcome(
        source,
        target,
        notes=tuple(result.warnings[known:]),
        n_shapes=len(added),
        n_triangles=sum(shape.n_faces for shape in added),
        groups=tuple(sorted({shape.group for shape in added if shape.group})),
    )


def save_output(scene: Scene, target: Path) -> None:
    """:func:`shadowgeo.save` into ``target``'s folder, made if missing; an
    error of the file system (a full disk, a folder that cannot be written)
    is a :class:`SceneError` naming ``target``. Atomic: ``target`` is left
    whole or as it was, with no temporary file beside it."""
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise SceneError(f"cannot write: {error.strerror or error}", path=str(target)) from None
    save(scene, target)


def convert_files(
    jobs: Sequence[tuple[Path, Path]],
    options: ConvertOptions,
    *,
    scheduler: Any = None,
    workers: int | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> list[Outcome]:
    """:func:`convert_file` for each ``(source, target)`` of ``jobs``.

    Parameters
    ----------
    jobs : sequence of (Path, Path)
        Inputs and outputs; outputs must differ.
    options : ConvertOptions
    scheduler : None, "local", address or dask.distributed.Client
        None runs the files one after another in this process; otherwise
        :func:`shadowgeo.parallel.client_for` gives the Dask client (``"local"``
        starts a ``LocalCluster`` of ``workers`` processes here).
    progress : callable, optional
        ``progress(done, total)`` as files finish.

    Returns
    -------
    list of Outcome
        In the order of ``jobs``, whatever order they finished in; a file
        whose task never came back (its Dask worker died on every try) has
        an ``error`` saying so.
    """
    total = len(jobs)
    first: dict[Path, Path] = {}
    for source, target in jobs:
        if target in first:
            raise SceneError(
                f"{first[target]} and {source} would be written to the same output file {target}"
            )
        first[target] = source
    try:
        if scheduler is None:
            outcomes = []
            for done, (source, target) in enumerate(jobs, start=1):
                outcomes.append(convert_file(source, target, options))
                if progress:
                    progress(done, total)
            return outcomes
        return _on_dask(jobs, options, scheduler, workers, progress)
    finally:
        # after the cluster is shut down: what its killed workers left
        remove_stale(target for _, target in jobs)


def _on_dask(
    jobs: Sequence[tuple[Path, Path]],
    options: ConvertOptions,
    scheduler: Any,
    workers: int | None,
    progress: Callable[[int, int], None] | None,
) -> list[Outcome]:
    total = len(jobs)
    from .parallel import client_for

    with client_for(scheduler, workers=workers) as client:
        from dask.distributed import as_completed

        # absolute paths: a worker's working folder is not ours
        futures = [
            client.submit(convert_file, source.resolve(), target.resolve(), options, pure=False)
            for source, target in jobs
        ]
        index_of = {future.key: index for index, future in enumerate(futures)}
        finished: dict[int, Outcome] = {}
        for future in as_completed(futures):
            index = index_of[future.key]
            try:
                outcome = future.result()
            except Exception as lost:  # the task never returned
                outcome = Outcome(*jobs[index], error=_lost(lost, jobs[index][1]))
            # report the paths as the caller gave them, as the serial run does
            source, target = jobs[index]
            given = {str(source.resolve()): str(source), str(target.resolve()): str(target)}
            error = outcome.error
            for absolute, relative in given.items():
                error = error.replace(absolute, relative) if error is not None else None
            finished[index] = Outcome(
                source,
                target,
                error,
                outcome.notes,
                outcome.n_shapes,
                outcome.n_triangles,
                outcome.groups,
            )
            if progress:
                progress(len(finished), total)
        return [finished[index] for index in range(total)]


def _lost(error: Exception, target: Path) -> str:
    """One line for a task Dask gave up on: usually every worker that ran it
    died (``KilledWorker``: killed, out of memory, crashed)."""
    if type(error).__name__ == "KilledWorker":
        why = "the Dask worker converting it died on each try (KilledWorker)"
    else:
        first = str(error).splitlines()[0][:200] if str(error) else ""
        why = f"its Dask task failed: {type(error).__name__}" + (f": {first}" if first else "")
    return f"not converted to {target}: {why}"
