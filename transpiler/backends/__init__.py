"""The back ends: one resolved IR program becomes the files a user takes to the new PLC.

In: an `ir.Program`, its diagnostics and the machine-parameter values. `st/` decides the IEC
project (`iec_model`: POUs, variables, bodies) and prints it as Structured Text; `plcopen/`
prints the same project as PLCopen TC6 XML and validates it against the official schema;
`report/` writes the migration report and the operand <-> variable map; `twincat/` arranges the same
project as a TwinCAT 3 PLC project folder (one file per object); `readme` tells a CODESYS or TwinCAT user
how to load the output and which task to create; `transpile` runs them.
Out: file texts, never written here. Must not know: executors, scenarios, the command line.
"""
