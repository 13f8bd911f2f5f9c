"""Relative urls of an X3D document, rewritten for the folder it is written to.

An X3D document names other files by relative urls (Inline, ImageTexture,
MovieTexture, AudioClip, Script, ShaderPart, ExternProtoDeclare, Anchor,
Background's ``frontUrl`` and its kind, a prototype's ``url`` field):
relative to the file that holds them. Written to another folder, the same
text would name other files, or none. So each such url that names a local
file is rewritten to the path from the output's folder to that same file
(``os.path.relpath``, ``/``-separated, a ``#fragment`` kept); remote and
absolute urls (``http:``, ``https:``, ``urn:``, ``data:``, ``ecmascript:``
code, ``/...``), a lone ``#name`` and every url of a document written in its
own folder are left as they are (a file on another Windows drive, which no
relative path reaches, gets a ``file:`` url). A url naming no existing file
is kept as it is, with a note naming the file, line and url. Only the urls
change: the rest of each ``MFString`` value is kept byte for byte.

The files are not copied and nothing is read: a browser follows the
rewritten urls; shadowgeo's own reader still opens nothing outside a scene's
folder (see :mod:`.inline`).
"""

from __future__ import annotations

import functools
import os
import re
from collections.abc import Callable
from pathlib import Path
from urllib.parse import quote, unquote

from .classic_tokens import quote as quoted
from .fields import Tree, local_name
from .inline import URL_SCHEME

__all__ = ["rewrite_urls"]

# The fields that hold urls: X3D's ``url`` and Background's ``frontUrl``, ...
_URL_FIELD = re.compile(r"url|[a-z]+Url")
# The elements that may hold one (found by XPath, in C: a Python loop over a
# big document's every node is slow), each then checked with _URL_FIELD.
_ENDS_IN_URL = "substring({0}, string-length({0}) - 2) = 'Url'"
_HOLDERS = (
    f"//*[@url or @*[{_ENDS_IN_URL.format('name()')}]]"
    "[local-name() != 'field' and local-name() != 'fieldValue']"
    f" | //*[local-name() = 'field' or local-name() = 'fieldValue']"
    f"[@name = 'url' or {_ENDS_IN_URL.format('@name')}]"
)
# One string of an MFString attribute, its escapes (\" and \\) inside.
_STRING = re.compile(r'"((?:[^"\\]|\\.)*)"', re.DOTALL)
_ESCAPE = re.compile(r"\\(.)", re.DOTALL)
# A path from the root, or a Windows drive or share (URL_SCHEME skips "C:").
_ABSOLUTE = re.compile(r"[/\\]|[A-Za-z]:")


def rewrite_urls(tree: Tree, source: Path, output: Path) -> list[str]:
    """Rewrite in ``tree`` (a copy: changed in place) each relative url that
    names a file from ``source`` (the document's file) so that it names the
    same file from ``output`` (the file being written); returns the notes,
    one for each url that names no file.

    Examples
    --------
    >>> import tempfile
    >>> from lxml import etree
    >>> top = Path(tempfile.mkdtemp())
    >>> (top / "in").mkdir()
    >>> _ = (top / "in" / "house.x3d").write_text("<X3D/>")
    >>> tree = etree.ElementTree(etree.fromstring(
    ...     '<X3D><Scene><Inline url=\\'"house.x3d" "https://x.org/h.x3d"\\'/></Scene></X3D>'
    ... ))
    >>> rewrite_urls(tree, top / "in" / "scene.x3d", top / "out" / "deeper" / "scene.x3d")
    []
    >>> tree.getroot()[0][0].get("url")
    '"../../in/house.x3d" "https://x.org/h.x3d"'
    """
    source_folder = Path(os.path.abspath(source.parent))
    output_folder = Path(os.path.abspath(output.parent))
    if source_folder == output_folder:
        return []  # the urls already name the right files
    notes: list[str] = []
    for element in tree.xpath(_HOLDERS):
        tag = local_name(element)
        if tag in ("field", "fieldValue"):
            names = ["value"] if _URL_FIELD.fullmatch(element.get("name") or "") else []
        else:
            names = [name for name in element.keys() if _URL_FIELD.fullmatch(name)]
        where = f"{source.name}{f' line {element.sourceline}' if element.sourceline else ''}"
        for name in names:
            value = element.get(name) or ""
            missing: list[str] = []
            changed = _each_url(
                value,
                functools.partial(
                    _relocated, source=source_folder, output=output_folder, missing=missing
                ),
            )
            notes += [
                f"{where}, {tag}: url '{url}' names no file; kept as it is "
                "(it cannot be rewritten for the output's folder)"
                for url in missing
            ]
            if changed != value:
                element.set(name, changed)
    return notes


def _each_url(value: str, change: Callable[[str], str]) -> str:
    """``value`` (an MFString attribute: quoted strings, or one bare url, as
    browsers accept) with each url passed through ``change``; a url it leaves
    alone keeps its text."""
    if '"' not in value:
        url = value.strip()
        if not url:
            return value
        new = change(url)
        return value if new == url else value.replace(url, new, 1)

    def one(match: re.Match[str]) -> str:
        url = _ESCAPE.sub(r"\1", match.group(1))
        new = change(url.strip())
        return match.group(0) if new == url.strip() else quoted(new)

    return _STRING.sub(one, value)


def _relocated(url: str, *, source: Path, output: Path, missing: list[str]) -> str:
    """``url`` rewritten from the ``source`` folder to the ``output`` one; the
    same text when it is not a relative path, or names no file (then added to
    ``missing``)."""
    location, hash_sign, fragment = url.partition("#")
    if not location or URL_SCHEME.match(url) or _ABSOLUTE.match(location):
        return url
    for text in (location, unquote(location)):  # as written, else %-decoded
        target = os.path.normpath(source / text)
        if os.path.exists(target):
            break
    else:
        missing.append(url)
        return url
    try:
        relative = os.path.relpath(target, output).replace(os.sep, "/")
    except ValueError:  # another Windows drive: no relative path reaches it
        return Path(target).as_uri() + hash_sign + fragment
    if text != location:
        relative = quote(relative, safe="/")
    return relative + hash_sign + fragment
