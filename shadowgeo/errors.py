"""Exceptions raised by shadowgeo.

Every error says what is wrong and, where there is one, which file, node or
element it comes from, so a user can find the problem without a traceback.
"""

from __future__ import annotations

__all__ = ["EXCERPT", "BudgetError", "GeometryError", "SceneError", "excerpt"]


class GeometryError(ValueError):
    """Input geometry that has no meaningful shadow (NaN, a zero normal, a light
    on the receiving plane or inside a closed caster, faces indexing missing
    vertices, ...)."""


class BudgetError(GeometryError):
    """Work refused before it starts because it would pass one of the budgets
    of :mod:`shadowgeo.limits` (a union's crossings or sweep, the pairs a
    surface's shadow searches), which the message names. The same work in
    smaller pieces (fewer receiving faces at a time) may pass."""


class SceneError(ValueError):
    """A scene file that cannot be read or written.

    Parameters
    ----------
    message : str
        What is wrong.
    path : str, optional
        The file.
    line : int, optional
        The line in the file, where known.
    node : str, optional
        The node or element, e.g. ``"IndexedFaceSet DEF='roof'"``.
    """

    def __init__(
        self,
        message: str,
        *,
        path: str | None = None,
        line: int | None = None,
        node: str | None = None,
    ) -> None:
        self.message = message
        self.path = path
        self.line = line
        self.node = node
        super().__init__(str(self))

    def __str__(self) -> str:
        where = []
        if self.path:
            where.append(str(self.path) + (f" line {self.line}" if self.line else ""))
        elif self.line:
            where.append(f"line {self.line}")
        if self.node:
            where.append(self.node)
        prefix = ", ".join(where)
        return f"{prefix}: {self.message}" if prefix else self.message


EXCERPT = 200  # characters of a file's own text that a message quotes, at most


def excerpt(text: str, limit: int = EXCERPT) -> str:
    """``text`` (a token or name from a file) as a message quotes it: on one
    line (each run of white space, newlines included, as one space) and at
    most ``limit`` characters, ``...`` ending a cut, however long the text.

    Examples
    --------
    >>> excerpt("[ 1 2 3\\n 4 5 6 ]")
    '[ 1 2 3 4 5 6 ]'
    >>> excerpt("1 2 3\\n" * 1_000_000, limit=12)
    '1 2 3 1 2...'
    """
    # Only the start is looked at: a 12 MB token must not be copied whole.
    head = text[: 2 * limit + 2]
    one_line = " ".join(head.split())
    if len(head) < len(text) or len(one_line) > limit:
        return one_line[: limit - 3].rstrip() + "..."
    return one_line
