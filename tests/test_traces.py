"""Tests of trace recording and of the CSV and VCD writers."""

from __future__ import annotations

import csv
import os
from pathlib import Path

import pytest
from vcd.reader import TokenKind, tokenize

from transpiler.verify.scenario import OperandRef
from transpiler.verify.traces import TraceRecorder

R = OperandRef
COLUMNS = [("O_lamp", R("O", 5)), ("B_byte", R("B", 10)), ("W262", R("W", 262)), ("D_pos", R("D", 40)),
           ("S_msg", R("S", 3))]


def recorder() -> TraceRecorder:
    t = TraceRecorder(COLUMNS)
    t.record(0, [1, 252, 65535, 7, "a b"])
    t.record(1, [0, 252, -2, 2 ** 32 - 1, "a b"])
    t.record(2, [True, 3, -2, -1, "next"])
    return t


def test_csv_has_a_header_and_one_row_per_cycle_with_signed_words(tmp_path: Path) -> None:
    path = tmp_path / "trace.csv"
    recorder().write_csv(path)
    rows = list(csv.reader(path.open(newline="")))
    assert rows == [
        ["cycle", "O_lamp", "B_byte", "W262", "D_pos", "S_msg"],
        ["0", "1", "-4", "-1", "7", "a b"],
        ["1", "0", "-4", "-2", "-1", "a b"],
        ["2", "1", "3", "-2", "-1", "next"],
    ]


def test_record_rejects_wrong_width_rows_and_time_going_back() -> None:
    t = TraceRecorder(COLUMNS)
    with pytest.raises(ValueError):
        t.record(0, [1, 2])
    t.record(3, [1, 2, 3, 4, "x"])
    with pytest.raises(ValueError):
        t.record(3, [1, 2, 3, 4, "x"])
    assert t.column("W262") == [3]


def test_duplicate_column_names_are_rejected() -> None:
    with pytest.raises(ValueError):
        TraceRecorder([("A", R("M", 1)), ("A", R("M", 2))])


def _parse_vcd(path: Path) -> tuple[dict, dict, list]:
    """(timescale, {ident: (name, type, size)}, [(time, ident, value)]) read back with pyvcd's tokenizer."""
    variables: dict[str, tuple[str, str, int]] = {}
    changes: list[tuple[int, str, object]] = []
    timescale = None
    time = 0
    with path.open("rb") as handle:
        for token in tokenize(handle):
            if token.kind is TokenKind.TIMESCALE:
                timescale = (int(token.timescale.magnitude), token.timescale.unit.value)
            elif token.kind is TokenKind.VAR:
                variables[token.var.id_code] = (token.var.reference, token.var.type_.value, token.var.size)
            elif token.kind is TokenKind.CHANGE_TIME:
                time = token.time_change
            elif token.kind is TokenKind.CHANGE_SCALAR:
                changes.append((time, token.scalar_change.id_code, token.scalar_change.value))
            elif token.kind is TokenKind.CHANGE_VECTOR:
                changes.append((time, token.vector_change.id_code, token.vector_change.value))
            elif token.kind is TokenKind.CHANGE_STRING:
                changes.append((time, token.string_change.id_code, token.string_change.value))
    return timescale, variables, changes


def test_vcd_parses_back_with_widths_twos_complement_and_times(tmp_path: Path) -> None:
    path = tmp_path / "trace.vcd"
    recorder().write_vcd(path, cycle_time_ms=20)
    timescale, variables, changes = _parse_vcd(path)
    assert timescale == (1, "ms")
    by_name = {name: (ident, kind, size) for ident, (name, kind, size) in variables.items()}
    assert {n: (k, s) for n, (_, k, s) in by_name.items()} == {
        "O_lamp": ("wire", 1), "B_byte": ("wire", 8), "W262": ("wire", 16), "D_pos": ("wire", 32),
        "S_msg": ("string", 1)}

    def history(name: str) -> list:
        ident = by_name[name][0]
        return [(t, v) for t, i, v in changes if i == ident]

    assert history("O_lamp") == [(0, "1"), (20, "0"), (40, "1")]
    assert history("B_byte") == [(0, 252), (40, 3)]          # 252 == -4: no change dumped at cycle 1
    assert history("W262") == [(0, 65535), (20, 65534)]        # -2 as 16-bit two's complement
    assert history("D_pos") == [(0, 7), (20, 2 ** 32 - 1)]
    assert history("S_msg") == [(0, "a\\x20b"), (40, "next")]
    assert path.read_text().count("$enddefinitions") == 1


def test_writes_are_atomic(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "trace.csv"
    path.write_text("old\n")

    def failing_replace(src: str, dst: str) -> None:
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", failing_replace)
    with pytest.raises(OSError):
        recorder().write_csv(path)
    with pytest.raises(OSError):
        recorder().write_vcd(path)
    assert path.read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["trace.csv"]   # no temp files left behind
    monkeypatch.undo()
    recorder().write_csv(path)
    assert path.read_text().startswith("cycle,O_lamp")
