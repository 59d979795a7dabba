"""The migration report (report.md) and the I/O map (io_map.csv) of one translation: what a user reads to wire
and review the port: modules, POUs, I/O and NC interface, presets, assumptions, target limits, renames, and
everything not translated."""

from __future__ import annotations

from transpiler.backends.st.readability import measure
from transpiler.backends.iec_model import Pou
from transpiler.backends.report.screens import screens_section
from transpiler.backends.report.target import target_must_provide
from transpiler.backends.st import hh_lib
from transpiler.backends.st.sys_library import ST_FILE as LIB_ST, XML_FILE as LIB_XML, library_project
from transpiler.backends.report.iomap import IoMap, MapRow, iec_address
from transpiler.backends.st.backend import StResult
from transpiler.backends.st.liveness import SA_CODES
from transpiler.diagnostics import Diagnostics
from transpiler.ir import Program
from transpiler.language.semantics import ASSUMPTION_BY_KEY


def configuration_text(program: Program) -> str:
    """The configuration a translation was made with: the configuration file, the -D values, NUMBERMP4111."""
    parts = [program.config_file if program.config_file else "no configuration file"]
    if program.command_line_defines:
        parts.append("-D " + ", ".join(f"{name}={value!r}" if isinstance(value, str) else f"{name}={value}"
                                         for name, value in program.command_line_defines))
    if program.semantics["number_mp4111"]:
        parts.append(f"NUMBERMP4111 = {program.semantics['number_mp4111']}")
    return "; ".join(parts)


