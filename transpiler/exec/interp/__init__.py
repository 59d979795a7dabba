"""The reference interpreter: cycle-accurate execution of the resolved HEIDENHAIN program with the control's
semantics (operands and memory overlap, accumulator, timers, counters, strobes, submit jobs, PLC modules).

In: an `ir.Program`, machine parameters and per-cycle writes/NC actions. Out: machine state to read after every
cycle, runtime faults and coverage. `compile` turns the IR into Python code once; `machine` runs it.
Must not know: ST, back ends, scenarios.
"""

from transpiler.exec.interp.compile import CompiledProgram, compile_program
from transpiler.exec.interp.faults import CycleReport, MachineConfigError, MachineHalted, RuntimeFault
from transpiler.exec.interp.machine import Coverage, Machine, normalize_mp

__all__ = ["CompiledProgram", "Coverage", "CycleReport", "Machine", "MachineConfigError", "MachineHalted",
           "RuntimeFault", "compile_program", "normalize_mp"]
