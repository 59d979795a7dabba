"""PLC module calls (CM <number>) in the ST: the pushes before the call become named inputs, the pulls after it
read the named outputs, and the module error marker and error-code word follow the call (see docs/modules.md).

A *data* or *machine* module is a call of its `HH_Sys` FUNCTION_BLOCK (hh_sys.py), one instance per call site.
Its parameters are the entries the symbolic data stack holds (the pushes of the caller, usually static), so
`PS K9032 ... CM 9032 PL W102` reads `inst(NUMBER := ..., INDEX := ..., IN_JOB := ...); W102 := inst.VALUE`.
Where the caller's stack is dynamic the parameters come from the emulated stack and the results go back to it.
A *pure* module (9050, 9052-9054, 9070) is a call of its block in the generated library (pure_lib.py): the
caller reads the string contents (and whether the string numbers are valid) into the block and stores its TEXT
into the destination string when the call did not fail; 9053/9054 get the byte memory as VAR_IN_OUT, which
exists only where the program keeps all of its memory in the byte array. A conditional call (CMT/CMF) is the
same call inside an IF on the logic accumulator. 9019 (stack depth) reads the emulated stack's pointer: a program
that calls it keeps all of its data stack there. 9006 stays E-UNSUPPORTED at its line.
"""

from __future__ import annotations

from transpiler.ir import Op, Operand
from transpiler.backends.st import exprs as E
from transpiler.backends.st import stmt as S
from transpiler.backends.iec_model import Pou
from transpiler.backends.st import hh_sys, pure_lib
from transpiler.backends.st.hh_sys import FAULT, FAULT_CODE, IN_JOB, interface
from transpiler.backends.st.liveness import REGS
from transpiler.backends.st.routine import Unsupported, tag
from transpiler.language.module_table import MODULE_TABLE, PURE

IN_JOB_VAR = "HH_IN_JOB"


def stack_effect(number: int) -> tuple[tuple[str, ...], tuple[str, ...], int] | None:
    """The static stack effect of a module call (parameter kinds, result kinds, words it leaves): 32-bit
    parameters pulled, 32-bit results pushed; None for a number without a row."""
    row = MODULE_TABLE.get(number)
    if row is None:
        return None
    return ("val",) * row.nparams, ("val",) * row.nresults, 2 * row.nresults


STACK_DEPTH = 9019


def translatable(number: int) -> str | None:
    """None when module `number` translates, else why not."""
    row = MODULE_TABLE.get(number)
    if row is None:
        return f"PLC module {number} has no row in the module table"
    if number == STACK_DEPTH:
        return None
    if row.kind == PURE and number not in pure_lib.PURE_TRANSLATED:
        return f"PLC module {number} ({row.st_name}, a pure module) is not translated yet"
    if row.number == 9006:
        return "PLC module 9006 (additional timers T96-T999) is not translated yet"
    return None


def library_pous(used: set[int], string_len: int) -> list[Pou]:
    """The library blocks of the modules `used`: the generated pure ones, then the HH_Sys interface blocks."""
    return pure_lib.pure_pous(used, string_len) + [hh_sys.fb_pou(n) for n in sorted(used)
                                                   if MODULE_TABLE[n].kind != PURE]


def emit_module_call(ex, op: Op, live: frozenset[str], in_job: str, used: set[int], decimal_point: str = ".") -> None:
    """Translate `op` (an unconditional CM of a module) with the symbolic executor `ex`; `in_job` is the global
    that is TRUE while a submit job runs; the module number goes into `used` (the library needs its FB);
    `decimal_point` is the character 9050 writes (MP7280)."""
    number = op.call.module
    why = translatable(number)
    if why is not None:
        raise Unsupported(why, op.span)
    if op.code != "CALL":
        _emit_conditional(ex, op, live, in_job, used, decimal_point)
        return
    _emit_call(ex, op, live, in_job, used, decimal_point)


