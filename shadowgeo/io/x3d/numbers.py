"""The big number fields of written X3D: their text, and how it reaches the file.

A shape's ``point`` and ``index`` are most of an X3D file's bytes. Setting
them as lxml attributes and letting lxml serialise them costs more than
formatting them: lxml checks and copies every character when the attribute
is set and scans it again for escapes when it is written. The numbers need
neither (digits, signs, ``.``, ``e``, spaces and commas), so the writer puts
a short placeholder in the tree instead (:class:`Splicer`) and the formatted
bytes go into the file where lxml writes the placeholder.

Floats are written with the shortest text that reads back as the same float64
(Python's ``repr``; orjson's, when the ``speed`` extra installs it, is the
same digits ten times faster).
"""

from __future__ import annotations

import copy
import re
import secrets
from typing import BinaryIO

import numpy as np
from lxml import etree

from ...errors import SceneError
from .. import optional_module
from .fields import Element, Tree

__all__ = [
    "LONG_VALUE",
    "NUMBER_CHARACTERS",
    "Splicer",
    "integers_text",
    "long_number_bytes",
    "orjson",
    "points_text",
]

# The shortest float64 text (as repr), ten times faster: the `speed` extra.
orjson = optional_module("orjson")


def points_text(vertices: np.ndarray) -> bytes:
    """An MFVec3f's text, ``x y z, x y z, ...``, each number the shortest that
    reads back as the same float64; from ``_FLAT_POINTS`` points on, with
    spaces only (``x y z x y z ...``: X3D reads a comma as a space), which
    orjson writes in one pass instead of three.

    Raises
    ------
    SceneError
        A coordinate is not finite.

    Examples
    --------
    >>> points_text(np.array([[0.1, -2.0, 3e-20], [1.0, 0.0, 5.0]]))
    b'0.1 -2.0 3e-20, 1.0 0.0 5.0'
    """
    values = np.ascontiguousarray(vertices, dtype=np.float64).reshape(-1, 3)  # orjson needs it
    # a NaN or an infinity makes the sum one (a finite sum rules them out)
    with np.errstate(over="ignore", invalid="ignore"):
        total = np.add.reduce(values.ravel())
    if not np.isfinite(total) and not np.isfinite(values).all():
        finite = np.isfinite(values).all(axis=1)
        bad = values[np.argmin(finite)].tolist()
        raise SceneError(f"cannot write a non-finite number in X3D: {bad}")
    if orjson is not None and len(values) >= _FLAT_POINTS:
        flat: bytes = orjson.dumps(values.ravel(), option=orjson.OPT_SERIALIZE_NUMPY)
        return flat[1:-1].replace(b",", b" ")
    if orjson is not None and len(values):
        listed: bytes = orjson.dumps(values, option=orjson.OPT_SERIALIZE_NUMPY)
        # [[x,y,z],[x,y,z]] -> x y z] [x y z -> x y z, x y z: two passes in C
        return listed[2:-2].replace(b",", b" ").replace(b"] [", b", ")
    words = list(map(repr, values.ravel().tolist()))
    triples = map(" ".join, zip(words[0::3], words[1::3], words[2::3], strict=True))
    return ", ".join(triples).encode("ascii")


# Points from which points_text leaves out the commas between them.
_FLAT_POINTS = 1 << 14


def integers_text(values: np.ndarray) -> bytes:
    """Integers separated by single spaces.

    >>> integers_text(np.array([[0, 1, 2], [2, 1, 30]]))
    b'0 1 2 2 1 30'
    """
    values = np.ascontiguousarray(values, dtype=np.int64).ravel()
    if orjson is not None and len(values):
        listed: bytes = orjson.dumps(values, option=orjson.OPT_SERIALIZE_NUMPY)
        return listed[1:-1].replace(b",", b" ")
    return " ".join(map(str, values.tolist())).encode("ascii")


# Attribute values at least this long made only of number characters (which
# XML escapes nowhere) are held as bytes beside the lxml tree: the reader's
# (see Splicer.hold) and the writer's (see write._spliced_out).
LONG_VALUE = 1 << 16
NUMBER_CHARACTERS = b"0123456789+-.eE ,"


def long_number_bytes(value: str) -> bytes | None:
    """``value`` as ASCII bytes when it is at least :data:`LONG_VALUE` long
    and made of number characters only (which XML escapes nowhere), else
    None."""
    if len(value) < LONG_VALUE or not value.isascii():
        return None
    data = value.encode("ascii")
    return None if data.translate(None, NUMBER_CHARACTERS) else data


