"""Exceptions of the built-in ST executor: StError for rejected source, StRuntimeError for faults while running."""

from __future__ import annotations

from typing import Iterable, Optional

from transpiler.diagnostics import CompileFailed, Diagnostic, Span

ST_CODE = "E-ST-PARSE"


def st_diag(span: Span, message: str) -> Diagnostic:
    return Diagnostic.of(ST_CODE, span, message)


class StError(CompileFailed):
    """The ST text was rejected (syntax, declarations or types); `diagnostics` lists every error found."""

    def __init__(self, diagnostics: Iterable[Diagnostic]):
        super().__init__(diagnostics)


class StRuntimeError(Exception):
    """A fault while executing ST (division by zero, array index out of range, loop watchdog, ...).

    `span` is the ST statement that was executing (None when it cannot be determined).
    """

    def __init__(self, message: str, span: Optional[Span] = None):
        self.message = message
        self.span = span
        super().__init__(self.render())

    def render(self) -> str:
        where = f"{self.span}: " if self.span is not None else ""
        return f"{where}runtime error: {self.message}"


class Trap(Exception):
    """Raised by generated code and runtime helpers; the runtime turns it into StRuntimeError with the ST line."""

    def __init__(self, message: str):
        super().__init__(message)
        self.message = message
