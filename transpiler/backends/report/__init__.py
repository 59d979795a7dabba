"""The migration report's data: the operand <-> IEC variable map (`io_map.csv`) that users read
to wire the new PLC and that the co-simulation uses to reach every operand in the ST program.
"""
