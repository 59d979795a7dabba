"""A small element tree for the PLCopen writer, printed as lxml prints a tree with `pretty_print=True`.

The project file of a large program has a hundred thousand elements or more; building them as lxml elements cost
about 2 us each (one call into lxml per element and the namespace lookups), several times what plain Python
objects and one joined text cost. The trees written here are simple: an element holds either child elements or
text, never both, and the namespaces are declared on the root (and on the one element of a foreign namespace that
declares its own). For such trees the text below is lxml's own byte for byte: two blanks of indent per level, an
element without children or text as `<tag/>`, one with empty text as `<tag></tag>`, attributes in the order
given, and the same character escapes (tests/test_plcopen.py compares both on awkward text).

Callers pass text that XML 1.0 can carry (writer.xml_safe); tags are written with their prefix (`xhtml:p`).
"""

from __future__ import annotations

import re
from typing import Callable, Iterable

_TEXT_SPECIAL = re.compile("[&<>\r]")
_ATTRIBUTE_SPECIAL = re.compile('[&<>"\t\n\r]')
_ATTRIBUTE_ESCAPES = {"&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "\t": "&#9;", "\n": "&#10;",
                      "\r": "&#13;"}


def attribute_text(attributes: Iterable[tuple[str, str]]) -> str:
    """Attributes as they stand in a start tag: ` name="value"` each, escaped."""
    text = ""
    for key, value in attributes:
        if _ATTRIBUTE_SPECIAL.search(value):
            value = _ATTRIBUTE_SPECIAL.sub(_attribute_escape, value)
        text += f' {key}="{value}"'
    return text


def _attribute_escape(match: re.Match) -> str:
    return _ATTRIBUTE_ESCAPES[match.group(0)]


class Element:
    """One element: its tag (with prefix), its attributes as printed, and either children or text (None: no
    text). The attributes are printed when they are given: an element is printed once, and built in one go."""

    __slots__ = ("tag", "attributes", "children", "text", "printed")

    def __init__(self, tag: str, attributes: str = "") -> None:
        self.tag = tag
        self.attributes = attributes
        self.children: list[Element] = []
        self.text: str | None = None
        self.printed: dict[str, str] | None = None      # a shared element's text by indent

    def share(self) -> None:
        """Let the element stand under several parents (or several times under one): it is printed once for each
        indent it stands at, and its other places repeat that text (so it must not change once printed)."""
        self.printed = {}

    def set(self, key: str, value: str) -> None:
        """Add an attribute (as lxml's `set` of a new name)."""
        self.attributes += attribute_text(((key, value),))

    def sub(self, tag: str, attributes: str = "") -> "Element":
        """A new last child; `attributes` as attribute_text prints them."""
        child = Element(tag, attributes)
        self.children.append(child)
        return child


def to_bytes(root: Element) -> bytes:
    """The tree as UTF-8 with lxml's XML declaration, pretty-printed."""
    out = ["<?xml version='1.0' encoding='UTF-8'?>\n"]
    _write(root, "", out.append)
    return "".join(out).encode("utf-8")


def _write(element: Element, pad: str, append: Callable[[str], None]) -> None:
    # (recursive: the trees are a dozen levels deep at most; the root is never shared)
    if element.children:
        append(f"{pad}<{element.tag}{element.attributes}>\n")
        inner = pad + "  "
        for child in element.children:
            if child.printed is None:
                _write(child, inner, append)
            else:       # (a printed element is never empty text)
                append(child.printed.get(inner) or _print_shared(child, inner))
        append(f"{pad}</{element.tag}>\n")
    elif element.text is not None:
        text = element.text
        if _TEXT_SPECIAL.search(text):
            # (replace, '&' first, is three times as fast as a substitution per match on the long ST bodies)
            text = text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace("\r", "&#13;")
        append(f"{pad}<{element.tag}{element.attributes}>{text}</{element.tag}>\n")
    else:
        append(f"{pad}<{element.tag}{element.attributes}/>\n")


def _print_shared(element: Element, pad: str) -> str:
    """A shared element's text at `pad`, printed the first time it stands there."""
    printed: list[str] = []
    _write(element, pad, printed.append)
    text = element.printed[pad] = "".join(printed)       # type: ignore[index]
    return text
