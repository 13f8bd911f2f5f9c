"""``shadowgeo convert``: not built yet."""

from __future__ import annotations

import sys


def register(subparsers) -> None:
    parser = subparsers.add_parser("convert", help="(not built yet)")
    parser.set_defaults(func=run)


def run(args) -> int:
    print("shadowgeo convert: not built yet", file=sys.stderr)
    return 2