def io_map_of(result: StResult, mp_file: str | None = None, program: Program | None = None) -> IoMap:
    """Operand rows in a stable order (inputs and outputs with their IEC address), then one row per timer/counter
    preset variable (naming `mp_file`, the machine parameters its initial value comes from), then, given the
    `program`, one row naming the configuration the translation was made with."""
    def order(r):
        digits = r.operand[1:]
        return (r.operand[0], int(digits) if digits.isdigit() else 0)
    rows = [MapRow(r.symbol, r.operand, r.iec, r.iec_type, r.direction, r.comment,
                   iec_address(r.operand) if "[" not in r.iec else "")
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
        source = f"from {mp_file}" if mp_file else "no machine-parameter file: 0"
        rows.append(MapRow("", f"MP{number}.{index}", name, "DINT", "parameter", f"preset in PLC cycles ({source})"))
    for name, typ, row in result.data_vars.values():
        rows.append(MapRow(row.symbol, row.key, name, typ, "parameter",
                           f"data-table value of {row.operand_text} ({row.table}:{row.span.line})"))
    if program is not None:
        rows.append(MapRow("", "CONFIG", "", "", "configuration", configuration_text(program)))
    return IoMap(rows)


def user_pous(result: StResult) -> list[Pou]:
    """The POUs translated from the program's routines (not the library, service or accessor POUs), in project order."""
    names = set(result.pou_of_routine.values())
    return [p for p in result.project.pous if p.name in names]


def _target_limits(program: Program, codes: set[str]) -> list[str]:
    """What the vendor-neutral ST cannot hold the way the control does, as far as this program needs it (`codes`:
    the op codes of the program)."""
    if not codes & SA_CODES:
        return []       # (no string op: no pass over every op to find where)
    string_lines = [f"{f.path}:{op.span.line}" for f in program.files for op in f.ops if op.code in SA_CODES]
    if not string_lines:
        return []
    where = ", ".join(string_lines[:5]) + (f" and {len(string_lines) - 5} more" if len(string_lines) > 5 else "")
    return [f"- Strings ({where}): the control's strings hold 128 characters. The ST declares plain `STRING`, the only "
            "string declaration matiec accepts; it holds 126 characters in matiec/OpenPLC/Beremiz and 80 by default in "
            "CODESYS and TwinCAT. Longer values are cut there: on CODESYS/TwinCAT declare the string variables "
            "`STRING(128)` or raise the default string length; on matiec keep results within 126 characters."]


def _library_files(result: StResult) -> list[str]:
    """The paragraph on the HH_Sys library files (when the program calls such a module), then the HH_Lib section."""
    lines = []
    if library_project(result.project) is not None:
        lines += ["", f"The same FUNCTION_BLOCKs, and nothing else, are written as the library files `{LIB_ST}` (ST) and "
                  f"`{LIB_XML}` (PLCopen XML) next to this report (with the ST and XML output formats), to import "
                  "into the target IDE (CODESYS, TwinCAT) and implement there."]
    return lines + ["", "## Helper library", "", (f"`{hh_lib.ST_FILE}` (ST) and `{hh_lib.XML_FILE}` (PLCopen XML), next to this report with the ST and XML "
            f"output formats, are the library {hh_lib.LIBRARY_NAME}: every `HH_` helper function and the `HH_TIMER` and "
            "`HH_COUNTER` blocks, each with a comment saying which behaviour of the control it keeps. project.st is "
            "complete without it (it declares the helpers it uses, with the same bodies); import the library to keep "
            "the helpers in one place on the target instead (docs/hh_lib.md).")]


def _names(program: Program, result: StResult) -> list[str]:
    """The sections on names: the symbols renamed, and the marker STRUCTs."""
    lines = ["", "## Renamed symbols", ""]
    lines += [f"- `{r.original}` -> `{r.iec}` ({r.reason})" for r in result.names.renames] or ["none"]
    return lines + ["", "## Marker structs", ""] + _marker_structs(program, result)


def _marker_structs(program: Program, result: StResult) -> list[str]:
    """The STRUCTs the markers of one symbol prefix became, and each prefix kept as separate variables, with why."""
    if not program.semantics["marker_structs"]:
        return ["none: every marker is a variable of its own (marker_structs = false, A-62)"]
    layout = result.layout
    lines = []
    if layout.marker_groups:
        lines += ["Markers whose symbols share a prefix are the members of one STRUCT (A-62); io_map.csv names each "
                  "member (`ML_ax.inpos`):", ""]
        lines += [f"- `{g.name} : {g.type_name}`: {len(g.members)} markers, {g.addresses()}" for g in layout.marker_groups]
    if layout.group_refusals:
        lines += ([""] if lines else []) + ["Prefixes kept as separate variables:", ""]
        lines += [f"- `{r.prefix}_*`: {r.reason}" for r in layout.group_refusals]
    return lines or ["none: no symbol prefix is shared by enough markers"]


def _not_translated(result: StResult) -> list[str]:
    return [f"- {span}: {text}" for span, text in result.untranslated]


def render_report(program: Program, result: StResult, diags: Diagnostics, iomap: IoMap, mp_file: str | None = None
                  ) -> str:
    """report.md; `iomap` is io_map_of the translation (the screens section names the variables it holds)."""
    user = user_pous(result)
    fallback_names = {f.pou for f in result.fallbacks}
    structured = len([p for p in user if p.name not in fallback_names])
    lines = [f"# Migration report: {program.main.path}", "",
             f"Profile `{program.semantics.profile.name}`, cycle time {program.semantics['cycle_time_ms']} ms. "
             f"Generated by hh2iec.", ""]
    if result.untranslated:     # allowed by the user: the first thing a reader must see
        lines += ["## Not translated: this translation is incomplete", "",
                  f"{len(result.untranslated)} places were left out (--allow-untranslated); the ST does not do what "
                  "the original does there, and no equivalence check can prove it does:", ""]
        lines += _not_translated(result) + [""]
    lines += [f"Configuration: {configuration_text(program)}.", ""]
    if mp_file:
        lines += [f"Machine parameters: `{mp_file}` (timer and counter presets).", ""]
    elif any(result.presets.values()):
        lines += ["Machine parameters: given to the translation (timer and counter presets).", ""]
    elif result.preset_vars:
        lines += ["Machine parameters: none found; every timer and counter preset is 0.", ""]
    lines += ["## Modules", "",
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
    lines += ["", "### Data stack", ""]
    if result.dynamic_stack:
        lines.append("These POUs keep the emulated data stack (HH_STACK, HH_SP) because its depth is not the same "
                     "on every path or call there; every other subprogram passes its PS/PL operands as "
                     "VAR_INPUT/VAR_OUTPUT:")
        lines += [f"- `{pou}` at {span}: {reason}" for pou, reason, span in result.dynamic_stack]
    else:
        lines.append("No POU emulates the data stack: every PS/PL passes through VAR_INPUT/VAR_OUTPUT or local variables.")
    if result.jobs_program is not None:
        lines += ["", "### Submit jobs", "", f"`{result.jobs_program}` runs in the same task right after the main "
                  "program and calls the queued jobs one after the other (keep that order on the target):", ""]
        lines += [f"- job {number}: `{pou}` ({span.file}:{span.line})" for number, pou, span in result.submit_jobs]
    lines += ["", "### Readability", "", measure(result.project, program.instruction_count()).line() + "."]
    lines += ["", "## I/O map", "", "| symbol | operand | IEC variable | IEC address | type | direction |",
              "|---|---|---|---|---|---|"]
    for r in result.layout.rows:
        if r.operand[0] in "IO":
            address = iec_address(r.operand) if "[" not in r.iec else "(indexed: array element)"
            lines.append(f"| {r.symbol} | {r.operand} | {r.iec} | {address} | {r.iec_type} | {r.direction} |")
    lines += ["", "## NC interface operands used", "", "| symbol | operand | IEC variable | direction |", "|---|---|---|---|"]
    for r in result.layout.rows:
        if r.direction in ("nc_to_plc", "plc_to_nc") or program.semantics.profile.is_interface(r.operand[0], int(r.operand[1:])):
            lines.append(f"| {r.symbol} | {r.operand} | {r.iec} | {r.direction} |")
    lines += screens_section(program, iomap)
    lines += ["", "## What the target must provide", ""] + target_must_provide(program, result) + _library_files(result)
    lines += ["", "## Timers and counters", ""]
    lines += [f"- `{name}` = {cycles} cycles" for name, cycles in sorted(result.presets.items())] or ["none"]
    lines += _data_tables(result)
    lines += ["", "## Assumptions applied", "", "| id | setting | value | default |", "|---|---|---|---|"]
    for aid, key, value, is_default in program.semantics.describe():
        lines.append(f"| {aid} | {key} | {value} | {'yes' if is_default else '**no**'} |")
    codes = {op.code for f in program.files for op in f.ops}
    lines += ["", "## Target limits", ""] + ((limits := _target_limits(program, codes)) or ["none"])
    lines += ["", "## Auto-assigned operands", ""]
    lines += [f"- `{s.name}` -> {s.operand_text}" for s in program.auto_assigned] or ["none"]
    lines += _names(program, result)
    lines += ["", "## Not translated", ""]
    lines += _not_translated(result) or ["nothing"]
    lines += ["", "## Inactive conditional regions", ""]
    lines += [f"- {r.file}:{r.first_line}-{r.last_line} (`{r.condition}`)" for r in program.inactive_regions] or ["none"]
    lines += ["", "## Warnings", ""]
    lines += [f"- {d.render()}" for d in diags.warnings] or ["none"]
    lines += ["", "## Next steps", ""] + _next_steps(program, result, mp_file, bool(limits), codes)
    return "\n".join(lines) + "\n"


# Assumptions whose choice changes what a program using the construct does: confirm them on the machine.
_CONFIRM_BY_USE = (
    ("timers", ("A-32", "A-34a", "A-34b", "A-35")),
    ("counters", ("A-36a", "A-36b")),
    ("CASE", ("A-24",)),
    ("arithmetic", ("A-09", "A-10", "A-11")),
    ("word loads and stores", ("A-06", "A-08", "A-42")),
)



def _data_tables(result: StResult) -> list[str]:
    """The section of the PLC data tables: every row with the global holding it and the operand it loads."""
    if not result.data_vars:
        return []
    lines = ["", "## PLC data tables", "",
             "Each row's value is the initial value of a retained global; the program loads it into the operand "
             "before its first cycle and in a cycle that sees M4174 (MP restart). Commissioning changes the global.",
             "", "| table | NR | symbol | operand | value | IEC variable | loaded into |", "|---|---|---|---|---|---|---|"]
    operand_vars = {r.operand: r.iec for r in result.layout.rows}
    for name, typ, row in result.data_vars.values():
        nr = "" if row.nr is None else str(row.nr)
        lines.append(f"| {row.table}:{row.span.line} | {nr} | {row.symbol} | {row.operand_text} | {row.value!r} | "
                     f"`{name}` ({typ}) | `{operand_vars.get(row.operand_text, '(byte memory)')}` |")
    return lines


def _next_steps(program: Program, result: StResult, mp_file: str | None, limited: bool, codes: set[str]
                ) -> list[str]:
    """What a porting engineer does with this output: wire the I/O, provide the NC interface and the PLC task,
    confirm the assumptions the program depends on, and what is still open (`limited`: the program meets a
    target limit; `codes`: the op codes of the program)."""
    rows = result.layout.rows
    inputs = sum(1 for r in rows if r.operand[0] == "I")
    outputs = sum(1 for r in rows if r.operand[0] == "O")
    nc = [r for r in rows if r.direction in ("nc_to_plc", "plc_to_nc")]
    used = {"timers": bool(result.timers), "counters": bool(result.counters), "CASE": "CASE" in codes,
            "arithmetic": bool(codes & {"ADD", "SUB", "MUL", "DIV", "MOD"}),
            "word loads and stores": bool(codes & {"WLD", "WST"})}
    steps = [f"- Wire the process image: {inputs} inputs (`%IX`) and {outputs} outputs (`%QX`) are declared at the "
             "IEC addresses of the I/O map above (column `iec_address` of io_map.csv; byte = HEIDENHAIN address div 8, "
             "bit = address mod 8). Map them onto the target's I/O modules; the comments name the original terminals.",
             f"- Provide the NC interface: the target must write the {sum(r.direction == 'nc_to_plc' for r in nc)} "
             f"NC-to-PLC variables before each PLC cycle and read the {sum(r.direction == 'plc_to_nc' for r in nc)} "
             "PLC-to-NC variables after it (section NC interface operands used; docs/import.md describes the `HH_` "
             "interface).",
             f"- Run the main POU in a cyclic task of {program.semantics['cycle_time_ms']} ms: timer presets are "
             "counted in PLC cycles of this length."]
    if result.preset_vars and not mp_file:
        steps.append("- Give the machine-parameter file (--mp): without one every timer and counter preset is 0.")
    confirm = sorted({aid for feature, ids in _CONFIRM_BY_USE if used[feature] for aid in ids})
    changed = [aid for aid, key, _, is_default in program.semantics.describe()
               if not is_default and not ASSUMPTION_BY_KEY[key].layout_only]
    if confirm or changed:
        ids = ", ".join(sorted(set(confirm) | set(changed)))
        steps.append(f"- Confirm on the machine the assumptions this program depends on: {ids} (section Assumptions "
                     "applied; docs/assumptions.md says what each means and how to switch it with -S).")
    if limited:
        steps.append("- Check the target limits above on the chosen target (string lengths).")
    if result.untranslated:
        steps.append(f"- Translate by hand the {len(result.untranslated)} places left out (section Not translated).")
    if result.fallbacks:
        steps.append(f"- Review the {len(result.fallbacks)} state-machine fallbacks: correct, but less readable.")
    steps.append("- Prove the port: `hh2iec equiv` with scenarios of the machine's sequences (docs/scenarios.md).")
    return steps
