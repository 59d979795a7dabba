"""The back ends: one resolved IR program becomes the files a user takes to the new PLC.

In: an `ir.Program`, its diagnostics and the machine-parameter values. `st/` decides the IEC
project (`iec_model`: POUs, variables, bodies) and prints it as Structured Text; `plcopen/`
prints the same project as PLCopen TC6 XML and validates it against the official schema;
`report/` writes the migration report and the operand <-> variable map; `transpile` runs them.
Out: file texts, never written here. Must not know: executors, scenarios, the command line.
"""
