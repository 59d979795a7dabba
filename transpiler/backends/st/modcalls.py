"""PLC module calls (CM <number>) in the ST: the pushes before the call become named inputs, the pulls after it
read the named outputs, and the module error marker and error-code word follow the call (see docs/modules.md).

A *data* or *machine* module is a call of its `HH_Sys` FUNCTION_BLOCK (hh_sys.py), one instance per call site.
Its parameters are the entries the symbolic data stack holds (the pushes of the caller, usually static), so
`PS K9032 ... CM 9032 PL W102` reads `inst(NUMBER := ..., INDEX := ..., IN_JOB := ...); W102 := inst.VALUE`.
Where the caller's stack is dynamic the parameters come from the emulated stack and the results go back to it.
Pure modules are not translated yet: they are E-UNSUPPORTED at their line.
"""

from __future__ import annotations

from transpiler.ir import Op, Operand
from transpiler.backends.st import exprs as E
from transpiler.backends.st.hh_sys import FAULT, FAULT_CODE, IN_JOB, interface
from transpiler.backends.st.liveness import REGS
from transpiler.backends.st.routine import Unsupported
from transpiler.language.module_table import MODULE_TABLE, PURE

IN_JOB_VAR = "HH_IN_JOB"


def stack_effect(number: int) -> tuple[tuple[str, ...], tuple[str, ...], int] | None:
    """The static stack effect of a module call (parameter kinds, result kinds, words it leaves): 32-bit
    parameters pulled, 32-bit results pushed; None for a number without a row."""
    row = MODULE_TABLE.get(number)
    if row is None:
        return None
    return ("val",) * row.nparams, ("val",) * row.nresults, 2 * row.nresults


def translatable(number: int) -> str | None:
    """None when module `number` translates, else why not."""
    row = MODULE_TABLE.get(number)
    if row is None:
        return f"PLC module {number} has no row in the module table"
    if row.kind == PURE:
        return f"PLC module {number} ({row.st_name}, a pure module) is not translated yet"
    if row.number == 9006:
        return "PLC module 9006 (additional timers T96-T999) is not translated yet"
    return None


def emit_module_call(ex, op: Op, live: frozenset[str], in_job: str, used: set[int]) -> None:
    """Translate `op` (an unconditional CM of a module) with the symbolic executor `ex`; `in_job` is the global
    that is TRUE while a submit job runs; the module number goes into `used` (the library needs its FB)."""
    number = op.call.module
    why = translatable(number)
    if why is not None:
        raise Unsupported(why, op.span)
    if op.code != "CALL":
        raise Unsupported(f"conditional call of PLC module {number} ({op.mnemonic})", op.span)
    row = MODULE_TABLE[number]
    itf = interface(number)
    ctx = ex.ctx
    for reg in REGS:
        if reg in live:
            ex.materialize(reg)
        else:
            ex.s.regs[reg] = None
    args = [ex._pop("val") for _ in row.params][::-1]
    # Entries below the arguments may read the error marker or word the call writes: they go to their variables.
    ex.flush_stack()
    inst = ctx.temp(itf.name)
    used.add(number)
    named = [f"{name} := {arg.text}" for name, arg in zip(itf.inputs, args)] + [f"{IN_JOB} := {in_job}"]
    span = op.span
    ctx.out.line(f"{inst}({', '.join(named)}); (* CM {number} {row.st_name}  {span.file}:{span.line} *)")
    _error_marker(ex, inst)
    ex.forget()
    for name in reversed(itf.outputs):
        ex.s.stack.append(("val", E.var(f"{inst}.{name}", "DINT")))


def _error_marker(ex, inst: str) -> None:
    """The module error marker gets FAULT; the error-code word gets FAULT_CODE only when the call failed."""
    layout = ex.ctx.layout
    itf = ex.ctx.semantics.profile.interface
    fault = E.var(f"{inst}.{FAULT}", "BOOL")
    marker = Operand("M", itf.module_err)
    if ("M", itf.module_err) in layout._bit_var or "M" in layout.bit_arrays:
        ex.bit_store(marker, lambda: fault, frozenset())
    word = itf.module_err_code_word
    if word is None or not (("W", word) in layout._mem_var or layout.mem_array is not None):
        return
    assignments = layout.write_value(Operand("W", word), None, E.var(f"{inst}.{FAULT_CODE}", "DINT"))
    for lhs, _ in assignments:
        ex.prepare_write(E.base_name(lhs).upper())
    ex.ctx.out.line(f"IF {inst}.{FAULT} THEN")
    for lhs, value in assignments:
        ex.ctx.out.line(f"    {lhs} := {value.text};")
    ex.ctx.out.line("END_IF;")
