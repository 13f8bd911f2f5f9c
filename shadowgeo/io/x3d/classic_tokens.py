"""Tokens of X3D's ClassicVRML encoding (ISO/IEC 19776-2) and of VRML 97.

Both share one lexical grammar: white space and commas separate tokens; ``#``
starts a comment to the end of the line, except inside a string; a string is
double-quoted, may span lines, and escapes ``"`` and ``\\`` with a backslash;
``{ } [ ]`` are tokens of their own; everything else is a word (a name, a
keyword, ``TRUE``/``FALSE``/``NULL``, or a number such as ``1e-3``, ``.5``,
``-0`` or hex ``0xFF``).
"""

from __future__ import annotations

import re
from typing import NamedTuple, cast

from ...errors import SceneError

__all__ = ["Token", "is_number", "number_text", "quote", "tokens"]

# One match a token, with the white space (and commas) before it.
_TOKEN = re.compile(
    r"""[ \t\r\n,]*
      (?: (?P<comment>\#[^\n\r]*)
        | (?P<string>")
        | (?P<numbers>\[[0-9a-fA-FxX.+\- \t\r\n,]*\])
        | (?P<punct>[{}\[\]])
        | (?P<word>[^ \t\r\n,\#"{}\[\]]+) )""",
    re.VERBOSE | re.DOTALL,
)
_NUMBER = re.compile(r"[+-]?(?:0[xX][0-9A-Fa-f]+|(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)")
_HEX = re.compile(r"[+-]?0[xX][0-9A-Fa-f]+")
_BREAK = re.compile("\n")


class Token(NamedTuple):
    """One token: ``kind`` is ``"word"``, ``"string"`` (``text`` unescaped),
    ``"punct"``, ``"comment"`` (``text`` without the ``#``) or ``"numbers"``:
    brackets holding only characters of numbers (``text`` between them), one
    token so that large arrays are read at the speed of a regular expression
    (the numbers are checked where they are used, as in the XML encoding)."""

    kind: str
    text: str
    line: int


def tokens(text: str, path: str) -> list[Token]:
    """The tokens of ``text``, comments included, with their line numbers.

    Raises
    ------
    SceneError
        A string that is not closed before the end of the file.

    Examples
    --------
    >>> [(t.kind, t.text) for t in tokens('a [1,.5] ["x \\\\"#y" b] # c', "f")]
    ... # doctest: +NORMALIZE_WHITESPACE
    [('word', 'a'), ('numbers', '1,.5'), ('punct', '['), ('string', 'x "#y'),
     ('word', 'b'), ('punct', ']'), ('comment', ' c')]
    """
    found: list[Token] = []
    # Lines are counted once for the whole text: each token's is the number
    # of line breaks before its start.
    breaks = [match.start() for match in _BREAK.finditer(text)]
    next_break, seen = (breaks[0] if breaks else len(text)), 0
    position = 0
    # (each token matched in turn: a string's end is found by scanning, see
    # _string_end, so the next match starts after it)
    while (match := _TOKEN.match(text, position)) is not None:
        # every alternative of _TOKEN is a named group
        kind = cast(str, match.lastgroup)
        start = match.start(kind)
        position = match.end()
        while next_break < start:  # the breaks before this token
            seen += 1
            next_break = breaks[seen] if seen < len(breaks) else len(text)
        line = seen + 1
        if kind == "string":
            position = _string_end(text, start)
            if position < 0:
                raise SceneError(
                    "a string is not closed before the end of the file", path=path, line=line
                )
            found.append(Token(kind, _unescaped(text[start + 1 : position - 1]), line))
            continue
        value = match.group(kind)
        if kind == "numbers":
            found.append(Token(kind, value[1:-1], line))
        elif kind == "comment":
            found.append(Token(kind, value[1:], line))
        else:
            found.append(Token(kind, value, line))
    return found


def _string_end(text: str, start: int) -> int:
    """Where the string opening at ``text[start]`` ends (just past its closing
    quote: the first ``"`` after an even run of backslashes), or -1 when it
    is never closed. Found by ``str.find``, not a regular expression: one
    that repeats a group per character (``(?:[^"\\\\]|\\\\.)*``) keeps
    ~170 bytes of backtracking state per character of a long string."""
    position = start + 1
    while (close := text.find('"', position)) >= 0:
        backslashes = 0
        while close - backslashes - 1 > start and text[close - backslashes - 1] == "\\":
            backslashes += 1
        if backslashes % 2 == 0:
            return close + 1
        position = close + 1
    return -1


def _unescaped(body: str) -> str:
    """A string's text with its escapes undone (a backslash and the
    character it escapes become that character): split at the escaped
    backslashes (paired from the left, as read), every other backslash
    dropped from each piece."""
    if "\\" not in body:
        return body
    return "\\".join(piece.replace("\\", "") for piece in body.split("\\\\"))


def is_number(word: str) -> bool:
    """Whether ``word`` is an X3D number (integer, float or hex integer)."""
    return _NUMBER.fullmatch(word) is not None


def number_text(word: str) -> str:
    """``word`` as the XML encoding writes it: hex integers in decimal."""
    return str(int(word, 16)) if _HEX.fullmatch(word) else word


def quote(text: str) -> str:
    """``text`` as a double-quoted string, ``"`` and ``\\`` escaped."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'
