"""Exceptions raised by shadowgeo.

Every error says what is wrong and, where there is one, which file, node or
element it comes from, so a user can find the problem without a traceback.
"""

from __future__ import annotations


class GeometryError(ValueError):
    """Input geometry that has no meaningful shadow (NaN, a zero normal, a light
    on the receiving plane or inside a closed caster, faces indexing missing
    vertices, ...)."""


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
