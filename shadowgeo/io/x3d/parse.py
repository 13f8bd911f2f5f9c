"""Parsing untrusted X3D XML safely.

lxml is told never to touch the network, never to load a DTD and never to
expand entities; a document whose DOCTYPE declares entities at all (the shape
of XXE and "billion laughs" attacks) is refused, and gzip input (``.x3dz``) is
inflated only up to :data:`MAX_BYTES`.

Big meshes need attributes longer than libxml2's 10 MB limit for untrusted
input, so the parser runs with ``huge_tree`` -- which also lifts libxml2's
entity-amplification guard and its depth limit. Both are put back here: the
bytes are scanned for ``<!ENTITY`` *before* libxml2 sees them (a declaration
is refused before anything could be expanded -- even one inside a comment,
which costs nothing real), and the tree is refused past
:data:`~shadowgeo.limits.MAX_XML_DEPTH` elements deep. The scan is only
conclusive for an ASCII-compatible encoding (UTF-8, ASCII, ISO-8859-x,
windows-125x, declared or defaulted); a document in any other encoding (UTF-16,
say) is parsed with libxml2's own untrusted-input limits, as before.
"""

from __future__ import annotations

import gzip
import importlib
import io
import re
import zlib
from pathlib import Path

from lxml import etree

from ... import limits
from ...errors import SceneError
from . import classic_read as x3d_classic_read

__all__ = ["ENCODINGS", "MAX_BYTES", "MAX_DEPTH", "parse", "read_bytes"]

# X3D encodings other than XML: extension -> module whose parse(path) gives the tree.
ENCODINGS = {".x3dj": "json", ".json": "json"}
# Largest X3D document read, after inflating .x3dz (an inflation bomb stops here).
MAX_BYTES = limits.MAX_DOCUMENT_BYTES  # see shadowgeo.limits
MAX_DEPTH = limits.MAX_XML_DEPTH
# Encodings in which "<!ENTITY" can only be written as those ASCII bytes.
_ASCII_COMPATIBLE = re.compile(rb"(utf-?8|us-ascii|ascii|iso[-_]?8859-\d+|latin-?1|windows-125\d)$")
_DECLARED_ENCODING = re.compile(rb"""^<\?xml[^>]*?encoding\s*=\s*["']([A-Za-z0-9._-]+)["']""")


def _parser(huge: bool = False) -> etree.XMLParser:
    return etree.XMLParser(
        resolve_entities=False,
        no_network=True,
        load_dtd=False,
        dtd_validation=False,
        huge_tree=huge,
        remove_comments=False,
        remove_blank_text=False,
    )


def read_bytes(path: Path) -> bytes:
    """The document's bytes, inflated if gzip (by extension or magic number)."""
    try:
        with open(path, "rb") as handle:
            head = handle.read(2)
            handle.seek(0)
            if path.suffix.lower() in (".x3dz", ".x3dvz", ".wrz") or head == b"\x1f\x8b":
                with gzip.GzipFile(fileobj=handle) as inflated:
                    data = inflated.read(MAX_BYTES + 1)
            else:
                data = handle.read(MAX_BYTES + 1)
    except (OSError, EOFError, gzip.BadGzipFile, zlib.error) as problem:
        raise SceneError(f"cannot read: {problem}", path=str(path)) from None
    if len(data) > MAX_BYTES:
        raise SceneError(f"document larger than {MAX_BYTES} bytes; refused", path=str(path))
    return data


