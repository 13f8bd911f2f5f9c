"""``shadowgeo view``: not built yet."""

from __future__ import annotations

import sys


def register(subparsers) -> None:
    parser = subparsers.add_parser("view", help="(not built yet)")
    parser.set_defaults(func=run)


def run(args) -> int:
    print("shadowgeo view: not built yet", file=sys.stderr)
    return 2
