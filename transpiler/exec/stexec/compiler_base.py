"""State shared by the parts of the Compiler (diagnostics, declarations, located storage, program
instances and tasks) and the name rules every declaration obeys."""

from __future__ import annotations

from types import MappingProxyType
from typing import Optional

from transpiler.diagnostics import Diagnostics, Span
from transpiler.exec.stexec import typesys as T
from transpiler.exec.stexec.errors import ST_CODE
from transpiler.exec.stexec.keywords import is_reserved_word
from transpiler.exec.stexec.model import ProgramInstance, TaskInfo
from transpiler.exec.stexec.pycode import Context, location_attr
from transpiler.exec.stexec.stdlib import is_standard_name


# The type an address's size prefix implies: its width must match a declaration, and it types an undeclared use.
SIZE_TYPE = MappingProxyType({"X": T.BOOL, "B": T.BYTE, "W": T.WORD, "D": T.DWORD, "L": T.LWORD})
KIND_NAMES = MappingProxyType({"input": "VAR_INPUT", "output": "VAR_OUTPUT", "inout": "VAR_IN_OUT", "var": "VAR",
                               "temp": "VAR_TEMP", "external": "VAR_EXTERNAL", "global": "VAR_GLOBAL"})
ALLOWED_KINDS = MappingProxyType({
    "function": frozenset({"input", "output", "inout", "var", "temp"}),
    "function_block": frozenset({"input", "output", "inout", "var", "temp", "external"}),
    "program": frozenset({"input", "output", "inout", "var", "temp", "external"}),
})


class CompilerBase:
    """Diagnostics and everything declared so far; the parts (declare_*, emit) add to it."""

    def __init__(self, filename: str, loop_limit: int):
        self.filename = filename
        self.diags = Diagnostics()
        self.ctx = Context(self.error, loop_limit)
        self.locations: dict[str, tuple[T.Type, str, Span]] = {}
        self.programs: list[ProgramInstance] = []
        self.tasks: list[TaskInfo] = []
        self.has_configuration = False
        self.structs: list[T.StructT] = []
        self.prelude_keys: set[str] = set()
        self.ctx.use_address = self.use_address

    def use_address(self, addr: str, span: Span) -> Optional[tuple[T.Type, str]]:
        """Storage of an address used directly in code: the declared type, else the size prefix's bit string."""
        prev = self.locations.get(addr)
        if prev is not None:
            return prev[0], prev[1]
        ty = SIZE_TYPE[addr[2]]
        attr = location_attr(addr)
        self.locations[addr] = (ty, attr, span)
        return ty, attr

    def error(self, span: Optional[Span], message: str) -> None:
        self.diags.report(ST_CODE, span or Span(self.filename, 1, 1), message)

    def check_name(self, name: str, span: Span, prelude: bool, what: str) -> bool:
        key = name.lower()
        if prelude:
            return True
        if "__" in key or key.endswith("_"):
            self.error(span, f"invalid {what} name '{name}': IEC identifiers have no double or trailing underscore")
            return False
        if is_reserved_word(key):
            self.error(span, f"'{name}' is a reserved word of IEC 61131-3 and cannot be a {what} name")
            return False
        if is_standard_name(key) or key in self.prelude_keys or key in ("en", "eno"):
            self.error(span, f"'{name}' is the name of a standard function or function block and cannot be a "
                             f"{what} name")
            return False
        return True
