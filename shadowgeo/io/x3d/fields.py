"""X3D XML field values: parsing attribute text by field type, with defaults.

Field types and defaults come from :mod:`.tables` (generated from the X3D
4.0 schemas by ``tools/x3d_tables.py``). X3D 3.x files differ in a few
defaults; :data:`X3D3_DEFAULTS` holds those, chosen by the ``<X3D version>``.

As X3D browsers do, a field whose value cannot be read takes its default, with
a warning naming the file, line, node and field: ``scene.x3d line 12,
Transform DEF='arm': field translation: '1 abc 3' is not numbers (SFVec3f:
'abc' is not a number); the default '0 0 0' is used``. A USE naming no DEF,
or a node of another type, stands for no node, with a warning.
Every number must be finite and within ``+-limits.LARGEST_COORDINATE``; one
that is not is a value that cannot be read.
"""

from __future__ import annotations

import bisect
import math
import re
import warnings
from collections.abc import Callable, Collection
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypeAlias

import numpy as np
from lxml import etree

from ...errors import SceneError
from ...limits import LARGEST_COORDINATE
from .tables import DEFAULTS

if TYPE_CHECKING:
    from .proto import Prototypes

__all__ = [
    "ANGLE_FIELDS",
    "Context",
    "Element",
    "Tree",
    "WIDTH",
    "X3D3_DEFAULTS",
    "local_name",
    "numbers_or_none",
    "parse",
    "rotation_matrix",
]

# lxml ships no type information: to mypy both are Any, named for the reader.
Element: TypeAlias = etree._Element
Tree: TypeAlias = etree._ElementTree

# VRML 97 / X3D 3.3 SpotLight defaults; X3D 4.0 changed both (the schema's
# 0.589049 = 3 pi / 16 and 1.570796 = pi / 2).
X3D3_DEFAULTS = {
    ("SpotLight", "beamWidth"): "1.570796",
    ("SpotLight", "cutOffAngle"): "0.785398",
}

# Number of components per value of each vector type.
WIDTH = {
    "SFVec2f": 2, "SFVec2d": 2, "SFVec3f": 3, "SFVec3d": 3, "SFColor": 3, "SFColorRGBA": 4,
    "SFVec4f": 4, "SFVec4d": 4, "SFRotation": 4, "SFMatrix3f": 9, "SFMatrix4f": 16,
    "SFMatrix4d": 16, "SFMatrix3d": 9,
    "MFVec2f": 2, "MFVec2d": 2, "MFVec3f": 3, "MFVec3d": 3, "MFColor": 3, "MFColorRGBA": 4,
    "MFVec4f": 4, "MFRotation": 4, "MFFloat": 1, "MFDouble": 1, "MFTime": 1, "MFInt32": 1,
}  # fmt: skip
# Fields holding angles, scaled by an X3D ``<unit category="angle">``.
ANGLE_FIELDS = {"cutOffAngle", "beamWidth", "creaseAngle", "fieldOfView"}
_STRING = re.compile(r'"((?:[^"\\]|\\.)*)"')


def local_name(element: Element) -> str:
    """Tag without namespace; '' for comments and processing instructions."""
    tag = element.tag
    if not isinstance(tag, str):
        return ""
    return tag if tag[0] != "{" else tag[tag.index("}") + 1 :]


