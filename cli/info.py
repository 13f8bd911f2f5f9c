"""``shadowgeo info``: not built yet."""

from __future__ import annotations

import sys


def register(subparsers) -> None:
    parser = subparsers.add_parser("info", help="(not built yet)")
    parser.set_defaults(func=run)


def run(args) -> int:
    print("shadowgeo info: not built yet", file=sys.stderr)
    return 2
