"""report.md: what the target must provide — every HH_Sys FUNCTION_BLOCK the translation calls (docs/modules.md)."""

from __future__ import annotations

from transpiler.backends.st.backend import StResult
from transpiler.backends.st.hh_sys import fb_names, interface
from transpiler.ir import Program
from transpiler.language.module_table import MODULE_TABLE


def _unit(unit: str) -> str:
    return f" [{unit}]" if unit else ""


def target_must_provide(program: Program, result: StResult) -> list[str]:
    """One block per module: FB name and interface, call sites (file:line), units, error codes, assumptions."""
    known = fb_names()
    used = sorted(known[p.name.upper()] for p in result.project.pous if p.name.upper() in known)
    if not used:
        return ["The program calls no PLC module that the target must provide."]
    sites: dict[int, list[str]] = {}
    for f in program.files:
        for op in f.ops:
            if op.call is not None and op.call.is_module:
                sites.setdefault(op.call.module, []).append(f"{op.span.file}:{op.span.line}")
    lines = ["Each module below is a FUNCTION_BLOCK of the HH_Sys interface library, declared in project.st. Its "
             "body is a stub that applies the calling-context rule and otherwise reports FAULT with FAULT_CODE 1: "
             "implement it on the target. The co-simulation ran the documented model of docs/modules.md instead.", ""]
    for number in used:
        row = MODULE_TABLE[number]
        itf = interface(number)
        ins = ", ".join(f"{n} : DINT{_unit(v.unit)}" for n, v in zip(itf.inputs, row.params))
        outs = ", ".join(f"{n} : DINT{_unit(v.unit)}" for n, v in zip(itf.outputs, row.results))
        lines.append(f"### {itf.name} (module {number}, {row.kind})")
        lines.append("")
        lines.append(f"- Purpose: {row.purpose}")
        lines.append(f"- Inputs: {ins + ', ' if ins else ''}IN_JOB : BOOL")
        lines.append(f"- Outputs: {outs + ', ' if outs else ''}FAULT : BOOL, FAULT_CODE : DINT")
        lines.append(f"- Called at: {', '.join(sites.get(number, [])) or '(none)'}")
        lines.append(f"- Context: {row.context}" + (", strobe-bound while an NC program runs" if row.strobe else ""))
        errors = "; ".join(f"{c} {t}" for c, t in sorted(row.errors.items()))
        lines.append(f"- Error codes: {errors or 'none documented'}")
        lines.append(f"- Assumptions of the model: {'; '.join(row.assumptions) or 'none (documented call format)'}")
        lines.append("")
    return lines
