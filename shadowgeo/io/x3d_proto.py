"""X3D prototypes: a ProtoInstance read as a copy of its ProtoBody.

The instance stands for the first node of its declaration's ProtoBody (the
rule X3D gives). The body is copied (the document is never modified), every
``<IS><connect nodeField protoField/></IS>`` takes the instance's
``fieldValue`` or the interface's default, and the body's DEF names are made
private to the copy. ExternProtoDeclare is not followed (that would mean
reading another file or the network): its instances are skipped with a
warning, as are instances of undeclared prototypes.
"""

from __future__ import annotations

import copy
import itertools
import re
from typing import TYPE_CHECKING

from .. import limits
from .x3d_fields import Element, local_name

if TYPE_CHECKING:
    from .x3d_fields import Context

# Copies made per document at most: a prototype whose body holds an instance
# of itself would otherwise expand for ever.
MAX_EXPANSIONS = limits.MAX_PROTO_EXPANSIONS  # see shadowgeo.limits
_FIELD_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


class Prototypes:
    """The ProtoDeclare elements of one document and the copies made of them."""

    def __init__(self, root: Element) -> None:
        self.declarations: dict[str, Element] = {}
        for element in root.iter():
            if local_name(element) == "ProtoDeclare" and element.get("name"):
                self.declarations.setdefault(element.get("name"), element)
        self.copies: dict[Element, Element | None] = {}
        self.serial = itertools.count()

    def expand(self, context: Context, instance: Element) -> Element | None:
        """The node ``instance`` (a ProtoInstance element) stands for, or None
        with a warning. The same instance always gives the same copy."""
        if instance in self.copies:
            return self.copies[instance]
        name = instance.get("name", "")
        declaration = self.declarations.get(name)
        body = None if declaration is None else _child(declaration, "ProtoBody")
        nodes = [] if body is None else [node for node in body if local_name(node)]
        if not nodes:
            why = "no ProtoDeclare of that name (ExternProtoDeclare is not followed)"
            context.warn(instance, f"ProtoInstance name='{name}' skipped: {why}")
            self.copies[instance] = None
            return None
        if len(self.copies) >= MAX_EXPANSIONS:
            raise context.error(
                instance, f"prototypes expand more than {MAX_EXPANSIONS} times (one inside itself?)"
            )
        values, node_values = _field_values(declaration, instance)
        copied: Element = copy.deepcopy(body)
        # names first: the nodes IS brings in keep the names of the scope they come from
        self._private_names(context, copied)
        _connect(context, copied, values, node_values)
        first = next((node for node in copied if local_name(node)), None)
        if first is None:  # the body held only IS elements, which connecting removes
            why = "its ProtoBody has no node once its IS connections are made"
            context.warn(instance, f"ProtoInstance name='{name}' skipped: {why}")
        self.copies[instance] = first
        return first

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


def _child(element: Element, tag: str) -> Element | None:
    return next((child for child in element if local_name(child) == tag), None)


def _field_values(
    declaration: Element, instance: Element
) -> tuple[dict[str, str], dict[str, list[Element]]]:
    """Attribute values and node values of the prototype's fields: the
    interface's defaults overridden by the instance's fieldValue elements."""
    values: dict[str, str] = {}
    node_values: dict[str, list[Element]] = {}
    interface = _child(declaration, "ProtoInterface")
    for source in [interface, instance]:
        if source is None:
            continue
        for item in source:
            if local_name(item) not in ("field", "fieldValue") or not item.get("name"):
                continue
            nodes = [node for node in item if local_name(node)]
            if item.get("value") is not None:
                values[item.get("name")] = item.get("value")
            elif nodes:
                node_values[item.get("name")] = nodes
    return values, node_values


def _connect(
    context: Context,
    body: Element,
    values: dict[str, str],
    node_values: dict[str, list[Element]],
) -> None:
    for holder in [e for e in body.iter() if local_name(e) == "IS"]:
        node = holder.getparent()
        for connect in holder:
            if local_name(connect) != "connect":
                continue
            node_field, proto_field = connect.get("nodeField"), connect.get("protoField")
            if not _FIELD_NAME.fullmatch(node_field or ""):
                raise context.error(
                    connect, f"connect nodeField={node_field!r} is not a field name"
                )
            if proto_field in values:
                node.set(node_field, values[proto_field])
            for value in node_values.get(proto_field, []):
                target = context.resolve(value)
                if target is None:
                    continue  # a USE of no DEF (or of another type): noted, the field keeps no node
                child = copy.deepcopy(target)
                child.set("containerField", node_field)
                node.append(child)
        node.remove(holder)
