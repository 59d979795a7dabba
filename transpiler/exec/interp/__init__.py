"""Reference interpreter: cycle-accurate execution of the resolved HEIDENHAIN program (spec sections 5-15)."""

from transpiler.exec.interp.compile import CompiledProgram, compile_program
from transpiler.exec.interp.faults import CycleReport, MachineConfigError, MachineHalted, RuntimeFault
from transpiler.exec.interp.machine import Coverage, Machine, normalize_mp

__all__ = ["CompiledProgram", "Coverage", "CycleReport", "Machine", "MachineConfigError", "MachineHalted",
           "RuntimeFault", "compile_program", "normalize_mp"]
