"""`hh2iec transpile`: runs the ST backend and writes project.st, project.xml, report.md and io_map.csv atomically."""

from __future__ import annotations

import dataclasses
from decimal import Decimal
from pathlib import Path
from typing import Mapping

from transpiler.diagnostics import Diagnostics, NO_SPAN
from transpiler.backends.iec_model import Pou
from transpiler.backends.report.iomap import IoMap, MapRow
from transpiler.ir import Program
from transpiler.frontend.parse import MpParser
from transpiler.frontend.sources import ProjectFolders, read_source
from transpiler.backends.st.backend import StBackend, StResult
from transpiler.backends.st.liveness import use_def


@dataclasses.dataclass(frozen=True)
class Transpiled:
    result: StResult
    st_text: str
    files: dict[str, bytes]           # output file name -> content


def find_mp_file(main: Path) -> Path | None:
    """The one machine-parameter file beside the main program, if there is exactly one."""
    try:
        found = sorted(p for p in main.parent.iterdir() if p.suffix.lower() == ".mp" and p.is_file())
    except OSError:
        return None
    return found[0] if len(found) == 1 else None


def read_mp_file(path: Path, diags: Diagnostics) -> dict[tuple[int, int], Decimal]:
    text = read_source(path, ProjectFolders(path.parent, []), NO_SPAN, diags)
    if text is None:
        return {}
    return {(p.number, p.index): p.value for p in MpParser().parse_lines(text.display, text.lines, diags)}


def transpile_program(program: Program, diags: Diagnostics, mp: Mapping[tuple[int, int], Decimal],
                      formats: set[str]) -> Transpiled:
    from transpiler.backends.plcopen.writer import render_xml
    from transpiler.backends.st.writer import render_st
    result = StBackend(program, diags, mp).build()
    project = result.project
    files: dict[str, bytes] = {}
    st_text = render_st(project)
    if "st" in formats:
        files["project.st"] = st_text.encode("utf-8")
    if "xml" in formats:
        files["project.xml"] = render_xml(project)
    files["report.md"] = render_report(program, result, diags).encode("utf-8")
    files["io_map.csv"] = render_io_map(result).encode("utf-8")
    return Transpiled(result, st_text, files)


def io_map_of(result: StResult) -> IoMap:
    """Operand rows in a stable order, then one row per timer/counter preset variable."""
    def order(r):
        digits = r.operand[1:]
        return (r.operand[0], int(digits) if digits.isdigit() else 0)
    rows = [MapRow(r.symbol, r.operand, r.iec, r.iec_type, r.direction, r.comment)
            for r in sorted(result.layout.rows, key=order)]
    layout = result.layout
    order_tag = "LE" if layout.little else "BE"
    if layout.mem_array:
        rows.append(MapRow("", "B*", layout.mem_array, f"BYTE@{order_tag}", "internal", "all byte memory (B/W/D)"))
    for kind, arr in sorted(layout.bit_arrays.items()):
        rows.append(MapRow("", f"{kind}*", arr, "BOOL", "internal", f"all {kind} operands"))
    if layout.string_array:
        rows.append(MapRow("", "S*", layout.string_array, "STRING", "internal", "all strings"))
    for (number, index), name in sorted(result.preset_vars.items()):
        rows.append(MapRow("", f"MP{number}.{index}", name, "DINT", "parameter", "preset in PLC cycles"))
    return IoMap(rows)


def render_io_map(result: StResult) -> str:
    return io_map_of(result).to_csv()


def user_pous(result: StResult) -> list[Pou]:
    """The POUs translated from the program's routines (not the library, service or accessor POUs), in project order."""
    names = set(result.pou_of_routine.values())
    return [p for p in result.project.pous if p.name in names]


