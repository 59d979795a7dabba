"""Declarations the compiler resolves (variables, POUs, configuration) and the compiled project it hands to the runtime."""

from __future__ import annotations

import dataclasses
from typing import Any, Optional

from transpiler.diagnostics import Span
from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec.typesys import FbT, Type, is_aggregate


@dataclasses.dataclass
class VarInfo:
    """One declared variable. kind: input, output, inout, var, temp, external, global, result."""

    name: str
    ty: Type
    kind: str
    span: Span
    constant: bool = False
    retain: bool = False
    init: Optional[n.Init] = None
    location: Optional[str] = None       # normalised address, e.g. %QX0.1
    const_value: Any = None              # Python value of a scalar CONSTANT, inlined into code

    @property
    def key(self) -> str:
        return self.name.lower()


@dataclasses.dataclass
class PouInfo:
    kind: str                             # function, function_block, program
    name: str
    node: n.Pou
    ordinal: int
    prelude: bool
    vars: dict[str, VarInfo] = dataclasses.field(default_factory=dict)
    result: Optional[Type] = None
    fbtype: Optional[FbT] = None

    @property
    def key(self) -> str:
        return self.name.lower()

    @property
    def params(self) -> list[VarInfo]:
        return [v for v in self.vars.values() if v.kind in ("input", "inout", "output")]

    @property
    def pyparams(self) -> list[VarInfo]:
        """Parameters of the compiled Python function of a FUNCTION, in declaration order."""
        return [v for v in self.vars.values() if v.kind in ("input", "inout")]

    @property
    def tuple_outputs(self) -> list[VarInfo]:
        """What a FUNCTION returns after its result: outputs, then scalar in-outs (copied back by the caller)."""
        outs = [v for v in self.vars.values() if v.kind == "output"]
        return outs + [v for v in self.vars.values() if v.kind == "inout" and not is_aggregate(v.ty)]

    @property
    def state_vars(self) -> list[VarInfo]:
        """Variables stored in an FB or program instance (not temps, externals or located variables)."""
        return [v for v in self.vars.values()
                if v.kind in ("input", "output", "inout", "var") and v.location is None]


@dataclasses.dataclass
class TaskInfo:
    name: str
    interval_ms: int
    priority: int
    span: Span


@dataclasses.dataclass
class ProgramInstance:
    name: str
    pou: PouInfo
    task: Optional[TaskInfo]
    span: Span


@dataclasses.dataclass
class CompiledProject:
    """Everything instantiate() needs: the Python code object plus the metadata for scheduling and addressing."""

    filename: str
    code: Any                                # code object of the generated module
    source: str                              # generated Python source (for debugging)
    line_spans: list[Optional[Span]]         # generated line number (1-based index) -> ST span
    pous: dict[str, PouInfo]
    globals: dict[str, VarInfo]
    locations: dict[str, tuple[Type, str]]   # address -> (type, attribute on the globals object)
    programs: list[ProgramInstance]
    tasks: list[TaskInfo]
    has_configuration: bool
    loop_limit: int
    unswitched: frozenset = frozenset()      # mutations of a mutant schema compiled without a switch (schema.py)
