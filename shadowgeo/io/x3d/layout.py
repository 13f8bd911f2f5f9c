"""The XML layout of an X3D tree built from another encoding.

The ClassicVRML, VRML 97 and JSON readers build the lxml tree the XML parser
gives (see :mod:`.classic_read`, :mod:`.json`), but with no text
between the elements: written as XML as it is, a whole scene would be one
line, and every later message about it would say "line 2". :func:`lay_out`
gives that tree the layout a person writes: each element on its own line,
indented two spaces a level. Only text and tails that are absent get
whitespace, so a Script's source (its CDATA) and comments keep every
character. A tree read from XML keeps its author's layout: it is never laid
out again.
"""

from __future__ import annotations

from .fields import Element

__all__ = ["lay_out"]

_SPACE = "  "


def lay_out(root: Element) -> None:
    """Put each element under ``root`` on its own line, indented by depth.

    Parameters
    ----------
    root : Element
        Changed in place: an element with children gets a line break and
        the children's indentation as its text when it has none, each child
        the same as its tail (the last child its parent's indentation) when
        it has none. Text that is there, even whitespace, stays as it is.

    Examples
    --------
    >>> from lxml import etree
    >>> root = etree.fromstring('<X3D><Scene><Shape><Box/></Shape><!-- a --></Scene></X3D>')
    >>> lay_out(root)
    >>> print(etree.tostring(root, encoding="unicode"))
    <X3D>
      <Scene>
        <Shape>
          <Box/>
        </Shape>
        <!-- a -->
      </Scene>
    </X3D>
    """
    breaks = ["\n"]
    pending = [(root, 0)]
    while pending:  # a loop, not recursion: trees nest up to lxml's depth limit
        element, level = pending.pop()
        if len(element) == 0:  # a leaf, a comment or a processing instruction
            continue
        while len(breaks) < level + 2:
            breaks.append(breaks[-1] + _SPACE)
        inner = breaks[level + 1]
        if element.text is None:
            element.text = inner
        last_filled = False
        for child in element:
            last_filled = child.tail is None
            if last_filled:
                child.tail = inner
            pending.append((child, level + 1))
        if last_filled:
            child.tail = breaks[level]
