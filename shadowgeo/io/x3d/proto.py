"""X3D prototypes: a ProtoInstance read as a copy of its ProtoBody.

The instance stands for the first node of its declaration's ProtoBody (the
rule X3D gives; a body whose first node is an instance of another prototype
stands for what that one stands for). The body is copied (the document is
never modified), every ``<IS><connect nodeField protoField/></IS>`` takes the
instance's ``fieldValue`` or the interface's default -- an instance of another
prototype inside the body gets it as its own ``fieldValue``, so a field passed
on through nested prototypes arrives -- and the body's DEF names are made
private to the copy.

A prototype's name is looked up in the file that holds the instance: the
document, or for an instance inside a copy, the file the copied prototype was
declared in. An ExternProtoDeclare is followed to a PROTO in a local file
(:mod:`.extern`, under Inline's rules), whose copies then read their urls,
names and messages as that file's. Instances of an EXTERNPROTO that cannot be
followed (remote, missing, outside the scene's folder, no such PROTO) and of
undeclared prototypes are skipped with a warning naming the file, line and
why. A prototype used inside its own body, directly or through others, is a
SceneError.
"""

from __future__ import annotations

import copy
import itertools
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from lxml import etree

from ... import limits
from .extern import Found, find
from .fields import Element, local_name

if TYPE_CHECKING:
    from .fields import Context
    from .inline import InlineReader

__all__ = ["MAX_EXPANSIONS", "MAX_FILES_DEEP", "Prototypes"]

# Copies made per document at most: a prototype whose body holds an instance
# of itself would otherwise expand for ever.
MAX_EXPANSIONS = limits.MAX_PROTO_EXPANSIONS  # see shadowgeo.limits
MAX_FILES_DEEP = limits.MAX_INLINE_DEPTH  # EXTERNPROTO files reached through others' bodies
_FIELD_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


@dataclass(frozen=True)
class _File:
    """The prototypes one file declares (by name, the first of each)."""

    path: str  # as messages name it
    declarations: dict[str, Element]
    externals: dict[str, Element]
    depth: int  # files between it and the document, through EXTERNPROTOs


@dataclass(frozen=True)
class _Place:
    """Where nodes lie: the document, or a copy of a prototype's body made for
    an instance lying at ``outer``. Nodes passed into a copy through a field
    lie where they were written."""

    file: _File  # whose names, urls and lines they have
    copied: Element | None = None  # the ProtoDeclare copied, for a copy
    outer: _Place | None = None


def _declarations(root: Element, path: str, depth: int) -> _File:
    declarations: dict[str, Element] = {}
    externals: dict[str, Element] = {}
    for element in root.iter("{*}ProtoDeclare", "{*}ExternProtoDeclare"):
        held = declarations if local_name(element) == "ProtoDeclare" else externals
        if element.get("name"):
            held.setdefault(element.get("name"), element)
    return _File(path, declarations, externals, depth)


