"""PLC data tables (MP_Data.tab, MP_Config.tab): finding them, reading the TNC table text into typed rows with
spans, and binding each row to the .def symbol it names (E-TAB-* diagnostics, all of them, never a traceback).

The layout assumed (docs/language.md#plc-data-tables): a `BEGIN <name>` line, one line of fixed-width column
headers, one row per line, `[END]`. Each column starts where its header word starts and ends where the next one
starts (the last runs to the end of the line). Columns: NAME (the symbol) and VALUE are required; NR (row number),
UNIT and COMMENT are optional and NR, when present, must be a unique whole number; any other column is an error."""

from __future__ import annotations

import dataclasses
import difflib
import re
from pathlib import Path
from typing import Iterable, Mapping

from transpiler.diagnostics import Diagnostics, Span
from transpiler.frontend.sources import ProjectFolders, read_source
from transpiler.ir import VALUE_RANGES, WIDTH, DataRow, Symbol, sext

TABLE_NAMES = ("MP_Data.tab", "MP_Config.tab")       # the order they are read in; PLC:\MP\ on the control
TABLE_FOLDER = "MP"
COLUMNS = ("NR", "NAME", "VALUE", "UNIT", "COMMENT")
REQUIRED = ("NAME", "VALUE")
DATA_KINDS = "MBWDS"
# A value may be written signed or unsigned in its width (255 and -1 are the same byte).
RANGES: Mapping[str, tuple[int, int]] = {"M": (0, 1), **VALUE_RANGES}
_NUMBER = re.compile(r"[+-]?(\d+|\$[0-9A-Fa-f]+|%[01]+)")
_BEGIN = re.compile(r"\s*BEGIN\s+(\S+)(?:\s+.*)?", re.IGNORECASE)


@dataclasses.dataclass(frozen=True)
class TableRow:
    """One row as written: the cell texts (stripped) by column, with the span of each cell."""

    line: int
    cells: Mapping[str, str]
    spans: Mapping[str, Span]


def find_tables(main: Path, explicit: Mapping[str, Path | None], diags: Diagnostics) -> list[tuple[str, Path]]:
    """(table name, path) of every table the project has: the one given on the command line (`explicit`, by table
    name), else the file of that name (any case) in the folder MP beside the main program or beside it; one in
    both places is an error (E-MP-AMBIGUOUS)."""
    found = []
    for name in TABLE_NAMES:
        given = explicit.get(name)
        if given is not None:
            found.append((name, Path(given)))
            continue
        hits = [p for folder in (main.parent / TABLE_FOLDER, main.parent) for p in _named(folder, name)]
        if len(hits) > 1:
            diags.report("E-MP-AMBIGUOUS", Span(str(main), 1, 1),
                         f"{len(hits)} files {name} ({', '.join(str(p) for p in hits)}): keep one, or name it with "
                         f"--{'mp-data' if name == TABLE_NAMES[0] else 'mp-config'}")
        elif hits:
            found.append((name, hits[0]))
    return found


def _named(folder: Path, name: str) -> list[Path]:
    try:
        return sorted(p for p in folder.iterdir() if p.name.lower() == name.lower() and p.is_file())
    except OSError:
        return []