def _emit_conditional(ex, op: Op, live: frozenset[str], in_job: str, used: set[int], decimal_point: str) -> None:
    """CMT/CMF of a module: the call, with its pulls and pushes, only when LA is 1 (0); otherwise the stack keeps
    the parameters and nothing changes. The stack lives in its variables across the IF (a static stack never
    reaches here with parameters or results: the stack analysis makes such a routine keep the emulated stack)."""
    row = MODULE_TABLE[op.call.module]
    if ex.static is not None and (row.nparams or row.nresults):
        raise Unsupported(f"internal: conditional call of PLC module {row.number} on a static data stack", op.span)
    ex.flush(live | frozenset(["LA"]))
    cond = ex.la_is(op.code == "CALLT")
    out = ex.ctx.out
    with out.nested() as then:
        _emit_call(ex, op, live, in_job, used, decimal_point)
        ex.flush(live)
    out.add(S.If(cond, tuple(then), note=f"{op.mnemonic} {tag(op.span)}"))
    ex.forget()


def _emit_call(ex, op: Op, live: frozenset[str], in_job: str, used: set[int], decimal_point: str) -> None:
    number = op.call.module
    if number == STACK_DEPTH:
        _emit_stack_depth(ex, op, live)
        return
    row = MODULE_TABLE[number]
    if row.kind == PURE:
        _emit_pure(ex, op, live, used, decimal_point)
        return
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
    inst = ctx.instance(itf.name)
    used.add(number)
    named = tuple(zip(itf.inputs, args)) + ((IN_JOB, E.var(in_job, "BOOL")),)
    ctx.out.add(S.Call(inst, named, f"CM {number} {row.st_name}  {tag(op.span)}"))
    _error_marker(ex, inst)
    ex.forget()
    for name in reversed(itf.outputs):
        ex.s.stack.append(("val", E.var(f"{inst}.{name}", "DINT")))


def _emit_stack_depth(ex, op: Op, live: frozenset[str]) -> None:
    """9019: the bytes on the data stack (2 per 16-bit word). A program that calls it keeps its whole stack in the
    emulated stack (the back end turns the stack interfaces off), so after the flush the stack pointer is exact."""
    if ex.static is not None:
        raise Unsupported("internal: PLC module 9019 on a static data stack", op.span)
    _prepare(ex, live, 0)
    _, sp = ex.ctx.stack_names()
    ex.ctx.out.comment(f"CM 9019 (data stack depth in bytes)  {tag(op.span)}")
    depth = ex._temp_copy(E.Expr(f"INT_TO_DINT({sp}) * 2", "DINT", frozenset([E.base_name(sp)]), 0, 65534))
    marker = Operand("M", ex.ctx.semantics.profile.interface.module_err)
    ex.bit_store(marker, lambda: E.bool_const(False), frozenset())     # 9019 never fails
    ex.forget()
    ex.s.stack.append(("val", depth))


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
        ex.prepare_write(E.base_name(lhs))
    ex.ctx.out.add(S.If(fault, tuple(S.Assign(lhs, value) for lhs, value in assignments)))


def _prepare(ex, live: frozenset[str], nparams: int) -> list[E.Expr]:
    """Registers the call may clobber saved, the parameters popped (push order), the rest of the stack flushed."""
    for reg in REGS:
        if reg in live:
            ex.materialize(reg)
        else:
            ex.s.regs[reg] = None
    args = [E.to_dint(ex._pop("val")) for _ in range(nparams)][::-1]
    ex.flush_stack()
    return args


class _StringRef:
    """A string number given to a pure module: whether it is valid (a BOOL expression) and its variable (or None)."""

    def __init__(self, ex, arg: E.Expr, span):
        layout = ex.ctx.layout
        count = layout.profile.ranges.size("S")
        self.var: E.Expr | None = None
        if arg.const is not None:
            self.ok = E.bool_const(0 <= arg.const < count)
            if self.ok.bool_const:
                if layout.string_array is None:
                    layout.declare_string(arg.const)     # also a string only module calls touch
                self.var = layout.string_lvalue(Operand("S", arg.const), None)
            return
        if layout.string_array is None:
            raise Unsupported("a PLC module's string number computed at run time in a program without indexed "
                              "string access", span)
        index = ex.ctx.temp("DINT")
        ex.ctx.out.add(S.Assign(index, arg))
        i = E.var(index, "DINT")
        self.ok = E.Expr(f"({E.binop('>=', i, E.int_const(0), 'BOOL', E.PREC_CMP).text} AND "
                         f"{E.binop('<', i, E.int_const(count), 'BOOL', E.PREC_CMP).text})", "BOOL", i.deps, 0, 1)
        element = f"{layout.ref(layout.string_array)}[{index}]"
        self.var = E.Expr(element, "STRING", frozenset([layout.string_array.upper()]) | i.deps, var=element)

    def read(self, ex) -> E.Expr:
        """The contents, through a STRING temporary where the number may be invalid ('' for an invalid number:
        the module fails before reading)."""
        if self.var is None:
            return E.Expr("''", "STRING")
        if self.ok.bool_const:
            return self.var
        tmp = ex.ctx.temp("STRING")
        ex.ctx.out.add(S.Assign(tmp, E.Expr("''", "STRING")))
        ex.ctx.out.add(S.If(self.ok, (S.Assign(tmp, self.var),), inline=True))
        return E.var(tmp, "STRING")

    def write(self, ex, inst: str, value: str) -> None:
        if self.var is None:
            return
        ex.prepare_write(E.base_name(self.var.text))
        failed = E.var(f"{inst}.{FAULT}", "BOOL")
        ex.ctx.out.add(S.If(E.b_not(failed), (S.Assign(self.var.text, E.var(f"{inst}.{value}", "STRING")),)))