class Prototypes:
    """The prototypes of one document, and the copies made of them.

    Parameters
    ----------
    root : the document's root element
    path : the document's file, as messages name it
    reader : what following an EXTERNPROTO needs (the scene's folder, the
        files read); without one, EXTERNPROTOs are not followed
    """

    def __init__(self, root: Element, path: str, reader: InlineReader | None = None) -> None:
        self.home = _Place(_declarations(root, path, 0))
        # the document, each copy and each node passed into one -> where it lies
        self.places: dict[Element, _Place] = {root: self.home}
        self.files = {root: self.home.file}  # each file's root -> its prototypes
        self.copies: dict[Element, Element | None] = {}
        self.followed: dict[Element, tuple[Element, _File] | str] = {}  # per ExternProtoDeclare
        self.reader = reader
        self.serial = itertools.count()

    def file_of(self, element: Element) -> str:
        """The file ``element`` was read from (see the module notes)."""
        return self._place(element).file.path

    def _place(self, element: Element) -> _Place:
        for holder in itertools.chain([element], element.iterancestors()):
            if holder in self.places:
                return self.places[holder]
        return self.home

    def expand(self, context: Context, instance: Element) -> Element | None:
        """The node ``instance`` (a ProtoInstance element) stands for, or None
        with a warning. The same instance always gives the same copy."""
        if instance in self.copies:
            return self.copies[instance]
        name = instance.get("name", "")
        found = self._declaration(context, instance)
        if isinstance(found, str):
            context.warn(instance, f"ProtoInstance name='{name}' skipped: {found}")
            self.copies[instance] = None
            return None
        declaration, file = found
        body = _child(declaration, "ProtoBody")
        if body is None or not any(local_name(node) for node in body):
            context.warn(instance, f"ProtoInstance name='{name}' skipped: its ProtoBody is empty")
            self.copies[instance] = None
            return None
        place = self._place(instance)
        self._refuse_cycle(context, instance, declaration, place)
        if len(self.copies) >= MAX_EXPANSIONS:
            raise context.error(
                instance, f"prototypes expand more than {MAX_EXPANSIONS} times (one inside itself?)"
            )
        self.copies[instance] = None  # (until the copy is made)
        values, node_values = _field_values(declaration, instance)
        copied: Element = copy.deepcopy(body)
        self.places[copied] = _Place(file, declaration, place)
        # names first: the nodes IS brings in keep the names of the scope they come from
        self._private_names(context, copied)
        self._connect(context, copied, values, node_values)
        first = next((node for node in copied if local_name(node)), None)
        if first is None:  # the body held only IS elements, which connecting removes
            why = "its ProtoBody has no node once its IS connections are made"
            context.warn(instance, f"ProtoInstance name='{name}' skipped: {why}")
        elif local_name(first) == "ProtoInstance":
            first = context.node(first)
        self.copies[instance] = first
        return first

    def _declaration(self, context: Context, instance: Element) -> tuple[Element, _File] | str:
        """The ProtoDeclare ``instance`` names and the file it is in, or why none."""
        name = instance.get("name", "")
        file = self._place(instance).file
        if name in file.declarations:
            return file.declarations[name], file
        extern = file.externals.get(name)
        if extern is None:
            return f"no PROTO or EXTERNPROTO of that name in {Path(file.path).name}"
        if extern not in self.followed:
            self.followed[extern] = self._follow(context, extern, file)
        return self.followed[extern]

    def _follow(
        self, context: Context, extern: Element, file: _File
    ) -> tuple[Element, _File] | str:
        where = f"EXTERNPROTO at {Path(file.path).name} line {extern.sourceline}"
        if self.reader is None:
            return f"{where} is not followed here"
        if file.depth >= MAX_FILES_DEEP:
            raise context.error(extern, f"EXTERNPROTO files nested more than {MAX_FILES_DEEP} deep")
        found = find(self.reader, extern, Path(file.path).resolve())
        if not isinstance(found, Found):
            return f"{where}: {found}"
        if found.root not in self.files:
            self.files[found.root] = _declarations(found.root, str(found.path), file.depth + 1)
            # (its defaults passed through IS read their urls as its own)
            self.places.setdefault(found.root, _Place(self.files[found.root]))
        return found.declaration, self.files[found.root]

    def _refuse_cycle(
        self, context: Context, instance: Element, declaration: Element, place: _Place
    ) -> None:
        """A SceneError if ``instance`` lies (through copies) inside a copy of
        ``declaration``: the prototype would hold itself for ever. (One passed
        into its own prototype through a field lies where it was written.)"""
        at: _Place | None = place
        while at is not None:
            if at.copied is declaration:
                name = instance.get("name", "")
                raise context.error(
                    instance, f"prototype '{name}' is used inside its own body (prototype cycle)"
                )
            at = at.outer

    def _private_names(self, context: Context, body: Element) -> None:
        """Rename the copy's DEF/USE names apart and register its DEFs."""
        prefix = f"{next(self.serial)}#"
        for element in body.iter():
            if not isinstance(element.tag, str):
                continue
            for attribute in ("DEF", "USE"):
                if element.get(attribute) is not None:
                    element.set(attribute, prefix + element.get(attribute))
            if element.get("DEF") is not None:
                context.defs.setdefault(element.get("DEF"), []).append(element)

    def _connect(
        self,
        context: Context,
        body: Element,
        values: dict[str, str],
        node_values: dict[str, list[Element]],
    ) -> None:
        for holder in [e for e in body.iter("{*}IS") if not _declared_inside(e)]:
            node = holder.getparent()
            for connect in holder:
                if local_name(connect) == "connect":
                    self._connect_field(context, node, connect, values, node_values)
            node.remove(holder)

    def _connect_field(
        self,
        context: Context,
        node: Element,
        connect: Element,
        values: dict[str, str],
        node_values: dict[str, list[Element]],
    ) -> None:
        """One ``<connect>``: the instance's value of the prototype field set on
        (or its nodes appended to) ``node``, or passed on to a nested instance."""
        node_field, proto_field = connect.get("nodeField"), connect.get("protoField")
        if not _FIELD_NAME.fullmatch(node_field or ""):
            raise context.error(connect, f"connect nodeField={node_field!r} is not a field name")
        nodes = self._copies(context, node_values, proto_field)
        if local_name(node) == "ProtoInstance":
            _pass_on(node, node_field, values.get(proto_field), nodes, connect.sourceline)
            return
        if proto_field in values:
            node.set(node_field, values[proto_field])
        for child in nodes or []:
            child.set("containerField", node_field)
            node.append(child)

    def _copies(
        self, context: Context, node_values: dict[str, list[Element]], proto_field: str | None
    ) -> list[Element] | None:
        """Copies of the nodes the instance gives ``proto_field`` (None when it
        is no node field of the instance)."""
        if proto_field not in node_values:
            return None
        nodes: list[Element] = []
        for value in node_values[proto_field]:
            target = context.resolve(value)
            if target is not None:  # (a bad USE: noted)
                nodes.append(copy.deepcopy(target))
                self.places[nodes[-1]] = self._place(target)
        return nodes


