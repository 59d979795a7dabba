"""Runtime faults and warnings of the reference interpreter and the per-cycle report."""

from __future__ import annotations

import dataclasses

from transpiler.diagnostics import CompileFailed, Span


class Fault(Exception):
    """Raised by generated code and its helpers; the machine adds file, line and cycle from the traceback."""

    def __init__(self, code: str, message: str):
        super().__init__(message)
        self.code = code
        self.message = message


class BudgetExceeded(Exception):
    """The fast variant's per-block pre-count passed the budget; the machine re-runs the cycle exactly."""


class JobCancelled(Exception):
    """CAN cancelled the submit job that is running; unwinds the job's Python frames."""


class MachineConfigError(CompileFailed):
    """The machine cannot be set up (bad machine-parameter values, E-MP-VALUE); carries diagnostics."""


class MachineHalted(RuntimeError):
    """run_cycle after a runtime fault stopped the PLC program."""


@dataclasses.dataclass(frozen=True)
class RuntimeFault:
    """One runtime diagnostic: an error stops the run, a warning (E-RT-STRING, E-RT-STACK-LEFTOVER, E-RT-MODULE) does not."""

    code: str
    message: str
    cycle: int
    span: Span | None = None            # None for faults without a program location (NC handshake timeout)
    severity: str = "error"
    op: tuple[int, int] | None = None   # (file index, op index) of the instruction
    job: str | None = None              # label of the submit job the fault happened in

    @property
    def is_error(self) -> bool:
        return self.severity == "error"

    def render(self, where: Span | None = None) -> str:
        """`file:line:col: error[CODE]: message (cycle N)`; `where` stands in when the fault has no span."""
        span = self.span or where or Span("<simulation>", 1, 1)
        job = f" in submit job {self.job}" if self.job else ""
        return f"{span}: {self.severity}[{self.code}]: {self.message} (cycle {self.cycle}{job})"


@dataclasses.dataclass
class CycleReport:
    """What one run_cycle produced: the fault that stopped it (if any), warnings, executed instruction count.

    `instructions` is exact for a cycle that completes; the fast code counts the block in which a
    fault happened as a whole.
    """

    cycle: int
    faults: list[RuntimeFault] = dataclasses.field(default_factory=list)
    warnings: list[RuntimeFault] = dataclasses.field(default_factory=list)
    instructions: int = 0
    nc_writes: list[tuple[str, int, int]] = dataclasses.field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.faults
