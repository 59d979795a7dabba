"""Per-cycle traces of observed operands, written atomically as CSV or as a value-change dump (VCD) for GTKWave."""

from __future__ import annotations

import contextlib
import csv
import os
import tempfile
from pathlib import Path
from typing import IO, Iterator, Mapping, Sequence

from vcd import VCDWriter

from transpiler.atomic import new_file_mode
from transpiler.verify.scenario import WIDTHS, OperandRef, normalize_value


@contextlib.contextmanager
def atomic_text_file(path: Path) -> Iterator[IO[str]]:
    """A text file that appears under `path` only once it is completely written (temp file + os.replace)."""
    path = Path(path)
    if not path.parent.is_dir():
        raise FileNotFoundError(f"folder '{path.parent}' does not exist")
    fd, temp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as handle:
            yield handle
        os.chmod(temp, new_file_mode())      # an output like any other, not mkstemp's private 0600
        os.replace(temp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(temp)
        raise


class TraceRecorder:
    """Collects the observed values after each cycle; columns are (display name, operand)."""

    def __init__(self, columns: Sequence[tuple[str, OperandRef]]):
        names = [name for name, _ in columns]
        duplicates = sorted({n for n in names if names.count(n) > 1})
        if duplicates:
            raise ValueError(f"duplicate trace column names: {', '.join(duplicates)}")
        self.columns: tuple[tuple[str, OperandRef], ...] = tuple(columns)
        self.rows: list[tuple[int, tuple[int | str, ...]]] = []

    def record(self, cycle: int, values: Sequence[int | str]) -> None:
        """Values in column order; B/W/D are kept as signed two's complement, bits as 0/1."""
        if len(values) != len(self.columns):
            raise ValueError(f"{len(values)} values for {len(self.columns)} trace columns")
        if self.rows and cycle <= self.rows[-1][0]:
            raise ValueError(f"trace cycle {cycle} recorded after cycle {self.rows[-1][0]}")
        row = tuple(normalize_value(ref.kind, v) for (_, ref), v in zip(self.columns, values))
        self.rows.append((cycle, row))

    def column(self, name: str) -> list[int | str]:
        """Every recorded value of one column, in cycle order."""
        index = [n for n, _ in self.columns].index(name)
        return [row[index] for _, row in self.rows]

    def write_csv(self, path: Path) -> None:
        """Header `cycle,<display names>`, then one row per recorded cycle."""
        with atomic_text_file(path) as handle:
            writer = csv.writer(handle, lineterminator="\n")
            writer.writerow(["cycle", *(name for name, _ in self.columns)])
            for cycle, row in self.rows:
                writer.writerow([cycle, *row])

    def write_vcd(self, path: Path, cycle_time_ms: int = 20, scope: str = "plc") -> None:
        """Bits as 1-bit wires, B/W/D as 8/16/32-bit vectors (two's complement), S as string variables.

        The value recorded after cycle n is dumped at time n * cycle_time_ms (timescale 1 ms).
        """
        write_vcd_scopes(path, {scope: self}, cycle_time_ms)

    @staticmethod
    def _register(writer: VCDWriter, scope: str, name: str, ref: OperandRef):  # noqa: ANN205 (pyvcd Variable)
        if ref.kind == "S":
            return writer.register_var(scope, name, "string", init="")
        return writer.register_var(scope, name, "wire", size=WIDTHS.get(ref.kind, 1))


def write_vcd_scopes(path: Path, traces: Mapping[str, TraceRecorder], cycle_time_ms: int = 20) -> None:
    """Traces of the same cycles in one value-change dump, one scope each: the original and the translation side by
    side in one GTKWave window. Rows are taken cycle by cycle from every trace, so the times never go back."""
    with atomic_text_file(path) as handle:
        # a fixed date keeps the file reproducible for the same trace
        with VCDWriter(handle, timescale="1 ms", date="", version="hh2iec") as writer:
            scopes = [(trace, [TraceRecorder._register(writer, scope, name, ref) for name, ref in trace.columns])
                      for scope, trace in traces.items()]
            last_time = 0
            cycles = max((len(trace.rows) for trace in traces.values()), default=0)
            for index in range(cycles):
                for trace, variables in scopes:
                    if index >= len(trace.rows):
                        continue
                    cycle, row = trace.rows[index]
                    last_time = cycle * cycle_time_ms
                    for (_, ref), var, value in zip(trace.columns, variables, row):
                        writer.change(var, last_time, _vcd_value(ref, value))
            writer.close(last_time + cycle_time_ms if cycles else None)


def _vcd_value(ref: OperandRef, value: int | str) -> int | str:
    if ref.kind == "S":
        return str(value)
    width = WIDTHS.get(ref.kind, 1)
    return int(value) & ((1 << width) - 1)
