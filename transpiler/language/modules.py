"""The PLC module catalogue (spec 14.2/14.3): parameter and result counts of every module hh2iec knows."""

from __future__ import annotations

import dataclasses


@dataclasses.dataclass(frozen=True)
class ModuleSignature:
    number: int
    params: int
    results: int
    modelled: bool
    purpose: str


_sig = ModuleSignature          # (short name for the rows below)

# The C runtime shim (runtime_shim/hh_modules.c) implements the effects; tests/test_shim.py checks that
# its table agrees with this one for every number 9000-9999.
MODULES: dict[int, ModuleSignature] = {m.number: m for m in (
    _sig(9006, 1, 0, True, "start an additional timer T96-T999"),
    _sig(9031, 3, 1, True, "overwrite a machine parameter (run-time value)"),
    _sig(9032, 2, 1, True, "read a machine parameter"),
    _sig(9035, 1, 1, True, "read status information"),
    _sig(9036, 2, 1, True, "write status information"),
    _sig(9040, 2, 0, False, "read axis coordinates"),
    _sig(9041, 2, 0, False, "read axis coordinates"),
    _sig(9094, 4, 1, False, "write an element of a tool/datum table"),
    _sig(9097, 2, 1, False, "select a geometry description"),
    _sig(9192, 1, 1, True, "read an operating time in seconds"),
    _sig(9195, 0, 1, True, "system time"),
    *(_sig(n, 0, 0, False, "named in the sources without a usable signature (stub)")
      for n in (9042, 9051, 9095, 9105, 9106, 9123, 9124, 9148, 9150, 9159, 9162, 9166, 9190, 9191, 9194)),
)}