class Splicer:
    """Number attributes kept out of the lxml tree until the file is written.

    :meth:`set` puts a placeholder (``shadowgeo-numbers-<random>-<index>``,
    a token no document holds by chance) in the attribute; :meth:`writer`
    wraps the output file so that each placeholder lxml writes becomes the
    numbers; :meth:`fill` sets the real text instead, for the encodings that
    read the tree (JSON, ClassicVRML).

    The reader holds a document's long number attributes the same way
    (:meth:`hold`; :attr:`shadowgeo.Scene.numbers`): a writer's splicer made
    from it (``Splicer(inherited)``) knows their placeholders too, and the
    big texts are never copied with the tree nor escaped by lxml.
    """

    def __init__(self, inherited: Splicer | None = None) -> None:
        if inherited is None:
            self.prefix = f"shadowgeo-numbers-{secrets.token_hex(8)}-".encode("ascii")
            self.texts: list[bytes] = []
        else:
            self.prefix = inherited.prefix
            self.texts = list(inherited.texts)  # the same bytes, not copied
        self.inherited = len(self.texts)
        self.pattern = re.compile(re.escape(self.prefix) + rb"(\d{9})")
        self._head = self.prefix.decode("ascii")
        self.places: list[tuple[Element, str]] = []

    def set(self, element: Element, name: str, text: bytes) -> None:
        """Give ``element``'s attribute ``name`` the numbers ``text`` (ASCII)."""
        self.places.append((element, name))
        self._put(element, name, text)

    def _put(self, element: Element, name: str, text: bytes) -> None:
        token = self.prefix + b"%09d" % len(self.texts)
        self.texts.append(text)
        element.set(name, token.decode("ascii"))

    def hold(self, element: Element, name: str, text: str, root: Element) -> None:
        """Keep ``text``, the value of ``element``'s attribute ``name`` read as
        numbers, as bytes, a placeholder in its place: when it is long, of
        number characters only, and ``element`` is in the tree of ``root``
        (not a prototype's copy, nor an Inline's document)."""
        if len(text) < LONG_VALUE or element.getroottree().getroot() is not root:
            return
        data = long_number_bytes(text)
        if data is not None:
            self._put(element, name, data)

    def held(self, text: str) -> str:
        """``text``, or the numbers it holds the place of."""
        if text.startswith(self._head):
            found = self.pattern.fullmatch(text.encode("utf-8"))
            if found is not None and int(found.group(1)) < len(self.texts):
                return self.texts[int(found.group(1))].decode("ascii")
        return text

    def fill(self, tree: Tree | None = None) -> None:
        """Set every placeholder's attribute to its numbers, in the tree
        (``tree``: where the inherited placeholders are, a copy of the
        reader's document)."""
        for (element, name), text in zip(self.places, self.texts[self.inherited :], strict=True):
            element.set(name, text.decode("ascii"))
        self.places = []
        if self.inherited and tree is not None:
            for element in tree.getroot().iter(etree.Element):
                for name, value in element.items():
                    if value.startswith(self._head):
                        element.set(name, self.held(value))
        del self.texts[self.inherited :]

    def filled_copy(self, tree: Tree) -> Tree:
        """A copy of ``tree`` (the document this splicer holds numbers of)
        with the numbers in place of their placeholders."""
        copied = copy.deepcopy(tree)
        Splicer(self).fill(copied)
        return copied

    def splice(self, data: bytes) -> bytes:
        """``data`` (serialised XML) with every placeholder replaced."""
        return self.pattern.sub(lambda match: self.texts[int(match.group(1))], data)

    def writer(self, handle: BinaryIO) -> _SplicingWriter:
        """A file-like object that writes to ``handle`` with the placeholders
        replaced; :meth:`_SplicingWriter.close` writes the rest and checks
        that every placeholder set (not inherited) was met once."""
        return _SplicingWriter(self, handle)


class _SplicingWriter:
    """What :meth:`Splicer.writer` returns: lxml writes in chunks, so a
    placeholder may arrive in two pieces; the last bytes of each chunk that
    could begin one wait for the next chunk."""

    def __init__(self, splicer: Splicer, handle: BinaryIO) -> None:
        self.splicer = splicer
        self.handle = handle
        self.pending = b""
        self.held = len(splicer.prefix) + 9 - 1  # a token's length, less one
        self.met = 0

    def write(self, data: bytes) -> int:
        buffer = self.pending + data if self.pending else data
        view = memoryview(buffer)  # slices written without copies
        done = 0
        for match in self.splicer.pattern.finditer(buffer):
            self.handle.write(view[done : match.start()])
            index = int(match.group(1))
            self.handle.write(self.splicer.texts[index])
            self.met += index >= self.splicer.inherited
            done = match.end()
        keep = self._start_of_token(buffer, max(done, len(buffer) - self.held))
        self.handle.write(view[done:keep])
        self.pending = bytes(view[keep:])
        return len(data)

    def _start_of_token(self, buffer: bytes, start: int) -> int:
        """Where the end of ``buffer`` from ``start`` on may begin a placeholder
        that the next chunk completes (``len(buffer)`` when nowhere)."""
        prefix = self.splicer.prefix
        position = buffer.find(prefix[:1], start)
        while position >= 0:
            tail = buffer[position:]
            head, digits = tail[: len(prefix)], tail[len(prefix) :]
            if prefix.startswith(head) and (not digits or digits.isdigit()):
                return position
            position = buffer.find(prefix[:1], position + 1)
        return len(buffer)

    def close(self) -> None:
        self.handle.write(self.pending)
        self.pending = b""
        own = len(self.splicer.texts) - self.splicer.inherited
        if self.met != own:
            raise SceneError(f"internal error: {self.met} of {own} number fields written")