def _child(element: Element, tag: str) -> Element | None:
    return next((child for child in element if local_name(child) == tag), None)


def _field_values(
    declaration: Element, instance: Element
) -> tuple[dict[str, str], dict[str, list[Element]]]:
    """Attribute values and node values of the prototype's fields: the
    interface's defaults overridden by the instance's fieldValue elements (a
    node field given no node is NULL, which overrides a default too)."""
    values: dict[str, str] = {}
    node_values: dict[str, list[Element]] = {}
    interface = _child(declaration, "ProtoInterface")
    sources = [] if interface is None else [interface]
    types = {item.get("name"): item.get("type") or "" for item in sources[0]} if sources else {}
    for source in [*sources, instance]:
        for item in source:
            name = item.get("name")
            if local_name(item) not in ("field", "fieldValue") or not name:
                continue
            nodes = [node for node in item if local_name(node)]
            if item.get("value") is not None:
                values[name] = item.get("value")
            elif nodes or types.get(name, "").endswith("Node"):
                node_values[name] = nodes
    return values, node_values


def _declared_inside(holder: Element) -> bool:
    """Whether an IS element belongs to a prototype declared inside the body
    being connected (its fields are that prototype's)."""
    return any(local_name(a) == "ProtoDeclare" for a in holder.iterancestors())


def _pass_on(
    instance: Element, field: str, value: str | None, nodes: list[Element] | None, line: int | None
) -> None:
    """Give a ProtoInstance inside a body the value of one of the body's
    prototype's fields, as its fieldValue ``field`` (in place of any written);
    ``nodes`` empty is NULL, None no node value."""
    if value is None and nodes is None:
        return  # the field has no value (an event): the inner prototype's default stands
    for written in [
        e for e in instance if local_name(e) == "fieldValue" and e.get("name") == field
    ]:
        instance.remove(written)
    passed = etree.SubElement(instance, "fieldValue", name=field)
    if line is not None:
        passed.sourceline = line
    if value is not None:
        passed.set("value", value)
    passed.extend(nodes or [])
