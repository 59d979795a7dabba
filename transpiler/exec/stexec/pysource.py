"""The generated Python module as it is built: lines with the ST span each came from, and storage classes."""

from __future__ import annotations

from typing import Optional

from transpiler.diagnostics import Span
from transpiler.exec.stexec import typesys as T


class PySource:
    """Accumulates generated Python lines together with the ST span each one came from."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.spans: list[Optional[Span]] = []

    def add(self, indent: int, text: str, span: Optional[Span] = None) -> None:
        self.lines.append("    " * indent + text)
        self.spans.append(span)


def storage_class(src: PySource, name: str, fields: list[tuple[str, str, Optional[Span]]],
                   span: Optional[Span] = None) -> None:
    """A slotted class whose __init__ gives every field (attribute, initial value code, ST span) its value."""
    src.add(0, f"class {name}:", span)
    src.add(1, f"__slots__ = {tuple(attr for attr, _c, _s in fields)!r}")
    src.add(1, "def __init__(self):")
    for attr, code, fspan in fields:
        src.add(2, f"self.{attr} = {code}", fspan)
    if not fields:
        src.add(2, "pass")


def st_span(field: T.StructField, filename: str) -> Span:
    init = field.init
    span = getattr(init, "span", None)
    return span or Span(filename, 1, 1)