@dataclass
class Context:
    """Where the reader is, for messages and unit conversion."""

    path: str
    version: tuple[int, int] = (4, 0)
    angle_factor: float = 1.0
    warnings: list[str] = field(default_factory=list)
    defs: dict[str, list[Element]] = field(default_factory=dict)  # DEF name -> [elements, in order]
    # element -> (its tree's number, its index in that tree)
    _order: dict[Element, tuple[int, int]] = field(default_factory=dict)
    # (DEF name, tree, DEFs of that name so far) -> the indices, sorted, and
    # the elements of that name's DEFs in that tree
    _named: dict[tuple[str, int, int], tuple[list[int], list[Element]]] = field(
        default_factory=dict
    )
    _trees: int = 0  # trees indexed in _order
    prototypes: Prototypes | None = None  # of the document
    _said: set[str] = field(default_factory=set)  # warnings given once (fields read again)
    # Values built from a node's attributes alone, by (kind, tag, attributes):
    # ten thousand identical Materials are read once.
    by_content: dict[tuple[Any, ...], Any] = field(default_factory=dict)
    # The scene's long number attributes, held as bytes (a numbers
    # Splicer), and the root of the document they are held for.
    kept: Any = None
    kept_root: Element | None = None

    def definition(self, element: Element) -> Element | None:
        """The element a ``USE`` names: the latest DEF of that name before it in
        the document (X3D lets a later DEF rebind a name), or None."""
        name = element.get("USE")
        found = self.defs.get(name, [])
        if len(found) < 2:
            return found[0] if found else None
        # a prototype copy is a tree of its own (its names are its own, so the
        # DEFs found are in the same tree as the USE): index each tree once
        if element not in self._order:
            root = element.getroottree().getroot()
            self._trees += 1
            tree = self._trees
            self._order.update((node, (tree, index)) for index, node in enumerate(root.iter()))
        tree, here = self._order[element]
        # DEFs of another tree (the document, seen from a prototype copy) do
        # not count; each name's DEFs in a tree sorted once, then bisected
        # (a scan per USE was quadratic: 10,000 DEFs of one name, 20 s)
        key = (name, tree, len(found))
        if key not in self._named:
            ranked = sorted(
                (place[1], position)
                for position, node in enumerate(found)
                if (place := self._order.get(node)) is not None and place[0] == tree
            )
            self._named[key] = ([index for index, _ in ranked], [found[k] for _, k in ranked])
        indices, nodes = self._named[key]
        before = bisect.bisect_left(indices, here)
        return nodes[before - 1] if before else found[0]

    def resolve(self, element: Element) -> Element | None:
        """The node a ``USE`` names (the same element, not a copy), or ``element``;
        None, with a warning, when the USE names no DEF or a node of another type
        (X3D browsers skip such a node)."""
        name = element.get("USE")
        if name is None:
            return element
        target = self.definition(element)
        if target is None:
            self.warn_once(element, f"USE='{name}' names no DEF in this file; skipped")
            return None
        if local_name(target) != local_name(element):
            self.warn_once(
                element,
                f"USE='{name}' names a {local_name(target)} (line {target.sourceline}), "
                f"not a {local_name(element)}; skipped",
            )
            return None
        return target

    def node(self, element: Element) -> Element | None:
        """The node ``element`` stands for: itself, the DEF a USE names, or the
        copy of a prototype's body a ProtoInstance stands for (None if none)."""
        element = self.resolve(element)
        if element is not None and local_name(element) == "ProtoInstance":
            return None if self.prototypes is None else self.prototypes.expand(self, element)
        return element

    def children(self, element: Element, tags: Collection[str] | None = None) -> list[Element]:
        """Child nodes (see :meth:`node`), optionally only those whose tag is in ``tags``."""
        out = []
        for child in element:
            if local_name(child):
                child = self.node(child)
                if child is not None and (tags is None or local_name(child) in tags):
                    out.append(child)
        return out

    def describe(self, element: Element) -> str:
        name = local_name(element)
        for attribute in ("DEF", "USE"):
            if element.get(attribute):
                return f"{name} {attribute}='{element.get(attribute)}'"
        return name

    def file_of(self, element: Element) -> str:
        """The file ``element`` was read from: the document's, or that of the
        prototype (EXTERNPROTO) whose copy holds it."""
        return self.path if self.prototypes is None else self.prototypes.file_of(element)

    def where(self, element: Element) -> str:
        return f"{self.file_of(element)} line {element.sourceline}, {self.describe(element)}"

    def error(self, element: Element, message: str) -> SceneError:
        return SceneError(
            message,
            path=self.file_of(element),
            line=element.sourceline,
            node=self.describe(element),
        )

    def warn(self, element: Element, message: str) -> None:
        self.warnings.append(f"{self.where(element)}: {message}")

    def warn_once(self, element: Element, message: str) -> None:
        """:meth:`warn`, once per element and message (a node used again is
        read again)."""
        text = f"{self.where(element)}: {message}"
        if text not in self._said:
            self._said.add(text)
            self.warnings.append(text)

    def _radians(self, kind: str, value: Any) -> Any:
        with np.errstate(over="ignore", invalid="ignore"):  # (refused just below)
            if kind in ("SFRotation", "MFRotation"):
                value = value * np.array([1.0, 1.0, 1.0, self.angle_factor])
            else:
                value = value * self.angle_factor
        if not np.all(np.isfinite(value)):
            raise ValueError("is not finite in radians")
        return value

    def field(self, element: Element, name: str, kind: str | None = None) -> Any:
        """The value of field ``name`` of ``element``, or its default (also,
        with a warning, when the value written cannot be read).

        Returns a bool, int, float, str, list[str] (MFString) or float64 /
        int64 numpy array ((k,) for SF vectors, (n, k) for MF vectors).
        """
        tag = local_name(element)
        spec = DEFAULTS.get(tag, {}).get(name)
        if kind is None:
            if spec is None:
                raise KeyError(f"{tag}.{name} is not in the defaults table")
            kind = spec[0]
        default = spec[1] if spec else ""
        if self.version < (4, 0):
            default = X3D3_DEFAULTS.get((tag, name), default)
        text = element.get(name)
        if text is not None:
            written = text
            if self.kept is not None:
                text = self.kept.held(text)  # (a node read again)
            try:
                value = parse(text, kind)
                if name in ANGLE_FIELDS or kind in ("SFRotation", "MFRotation"):
                    value = self._radians(kind, value)
                elif text is written and self.kept is not None and kind in WIDTH:
                    self.kept.hold(element, name, text, self.kept_root)
                return value
            except ValueError as problem:
                shown = text if len(text) <= 40 else text[:37] + "..."
                self.warn_once(
                    element, f"field {name}: '{shown}' {problem}; the default '{default}' is used"
                )
        return parse(default, kind)