def _emit_pure(ex, op: Op, live: frozenset[str], used: set[int], point: str) -> None:
    """A pure module: its library block with the string contents in, the destination string written back."""
    # Kept whole (~60 lines): one branch per module, each a handful of lines that share the call's temporaries.
    number = op.call.module
    row = MODULE_TABLE[number]
    ctx = ex.ctx
    layout = ctx.layout
    span = op.span
    if number in pure_lib.NEEDS_MEMORY and (layout.mem_array is None or layout._mem_var):
        raise Unsupported(f"PLC module {number} reads or writes the byte memory, which this program does not keep "
                          "in one byte array (only programs with indexed memory access do)", span)
    args = _prepare(ex, live, row.nparams)
    inst = ctx.instance(pure_lib.fb_name(number))
    used.add(number)
    mem_size = layout.profile.ranges.size("B")
    note = f"CM {number} {row.st_name}  {tag(span)}"

    def memory() -> tuple[tuple[str, E.Expr], ...]:
        return ("MEM_SIZE", E.int_const(mem_size)), ("MEM", E.var(layout.ref(layout.mem_array), "ARRAY"))

    outputs: tuple[str, ...] = ()
    if number == 9050:
        ref = _StringRef(ex, args[2], span)
        point_text = E.Expr(f"'{point}'", "STRING")
        ctx.out.add(S.Call(inst, (("MANTISSA", args[0]), ("EXPONENT", args[1]), ("STRING_OK", ref.ok),
                                  ("POINT", point_text)), note))
        ref.write(ex, inst, "TEXT")
    elif number == 9052:
        ref = _StringRef(ex, args[0], span)
        ctx.out.add(S.Call(inst, (("TEXT", ref.read(ex)), ("STRING_OK", ref.ok)), note))
        outputs = ("VALUE", "EXPONENT")
    elif number == 9070:
        src, dst = _StringRef(ex, args[0], span), _StringRef(ex, args[1], span)
        if dst.ok.bool_const:
            ok = src.ok
        elif src.ok.bool_const:
            ok = dst.ok
        else:
            # Not b_and: a number known to be invalid still shows in the text, as the module receives it.
            ok = E.Expr(f"{src.ok.text} AND {dst.ok.text}", "BOOL", src.ok.deps | dst.ok.deps, 0, 1, E.PREC_AND)
        ctx.out.add(S.Call(inst, (("TEXT", src.read(ex)), ("STRINGS_OK", ok)), note))
        dst.write(ex, inst, "NUMBER_TEXT")
        outputs = ("OFFSET",)
    elif number == 9053:
        ref = _StringRef(ex, args[1], span)
        ctx.out.add(S.Call(inst, (("ADDRESS", args[0]), ("COUNT", args[2]), ("STRING_OK", ref.ok)) + memory(), note))
        ref.write(ex, inst, "TEXT")
    else:   # 9054
        ref = _StringRef(ex, args[0], span)
        text = ref.read(ex)
        ex.prepare_write(layout.mem_array.upper())
        ctx.out.add(S.Call(inst, (("TEXT", text), ("STRING_OK", ref.ok), ("ADDRESS", args[1])) + memory(), note))
    _error_marker(ex, inst)
    ex.forget()
    for name in reversed(outputs):
        ex.s.stack.append(("val", E.var(f"{inst}.{name}", "DINT")))
