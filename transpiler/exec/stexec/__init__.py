"""Built-in Structured Text executor: parses ST text, checks it like strict matiec, compiles it to Python and runs it.

It is the `builtin` backend of `hh2iec equiv`: an independent check of the ST that hh2iec writes, because it reads
the emitted *text* (its own LALR grammar), not the transpiler's IR.

Public API
----------
    project = load_st(text, filename="project.st", *, loop_limit=1_000_000)
        Parse, check and compile. Raises StError (a transpiler.diagnostics.CompileFailed) whose .diagnostics
        lists every error as Diagnostic(code "E-ST-PARSE", span file:line:col). Never a traceback for bad input.
    rt = project.instantiate(externals=None)
        A fresh runtime of the file's single CONFIGURATION (StError if there is none).
    schema = load_st(text, mutations=[TextMutation(number, changes), ...], impure=names)
        A mutant schema (schema.py): the file compiled once with each mutation behind a switch;
        schema.unswitched are the mutations it could not switch. schema.instantiate(externals, mutant=k) runs
        mutant k (0: the original; PROBE: the original, recording in rt.infected the mutations it infects).
    rt.run_cycle()
        One cycle: CURRENT_TIME (what TON/TOF/TP read) is cycle_index * cycle_time_ms, every program instance whose
        task interval divides into the elapsed time runs (in the order of the PROGRAM lines of the resource,
        like matiec), then the clock advances by one base tick. Cycle 0 runs at time 0 and runs every task.
        A fault raises StRuntimeError (message, .span of the ST statement); the cycle counter does not advance.
    rt.cycle_time_ms        base tick: GCD of all task intervals (int ms)
    rt.get(path) / rt.set(path, value)
        Paths (case-insensitive): 'G_NAME' (global), 'inst0.VAR' (program variable, also its VAR_EXTERNALs),
        'inst0.fb1.Q' (FB instance members), 'G_ARR[3]', 'G_MAT[1,2]', 'G_S.field', '%QX0.1' (located).
        Unknown paths raise KeyError; set() raises ValueError for a CONSTANT, an aggregate or a value that does not
        fit (BOOL needs bool or 0/1; integers are wrapped to the declared width, two's complement; a subrange
        rejects values outside it; STRING at most 126 characters).
    rt.names()              every addressable leaf path (arrays, structs and FB instances expanded) plus addresses.

Values: int for integer and bit-string types (signed types signed; BYTE/WORD/DWORD/LWORD unsigned), bool for BOOL,
float for REAL/LREAL (REAL rounded to single precision), int milliseconds for TIME, str for STRING, the value's
name (str) for an enum; get() of an array gives a list, of a struct or FB instance a dict.

Externals (replace the body of a FUNCTION, FUNCTION_BLOCK or PROGRAM that the ST file declares; keys are the
POU names, case-insensitive):
  * FUNCTION: called with keyword arguments, one per VAR_INPUT and VAR_IN_OUT, named in lower case, values as
    above (arrays as the live list, structs as the live object). Returns the result, or a tuple
    (result, {name: value}) giving VAR_OUTPUTs and new VAR_IN_OUT values (missing outputs get their type's
    default, missing in-outs stay unchanged). Values are wrapped/validated to the declared types.
  * FUNCTION_BLOCK / PROGRAM: called once per invocation with `state`, a dict of the instance's VAR_INPUT,
    VAR_OUTPUT, VAR_IN_OUT and VAR variables (lower-case names, runtime representation: enums as their index).
    Mutate the dict; every key is written back to the instance (scalars wrapped/validated). Inputs passed in
    the call are already stored; outputs are read by the caller afterwards.
  An exception inside an external becomes StRuntimeError.

Semantics (IEC 61131-3; where matiec differs, see targets.md section 1.3):
  * Every integer result is wrapped to its type's width (two's complement), also intermediate results of
    SINT/INT (matiec's C evaluates those in int and wraps only on store). `/` and MOD truncate toward zero;
    an integer `/` or MOD by zero raises StRuntimeError ("division by zero" / "MOD by zero"), while the
    functions DIV(a, 0) and MOD(a, 0) return 0 as matiec's do.
  * REAL_TO_<int> rounds half to even; TIME_TO_<int> and <int>_TO_TIME count seconds (matiec); REAL to TIME
    rounds to whole milliseconds. FOR follows the standard (the body runs for start..end inclusive), not
    matiec's skip-when-shorter-than-one-step bug. FIND and REPLACE follow IEC, not matiec's quirks.
  * Array indexes are checked at run time (StRuntimeError). Every loop has a watchdog of loop_limit
    iterations per execution of the loop.
  * Each located address is one storage cell shared by all declarations at that address; different addresses
    never overlap (%MW0 and %MB0 are independent). A PROGRAM may also use an undeclared address directly
    (%QX0.1 := TRUE); its type then follows the size prefix (X BOOL, B BYTE, W WORD, D DWORD, L LWORD).
  * Arithmetic on untyped literals takes the type of its context (x + 40000 * 2 is INT arithmetic when x is an
    INT); a comparison between two literal-only expressions is computed without wrapping.
  * A scalar VAR_IN_OUT is passed copy-in/copy-out (arrays and structs by reference): this differs from a
    reference only if the same variable is also reached another way inside the call (aliasing).

Type checking is as strict as matiec where that is cheap: no implicit conversions between different types in
assignments, operators or parameters (untyped literals adapt and must fit), no arithmetic on bit strings,
no logic on integers, names declared before use, VAR_EXTERNAL must match its global (type, CONSTANT), CASE labels
plain decimal or enum values (overlapping labels are legal, as in matiec: the first matching branch wins),
no IEC keywords as names, no function calls as statements, no STRING[n]. tests/data/matiec_verdicts records
strict matiec's verdict on a corpus of small files; this checker must agree with every one.
"""

from __future__ import annotations

from typing import Callable, Iterable, Optional, Sequence

from transpiler.diagnostics import Span
from transpiler.exec.stexec.compiler import compile_st
from transpiler.exec.stexec.errors import StError, StRuntimeError, st_diag
from transpiler.exec.stexec.model import CompiledProject
from transpiler.exec.stexec.runtime import Runtime
from transpiler.exec.stexec.schema import PROBE, TextMutation

__all__ = ["load_st", "StError", "StRuntimeError", "StProject", "Runtime", "TextMutation", "PROBE"]


class StProject:
    """A parsed, checked and compiled ST file; instantiate() gives independent runtimes."""

    def __init__(self, compiled: CompiledProject):
        self.compiled = compiled

    @property
    def python_source(self) -> str:
        """The generated Python module (for debugging the executor)."""
        return self.compiled.source

    @property
    def unswitched(self) -> frozenset:
        """The mutations of a mutant schema that are not in it (their text must be compiled on its own)."""
        return self.compiled.unswitched

    def instantiate(self, externals: Optional[dict[str, Callable]] = None, mutant: int = 0) -> Runtime:
        return Runtime(self.compiled, externals, mutant)


def load_st(text: str, filename: str = "project.st", *, loop_limit: int = 1_000_000,
            mutations: Sequence[TextMutation] = (), impure: Iterable[str] = ()) -> StProject:
    """Parse, type-check and compile an ST file; raises StError with E-ST-PARSE diagnostics. With `mutations`,
    a mutant schema of them; `impure` names the POUs whose calls probing must not repeat (externals with state)."""
    try:
        compiled = compile_st(text, filename, loop_limit, tuple(mutations), tuple(impure))
    except RecursionError:
        raise StError([st_diag(Span(filename, 1, 1), "expression nesting too deep for the built-in executor")]) from None
    return StProject(compiled)
