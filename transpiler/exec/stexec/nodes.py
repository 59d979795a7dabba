"""Syntax tree of a Structured Text file as the built-in executor's parser produces it (every node has a span)."""

from __future__ import annotations

import dataclasses
from typing import Optional, Union

from transpiler.diagnostics import Span


# ------------------------------------------------------------------ expressions

@dataclasses.dataclass
class Lit:
    """A literal as written: kind is int, based, real, typed or string; text is the source text.

    TRUE and FALSE are names (resolved by the code generator), not literals of the grammar."""

    kind: str
    text: str
    span: Span


@dataclasses.dataclass
class Name:
    name: str
    span: Span


@dataclasses.dataclass
class Addr:
    """A directly represented variable used in code, e.g. %QX0.1."""

    address: str
    span: Span


@dataclasses.dataclass
class Field:
    base: "Expr"
    name: str
    span: Span


@dataclasses.dataclass
class Index:
    base: "Expr"
    indices: list["Expr"]
    span: Span


@dataclasses.dataclass
class Arg:
    """One actual parameter: positional (name None), `name := value`, or `name => target` (out)."""

    name: Optional[str]
    value: Optional["Expr"]
    target: Optional["Expr"]
    negated: bool
    span: Span


@dataclasses.dataclass
class Call:
    name: str
    args: list[Arg]
    span: Span


@dataclasses.dataclass
class Unary:
    op: str
    operand: "Expr"
    span: Span


@dataclasses.dataclass
class Binary:
    op: str
    left: "Expr"
    right: "Expr"
    span: Span


Expr = Union[Lit, Name, Addr, Field, Index, Call, Unary, Binary]


# ------------------------------------------------------------------ initialisers

@dataclasses.dataclass
class ArrayInit:
    """`[a, b, 3(c)]`: items are (repeat count or None, initialiser or None)."""

    items: list[tuple[Optional[int], Optional["Init"]]]
    span: Span


@dataclasses.dataclass
class StructInit:
    fields: list[tuple[str, "Init", Span]]
    span: Span


Init = Union[Expr, ArrayInit, StructInit]


# ------------------------------------------------------------------ type specifications

@dataclasses.dataclass
class NamedTypeSpec:
    name: str
    span: Span


@dataclasses.dataclass
class StringSpec:
    length: int
    span: Span


@dataclasses.dataclass
class SubrangeSpec:
    base: str
    lo: int
    hi: int
    span: Span


@dataclasses.dataclass
class ArraySpec:
    ranges: list[tuple[int, int]]
    elem: "TypeSpec"
    span: Span


@dataclasses.dataclass
class StructElem:
    name: str
    spec: "TypeSpec"
    init: Optional[Init]
    span: Span


@dataclasses.dataclass
class StructSpec:
    elems: list[StructElem]
    span: Span


@dataclasses.dataclass
class EnumSpec:
    values: list[tuple[str, Span]]
    default: Optional[str]
    span: Span


TypeSpec = Union[NamedTypeSpec, StringSpec, SubrangeSpec, ArraySpec]


@dataclasses.dataclass
class TypeDecl:
    name: str
    spec: Union[TypeSpec, StructSpec, EnumSpec]
    init: Optional[Init]
    span: Span


# ------------------------------------------------------------------ declarations

@dataclasses.dataclass
class VarDecl:
    names: list[tuple[str, Span]]
    spec: TypeSpec
    init: Optional[Init]
    location: Optional[str]
    span: Span


@dataclasses.dataclass
class VarBlock:
    kind: str          # var, input, output, inout, external, temp, global
    constant: bool
    retain: bool
    decls: list[VarDecl]
    span: Span


# ------------------------------------------------------------------ statements

@dataclasses.dataclass
class Assign:
    target: Expr
    value: Expr
    span: Span


@dataclasses.dataclass
class CallStmt:
    name: str
    args: list[Arg]
    span: Span


@dataclasses.dataclass
class If:
    branches: list[tuple[Expr, list["Stmt"]]]
    orelse: Optional[list["Stmt"]]
    span: Span


@dataclasses.dataclass
class CaseLabel:
    """An integer label (lo == hi), a range, or an enum value (enum set, possibly `Type#Value`)."""

    lo: Optional[int]
    hi: Optional[int]
    enum: Optional[str]
    span: Span


@dataclasses.dataclass
class Case:
    selector: Expr
    elems: list[tuple[list[CaseLabel], list["Stmt"]]]
    orelse: Optional[list["Stmt"]]
    span: Span


@dataclasses.dataclass
class For:
    var: str
    var_span: Span
    start: Expr
    end: Expr
    step: Optional[Expr]
    body: list["Stmt"]
    span: Span


@dataclasses.dataclass
class While:
    cond: Expr
    body: list["Stmt"]
    span: Span


@dataclasses.dataclass
class Repeat:
    body: list["Stmt"]
    cond: Expr
    span: Span


@dataclasses.dataclass
class Exit:
    span: Span


@dataclasses.dataclass
class Return:
    span: Span


@dataclasses.dataclass
class Continue:
    span: Span


Stmt = Union[Assign, CallStmt, If, Case, For, While, Repeat, Exit, Return, Continue]


# ------------------------------------------------------------------ library elements

@dataclasses.dataclass
class Pou:
    kind: str                       # function, function_block, program
    name: str
    result: Optional[TypeSpec]
    blocks: list[VarBlock]
    body: list[Stmt]
    span: Span
    end_span: Span


@dataclasses.dataclass
class TypeBlock:
    decls: list[TypeDecl]
    span: Span


@dataclasses.dataclass
class GlobalBlock:
    block: VarBlock


@dataclasses.dataclass
class Task:
    name: str
    params: list[tuple[str, Expr, Span]]
    span: Span


@dataclasses.dataclass
class ProgramConf:
    name: str
    task: Optional[str]
    type_name: str
    has_args: bool
    span: Span


@dataclasses.dataclass
class Resource:
    name: str
    globals: list[VarBlock]
    tasks: list[Task]
    programs: list[ProgramConf]
    span: Span


@dataclasses.dataclass
class Configuration:
    name: str
    globals: list[VarBlock]
    resources: list[Resource]
    span: Span


Element = Union[TypeBlock, Pou, GlobalBlock, Configuration]


@dataclasses.dataclass
class SourceFile:
    elements: list[Element]
    filename: str
