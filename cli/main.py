"""``shadowgeo`` command: parse arguments, call the public API, print, exit.

Exit codes: 0 done, 1 bad input, 2 bad usage.
"""

from __future__ import annotations

import argparse
import sys

import shadowgeo


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="shadowgeo",
        description="Exact shadow geometry for 3-D scenes.",
    )
    parser.add_argument("--version", action="version", version=shadowgeo.__version__)
    parser.add_subparsers(dest="command", metavar="COMMAND")
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help(sys.stderr)
        return 2
    return 0
