"""Parse X3D ClassicVRML (``.x3dv``) and VRML 97 (``.wrl``) into the X3D XML tree.

The result is the lxml tree the XML parser (:mod:`.parse`) gives for the
same scene, so the one X3D reader handles nodes, DEF/USE, prototypes, Inline,
containerField and units for every encoding:

- a node is an element of its type; a field that holds numbers, strings or
  booleans is an attribute in the XML encoding's syntax (``true``, an SFString
  unquoted, an MFString as ``"a" "b"``, hex integers in decimal); a field that
  holds nodes gives child elements, with ``containerField`` when the field is
  not the node's default one;
- ``PROTO`` / ``EXTERNPROTO`` / ``IS`` / ``ROUTE`` / ``IMPORT`` / ``EXPORT``
  become ProtoDeclare (ProtoInterface, field, ProtoBody), ProtoInstance
  (fieldValue), IS/connect, ExternProtoDeclare, ROUTE, IMPORT and EXPORT;
  Script and shader interface declarations become ``<field>`` elements;
- ``PROFILE``, ``COMPONENT``, ``UNIT``, ``META`` become ``<head>`` entries,
  the header's version the ``version`` attribute; comments become XML
  comments; every element's ``sourceline`` is its line in the file;
- the tree is laid out as XML is written, one element a line, indented by
  depth (:mod:`.layout`), so the XML writer gives a readable file.

VRML 97 (``#VRML V2.0 utf8``) is read as X3D 3.0: ``exposedField``,
``eventIn``, ``eventOut`` and ``field`` become X3D's access types, and the
fields X3D renamed (Collision ``collide``, LOD ``level``, Switch ``choice``)
get their X3D names. VRML 1.0 is refused with a SceneError.

Where X3D browsers recover, so does this parser (as Castle Game Engine and
FreeWRL do): a statement or node that cannot be read (a stray ``}``, ``DEF``
without a node type, a PROTO without a name, a USE naming no DEF) is skipped
to the next node or statement at the same bracket depth, a field that cannot
be read to the next field of its node, each with a note naming the file, line
and what was skipped (``notes``). A file whose last statement is cut short
keeps the statements before it. What is not a scene at all stays one
SceneError: a bad header, a string never closed, a file in which no statement
can be read, nesting or size beyond the limits, more than :data:`MAX_SKIPPED`
skips.

Parsing is bounded: nesting depth :data:`MAX_DEPTH`, :data:`MAX_ELEMENTS`
elements; nothing is fetched (EXTERNPROTO and Inline are left to the reader).
"""

from __future__ import annotations

import re
from typing import cast

from lxml import etree

from ...errors import SceneError, excerpt
from .classic_tokens import Token, is_number, number_text, quote, tokens
from .fields import Element
from .layout import lay_out
from .tables import CONTAINER_FIELDS, field_type

__all__ = [
    "ACCESS",
    "MAX_DEPTH",
    "MAX_ELEMENTS",
    "MAX_SKIPPED",
    "STATEMENTS",
    "VRML97_FIELDS",
    "XSD",
    "ZERO_WIDTH",
    "classic_comment",
    "is_classic",
    "parse_bytes",
    "xml_comment",
]

MAX_DEPTH = 100
MAX_ELEMENTS = 2_000_000
# Statements and fields skipped at most before the file is refused as unreadable.
MAX_SKIPPED = 100
ACCESS = {
    "field": "initializeOnly", "exposedField": "inputOutput", "eventIn": "inputOnly",
    "eventOut": "outputOnly", "initializeOnly": "initializeOnly", "inputOutput": "inputOutput",
    "inputOnly": "inputOnly", "outputOnly": "outputOnly",
}  # fmt: skip
# VRML 97 field names X3D changed: (node, VRML 97 name) -> X3D name.
VRML97_FIELDS = {("Collision", "collide"): "enabled", ("LOD", "level"): "children"}
VRML97_FIELDS[("Switch", "choice")] = "children"
STATEMENTS = ("ROUTE", "PROTO", "EXTERNPROTO", "IMPORT", "EXPORT")
_BRACKETS = {"{": 1, "[": 1, "}": -1, "]": -1}
_HEADER = re.compile(rb"\A(?:\xef\xbb\xbf)?#(X3D|VRML) V(\d+)\.(\d+)")
# An X3D name (node type, DEF): no control characters, quotes, '#', ',', '.', brackets,
# braces or backslash; it does not start with a digit, '+' or '-'.
_NAME = re.compile(
    r"[^\x00-\x20\x22\x23\x27\x2b-\x2e\x30-\x39\x5b-\x5d\x7b\x7d\x7f]"
    r"[^\x00-\x20\x22\x23\x27\x2c\x2e\x5b-\x5d\x7b\x7d\x7f]*"
)
ZERO_WIDTH = "\u200b"
# Characters XML 1.0 cannot hold.
_NOT_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")
XSD = "http://www.w3.org/2001/XMLSchema-instance"


