"""The simulated system context with the module table's calling-context rule and the scenario's machine data.

`SysModules` (exec/compiled/shim.py) binds the original shim functions; this subclass binds the ones
the module table added (hh_modules.h): calls with the caller's context (cyclic program or submit job),
table metadata, axes, drives and the tables 9092-9094 read.
"""

from __future__ import annotations

import ctypes
from typing import Sequence

from transpiler.exec.compiled.shim import SysModules, UnknownModule

CALLER_CYCLIC, CALLER_JOB = 1, 2

_I32 = ctypes.c_int32
_PI32 = ctypes.POINTER(ctypes.c_int32)
_PROTOTYPES = {
    "hh_module_call_ctx": (ctypes.c_int, [ctypes.c_void_p, _I32, _I32, _PI32, _PI32, _PI32]),
    "hh_module_meta": (ctypes.c_int, [_I32, _PI32, _PI32, _PI32, _PI32, _PI32]),
    "hh_sys_set_axis": (ctypes.c_int, [ctypes.c_void_p, _I32, _I32, _I32]),
    "hh_sys_set_drives": (None, [ctypes.c_void_p, _I32, _I32]),
    "hh_sys_set_memory_size": (None, [ctypes.c_void_p, _I32]),
    "hh_sys_set_table": (ctypes.c_int, [ctypes.c_void_p, _I32, _I32, _I32, _I32]),
}


def bind(lib: ctypes.CDLL) -> None:
    """Declare the prototypes (idempotent: the same values every time)."""
    for name, (restype, argtypes) in _PROTOTYPES.items():
        fn = getattr(lib, name)
        fn.restype = restype
        fn.argtypes = argtypes


def module_meta(lib: ctypes.CDLL, number: int) -> tuple[int, int, int, int, int] | None:
    """(kind, context, strobe, profile mask, error result) of the C table's row, None for an unknown number."""
    bind(lib)
    out = [ctypes.c_int32() for _ in range(5)]
    if not lib.hh_module_meta(number, *(ctypes.byref(o) for o in out)):
        return None
    kind, context, strobe, profiles, error_result = (o.value for o in out)
    return kind, context, strobe, profiles, error_result


class SysContext(SysModules):
    """SysModules plus the calling-context rule and the scenario data of the data and machine modules."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        bind(self._lib)
        self._call_ctx = self._lib.hh_module_call_ctx

    def call_in(self, number: int, params: Sequence[int], in_job: bool) -> tuple[list[int], int, int | None]:
        """As call(), as the cyclic program (in_job False) or a submit job calls it: a submit-only module in the
        cyclic program fails with code 20, a cyclic-only module in a job with 24."""
        entry = self.info(number)
        if not entry.known:
            raise UnknownModule(f"PLC module {number} has no entry in the module table")
        if len(params) != entry.nparams:
            raise ValueError(f"module {number} takes {entry.nparams} parameter(s), got {len(params)}")
        buf = self._params
        for i, value in enumerate(params):
            buf[i] = value
        status = self._call_ctx(self._handle, number, CALLER_JOB if in_job else CALLER_CYCLIC, buf, self._results,
                                ctypes.byref(self._code))
        return list(self._results[:entry.nresults]), status, (self._code.value if status else None)

    def set_axis(self, axis: int, active: bool, position: int = 0) -> None:
        """Axis 0..15: active (9038 info 0) and actual REF position in 0.0001 mm (9049 info 2)."""
        if self._lib.hh_sys_set_axis(self._handle, axis, int(bool(active)), position) != 0:
            raise ValueError(f"axis {axis} is outside 0..15")

    def set_drives(self, available: int, switching_off: int = 0) -> None:
        """Ready power stages (9162 = available AND the mask of 9161) and the early warning of 9159."""
        self._lib.hh_sys_set_drives(self._handle, available, switching_off)

    def set_memory_size(self, size: int) -> None:
        """Bytes of the PLC's B/W/D memory: 9040/9042 refuse a block of double words that does not fit."""
        self._lib.hh_sys_set_memory_size(self._handle, size)

    def set_table(self, file_type: int, line: int, element: int, value: int) -> None:
        """Element of a table selected for program run (0 .T, 1 .D, 2 .TCH): what 9092/9093 read, 9094 writes."""
        if self._lib.hh_sys_set_table(self._handle, file_type, line, element, value) != 0:
            raise ValueError(f"table element {file_type}/{line}/{element} is out of range")
