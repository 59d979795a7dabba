"""The screen masks in the translation's output: report.md's section "What the operator screens show" (mask, line,
IEC variable, format) and one JSON file per mask (masks/<mask file>.json) for an HMI to draw the screen from."""

from __future__ import annotations

import json

from transpiler.backends.report.iomap import IoMap
from transpiler.ir import Mask, MaskField, MaskStatement, Program

MASK_FOLDER = "masks"
JSON_VERSION = 1


def mask_file_name(mask: Mask) -> str:
    """Where a mask's JSON goes in the output folder: masks/M_dia_wz.msk.json (the file name keeps .msk and .a
    masks of one stem apart)."""
    return f"{MASK_FOLDER}/{mask.name}.json"


def iec_variable(iomap: IoMap, operand: str) -> str:
    """The IEC variable (or array element) that holds `operand` in the translation, '' where it holds none."""
    if not operand or iomap.accessor(operand) is None:
        return ""
    return iomap.by_operand[operand].iec


def _error_markers(program: Program, iomap: IoMap) -> list[dict]:
    first, last = program.semantics.profile.interface.error_markers
    markers = []
    for marker in range(first, last + 1):
        variable = iec_variable(iomap, f"M{marker}")
        if variable:
            markers.append({"number": marker - first, "operand": f"M{marker}", "variable": variable})
    return markers


def _field(field: MaskField, iomap: IoMap) -> dict:
    ref = field.ref
    return {"format": field.spec, "conversion": field.conversion, "flags": field.flags, "width": field.width,
            "precision": field.precision, "decimals": ref.decimals, "reference": ref.text, "symbol": ref.symbol,
            "operand": ref.operand, "variable": iec_variable(iomap, ref.operand), "modifiers": list(ref.modifiers),
            "line": ref.span.line}


def _statement(stmt: MaskStatement, program: Program, iomap: IoMap) -> dict:
    base = {"kind": stmt.kind, "line": stmt.span.line}
    if stmt.kind == "setting":
        return {**base, "key": stmt.key, "value": stmt.value}
    if stmt.kind == "errque":
        return {**base, "lines": stmt.lines, "modifiers": list(stmt.modifiers),
                "error_markers": _error_markers(program, iomap)}
    pieces = [{"text": p} if isinstance(p, str) else {"field": _field(p, iomap)} for p in stmt.pieces]
    return {**base, "pieces": pieces}


def mask_json(mask: Mask, program: Program, iomap: IoMap) -> bytes:
    """One mask as data: its settings, static text and fields in file order, each field with its IEC variable,
    format and width (docs/import.md describes the layout)."""
    data = {"version": JSON_VERSION, "mask": mask.name, "file": mask.file,
            "statements": [_statement(s, program, iomap) for s in mask.statements]}
    return (json.dumps(data, indent=2, ensure_ascii=False) + "\n").encode("utf-8")


def mask_files(program: Program, iomap: IoMap) -> dict[str, bytes]:
    return {mask_file_name(m): mask_json(m, program, iomap) for m in program.masks}


def screens_section(program: Program, iomap: IoMap) -> list[str]:
    """report.md's lines on the masks: every field with the IEC variable it shows, and the error queue."""
    lines = ["", "## What the operator screens show", ""]
    if not program.masks:
        return lines + ["No screen masks (*.msk, *.a) beside the main program."]
    lines += [f"{len(program.masks)} screen masks; each is also written as data for an HMI: "
              + ", ".join(f"`{mask_file_name(m)}`" for m in program.masks) + ".", "",
              "| mask | line | reference | IEC variable | format |", "|---|---|---|---|---|"]
    for mask in program.masks:
        for stmt in mask.statements:
            if stmt.kind == "errque":
                held = len(_error_markers(program, iomap))
                lines.append(f"| {mask.file} | {stmt.span.line} | error queue, {stmt.lines} lines | the PLC error "
                             f"markers ({held} held by the translation) | ERRQUE |")
            for field in stmt.fields:
                variable = iec_variable(iomap, field.ref.operand) or "(not held)"
                lines.append(f"| {mask.file} | {field.ref.span.line} | `{field.ref.text}` ({field.ref.operand}) | "
                             f"`{variable}` | `{field.spec}`{_modifiers(field)} |")
    return lines


def _modifiers(field: MaskField) -> str:
    return " " + "".join(f"/{m}" for m in field.ref.modifiers) if field.ref.modifiers else ""