# Parsed values of short texts (defaults, colours, sizes: the same few strings
# over and over in a scene of many shapes), by (text, kind); arrays are copied out.
_SHORT = 64
_CACHE_SIZE = 4096
_parsed: dict[tuple[str, str], Any] = {}


def parse(text: str, kind: str) -> Any:
    """Parse ``text`` as X3D field type ``kind``; ValueError says why not.

    Short texts are parsed once and remembered (a copy is returned).

    Examples
    --------
    >>> parse("0 1, 0 1.5708", "SFRotation").tolist()
    [0.0, 1.0, 0.0, 1.5708]
    >>> parse("TRUE", "SFBool"), parse('"a b" "c"', "MFString")
    (True, ['a b', 'c'])
    >>> parse("1 2 3 -1", "MFInt32").tolist()
    [1, 2, 3, -1]
    """
    if len(text) > _SHORT:
        return _parse(text, kind)
    key = (text, kind)
    value = _parsed.get(key)
    if value is None:
        try:
            value = _parse(text, kind)
        except ValueError as problem:
            value = problem
        if len(_parsed) >= _CACHE_SIZE:
            _parsed.clear()
        _parsed[key] = value
    if isinstance(value, ValueError):
        raise ValueError(*value.args)
    return value.copy() if isinstance(value, (np.ndarray, list)) else value


def _parse(text: str, kind: str) -> Any:
    scalar = _SCALARS.get(kind)
    return _vectors(text, kind) if scalar is None else scalar(text, kind)


def _bool(text: str, kind: str) -> bool:
    word = text.strip().lower()
    if word not in ("true", "false"):
        raise ValueError("is not a boolean (true or false)")
    return word == "true"


def _int32(text: str, kind: str) -> int:
    try:
        numbers = _integers(text, kind)
    except ValueError:
        raise ValueError("is not an integer (SFInt32)") from None
    if len(numbers) != 1:
        raise ValueError("is not an integer (SFInt32)")
    return int(numbers[0])


def _one_number(text: str, kind: str) -> float:
    numbers = _numbers(text, kind)
    if len(numbers) != 1:
        raise ValueError(f"is not one number ({kind})")
    return float(numbers[0])


def _vectors(text: str, kind: str) -> np.ndarray:
    """A vector (SF) or array of vectors (MF) of ``kind``'s width."""
    numbers = _numbers(text, kind)
    width = WIDTH.get(kind)
    if width is None:
        raise ValueError(f"has a field type the reader does not parse ({kind})")
    if kind.startswith("SF"):
        if len(numbers) != width:
            raise ValueError(f"is not {width} numbers ({kind})")
        return numbers
    if len(numbers) % width:
        raise ValueError(f"has {len(numbers)} numbers, not a multiple of {width} ({kind})")
    return numbers.reshape(-1, width) if width > 1 else numbers


# Field types not read as vectors of numbers: type -> parser of (text, type).
_SCALARS: dict[str, Callable[[str, str], Any]] = {
    "SFBool": _bool,
    "SFString": lambda text, kind: text,
    "MFString": lambda text, kind: _strings(text),
    "SFInt32": _int32,
    "MFInt32": lambda text, kind: _integers(text, kind),
    "SFFloat": _one_number,
    "SFDouble": _one_number,
    "SFTime": _one_number,
}