def xml_comment(text: str) -> str:
    """``text`` as an XML comment can hold it: a zero-width space between dashes
    (XML forbids ``--`` and a final ``-``), which :func:`classic_comment` undoes,
    and U+FFFD for each character XML cannot hold (NUL, control characters,
    lone surrogates), which it does not."""
    return re.sub(r"-(?=-|\Z)", "-" + ZERO_WIDTH, _NOT_XML.sub("\ufffd", text))


def classic_comment(text: str) -> str:
    """The comment text :func:`xml_comment` was given."""
    return text.replace("-" + ZERO_WIDTH, "-")


def is_classic(data: bytes) -> bool:
    """Whether ``data`` starts like a ClassicVRML or VRML file (``#X3D`` / ``#VRML``)."""
    return data.lstrip(b"\xef\xbb\xbf")[:5] in (b"#X3D ", b"#VRML")


class _Refused(SceneError):
    """An error no skipping recovers from: a limit reached."""


class _Truncated(SceneError):
    """The file ends inside a statement: only the top level skips it."""


def parse_bytes(data: bytes, path: str, notes: list[str] | None = None) -> etree._ElementTree:
    """The X3D XML tree of a ClassicVRML or VRML 97 document.

    Statements and fields that cannot be read are skipped, each with a line
    appended to ``notes`` (see the module notes).

    Raises
    ------
    SceneError
        VRML 1.0, a header that is not ``#X3D V3.x`` / ``V4.x`` or ``#VRML
        V2.0``, a string never closed, a file in which no statement can be
        read, nesting or size beyond the limits, more than
        :data:`MAX_SKIPPED` skips.
    """
    header = _HEADER.match(data)
    first = data.split(b"\n", 1)[0][:40].decode("latin-1").strip()
    if header is None:
        raise SceneError(f"not a ClassicVRML or VRML header: {first!r}", path=path, line=1)
    encoding, major, minor = header.group(1), int(header.group(2)), int(header.group(3))
    if encoding == b"VRML" and major == 1:
        raise SceneError(
            "VRML 1.0 is not supported (it is a different language; VRML 97, "
            "'#VRML V2.0 utf8', and X3D are)",
            path=path,
            line=1,
        )
    if (encoding, major) not in ((b"VRML", 2), (b"X3D", 3), (b"X3D", 4)):
        raise SceneError(f"unsupported version: {first!r}", path=path, line=1)
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = data.decode("latin-1")  # older VRML files are often Latin-1
    vrml97 = encoding == b"VRML"
    version = "3.0" if vrml97 else f"{major}.{minor}"
    parser = _Parser(tokens(text, path)[1:], path, vrml97)
    tree = parser.document(version)
    lay_out(tree.getroot())  # written as XML, one element a line
    if notes is not None:
        notes.extend(parser.notes)
    return tree


