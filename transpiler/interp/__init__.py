"""Reference interpreter: cycle-accurate execution of the resolved HEIDENHAIN program (spec sections 5-15)."""

from .compile import CompiledProgram, compile_program
from .faults import CycleReport, MachineConfigError, MachineHalted, RuntimeFault
from .machine import Coverage, Machine, normalize_mp

__all__ = ["CompiledProgram", "Coverage", "CycleReport", "Machine", "MachineConfigError", "MachineHalted",
           "RuntimeFault", "compile_program", "normalize_mp"]