def parse(path: Path, notes: list[str] | None = None) -> etree._ElementTree:
    """Parse ``path`` (``.x3d`` or gzip ``.x3dz``) into an lxml tree, comments kept;
    a file of another encoding (:data:`ENCODINGS`) is parsed by its module into
    the same tree.

    ClassicVRML and VRML 97 files (known by their ``#X3D`` / ``#VRML`` header,
    whatever the extension) give the same tree, from :mod:`.classic_read`;
    what it skips is noted in ``notes``.

    Raises
    ------
    SceneError
        Malformed XML (with its line), a DOCTYPE declaring entities, a root
        element other than ``<X3D>``.
    """
    encoding = ENCODINGS.get(Path(path).suffix.lower())
    if encoding is not None:
        return importlib.import_module(f"{__package__}.{encoding}").parse(Path(path))
    data = read_bytes(path)
    if x3d_classic_read.is_classic(data):
        return x3d_classic_read.parse_bytes(data, str(path), notes)
    tree = _xml_tree(data, path)
    _refuse_entities(tree, path)
    _check_shape(tree, path)
    return tree


def _xml_tree(data: bytes, path: Path) -> etree._ElementTree:
    """``data`` parsed as XML; entity declarations refused before parsing
    where a scan is conclusive; libxml2's errors as SceneErrors."""
    huge = _ascii_compatible(data)
    if huge and b"<!ENTITY" in data:
        raise SceneError(
            "the DOCTYPE declares entities; entity declarations are refused "
            "(external entities and entity expansion are an attack vector)",
            path=str(path),
            line=data.count(b"\n", 0, data.index(b"<!ENTITY")) + 1,
        )
    try:
        return etree.parse(io.BytesIO(data), _parser(huge))
    except etree.XMLSyntaxError as problem:
        message = (problem.msg or str(problem)).strip()
        if "limit" in message.lower() and "amplification" not in message.lower():
            message = (
                "a text or attribute value is longer than libxml2's 10 MB limit for untrusted "
                f"input ({message.splitlines()[0]})"
            )
        else:
            message = f"malformed XML: {message}"
        raise SceneError(message, path=str(path), line=problem.lineno) from None


def _refuse_entities(tree: etree._ElementTree, path: Path) -> None:
    """Refuse a parsed document that declares or uses entities."""
    dtd = tree.docinfo.internalDTD
    if dtd is not None:
        entities = [entity.name for entity in dtd.entities()]
        if entities:
            shown = ", ".join(entities[:5])
            raise SceneError(
                f"the DOCTYPE declares entities ({shown}); entity declarations are refused "
                "(external entities and entity expansion are an attack vector)",
                path=str(path),
                line=1,
            )
    if _has_entity_references(tree):
        raise SceneError("the document uses entity references; refused", path=str(path))


def _check_shape(tree: etree._ElementTree, path: Path) -> None:
    """Refuse elements nested too deep and a root other than ``<X3D>``."""
    root = tree.getroot()
    # one XPath step per level, each over the elements of that level: linear
    too_deep = tree.xpath("/*" * (MAX_DEPTH + 1))
    if too_deep:
        raise SceneError(
            f"malformed XML: elements nested more than {MAX_DEPTH} deep; refused",
            path=str(path),
            line=too_deep[0].sourceline,
        )
    if not isinstance(root.tag, str) or etree.QName(root).localname != "X3D":
        raise SceneError(
            f"not an X3D document: the root element is <{root.tag}>, not <X3D>",
            path=str(path),
            line=root.sourceline,
        )


def _ascii_compatible(data: bytes) -> bool:
    """Whether ``data`` is in an encoding where a scan for ``<!ENTITY`` is
    conclusive: no byte-order mark but UTF-8's, no NUL byte, and no declared
    encoding outside :data:`_ASCII_COMPATIBLE`."""
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    if data[:1] != b"<" and data[:1].strip() != b"":
        return False  # a BOM or first byte of UTF-16/32, EBCDIC, ...
    if b"\x00" in data:
        return False
    declared = _DECLARED_ENCODING.match(data.lstrip()[:200])
    return declared is None or bool(_ASCII_COMPATIBLE.match(declared.group(1).lower()))


def _has_entity_references(tree: etree._ElementTree) -> bool:
    return any(True for _ in tree.iter(etree.Entity))
