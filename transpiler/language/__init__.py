"""What the HEIDENHAIN control is, as data: control profiles and the table of semantic choices, the
instruction set, the PLC module catalogue, and timer/counter presets from machine parameters.

In: nothing but constants and machine-parameter values. Out: tables every later stage reads.
Must not know: source files, the IR, any back end or executor; it sits on the floor beside
`diagnostics`.
"""
