"""Data types of the built-in ST executor: elementary types with exact widths, arrays, structs, enums, subranges."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from types import MappingProxyType
from typing import Any, Optional

STR_MAX = 126   # matiec's STR_MAX_LEN: longest STRING value


class Type:
    """Base of all types; derived types compare by identity (IEC name equivalence)."""

    def __str__(self) -> str:
        return getattr(self, "name", "?")


@dataclasses.dataclass(frozen=True, eq=False)
class Elem(Type):
    """An elementary type; cat is int, bit, bool, real, time or string."""

    name: str
    cat: str
    bits: int = 0
    signed: bool = False

    @property
    def lo(self) -> int:
        return -(1 << (self.bits - 1)) if self.signed else 0

    @property
    def hi(self) -> int:
        return (1 << (self.bits - 1)) - 1 if self.signed else (1 << self.bits) - 1

    @property
    def mask(self) -> int:
        return (1 << self.bits) - 1

    def __str__(self) -> str:
        return self.name


BOOL = Elem("BOOL", "bool", 1)
SINT = Elem("SINT", "int", 8, True)
INT = Elem("INT", "int", 16, True)
DINT = Elem("DINT", "int", 32, True)
LINT = Elem("LINT", "int", 64, True)
USINT = Elem("USINT", "int", 8)
UINT = Elem("UINT", "int", 16)
UDINT = Elem("UDINT", "int", 32)
ULINT = Elem("ULINT", "int", 64)
BYTE = Elem("BYTE", "bit", 8)
WORD = Elem("WORD", "bit", 16)
DWORD = Elem("DWORD", "bit", 32)
LWORD = Elem("LWORD", "bit", 64)
REAL = Elem("REAL", "real", 32)
LREAL = Elem("LREAL", "real", 64)
TIME = Elem("TIME", "time", 64, True)
STRING = Elem("STRING", "string")

ELEMENTARY: Mapping[str, Elem] = MappingProxyType({t.name.lower(): t for t in (
    BOOL, SINT, INT, DINT, LINT, USINT, UINT, UDINT, ULINT, BYTE, WORD, DWORD, LWORD, REAL, LREAL, TIME, STRING)})
UNSUPPORTED_ELEMENTARY = frozenset({"date", "tod", "time_of_day", "dt", "date_and_time", "wstring", "char", "wchar",
                                    "ltime"})


@dataclasses.dataclass(frozen=True, eq=False)
class LitType(Type):
    """The type of an untyped literal or of a generic result (ANY_INT, ANY_REAL) that adapts to its context."""

    name: str
    cat: str   # int or real


ANY_INT_LIT = LitType("ANY_INT", "int")
ANY_REAL_LIT = LitType("ANY_REAL", "real")


@dataclasses.dataclass(eq=False)
class ErrType(Type):
    """Placeholder after an error, so that one fault gives one message."""

    name: str = "<error>"


ERR = ErrType()


@dataclasses.dataclass(eq=False)
class SubrangeT(Type):
    base: Elem
    lo: int
    hi: int
    name: str = ""

    def __post_init__(self) -> None:
        if not self.name:
            self.name = f"{self.base.name}({self.lo}..{self.hi})"


@dataclasses.dataclass(eq=False)
class ArrayT(Type):
    name: str
    dims: list[tuple[int, int]]
    elem: Type

    @property
    def size(self) -> int:
        total = 1
        for lo, hi in self.dims:
            total *= hi - lo + 1
        return total

    def strides(self) -> list[int]:
        out = []
        acc = 1
        for lo, hi in reversed(self.dims):
            out.append(acc)
            acc *= hi - lo + 1
        return list(reversed(out))


@dataclasses.dataclass
class StructField:
    name: str
    ty: Type
    init: Any          # nodes.Init or None


@dataclasses.dataclass(eq=False)
class StructT(Type):
    name: str
    fields: dict[str, StructField]
    pyname: str = ""


@dataclasses.dataclass(eq=False)
class EnumT(Type):
    name: str
    values: list[str]
    default: int = 0

    def index(self, value: str) -> Optional[int]:
        low = value.lower()
        for i, v in enumerate(self.values):
            if v.lower() == low:
                return i
        return None


@dataclasses.dataclass(eq=False)
class FbT(Type):
    """A function block type (user-written or from the standard library prelude)."""

    name: str
    pou: Any            # compiler.PouInfo


def base(t: Type) -> Type:
    return t.base if isinstance(t, SubrangeT) else t


def is_int(t: Type) -> bool:
    b = base(t)
    return isinstance(b, Elem) and b.cat == "int"


def is_bit(t: Type) -> bool:
    b = base(t)
    return isinstance(b, Elem) and b.cat == "bit"


def is_real(t: Type) -> bool:
    b = base(t)
    return isinstance(b, Elem) and b.cat == "real"


def is_aggregate(t: Type) -> bool:
    return isinstance(t, (ArrayT, StructT, FbT))


def same(a: Type, b: Type) -> bool:
    return base(a) is base(b)


def default_value(t: Type) -> Any:
    """Python value of the type's default (scalars only)."""
    b = base(t)
    if isinstance(t, SubrangeT):
        return t.lo
    if isinstance(b, Elem):
        return {"bool": False, "real": 0.0, "string": ""}.get(b.cat, 0)
    if isinstance(b, EnumT):
        return b.default
    raise TypeError(f"no scalar default for {t}")
