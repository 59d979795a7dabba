"""The `HH_Sys` interface library: one FUNCTION_BLOCK per PLC module the program calls (see docs/modules.md).

Every module of kind *data* or *machine* becomes a call of a FUNCTION_BLOCK named after its row of the module
table (transpiler/language/module_table.py): the parameters in push order as DINT inputs, then `IN_JOB` (TRUE
while a submit job runs, for the calling-context rule); the results in pull order as DINT outputs, then `FAULT`
(what the TNC puts in its module error marker) and `FAULT_CODE` (its error-code word). The body written here only
applies the calling-context rule and otherwise reports "not provided" (code 1): the integrator replaces it on the
target. The co-simulation replaces it by the documented model that the reference interpreter runs.
"""

from __future__ import annotations

import dataclasses

from transpiler.backends.iec_model import IecVar, Pou, VarSection
from transpiler.backends.st.names import RESERVED
from transpiler.language.module_table import ANY, CYCLIC, MODULE_TABLE, PURE, SUBMIT, Module

FAULT, FAULT_CODE, IN_JOB = "FAULT", "FAULT_CODE", "IN_JOB"
NOT_PROVIDED = 1            # FAULT_CODE of the stub body: the target has not implemented the module


@dataclasses.dataclass(frozen=True)
class FbInterface:
    """The ST interface of one module's FUNCTION_BLOCK: input and output names in table order."""

    number: int
    name: str
    inputs: tuple[str, ...]          # parameters in push order (IN_JOB not included)
    outputs: tuple[str, ...]         # results in pull order (FAULT / FAULT_CODE not included)


def _ident(wanted: str, taken: set[str]) -> str:
    # Table names such as 'time', 'string' or 'type' are IEC keywords: those get a suffix, as does a repeat.
    name = wanted.upper()
    if name in RESERVED or name in taken:
        name += "_VALUE"
    n = 2
    base = name
    while name in taken:
        name = f"{base}{n}"
        n += 1
    taken.add(name)
    return name


def interface(number: int) -> FbInterface:
    """The FUNCTION_BLOCK interface of a data or machine module (KeyError for a number without a row)."""
    row = MODULE_TABLE[number]
    taken = {FAULT, FAULT_CODE, IN_JOB}
    inputs = tuple(_ident(v.name, taken) for v in row.params)
    outputs = tuple(_ident(v.name, taken) for v in row.results)
    return FbInterface(number, row.st_name, inputs, outputs)


def fb_names() -> dict[str, int]:
    """Upper-case FUNCTION_BLOCK name -> module number, for every module that has an FB (not the pure ones)."""
    return {m.st_name.upper(): m.number for m in MODULE_TABLE.values() if m.kind != PURE}


def _unit(unit: str) -> str:
    return f" [{unit}]" if unit else ""


def doc_comment(row: Module) -> str:
    """What the integrator needs: purpose, parameters and results with units, errors, context, assumptions."""
    lines = [f"PLC module {row.number} ({row.kind}): {row.purpose}."]
    if row.params:
        lines.append("Parameters (push order): " + ", ".join(f"{v.name}{_unit(v.unit)}" for v in row.params) + ".")
    if row.results:
        lines.append("Results (pull order): " + ", ".join(f"{v.name}{_unit(v.unit)}" for v in row.results) + ".")
    context = {ANY: "anywhere", CYCLIC: f"the cyclic program only (code {row.context_error(True)} in a job)",
               SUBMIT: f"submit/spawn jobs only (code {row.context_error(False)} in the cyclic program)"}[row.context]
    lines.append(f"Called from {context}" + ("; needs a pending strobe while an NC program runs." if row.strobe else "."))
    if row.errors:
        lines.append("Error codes (FAULT_CODE): " + "; ".join(f"{c} {t}" for c, t in sorted(row.errors.items())) + ".")
    for a in row.assumptions:
        lines.append(f"Assumption {a}.")
    lines.append("See docs/modules.md.")
    return "\n".join(lines)


def fb_pou(number: int) -> Pou:
    """The FUNCTION_BLOCK of module `number`, with the stub body the integrator replaces."""
    row = MODULE_TABLE[number]
    itf = interface(number)
    inputs = tuple(IecVar(n, "DINT", comment=f"{v.name}{_unit(v.unit)}") for n, v in zip(itf.inputs, row.params))
    inputs += (IecVar(IN_JOB, "BOOL", comment="TRUE when called from a submit job (calling-context rule)"),)
    outputs = tuple(IecVar(n, "DINT", comment=f"{v.name}{_unit(v.unit)}") for n, v in zip(itf.outputs, row.results))
    outputs += (IecVar(FAULT, "BOOL", comment="the module error marker after the call"),
                IecVar(FAULT_CODE, "DINT", comment="the error code when FAULT (else unchanged in the error word)"))
    body = [f"{FAULT} := FALSE;", f"{FAULT_CODE} := 0;"]
    if row.context in (SUBMIT, CYCLIC):
        wrong = not (row.context == SUBMIT)         # IN_JOB in the wrong context
        result = row.context_error_result(wrong)
        set_result = [] if result is None else [f"    {itf.outputs[row.error_result]} := {result};"]
        body += [f"IF {'' if wrong else 'NOT '}{IN_JOB} THEN", f"    {FAULT} := TRUE;",
                 f"    {FAULT_CODE} := {row.context_error(wrong)};", *set_result, "    RETURN;", "END_IF;"]
    body += ["(* TO BE PROVIDED BY THE TARGET: this body only reports that the module is missing. *)",
             f"{FAULT} := TRUE;", f"{FAULT_CODE} := {NOT_PROVIDED};"]
    return Pou(itf.name, "FUNCTION_BLOCK", (VarSection("VAR_INPUT", inputs), VarSection("VAR_OUTPUT", outputs)),
               "\n".join(body), comment=doc_comment(row))

