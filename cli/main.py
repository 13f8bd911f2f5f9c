"""``shadowgeo`` command: parse arguments, call the public API, print, exit.

Each command lives in its own module of this package and provides
``register(subparsers)``, which adds its parser and sets ``func`` to a function
``run(args) -> int``.

Exit codes: 0 done, 1 bad input, 2 bad usage.
"""

from __future__ import annotations

import argparse
import importlib
import sys

import shadowgeo

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


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help(sys.stderr)
        return 2
    try:
        return int(args.func(args) or 0)
    except (shadowgeo.SceneError, shadowgeo.GeometryError) as error:
        print(f"shadowgeo {args.command}: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("shadowgeo: interrupted", file=sys.stderr)
        return 130