def _numbers(text: str, kind: str) -> np.ndarray:
    """The numbers of ``text`` (white space or commas between them), converted
    in bulk by numpy's C parser; ValueError names the first word that is not a
    number, or the value out of range."""
    if "," in text:
        text = text.replace(",", " ")  # X3D separates by white space or commas
    if not text or text.isspace():
        return np.empty(0)  # (np.fromstring reads blank text as [-1.0])
    try:
        numbers = _bulk(text, np.float64)
    except ValueError:
        bad = next((word for word in text.split() if not _is_number(word)), text.strip())
        raise ValueError(f"is not numbers ({kind}: '{bad[:20]}' is not a number)") from None
    # two reductions; NaN fails both comparisons
    if numbers.size and not (
        -LARGEST_COORDINATE <= numbers.min() and numbers.max() <= LARGEST_COORDINATE
    ):
        if not np.all(np.isfinite(numbers)):
            raise ValueError(f"has a value that is not finite ({kind})")
        value = float(numbers[np.argmax(np.abs(numbers))])
        raise ValueError(
            f"has the value {value!r}, outside the supported range +-{LARGEST_COORDINATE:g} "
            "(see shadowgeo.limits)"
        )
    return numbers


def _integers(text: str, kind: str) -> np.ndarray:
    """MFInt32 / SFInt32 values as int64: integer words parse ten times faster
    as integers; anything else (``1.0``, a bad word) goes through :func:`_numbers`."""
    if "," in text:
        text = text.replace(",", " ")
    if not text or text.isspace():
        return np.empty(0, dtype=np.int64)
    try:
        numbers = _bulk(text, np.int64)
    except ValueError:
        numbers = _numbers(text, kind)
        if np.any(numbers != np.round(numbers)):
            raise ValueError(f"has a value that is not an integer ({kind})") from None
    if numbers.size and (numbers.max() > _INT32_MAX or numbers.min() < -_INT32_MAX - 1):
        raise ValueError(f"has a value outside the 32-bit integer range ({kind})")
    return numbers.astype(np.int64)


_INT32_MAX = 2**31 - 1


def _fromstring_is_strict() -> bool:
    """Whether np.fromstring raises on a word it cannot read (numpy >= 2.3)
    rather than warning and returning what it read before it (older numpy)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            np.fromstring("1 x", sep=" ")
        except ValueError:
            return True
    return False


_STRICT = _fromstring_is_strict()


def _bulk(text: str, dtype: Any) -> np.ndarray:
    """``np.fromstring(text, sep=" ")`` raising ValueError at any word it
    cannot read, whichever numpy."""
    if _STRICT:
        return np.fromstring(text, dtype=dtype, sep=" ")
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        try:
            return np.fromstring(text, dtype=dtype, sep=" ")
        except DeprecationWarning:
            raise ValueError("unmatched data") from None


def numbers_or_none(text: str) -> np.ndarray | None:
    """The numbers of ``text`` (white space or commas between them), float64,
    or None when a word is not a number; unlike field parsing, no range check
    (``inf`` and ``nan`` are read as such)."""
    if "," in text:
        text = text.replace(",", " ")
    if not text or text.isspace():
        return np.empty(0)
    try:
        return _bulk(text, np.float64)
    except ValueError:
        return None


def _is_number(word: str) -> bool:
    """Whether ``word`` is one number as :func:`_bulk` reads them (XML Schema
    style: no ``_`` digit groups, no hexadecimal)."""
    try:
        return _bulk(word, np.float64).size == 1
    except ValueError:
        return False


def _strings(text: str) -> list[str]:
    """MFString: ``"a" "b"``; a bare unquoted value counts as one string."""
    found = _STRING.findall(text)
    if not found:
        return [text.strip()] if text.strip() else []
    return [re.sub(r"\\(.)", r"\1", item) for item in found]


def rotation_matrix(rotation: np.ndarray) -> np.ndarray:
    """3x3 matrix of an X3D rotation ``(x, y, z, angle)`` (right-hand rule
    about the axis); a zero axis means no rotation."""
    axis, angle = np.asarray(rotation[:3], dtype=np.float64), float(rotation[3])
    length = float(np.linalg.norm(axis))
    if length == 0.0 or angle == 0.0:
        return np.eye(3)
    x, y, z = axis / length
    c, s, t = math.cos(angle), math.sin(angle), 1.0 - math.cos(angle)
    return np.array(
        [
            [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
        ]
    )