def parse_table(file: str, lines: Iterable[str], diags: Diagnostics) -> list[TableRow]:
    """The rows of one table text; every malformed line is an E-TAB-SYNTAX error at its line and column."""
    lines = list(lines)
    rows: list[TableRow] = []
    index = _skip_blank(lines, 0)
    if index >= len(lines) or _BEGIN.fullmatch(lines[index]) is None:
        diags.report("E-TAB-SYNTAX", Span(file, min(index, len(lines) - 1) + 1 if lines else 1, 1),
                     "a table starts with a line `BEGIN <table name>`")
        return rows
    index = _skip_blank(lines, index + 1)
    if index >= len(lines) or lines[index].strip().upper() == "[END]":
        diags.report("E-TAB-SYNTAX", Span(file, min(index, len(lines)) if lines else 1, 1),
                     f"the BEGIN line is followed by the column header ({' '.join(COLUMNS)})")
        return rows
    columns = _columns(file, index + 1, lines[index], diags)
    if columns is None:
        return rows
    ended = False
    for number in range(index + 2, len(lines) + 1):
        text = lines[number - 1]
        if not text.strip():
            continue
        if ended:
            diags.report("E-TAB-SYNTAX", Span(file, number, _indent(text)), "text after [END]")
            break
        if text.strip().upper() == "[END]":
            ended = True
            continue
        rows.append(_row(file, number, text, columns))
    if not ended:
        diags.report("E-TAB-SYNTAX", Span(file, len(lines), 1), "the table does not end with a line [END]")
    return rows


def _skip_blank(lines: list[str], index: int) -> int:
    while index < len(lines) and not lines[index].strip():
        index += 1
    return index


def _indent(text: str) -> int:
    return len(text) - len(text.lstrip()) + 1


def _columns(file: str, line: int, text: str, diags: Diagnostics) -> list[tuple[str, int, int | None]] | None:
    """(name, first column, end column or None for the last) of the header; None after reporting what is wrong."""
    words = [(m.group(0).upper(), m.start()) for m in re.finditer(r"\S+", text)]
    ok = True
    seen: set[str] = set()
    for word, start in words:
        if word not in COLUMNS:
            near = difflib.get_close_matches(word, COLUMNS, n=1)
            hint = f" (did you mean {near[0]}?)" if near else ""
            diags.report("E-TAB-SYNTAX", Span(file, line, start + 1),
                         f"unknown column '{word}'{hint}: the columns are {', '.join(COLUMNS)}")
            ok = False
        elif word in seen:
            diags.report("E-TAB-SYNTAX", Span(file, line, start + 1), f"column {word} appears twice")
            ok = False
        seen.add(word)
    for need in REQUIRED:
        if ok and need not in seen:
            diags.report("E-TAB-SYNTAX", Span(file, line, 1), f"the column header lacks the column {need}")
            ok = False
    if not ok:
        return None
    return [(word, start, words[i + 1][1] if i + 1 < len(words) else None) for i, (word, start) in enumerate(words)]


def _row(file: str, line: int, text: str, columns: list[tuple[str, int, int | None]]) -> TableRow:
    cells: dict[str, str] = {}
    spans: dict[str, Span] = {}
    for name, start, end in columns:
        # The first column also takes what is written left of its header (a row number written further left).
        raw = text[0 if start == columns[0][1] else start:end]
        cell = raw.strip()
        offset = (0 if start == columns[0][1] else start) + (len(raw) - len(raw.lstrip()) if cell else 0)
        cells[name] = cell
        spans[name] = Span(file, line, offset + 1)
    return TableRow(line, cells, spans)


def table_value(kind: str, text: str) -> tuple[int | str | None, str]:
    """The value a cell gives an operand of `kind`, normalised (signed in its width, text without quotes), or
    (None, why not)."""
    if kind == "S":
        if len(text) >= 2 and text[0] == text[-1] == '"':
            return text[1:-1], ""
        return None, f"a string operand takes text in double quotes, not {text!r}"
    if _NUMBER.fullmatch(text) is None:
        return None, f"{text!r} is not a whole number (decimal, $hex or %binary)"
    sign = -1 if text.startswith("-") else 1
    body = text.lstrip("+-")
    value = sign * (int(body[1:], 16) if body.startswith("$") else int(body[1:], 2) if body.startswith("%")
                    else int(body))
    lo, hi = RANGES[kind]
    if not lo <= value <= hi:
        what = "a marker holds 0 or 1" if kind == "M" else f"a {_KIND_NAMES[kind]} holds {lo}..{hi}"
        return None, f"{value} does not fit: {what}"
    return (sext(value, WIDTH[kind]) if kind in VALUE_RANGES else value), ""


