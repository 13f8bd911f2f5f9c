"""What several commands share: argument types, the Dask options and their
failure line, the progress bar, and the conversion options ``convert`` asks
of every file (its single and batch forms, :mod:`cli.convert` and
:mod:`cli.batch`).

The commands import from here, never from one another, so no command module
needs another to be read first.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from typing import TextIO

import shadowgeo
from shadowgeo.batch import ConvertOptions

# What a file's text must not bring to a terminal: C0 and C1 controls (ESC
# starts the sequences that set a title or clear the screen, BEL, newlines
# that fake a line), Unicode's line separators and the bidirectional
# overrides that reorder what is shown.
_UNSAFE = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029\u200e\u200f\u202a-\u202e\u2066-\u2069]")
# Characters of one message printed at most.
MAX_MESSAGE = 2000


def terminal(text: object) -> str:
    """``text`` (a note, an error, a name read from a file) as one line fit
    for a terminal: each control character as its escape (``\\x1b``,
    ``\\n``), at most :data:`MAX_MESSAGE` characters, ``...`` ending a cut."""
    line = _UNSAFE.sub(_escape, str(text)[: MAX_MESSAGE + 1])
    return line if len(line) <= MAX_MESSAGE else line[: MAX_MESSAGE - 3] + "..."


def _escape(match: re.Match[str]) -> str:
    return repr(match.group(0))[1:-1]


def plane_argument(text: str) -> shadowgeo.Plane:
    try:
        values = [float(part) for part in text.split(",")]
        if len(values) != 4:
            raise ValueError(f"{len(values)} numbers")
        return shadowgeo.Plane.from_coefficients(values)
    except (ValueError, shadowgeo.GeometryError) as error:
        raise argparse.ArgumentTypeError(
            f"expected four numbers a,b,c,d with (a, b, c) not zero, got {text!r} ({error})"
        ) from None


def positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}")
    return value


def add_dask_arguments(
    group: argparse.ArgumentParser | argparse._ArgumentGroup, item: str, default: str
) -> None:
    """``--scheduler ADDRESS | --serial`` and ``--workers N`` on ``group``:
    where the items (``item``: a file, a day) run; ``default``: where they
    run without either."""
    where = group.add_mutually_exclusive_group()
    where.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help=f"a running Dask scheduler (tcp://host:8786); default: {default}",
    )
    where.add_argument(
        "--serial", action="store_true", help=f"no Dask: one {item} after another in this process"
    )
    group.add_argument(
        "--workers",
        type=positive_int,
        metavar="N",
        help="worker processes of the LocalCluster (default: one per core)",
    )


def dask_failure(command: str, error: ImportError | OSError) -> int:
    """The one line and exit code for Dask missing (2: install it, or
    --serial) or a scheduler out of reach (1)."""
    if isinstance(error, ImportError):
        print(f"shadowgeo {command}: {error} (or --serial)", file=sys.stderr)
        return 2
    print(f"shadowgeo {command}: cannot reach the Dask scheduler: {error}", file=sys.stderr)
    return 1


class ProgressBar:
    """A one-line bar on stderr, redrawn in place."""

    def __init__(self, label: str, stream: TextIO | None = None, width: int = 30) -> None:
        self.label, self.width = label, width
        self.stream = sys.stderr if stream is None else stream
        self.shown = -1

    def __call__(self, done: int, total: int) -> None:
        percent = 100 * done // max(total, 1)
        if percent == self.shown:
            return
        self.shown = percent
        filled = self.width * percent // 100
        bar = "#" * filled + "." * (self.width - filled)
        self.stream.write(f"\r{self.label} [{bar}] {percent:3d}%")
        self.stream.flush()

    def close(self) -> None:
        if self.shown >= 0:
            self.stream.write("\n")
            self.stream.flush()


def options_of(args: argparse.Namespace) -> ConvertOptions:
    """What ``convert``'s command line asks of every file converted, one or a batch."""
    return ConvertOptions(
        method=args.method,
        lights=tuple(args.light) if args.light else None,
        receivers=tuple(args.receiver) if args.receiver else None,
        plane=args.plane,
        tolerance=args.tolerance,
        sun=args.sun,
        max_triangles=args.max_triangles,
        keep_runtime_shadows=args.keep_runtime_shadows,
        sun_angle=None if args.sun_angle is None else math.radians(args.sun_angle),
        light_sizes=tuple(args.light_size or ()),
        soft_levels=args.soft_levels,
        soft_samples=args.soft_samples,
    )
