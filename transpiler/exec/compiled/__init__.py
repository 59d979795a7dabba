"""The compiled side: `shim` binds the C runtime shim (NC model and PLC module table, used by the
interpreter too), `matiec_side` compiles emitted ST with matiec and drives the result by ctypes.
"""