def bind_rows(file: str, rows: Iterable[TableRow], symbols: Mapping[str, Symbol], string_len: int,
              diags: Diagnostics, seen: dict[str, Span] | None = None) -> list[DataRow]:
    """The rows bound to their symbols; unknown symbols (with the nearest names), operands a table cannot set,
    values that do not fit and duplicate rows are errors. `seen` (symbol -> first row) spans several tables."""
    seen = {} if seen is None else seen
    numbers: dict[int, Span] = {}
    bound = []
    candidates = [n for n, s in symbols.items() if s.kind in DATA_KINDS]
    for row in rows:
        name, value_text = row.cells["NAME"], row.cells["VALUE"]
        at, value_at = row.spans["NAME"], row.spans["VALUE"]
        nr = _row_number(row, numbers, diags)
        if not name:
            diags.report("E-TAB-SYNTAX", at, "the row has no NAME")
            continue
        sym = symbols.get(name)
        if sym is None:
            near = difflib.get_close_matches(name, candidates, n=3, cutoff=0.6)
            hint = f" (nearest: {', '.join(near)})" if near else ""
            diags.report("E-TAB-SYMBOL", at, f"unknown symbol '{name}': not defined in the project's .def files{hint}")
            continue
        if sym.kind not in DATA_KINDS:
            diags.report("E-TAB-SYMBOL", at, f"'{name}' is {_KIND_NAMES.get(sym.kind, sym.kind)} ({sym.operand_text}): "
                         "a table row sets a marker, byte, word, double word or string")
            continue
        if name in seen:
            diags.report("E-TAB-DUP", at, f"'{name}' has a row already (at {seen[name]})")
            continue
        seen[name] = at
        if not value_text:
            diags.report("E-TAB-SYNTAX", value_at, f"the row of '{name}' has no VALUE")
            continue
        value, why = table_value(sym.kind, value_text)
        if value is None:
            diags.report("E-TAB-VALUE", value_at, f"{name} ({sym.operand_text}): {why}")
            continue
        if isinstance(value, str) and len(value) > string_len:
            diags.report("E-TAB-VALUE", value_at, f"{name} ({sym.operand_text}): {len(value)} characters, a string "
                         f"operand holds {string_len}")
            continue
        bound.append(DataRow(file, nr, name, sym.kind, sym.addr, value, value_at))
    return bound


_KIND_NAMES = {"I": "an input", "O": "an output", "T": "a timer", "C": "a counter", "K": "a constant",
               "B": "byte", "W": "word", "D": "double word"}


def _row_number(row: TableRow, numbers: dict[int, Span], diags: Diagnostics) -> int | None:
    text = row.cells.get("NR")
    if text is None:
        return None
    if not text.isdigit():
        diags.report("E-TAB-SYNTAX", row.spans["NR"], f"NR is a whole number ≥ 0, not {text!r}" if text
                     else "the row has no NR")
        return None
    nr = int(text)
    if nr in numbers:
        diags.report("E-TAB-DUP", row.spans["NR"], f"row number {nr} is used already (at {numbers[nr]})")
    numbers.setdefault(nr, row.spans["NR"])
    return nr


def read_tables(main: Path, explicit: Mapping[str, Path | None], symbols: Mapping[str, Symbol], string_len: int,
                diags: Diagnostics, encoding: str | None = None) -> tuple[DataRow, ...]:
    """Every row of the project's data tables (see find_tables), bound to its symbol."""
    seen: dict[str, Span] = {}
    rows: list[DataRow] = []
    for _, path in find_tables(main, explicit, diags):
        text = read_source(path, ProjectFolders(main.parent, []), Span(str(main), 1, 1), diags, encoding=encoding)
        if text is None:
            continue
        rows += bind_rows(text.display, parse_table(text.display, text.lines, diags), symbols, string_len, diags,
                          seen)
    return tuple(rows)
