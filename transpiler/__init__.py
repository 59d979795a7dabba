"""hh2iec: HEIDENHAIN TNC PLC programs to IEC 61131-3 Structured Text and PLCopen XML, with proof by co-simulation.

The packages, from the floor up (a module imports only from its own floor or lower ones):
`diagnostics`, `atomic` (shared floor) -> `language` (the control as data) -> `ir` -> `frontend` (project files to
IR) -> `backends` (IR to ST, PLCopen XML, report) -> `exec` (interpreter, ST executor, compiled side) ->
`verify` (scenarios, simulation, co-simulation, equivalence) -> `api` (the public functions) -> `cli` (on top;
nothing imports it).
"""

__version__ = "0.1.0"
