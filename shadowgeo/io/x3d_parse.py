"""Parsing untrusted X3D XML safely.

lxml is told never to touch the network, never to load a DTD and never to
expand entities; a document whose DOCTYPE declares entities at all (the shape
of XXE and "billion laughs" attacks) is refused, and gzip input (``.x3dz``) is
inflated only up to :data:`MAX_BYTES`.
"""

from __future__ import annotations

import gzip
import importlib
import io
import zlib
from pathlib import Path

from lxml import etree

from .. import limits
from ..errors import SceneError
from . import x3d_classic_read

# X3D encodings other than XML: extension -> module whose parse(path) gives the tree.
ENCODINGS = {".x3dj": "x3d_json", ".json": "x3d_json"}
# Largest X3D document read, after inflating .x3dz (an inflation bomb stops here).
MAX_BYTES = limits.MAX_DOCUMENT_BYTES  # see shadowgeo.limits


def _parser() -> etree.XMLParser:
    return etree.XMLParser(
        resolve_entities=False,
        no_network=True,
        load_dtd=False,
        dtd_validation=False,
        huge_tree=False,
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
    whatever the extension) give the same tree, from :mod:`.x3d_classic_read`;
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
    try:
        tree = etree.parse(io.BytesIO(data), _parser())
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
    root = tree.getroot()
    if not isinstance(root.tag, str) or etree.QName(root).localname != "X3D":
        raise SceneError(
            f"not an X3D document: the root element is <{root.tag}>, not <X3D>",
            path=str(path),
            line=root.sourceline,
        )
    return tree


def _has_entity_references(tree: etree._ElementTree) -> bool:
    return any(True for _ in tree.iter(etree.Entity))