def _target_limits(program: Program) -> list[str]:
    """What the vendor-neutral ST cannot hold the way the control does, as far as this program needs it."""
    string_lines = [f"{f.path}:{op.span.line}" for f in program.files for op in f.ops
                    if "SA" in frozenset().union(*use_def(op))]
    if not string_lines:
        return []
    where = ", ".join(string_lines[:5]) + (f" and {len(string_lines) - 5} more" if len(string_lines) > 5 else "")
    return [f"- Strings ({where}): the control's strings hold 128 characters. The ST declares plain `STRING`, the only "
            "string declaration matiec accepts; it holds 126 characters in matiec/OpenPLC/Beremiz and 80 by default in "
            "CODESYS and TwinCAT. Longer values are cut there: on CODESYS/TwinCAT declare the string variables "
            "`STRING(128)` or raise the default string length; on matiec keep results within 126 characters."]


def render_report(program: Program, result: StResult, diags: Diagnostics) -> str:
    user = user_pous(result)
    fallback_names = {f.pou for f in result.fallbacks}
    structured = len([p for p in user if p.name not in fallback_names])
    lines = [f"# Migration report: {program.main.path}", "",
             f"Profile `{program.semantics.profile.name}`, cycle time {program.semantics['cycle_time_ms']} ms. "
             f"Generated by hh2iec.", "", "## Modules", "",
             "| file | lines | labels |", "|---|---|---|"]
    for f in program.files:
        lines.append(f"| {f.path} | {f.line_count} | {len(f.labels)} |")
    lines += ["", "## POUs", "",
              f"{len(user)} POUs translated from the program: {structured} structured, "
              f"{len(result.fallbacks)} with a state-machine fallback.", "",
              "| POU | kind | source |", "|---|---|---|"]
    for p in user:
        src = ", ".join(r.tag() for r in p.source_map)
        lines.append(f"| {p.name} | {p.kind} | {src} |")
    if result.fallbacks:
        lines += ["", "### State-machine fallbacks (irreducible control flow)", ""]
        for f in result.fallbacks:
            lines.append(f"- `{f.pou}` at {f.span}: {f.reason}")
    lines += ["", "## I/O map", "", "| symbol | operand | IEC variable | type | direction |", "|---|---|---|---|---|"]
    for r in result.layout.rows:
        if r.operand[0] in "IO":
            lines.append(f"| {r.symbol} | {r.operand} | {r.iec} | {r.iec_type} | {r.direction} |")
    lines += ["", "## NC interface operands used", "", "| symbol | operand | IEC variable | direction |", "|---|---|---|---|"]
    for r in result.layout.rows:
        if r.direction in ("nc_to_plc", "plc_to_nc") or program.semantics.profile.is_interface(r.operand[0], int(r.operand[1:])):
            lines.append(f"| {r.symbol} | {r.operand} | {r.iec} | {r.direction} |")
    lines += ["", "## Timers and counters", ""]
    for name, cycles in sorted(result.presets.items()):
        lines.append(f"- `{name}` = {cycles} cycles")
    if not result.presets:
        lines.append("none")
    lines += ["", "## Assumptions applied", "", "| id | setting | value | default |", "|---|---|---|---|"]
    for aid, key, value, is_default in program.semantics.describe():
        lines.append(f"| {aid} | {key} | {value} | {'yes' if is_default else '**no**'} |")
    lines += ["", "## Target limits", ""]
    lines += _target_limits(program) or ["none"]
    lines += ["", "## Auto-assigned operands", ""]
    lines += [f"- `{s.name}` -> {s.operand_text}" for s in program.auto_assigned] or ["none"]
    lines += ["", "## Renamed symbols", ""]
    lines += [f"- `{r.original}` -> `{r.iec}` ({r.reason})" for r in result.names.renames] or ["none"]
    lines += ["", "## Not translated", ""]
    lines += [f"- {span}: {text}" for span, text in result.untranslated] or ["nothing"]
    lines += ["", "## Inactive conditional regions", ""]
    lines += [f"- {r.file}:{r.first_line}-{r.last_line} (`{r.condition}`)" for r in program.inactive_regions] or ["none"]
    lines += ["", "## Warnings", ""]
    lines += [f"- {d.render()}" for d in diags.warnings] or ["none"]
    return "\n".join(lines) + "\n"