class _Parser:
    def __init__(self, found: list[Token], path: str, vrml97: bool) -> None:
        self.tokens, self.path, self.vrml97 = found, path, vrml97
        self.notes: list[str] = []
        self.first_error: SceneError | None = None
        self.position = 0
        self.comments: list[Token] = []
        self.scopes: list[dict[str, tuple[str, str | None]]] = [
            {}
        ]  # DEF name -> tag, per PROTO body
        self.protos: dict[str, dict[str, str]] = {}  # name -> field -> type
        self.elements = 0
        self.depth = 0

    # -- tokens ------------------------------------------------------------------
    def peek(self, ahead: int = 0) -> Token | None:
        index = self.position
        if ahead == 0 and index < len(self.tokens) and self.tokens[index].kind != "comment":
            return self.tokens[index]  # the common case, first
        while index < len(self.tokens):
            if self.tokens[index].kind != "comment":
                if ahead == 0:
                    return self.tokens[index]
                ahead -= 1
            index += 1
        return None

    def take(self, what: str = "a token") -> Token:
        position = self.position
        if position < len(self.tokens) and self.tokens[position].kind != "comment":
            self.position = position + 1  # the common case, first
            return self.tokens[position]
        while self.position < len(self.tokens) and self.tokens[self.position].kind == "comment":
            self.comments.append(self.tokens[self.position])
            self.position += 1
        if self.position >= len(self.tokens):
            raise self.error(
                f"the file ends where {what} was expected", self.tokens[-1:], _Truncated
            )
        self.position += 1
        return self.tokens[self.position - 1]

    def word(self, what: str) -> Token:
        token = self.take(what)
        if token.kind != "word":
            raise self.error(f"expected {what}, found {_shown(token)}", [token])
        return token

    def expect(self, punct: str) -> Token:
        token = self.take(f"'{punct}'")
        if token.kind != "punct" or token.text != punct:
            raise self.error(f"expected '{punct}', found {_shown(token)}", [token])
        return token

    def at(self, punct: str) -> bool:
        token = self.peek()
        return token is not None and token.kind == "punct" and token.text == punct

    def error(
        self, message: str, at: list[Token] | None = None, kind: type[SceneError] = SceneError
    ) -> SceneError:
        token = at[0] if at else self.peek()
        line = token.line if token else (self.tokens[-1].line if self.tokens else 1)
        return kind(message, path=self.path, line=line)

    def flush_comments(self, parent: Element) -> None:
        self.peek()  # comments before the next token are collected by take()
        while self.position < len(self.tokens) and self.tokens[self.position].kind == "comment":
            self.comments.append(self.tokens[self.position])
            self.position += 1
        for comment in self.comments:
            node = etree.Comment(xml_comment(comment.text))
            node.tail = None
            parent.append(node)
        self.comments = []

    def element(self, parent: Element | None, tag: str, line: int, **attributes: str) -> Element:
        self.elements += 1
        if self.elements > MAX_ELEMENTS:
            raise _Refused(f"more than {MAX_ELEMENTS} nodes; refused", path=self.path, line=line)
        try:
            element = etree.Element(tag) if parent is None else etree.SubElement(parent, tag)
            for name, value in attributes.items():
                element.set(name, value)
        except ValueError as problem:
            raise SceneError(f"{tag}: {problem}", path=self.path, line=line) from None
        if line < 65535:  # lxml keeps lines in 16 bits; past that, messages name the node
            element.sourceline = line
        return element

    def set(self, element: Element, name: str, value: str | None, line: int) -> None:
        try:
            element.set(name, value)
        except ValueError as problem:
            raise SceneError(
                f"field {excerpt(name)}: {problem}", path=self.path, line=line
            ) from None

    # -- document ----------------------------------------------------------------
    def document(self, version: str) -> etree._ElementTree:
        root = self.element(None, "X3D", 1, profile="Immersive", version=version)
        schema = f"https://www.web3d.org/specifications/x3d-{version}.xsd"
        root.set(f"{{{XSD}}}noNamespaceSchemaLocation", schema)
        head = self.element(root, "head", 1)
        scene = self.element(root, "Scene", 1)
        self.flush_comments(scene)
        self.head(root, head)
        if len(head) == 0:
            root.remove(head)
        self.statements(scene, None)
        if self.first_error is not None and not any(isinstance(c.tag, str) for c in scene):
            raise self.first_error  # nothing could be read: not a scene
        return etree.ElementTree(root)

    def head(self, root: Element, head: Element) -> None:
        token = self.peek()
        if token is not None and token.text == "PROFILE" and token.kind == "word":
            self.take()
            profile = self.word("a profile name")
            self.set(root, "profile", profile.text, profile.line)
        while (token := self.peek()) is not None and token.text in ("COMPONENT", "UNIT", "META"):
            self.take()
            if token.text == "COMPONENT":
                name = self.word("a component name").text
                if ":" not in name or name.endswith(":"):
                    name += self.word("':' and a level").text
                    if name.endswith(":"):
                        name += self.word("a component level").text
                name, _, level = name.partition(":")
                self.element(head, "component", token.line, name=name, level=level)
            elif token.text == "UNIT":
                words = [self.word("a unit category, name and factor").text for _ in range(3)]
                self.element(
                    head, "unit", token.line, category=words[0], name=words[1],
                    conversionFactor=number_text(words[2]),
                )  # fmt: skip
            else:
                meta_name, content = self.take("a META name"), self.take("a META content")
                self.element(head, "meta", token.line, name=meta_name.text, content=content.text)

    def statements(self, parent: Element, end: str | None) -> None:
        while True:
            self.flush_comments(parent)
            token = self.peek()
            if token is None:
                if end is not None:
                    raise self.error(f"the file ends before '{end}'", None, _Truncated)
                return
            if end is not None and token.kind == "punct" and token.text == end:
                return
            self.attempt(parent, top=end is None and parent.tag == "Scene")

    # -- skipping what cannot be read -------------------------------------------------
    def attempt(self, parent: Element, top: bool = False, container: str | None = None) -> None:
        """Read one statement or node into ``parent``; one that cannot be read is
        skipped with a note (at the top level even one the file ends inside)."""
        start, state = self.position, self.state(parent)
        try:
            token = cast(Token, self.peek())  # every caller has seen a token here
            if token.kind == "word" and token.text in STATEMENTS:
                self.statement(parent)
            else:
                self.node_statement(parent, container)
        except _Refused:
            raise
        except _Truncated as error:
            if not top:
                raise
            self.skip(parent, start, state, error, "the statement")
        except SceneError as error:
            self.skip(parent, start, state, error, "the statement")

    def state(self, parent: Element) -> tuple[int, int, int, Element | None]:
        """What :meth:`skip` restores: depth, scopes, prototypes and the last
        child of ``parent`` (in constant time: lxml's ``len`` counts children)."""
        last = _last_child(parent)
        return self.depth, len(self.scopes), len(self.protos), last

    def skip(
        self,
        parent: Element,
        start: int,
        state: tuple[int, int, int, Element | None],
        error: SceneError,
        what: str,
        fields: bool = False,
    ) -> None:
        """Undo a statement or field that failed at ``error``: drop what it added
        to ``parent`` since ``state`` was taken, move past its tokens to the next
        statement (or field) at the depth it started, and note it."""
        self.first_error = self.first_error or error
        if len(self.notes) >= MAX_SKIPPED:
            raise _Refused(
                f"more than {MAX_SKIPPED} statements or fields cannot be read (the first: "
                f"line {self.first_error.line}, {self.first_error.message}); refused",
                path=self.path,
                line=error.line,
            )
        self.depth, scopes, protos, last = state
        added = list(parent) if last is None else list(last.itersiblings())
        for child in added:
            parent.remove(child)
        del self.scopes[scopes:]
        for name in list(self.protos)[protos:]:
            del self.protos[name]
        self.comments = []
        self.resync(start, self.position, fields)
        first = self.tokens[start].line if start < len(self.tokens) else error.line
        last = self.tokens[self.position - 1].line if self.position > start else first
        lines = f"line {first}" if last == first else f"lines {first}-{last}"
        self.notes.append(
            f"{self.path} line {error.line}: {error.message}; {what} ({lines}) skipped"
        )

    def resync(self, start: int, failed: int, fields: bool) -> None:
        """Move to the first token after ``failed`` (and after ``start``) that
        can begin a statement (or, with ``fields``, a field) at the bracket
        depth of ``start``, or to the bracket that closes that depth."""
        depth = 0
        for index in range(start, min(failed, len(self.tokens))):
            depth += _BRACKETS.get(self.tokens[index].text, 0) * (
                self.tokens[index].kind == "punct"
            )
            if depth < 0:  # the failed read took the enclosing closing bracket
                self.position = max(index, start + 1)
                return
        self.position = max(failed, start + 1)
        while self.position < len(self.tokens):
            token = self.tokens[self.position]
            if token.kind == "punct":
                if depth == 0 and token.text in "}]":
                    return
                depth += _BRACKETS[token.text]
            elif depth == 0 and token.kind == "word" and self.resumes(fields):
                return
            self.position += 1

    def resumes(self, fields: bool) -> bool:
        """Whether the word at the current position can begin a statement or node
        (with ``fields``: a field) in a file being resynchronised."""
        token, before = self.tokens[self.position], self.tokens[self.position - 1]
        if before.kind == "word" and before.text in ("DEF", "USE", "IS", "TO", "AS"):
            return False  # a name
        if token.text in STATEMENTS:
            return True
        following = self.tokens[self.position + 1] if self.position + 1 < len(self.tokens) else None
        opens = following is not None and following.kind == "punct" and following.text == "{"
        if not fields:
            return opens or token.text in ("DEF", "USE")
        names = ("DEF", "USE", "NULL", "IS", "TO")
        return not opens and not _is_scalar(token) and token.text not in names

    def statement(self, parent: Element) -> None:
        keyword = self.take()
        if keyword.text == "ROUTE":
            source, to, target = self.word("a route source"), self.word("TO"), self.word("a node")
            if to.text != "TO" or "." not in source.text or "." not in target.text:
                raise self.error("expected ROUTE node.field TO node.field", [keyword])
            (from_node, from_field), (to_node, to_field) = (
                source.text.split(".", 1), target.text.split(".", 1)
            )  # fmt: skip
            self.element(
                parent, "ROUTE", keyword.line, fromNode=from_node, fromField=from_field,
                toNode=to_node, toField=to_field,
            )  # fmt: skip
        elif keyword.text == "IMPORT":
            inline, _, exported = self.word("inline.name").text.partition(".")
            imported = self.element(
                parent, "IMPORT", keyword.line, inlineDEF=inline, importedDEF=exported
            )
            if (token := self.peek()) is not None and token.text == "AS":
                self.take()
                self.set(imported, "AS", self.word("a name").text, keyword.line)
        elif keyword.text == "EXPORT":
            exported = self.element(
                parent, "EXPORT", keyword.line, localDEF=self.word("a DEF").text
            )
            if (token := self.peek()) is not None and token.text == "AS":
                self.take()
                self.set(exported, "AS", self.word("a name").text, keyword.line)
        else:
            self.proto(parent, keyword)

    # -- prototypes --------------------------------------------------------------
    def proto(self, parent: Element, keyword: Token) -> None:
        external = keyword.text == "EXTERNPROTO"
        name = self.word("a prototype name").text
        tag = "ExternProtoDeclare" if external else "ProtoDeclare"
        declaration = self.element(parent, tag, keyword.line, name=name)
        holder = (
            declaration if external else self.element(declaration, "ProtoInterface", keyword.line)
        )
        self.protos[name] = {}
        empty = self.peek()
        if empty is not None and empty.kind == "numbers" and not empty.text.strip(" \t\r\n,"):
            self.take()  # PROTO name [ ]: no fields (read as an empty list of numbers)
        else:
            self.expect("[")
            while not self.at("]"):
                self.flush_comments(holder)
                if self.at("]"):
                    break
                field = self.interface(holder, external, in_proto=True)
                self.protos[name][field.get("name")] = field.get("type")
            self.expect("]")
        if external:
            url = self.value("ExternProtoDeclare", "url", "MFString", keyword)
            self.set(declaration, "url", url, keyword.line)
            return
        self.expect("{")
        next_token = self.peek()
        body = self.element(declaration, "ProtoBody", next_token.line if next_token else 1)
        self.scopes.append({})
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise self.error(f"PROTOs nested more than {MAX_DEPTH} deep; refused", None, _Refused)
        self.statements(body, "}")
        self.depth -= 1
        self.scopes.pop()
        self.expect("}")

    def interface(self, parent: Element, external: bool, in_proto: bool) -> Element:
        """One ``accessType type name [value | IS name]`` declaration as a ``<field>``."""
        access = self.word("an access type")
        if access.text not in ACCESS:
            raise self.error(
                f"expected an access type (inputOutput, ...), found {_shown(access)}", [access]
            )
        kind, name = self.word("a field type").text, self.word("a field name").text
        if not kind.startswith(("SF", "MF")):
            raise self.error(f"{excerpt(kind)!r} is not a field type", [access])
        field = self.element(
            parent, "field", access.line, name=name, type=kind, accessType=ACCESS[access.text]
        )
        token = self.peek()
        if not in_proto and token is not None and token.text == "IS":
            self.take()
            self.connect(parent, name, self.word("a prototype field").text, access.line)
        elif not external and field.get("accessType") in ("initializeOnly", "inputOutput"):
            self.field_value(field, "value", None, name, kind, access)
        return field

    def connect(self, node: Element, node_field: str, proto_field: str, line: int) -> None:
        holder = next((child for child in node if child.tag == "IS"), None)
        if holder is None:
            holder = self.element(node, "IS", line)
        self.element(holder, "connect", line, nodeField=node_field, protoField=proto_field)

    # -- nodes -------------------------------------------------------------------
    def starts_node(self) -> bool:
        token, after = self.peek(), self.peek(1)
        if token is None or token.kind != "word":
            return False
        if token.text in ("DEF", "USE"):
            return True
        return after is not None and after.kind == "punct" and after.text == "{"

    def node_statement(self, parent: Element, field: str | None) -> Element:
        token = self.word("a node")
        if token.text == "USE":
            name = self.word("a DEF name").text
            found = self.scopes[-1].get(name)
            if found is None:  # e.g. a DEF outside the PROTO body it is used in
                raise self.error(f"USE '{name}' names no DEF before it in its scope", [token])
            tag, proto = found
            element = self.element(parent, tag, token.line, USE=name)
        else:
            name = None
            if token.text == "DEF":
                name = self.word("a DEF name").text
                token = self.word("a node type")
            element = self.node(parent, token, name)
            tag, proto = element.tag, element.get("name")
        default = CONTAINER_FIELDS.get(tag, "children") if proto is None else "children"
        if field is not None and field != default:
            self.set(element, "containerField", field, token.line)
        return element

    def node(self, parent: Element, kind: Token, name: str | None) -> Element:
        if not _NAME.fullmatch(kind.text):
            raise self.error(f"{_shown(kind)} is not a node type", [kind])
        self.expect("{")
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise self.error(f"nodes nested more than {MAX_DEPTH} deep; refused", [kind], _Refused)
        instance = kind.text in self.protos
        element = self.element(parent, "ProtoInstance" if instance else kind.text, kind.line)
        if name is not None:
            self.set(element, "DEF", name, kind.line)
            self.scopes[-1][name] = (element.tag, kind.text if instance else None)
        if instance:
            self.set(element, "name", kind.text, kind.line)
        self.body(element, kind.text, instance)
        self.expect("}")
        self.depth -= 1
        return element

    def body(self, element: Element, kind: str, instance: bool) -> None:
        while True:
            self.flush_comments(element)
            token = self.peek()
            if token is None:
                raise self.error(f"the file ends inside {kind} {{ }}", None, _Truncated)
            if token.kind == "punct" and token.text == "}":
                return
            start, state = self.position, self.state(element)
            try:
                self.field(element, kind, instance)
            except (_Refused, _Truncated):
                raise
            except SceneError as error:
                what = f"field {excerpt(token.text)} of {kind}"
                self.skip(element, start, state, error, what, fields=True)

    def field(self, element: Element, kind: str, instance: bool) -> None:
        """One field of a node (or an interface declaration or statement in it)."""
        token = cast(Token, self.peek())  # body() has seen a token here
        if token.kind != "word":
            raise self.error(f"expected a field of {kind}, found {_shown(token)}", [token])
        if token.text in STATEMENTS:
            self.statement(element)
            return
        after = self.peek(1)
        if token.text in ACCESS and after is not None and after.text[:2] in ("SF", "MF"):
            self.interface(element, False, in_proto=False)
            return
        self.take()
        field = token.text
        if self.vrml97:
            field = VRML97_FIELDS.get((kind, field), field)
        if (following := self.peek()) is not None and following.text == "IS":
            self.take()
            self.connect(element, field, self.word("a prototype field").text, token.line)
        elif instance:
            holder = self.element(element, "fieldValue", token.line, name=field)
            declared = self.protos[kind].get(field)
            self.field_value(holder, "value", None, field, declared, token)
        else:
            self.field_value(element, field, kind, field, field_type(kind, field), token)

    def field_value(
        self,
        holder: Element,
        attribute: str,
        kind: str | None,
        field: str,
        declared: str | None,
        token: Token,
    ) -> None:
        """Parse a field's value into ``holder``: attribute ``attribute``, or child
        nodes (with ``containerField`` unless ``kind`` is None: prototype values)."""
        container = None if kind is None else field
        value = self.value(kind, field, declared, token, holder, container)
        if value is not None:
            self.set(holder, attribute, value, token.line)

    def value(
        self,
        kind: str | None,
        field: str,
        declared: str | None,
        token: Token,
        holder: Element | None = None,
        container: str | None = None,
    ) -> str | None:
        """The XML attribute text of the next field value, or None when it was
        nodes (appended to ``holder``) or NULL."""
        following = self.peek()
        if following is not None and following.kind == "numbers":
            self.take()
            return _numbers(following, declared)
        if self.at("["):
            return self.bracketed(field, declared, token, holder, container)
        if self.starts_node():
            if holder is None:
                raise self.error(f"field {excerpt(field)} cannot hold nodes", [token])
            self.node_statement(holder, container)
            return None
        if following is not None and following.text == "NULL":
            self.take()
            return None
        return self.scalar(kind, field, declared, token)

    def bracketed(
        self,
        field: str,
        declared: str | None,
        token: Token,
        holder: Element | None,
        container: str | None,
    ) -> str | None:
        """A ``[ ... ]`` value: its values as text, its nodes appended to ``holder``."""
        self.take()
        items: list[Token] = []
        nodes = len(holder) if holder is not None else 0
        while not self.at("]"):
            following = self.peek()
            if following is None:
                raise self.error(f"the file ends inside field {field}'s [ ]", [token], _Truncated)
            if holder is not None and (following.text in STATEMENTS or self.starts_node()):
                self.attempt(holder, container=container)  # ROUTE, PROTO may stand among nodes
            elif self.starts_node():
                raise self.error(f"field {excerpt(field)} cannot hold nodes", [token])
            elif following.text == "NULL":
                self.take()
            elif following.kind == "punct":
                raise self.error(f"unexpected {_shown(following)} in field {excerpt(field)}")
            else:
                items.append(self.take())
        self.take()
        if items:
            return _text(items, declared, True)
        added = holder is not None and len(holder) > nodes
        return None if added else _empty(declared)

    def scalar(self, kind: str | None, field: str, declared: str | None, token: Token) -> str:
        """Single values (numbers, strings, TRUE/FALSE) up to the next field."""
        items = []
        while (following := self.peek()) is not None and _is_scalar(following):
            items.append(self.take())
        if not items:
            found = "the end of the file" if following is None else _shown(following)
            raise self.error(f"field {excerpt(field)} of {kind}: no value (found {found})", [token])
        return _text(items, declared, False)


