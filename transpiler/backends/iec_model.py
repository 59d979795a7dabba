"""The IEC 61131-3 project model: what the ST backend decides, and what the ST and PLCopen writers only format."""

from __future__ import annotations

import dataclasses
from types import MappingProxyType
from typing import Literal

from transpiler.records import quick_init

PouKind = Literal["PROGRAM", "FUNCTION_BLOCK", "FUNCTION"]
SectionKind = Literal["VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_EXTERNAL", "VAR_GLOBAL", "VAR_TEMP"]


@quick_init
@dataclasses.dataclass(frozen=True)
class SourceRange:
    """A range of lines in an original HEIDENHAIN file (for source maps and `file:line` tags)."""

    file: str
    first_line: int
    last_line: int

    def tag(self) -> str:
        if self.first_line == self.last_line:
            return f"{self.file}:{self.first_line}"
        return f"{self.file}:{self.first_line}-{self.last_line}"


@quick_init
@dataclasses.dataclass(frozen=True)
class IecVar:
    """One variable declaration. `type` is an elementary type name or the name of a declared DataType/FB."""

    name: str
    type: str
    initial: str | None = None          # ST literal text, e.g. "TRUE", "16#FF", "[10(0)]"
    address: str | None = None          # located address, e.g. "%IX0.5"
    comment: str | None = None


@quick_init
@dataclasses.dataclass(frozen=True)
class VarSection:
    kind: SectionKind
    vars: tuple[IecVar, ...]
    constant: bool = False
    retain: bool = False
    comment: str | None = None


@dataclasses.dataclass(frozen=True)
class ArrayDim:
    lo: int
    hi: int


@dataclasses.dataclass(frozen=True)
class DataType:
    """A named TYPE: an array (`base` element type with dims) or a struct (`fields`)."""

    name: str
    kind: Literal["array", "struct"]
    base: str | None = None
    dims: tuple[ArrayDim, ...] = ()
    fields: tuple[IecVar, ...] = ()
    comment: str | None = None


@quick_init
@dataclasses.dataclass(frozen=True)
class Pou:
    """A POU. `body` is the complete ST statement text of the body, unindented, lines joined with '\\n'.

    `statements` is the statement tree (backends/st/stmt.py) the ST back end printed `body` from, on every target;
    POUs whose body is written as text (the library) have none."""

    name: str
    kind: PouKind
    sections: tuple[VarSection, ...]
    body: str
    return_type: str | None = None
    comment: str | None = None
    source_map: tuple[SourceRange, ...] = ()
    statements: tuple[object, ...] = ()


@dataclasses.dataclass(frozen=True)
class Task:
    name: str
    interval_ms: int
    priority: int = 0


@dataclasses.dataclass(frozen=True)
class ProgramInstance:
    name: str
    task: str
    type_name: str


@dataclasses.dataclass(frozen=True)
class Configuration:
    """Exactly one configuration with one resource (matiec cannot link two resources)."""

    name: str
    resource: str
    tasks: tuple[Task, ...]
    instances: tuple[ProgramInstance, ...]
    globals: tuple[VarSection, ...]


@dataclasses.dataclass(frozen=True)
class IecProject:
    """A whole IEC project; `pous` are in dependency order (callees before callers)."""

    name: str
    types: tuple[DataType, ...]
    pous: tuple[Pou, ...]
    configuration: Configuration
    header_comment: str | None = None


def st_comment(text: str) -> str:
    """An ST comment that is safe whatever `text` contains (no nested or closing comment markers)."""
    safe = text.replace("(*", "( *").replace("*)", "* )")
    # Control characters other than tab would upset some importers; show them as '?'.
    if not (safe.isascii() and safe.isprintable()):     # (printable ASCII, nearly every comment, holds none)
        safe = safe.translate(_CONTROL_AS_QUESTION_MARK)
    return f"(* {safe} *)"


# (str.translate's table: every control character but tab becomes '?')
_CONTROL_AS_QUESTION_MARK = MappingProxyType({code: "?" for code in range(32) if chr(code) != "\t"})
