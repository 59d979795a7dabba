"""The executors: programs that run, cycle by cycle, for simulation and co-simulation.

`interp/` runs the resolved HEIDENHAIN program (the IR) with the control's semantics: the
reference side. `stexec/` parses, checks and runs Structured Text text: the built-in ST side.
`compiled/` is the compiled side: ctypes bindings of the C runtime shim (NC model, timers,
PLC modules; shared with the interpreter so both sides see one NC model) and the matiec driver
that compiles the emitted ST to a shared library. In: an IR program or ST text. Out: machines
to step and read. Must not know: scenarios, comparisons, verdicts, the command line.
"""
