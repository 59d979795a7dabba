"""Machine data on the translated side of a co-simulation: the shipped ST's machine-parameter values checked against
the project's, and the run's own machine data (the scenario's MPs) written into the ST's globals at power-on and at
an MP restart, converted by the function the translation converts them with (language.presets)."""

from __future__ import annotations

import dataclasses
from typing import Iterable, Mapping

from transpiler.backends.report.iomap import BYTES, IoMap, MapRow
from transpiler.diagnostics import Diagnostics
from transpiler.ir import Program
from transpiler.language.presets import COUNTER_MP, TIMER_MP, load_presets

# Codes of the two refusals (see transpiler/diagnostics.py): the shipped ST holds other machine data than the
# project's (a defect of the translation), and machine data of the run the emitted ST cannot hold (no verdict).
SHIPPED = "E-MP-TRANSLATION"
UNREPRESENTABLE = "E-MP-UNREPRESENTABLE"


@dataclasses.dataclass(frozen=True)
class DataWrite:
    """One value of the run's machine data: the operand text of the io map (MP4110.3) and the value written there."""

    operand: str
    value: int | str


@dataclasses.dataclass(frozen=True)
class RunData:
    """What the translated side is given before cycle 0 and again at an MP restart, or why it cannot run."""

    writes: tuple[DataWrite, ...]
    shipped: tuple[str, ...] = ()            # shipped values that differ from the project's (SHIPPED)
    unrepresentable: tuple[str, ...] = ()    # run values the ST cannot hold (UNREPRESENTABLE)
    shipped_against: str = ""                # what the shipped values were compared with

    @property
    def refusal(self) -> tuple[str, str] | None:
        """(code, message) of the reason the run must not start, or None."""
        if self.shipped:
            return SHIPPED, (f"the translated program's machine data differ from {self.shipped_against}: "
                             + "; ".join(self.shipped))
        if self.unrepresentable:
            return UNREPRESENTABLE, ("the scenario's machine data cannot be written into the translated program: "
                                     + "; ".join(self.unrepresentable))
        return None


def preset_rows(iomap: IoMap) -> list[tuple[MapRow, int, int]]:
    """The io map's rows of timer and counter presets, with (MP number, index)."""
    rows = []
    for row in iomap.rows:
        for number in (TIMER_MP, COUNTER_MP):
            prefix = f"MP{number}."
            if row.operand.startswith(prefix) and row.operand[len(prefix):].isdigit():
                rows.append((row, number, int(row.operand[len(prefix):])))
    return rows


def _presets(mp: Mapping, program: Program, cycle_time_ms: int) -> dict[tuple[int, int], int]:
    timers, counters = load_presets(mp, program.semantics, cycle_time_ms, Diagnostics())
    return {**{(TIMER_MP, n): c for n, c in timers.items()}, **{(COUNTER_MP, n): c for n, c in counters.items()}}


def _fits(row: MapRow, value: int) -> bool:
    size = BYTES.get(row.iec_type.split("@")[0])
    if size is None:
        return False
    return -(1 << (8 * size - 1)) <= value < (1 << (8 * size - 1))


def run_data(side, iomap: IoMap, program: Program, run_mp: Mapping, cycle_time_ms: int,
             base_mp: Mapping | None, table: Mapping[str, int | str] | None = None) -> RunData:
    """The checks and writes of one run; `side` (cosim.StSide) is read as emitted, before anything is written.

    (a) The shipped preset variables must hold the presets of the project's machine parameters (`base_mp`,
    converted with the translation's cycle time). A project without an MP file (`base_mp` None) has no machine
    data of its own: the run's machine parameters are then the machine's, and the ST must hold them as shipped.
    (b) The run's machine parameters (`run_mp`: the scenario's file or the project's, with the scenario's inline
    values over them), converted with the run's cycle time, are written into the preset variables.
    The PLC data tables alike: the globals holding their rows must hold the tables' values as shipped, and the
    run's values (`table`, symbol -> value: the scenario's `mp_data` over the tables) are written into them."""
    translation_cycle = int(program.semantics["cycle_time_ms"])
    rows = preset_rows(iomap)
    run = _presets(run_mp, program, cycle_time_ms)
    if base_mp is None:
        wanted, source = run, "the scenario's machine parameters"
        against = ("the scenario's machine parameters (the project has no machine-parameter file, so the "
                   "scenario's are the machine's) and the project's data tables")
    else:
        wanted, source = _presets(base_mp, program, translation_cycle), "the project's machine parameters"
        against = ("the project's machine-parameter file and data tables (made without them, or from other "
                   "ones?)")
    shipped = []
    for row, number, index in rows:
        held, want = _shipped(lambda: side.get(row.iec)), wanted.get((number, index), 0)
        if held is None:
            shipped.append(f"MP{number}.{index}: {want} cycles from {source}, the translated program has no "
                           f"variable {row.iec}")
        elif int(held) != want:
            shipped.append(f"MP{number}.{index}: {want} cycles from {source}, {held} cycles in the translated "
                           f"program ({row.iec})")
    for row in program.data_rows:
        accessor = iomap.accessor(row.key)
        held = _shipped(lambda: accessor.read(side)) if accessor is not None else None
        if held is None:
            shipped.append(f"{row.key}: the translated program holds no value of this data-table row")
        elif held != row.value:
            shipped.append(f"{row.key}: {row.value!r} in the data table ({row.table}:{row.span.line}), {held!r} in "
                           f"the translated program ({accessor.place.path})")
    writes, unrepresentable = [], []
    for row, number, index in rows:
        value = run.get((number, index), 0)
        if not _fits(row, value):
            unrepresentable.append(f"MP{number}.{index}: {value} cycles do not fit the translation's "
                                   f"{row.iec_type} {row.iec}")
            continue
        writes.append(DataWrite(row.operand, value))
    for row in program.data_rows:
        writes.append(DataWrite(row.key, (table or {}).get(row.symbol, row.value)))
    return RunData(tuple(writes), tuple(shipped), tuple(unrepresentable), against)


def _shipped(read):
    """A value as the ST holds it, or None when the ST has no such variable (an io map of another translation)."""
    try:
        return read()
    except (LookupError, ValueError):
        return None


def write_data(side, iomap: IoMap, writes: Iterable[DataWrite]) -> None:
    """Write the run's machine data into the ST side through the io map (power-on, MP restart)."""
    for write in writes:
        accessor = iomap.accessor(write.operand)
        if accessor is not None:
            accessor.write(side, write.value)
