"""When shadowgeo runs its compiled loops (:mod:`shadowgeo.kernels`, numba):
one rule, one override.

numba's import and its cached machine code cost about 0.5-0.8 s and 100 MB
(the first run after installing also compiles them, 5-10 s, and caches
them), so a job loads them only when it is big enough to repay that. Two
kinds of job can:

``"walk"``
    Walking an outline or a permutation (:func:`shadowgeo.topology.cycle_walk`,
    the successor matching of :mod:`shadowgeo.silhouette`). The numpy way and
    the compiled way give the same arrays, bit for bit; the compiled way
    saves about 0.4 s per million items walked (numpy's pointer doubling
    takes about 2 log2(k) passes over k items), so a walk takes it from
    :data:`WALK_ITEMS` items (``python benchmarks/bench_compiled.py`` on a
    shared two-core machine: the import 0.5 s; a walk and its successor
    matching of 2**20 items 1.1-1.3 s with numpy, 0.35 s compiled; of 2**18
    items they save 0.15 s, less than the import).
``"certificate"``
    The test that one outline loop is a light's whole shadow
    (:func:`shadowgeo.batchlights.whole_outlines`): a light whose outline has
    two to 64 loops of 128 corners or more, one loop's box holding the
    others' (a dented caster), is certified by compiled loops instead of
    a 2-D union. Its size is the number of such lights; one is enough
    (:data:`CERTIFICATE_LIGHTS`), as the union of those outlines costs more
    than the import. Without it the union gives the same region to rounding
    (about 1e-12 relative), not the same bits.

``"areas"``
    Each face's shadowed share under the sun, for a study that keeps no
    shadow outlines (:func:`shadowgeo.surface.shadowed_fractions`,
    ``surface_sunlight(..., shadows=False)``): each convex body's shadow on
    each face as one convex piece, and the area of the union of a face's
    convex pieces, by compiled loops instead of a 2-D union and its
    triangles, about four to ten times as fast per sun position over a city
    (a box of a block is one piece a face, not its three to six
    light-facing triangles', and a face inside one is shadowed whole). Its size
    is faces times sun positions; from :data:`AREAS_FACE_SAMPLES` (a day of
    a few thousand faces) the saving repays the import. Without it the
    union gives the same shares to rounding (about 1e-12 of a face's area),
    not the same bits.

The rule ("auto"): a job takes the compiled loops when its size reaches its
threshold. Whether :mod:`shadowgeo.kernels` happens to be imported already
does not matter. The override, innermost first:

1. ``mode=`` of :func:`use_compiled`;
2. a :func:`compiled_loops` block (``with compiled_loops("never"): ...``),
   which holds for the code it runs, in this thread or task;
3. the environment variable ``SHADOWGEO_COMPILED`` (read at each decision,
   so Dask workers started with it follow it);
4. ``"auto"``.

``"always"`` takes the compiled loops for every job of size one or more
(tests, and machines where numba is loaded anyway); ``"never"`` never
imports numba.

Examples
--------
>>> use_compiled("walk", 100, mode="auto"), use_compiled("walk", 10**7, mode="auto")
(False, True)
>>> with compiled_loops("never"):
...     use_compiled("walk", 10**7)
False
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Literal, get_args

__all__ = [
    "AREAS_FACE_SAMPLES",
    "CERTIFICATE_LIGHTS",
    "ENVIRONMENT",
    "WALK_ITEMS",
    "Job",
    "Mode",
    "compiled_loops",
    "current_mode",
    "use_compiled",
]

Mode = Literal["auto", "always", "never"]
Job = Literal["walk", "certificate", "areas"]

# The environment variable that sets the mode for a whole process.
ENVIRONMENT = "SHADOWGEO_COMPILED"
# Items of one walk from which the compiled walk repays numba's import (see above).
WALK_ITEMS = 1 << 20
# Lights needing the certificate from which the compiled test runs.
CERTIFICATE_LIGHTS = 1

# Faces times sun positions from which the compiled areas repay the import.
AREAS_FACE_SAMPLES = 20_000

_THRESHOLDS: dict[str, int] = {
    "walk": WALK_ITEMS,
    "certificate": CERTIFICATE_LIGHTS,
    "areas": AREAS_FACE_SAMPLES,
}
_MODES: tuple[str, ...] = get_args(Mode)
_block: ContextVar[Mode | None] = ContextVar("shadowgeo_compiled", default=None)


def _checked(value: str, where: str) -> Mode:
    if value not in _MODES:
        raise ValueError(f"{where}={value!r}: expected one of {', '.join(_MODES)}")
    return value  # type: ignore[return-value]


def current_mode() -> Mode:
    """The mode in force here: the innermost :func:`compiled_loops` block,
    else ``SHADOWGEO_COMPILED``, else ``"auto"``.

    Raises
    ------
    ValueError
        ``SHADOWGEO_COMPILED`` holds something other than auto, always, never.
    """
    chosen = _block.get()
    if chosen is not None:
        return chosen
    value = os.environ.get(ENVIRONMENT, "").strip().lower()
    return _checked(value, ENVIRONMENT) if value else "auto"


@contextmanager
def compiled_loops(chosen: Mode) -> Iterator[None]:
    """Run the block with the compiled loops ``"auto"`` (the rule),
    ``"always"`` or ``"never"``; the setting before it comes back after.

    Raises
    ------
    ValueError
        ``chosen`` is not one of those.
    """
    token = _block.set(_checked(chosen, "compiled_loops"))
    try:
        yield
    finally:
        _block.reset(token)


def use_compiled(job: Job, size: int, mode: Mode | None = None) -> bool:
    """Whether a ``job`` (``"walk"``, ``"certificate"`` or ``"areas"``) of ``size`` takes
    the compiled loops: ``mode`` (default: :func:`current_mode`) ``"always"`` for any
    size of one or more, ``"never"`` not, ``"auto"`` from its threshold
    (:data:`WALK_ITEMS`, :data:`CERTIFICATE_LIGHTS`, :data:`AREAS_FACE_SAMPLES`)."""
    chosen = _checked(mode, "mode") if mode is not None else current_mode()
    if chosen == "never" or size < 1:
        return False
    return chosen == "always" or size >= _THRESHOLDS[job]
