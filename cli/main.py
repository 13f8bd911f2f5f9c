"""``shadowgeo`` command: parse arguments, call the public API, print, exit.

Each command lives in its own module of this package and provides
``register(subparsers)``, which adds its parser and sets ``func`` to a function
``run(args) -> int``. What several commands share (argument types, the Dask
options, the progress bar) is in ``common.py``, which they import; no command
imports another's module but ``convert``, which hands its batch form to
``batch.py``.

Exit codes: 0 done, 1 bad input (or an output that cannot be written), 2 bad
usage; 130 interrupted (SIGINT, Ctrl-C), 143 terminated (SIGTERM), 129 hung up
(SIGHUP), after
removing what was half written (:mod:`cli.interrupt`).
"""

from __future__ import annotations

import argparse
import importlib
import re
import sys
from pathlib import Path

import shadowgeo
import shadowgeo.compiled

from .common import terminal
from .interrupt import Terminated, exit_code, signals_unwind

# Command modules, in the order --help lists them.
COMMANDS = ("convert", "sun", "info", "render", "view")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="shadowgeo",
        description="Exact shadow geometry for 3-D scenes.",
    )
    parser.add_argument("--version", action="version", version=shadowgeo.__version__)
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS:
        module = importlib.import_module(f"{__package__}.{name}")
        module.register(subparsers)
    return parser


# A value that is a list of numbers starting with a minus sign: "-0.3,-1,0.2".
_NEGATIVE_LIST = re.compile(r"^-\.?\d[\d.eE+\-,]*$")


def negative_values_joined(argv: list[str]) -> list[str]:
    """``--sun -0.3,-1,0.2`` as ``--sun=-0.3,-1,0.2``: argparse takes a value
    that starts with a minus sign for an option unless it is one plain
    number, so a list of numbers (a direction, a southern latitude, plan
    corners) would be refused after its flag."""
    joined: list[str] = []
    for token in argv:
        previous = joined[-1] if joined else ""
        if (
            _NEGATIVE_LIST.match(token)
            and previous.startswith("--")
            and "=" not in previous
            and previous != "--"
        ):
            joined[-1] = f"{previous}={token}"
        else:
            joined.append(token)
    return joined


def main(argv: list[str] | None = None) -> int:
    with signals_unwind():
        try:
            return run(argv)
        except KeyboardInterrupt as interrupt:  # SIGINT, or SIGTERM as Terminated
            why = f"stopped by {interrupt}" if isinstance(interrupt, Terminated) else "interrupted"
            print(f"shadowgeo: {why}", file=sys.stderr)
            return exit_code(interrupt)


def run(argv: list[str] | None) -> int:
    parser = build_parser()
    args = parser.parse_args(negative_values_joined(sys.argv[1:] if argv is None else argv))
    if args.command is None:
        parser.print_help(sys.stderr)
        return 2
    try:
        shadowgeo.compiled.current_mode()  # SHADOWGEO_COMPILED, checked before any work
    except ValueError as error:
        print(f"shadowgeo: {error}", file=sys.stderr)
        return 2
    try:
        return int(args.func(args) or 0)
    except (shadowgeo.SceneError, shadowgeo.GeometryError) as error:
        where = "" if isinstance(error, shadowgeo.SceneError) else _scene_of(args)
        print(f"shadowgeo {args.command}: {where}{terminal(error)}", file=sys.stderr)
        return 1


def _scene_of(args: argparse.Namespace) -> str:
    """``"FILE: "`` for the one scene a command read, to name it in a message
    about its geometry (a SceneError names its file itself); else ``""``."""
    source = getattr(args, "input", None)
    paths = getattr(args, "paths", None)
    if source is None and isinstance(paths, list) and len(paths) == 2:
        source = paths[0]
    return f"{terminal(str(source))}: " if isinstance(source, Path) else ""