def _numbers(following: Token, declared: str | None) -> str | None:
    """A run of numbers the tokenizer took whole, as attribute text of type ``declared``."""
    words = following.text.replace(",", " ").split()
    if not words:
        return _empty(declared)
    if declared in ("SFString", "MFString"):
        return _text([Token("word", word, following.line) for word in words], declared, True)
    if "x" in following.text or "X" in following.text:
        words = [number_text(word) for word in words]
    return " ".join(words)


def _empty(declared: str | None) -> str | None:
    """An empty value: no attribute for nodes (or an unknown type), else empty text."""
    return None if declared is None or declared.endswith("Node") else ""


def _last_child(parent: Element) -> Element | None:
    """The last child of ``parent`` (element or comment), or None."""
    return next(parent.iterchildren(reversed=True), None)


def _shown(token: Token) -> str:
    """``token`` as the file has it, for messages: one line, bounded."""
    return f"[{excerpt(token.text)}]" if token.kind == "numbers" else repr(excerpt(token.text))


def _is_scalar(token: Token) -> bool:
    if token.kind == "string":
        return True
    return token.kind == "word" and (is_number(token.text) or token.text in ("TRUE", "FALSE"))


def _text(items: list[Token], declared: str | None, bracketed: bool) -> str:
    """Field value tokens in the XML encoding's syntax for type ``declared``."""
    strings = all(item.kind == "string" for item in items)
    if declared == "SFString" or (
        declared is None and strings and len(items) == 1 and not bracketed
    ):
        return " ".join(item.text for item in items)
    if declared == "MFString" or (declared is None and strings):
        return " ".join(quote(item.text) for item in items)
    words = []
    for item in items:
        if item.kind == "string":
            words.append(quote(item.text))
        elif item.text in ("TRUE", "FALSE"):
            words.append(item.text.lower())
        else:
            words.append(number_text(item.text))
    return " ".join(words)
