"""The HH_Sys FUNCTION_BLOCKs in the co-simulation: the translated program's module calls run the same documented
model as the reference interpreter's (the C shim, runtime_shim/hh_modules.c), on a system context of their own.

`SysBinding.attach(machine)` copies the interpreter's system context before cycle 0 (hh_sys_clone: machine
parameters, axes, drives, tables, scripted module results, clock), so both sides start from the same state and
then evolve independently; each side's calls change only its own copy. The built-in executor replaces the FB
bodies by `externals()`; the matiec side links `c_bodies()` (C bodies that call the shim through a function
pointer the harness receives at run time). `tick()` advances the copy's clock at the end of each cycle, where
the interpreter advances its own.
"""

from __future__ import annotations

import ctypes
import re
from typing import Any, Callable

from transpiler.backends.st.hh_sys import FAULT, FAULT_CODE, IN_JOB, fb_names, interface
from transpiler.exec.interp.sysmodel import CALLER_CYCLIC, CALLER_JOB, SysContext

_FB = re.compile(r"^\s*FUNCTION_BLOCK\s+(\w+)", re.M | re.I)
CALL_PROTOTYPE = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_int32, ctypes.c_int32,
                                  ctypes.POINTER(ctypes.c_int32), ctypes.POINTER(ctypes.c_int32),
                                  ctypes.POINTER(ctypes.c_int32))


def modules_in(st_text: str) -> dict[str, int]:
    """FB name (as declared) -> module number of every HH_Sys FUNCTION_BLOCK the ST text declares."""
    known = fb_names()
    return {m.group(1): known[m.group(1).upper()] for m in _FB.finditer(st_text) if m.group(1).upper() in known}


class SysBinding:
    """The translated side's system context; calls before attach() fail loudly (a harness error, not a result)."""

    def __init__(self, st_text: str):
        self.modules = modules_in(st_text)
        self.sys: SysContext | None = None
        self.context_rule = True

    def attach(self, machine: Any) -> None:
        source: SysContext = machine.sys
        lib = source._lib
        lib.hh_sys_clone.restype = ctypes.c_void_p
        lib.hh_sys_clone.argtypes = [ctypes.c_void_p]
        copy = SysContext(machine.cycle_time_ms, lib=lib)
        lib.hh_sys_free(copy._handle)
        copy._handle = lib.hh_sys_clone(source._handle)
        if not copy._handle:
            raise MemoryError("hh_sys_clone failed")
        self.sys = copy
        self.context_rule = machine.semantics["module_context"] != "ignore"

    def call(self, number: int, params: list[int], in_job: bool) -> tuple[list[int], int, int | None]:
        if self.sys is None:
            raise RuntimeError("the HH_Sys model of the translated program has no system context (attach a machine)")
        if self.context_rule:
            return self.sys.call_in(number, params, in_job)
        return self.sys.call(number, params)

    def tick(self) -> None:
        if self.sys is not None:
            self.sys.tick()

    def externals(self) -> dict[str, Callable[[dict], None]]:
        """Bodies for the built-in executor, one per HH_Sys FB of the text."""
        return {name: self._external(number) for name, number in self.modules.items()}

    def _external(self, number: int) -> Callable[[dict], None]:
        itf = interface(number)
        inputs = [n.lower() for n in itf.inputs]
        outputs = [n.lower() for n in itf.outputs]

        def body(state: dict) -> None:
            results, status, code = self.call(number, [int(state[n]) for n in inputs], bool(state[IN_JOB.lower()]))
            for name, value in zip(outputs, results):
                state[name] = value
            state[FAULT.lower()] = bool(status)
            state[FAULT_CODE.lower()] = code if status and code is not None else 0
        return body

    # ---- the matiec side

    def c_bodies(self) -> dict[str, str]:
        """Upper-case FB name -> C statements that replace the start of its matiec body (see patch_pous)."""
        out = {}
        for name, number in self.modules.items():
            itf = interface(number)
            lines = [f"int32_t p[{max(len(itf.inputs), 1)}] = {{0}}, r[8] = {{0}}, code = 0;"]
            for k, n in enumerate(itf.inputs):
                lines.append(f"p[{k}] = (int32_t)__GET_VAR(data__->{n},);")
            lines.append(f"int st = hh_sysfb_call({number}, __GET_VAR(data__->{IN_JOB},) ? {CALLER_JOB} : {CALLER_CYCLIC}, "
                         "p, r, &code);")
            for k, n in enumerate(itf.outputs):
                lines.append(f"__SET_VAR(data__->,{n},,r[{k}]);")
            lines.append(f"__SET_VAR(data__->,{FAULT},,st ? 1 : 0);")
            lines.append(f"__SET_VAR(data__->,{FAULT_CODE},,st ? code : 0);")
            lines.append("goto __end;")
            out[name.upper()] = "{ " + " ".join(lines) + " }"
        return out

    def call_pointer(self) -> tuple[int, int, int]:
        """(address of hh_module_call_ctx or hh_module_call, handle, 1 when the context rule applies)."""
        if self.sys is None:
            raise RuntimeError("the HH_Sys model of the translated program has no system context (attach a machine)")
        lib = self.sys._lib
        fn = lib.hh_module_call_ctx
        return ctypes.cast(fn, ctypes.c_void_p).value or 0, int(self.sys._handle), int(self.context_rule)


HARNESS_C = [
    "typedef int (*hh_sysfb_fn)(void *, int32_t, int32_t, const int32_t *, int32_t *, int32_t *);",
    "static hh_sysfb_fn hh_sysfb_target;",
    "static void *hh_sysfb_handle;",
    "static int hh_sysfb_rule = 1;",
    "void hh_sysfb_bind(void *fn, void *handle, int rule) {",
    "    hh_sysfb_target = (hh_sysfb_fn)fn; hh_sysfb_handle = handle; hh_sysfb_rule = rule;",
    "}",
    "int hh_sysfb_call(int32_t number, int32_t caller, const int32_t *params, int32_t *results, int32_t *code) {",
    "    if (!hh_sysfb_target) { *code = 1; return 1; }",
    "    /* caller 0: the shim applies no calling-context rule (module_context = ignore) */",
    "    return hh_sysfb_target(hh_sysfb_handle, number, hh_sysfb_rule ? caller : 0, params, results, code);",
    "}", ""]


def patch_pous(text: str, bodies: dict[str, str]) -> str:
    """POUS.c with the body of every HH_Sys FB starting with its model call (the ST stub after it is skipped)."""
    if not bodies:
        return text
    decl = ("#include <stdint.h>\nint hh_sysfb_call(int32_t number, int32_t caller, const int32_t *params, "
            "int32_t *results, int32_t *code);\n")

    def replace(m: re.Match) -> str:
        body = bodies.get(m.group(1).upper())
        return m.group(0) + "\n  " + body + "\n" if body else m.group(0)
    return decl + re.sub(r"void\s+(\w+)_body__\(\s*\w+\s*\*\s*data__\s*\)\s*\{", replace, text)
