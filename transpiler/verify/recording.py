"""The reference half of a co-simulation run once and kept, to be replayed against many translated sides.

The reference interpreter's run of a scenario does not depend on the translated program: each half of a
co-simulation runs its own program, environment model (its own NC model, which reads that half's own markers)
and system context on the same stimulus, and the two meet only at the comparison. So mutation analysis runs each
scenario's reference once (Recording) and judges every mutant by running only its translated half against the
replay (RecordedReference), which gives the comparison, cycle by cycle, exactly what the reference half would
have given: its compared values (kept as the changes from one cycle to the next, so a long run stays small), the
addresses it stored to through the index register from the cycle of the first store, the operands the
translation has no place for, the scenario's expectation failures, a fault and the values swept after the last
cycle."""

from __future__ import annotations

import dataclasses
from typing import Any, Protocol


class ReferenceHalf(Protocol):
    """What is recorded: the original program with its stimulus, expectations and compared values (see
    pipeline.ReferenceHalf, the same protocol)."""

    def step(self, cycle: int) -> str | None: ...
    def values(self) -> tuple[list, list]: ...
    def take_news(self) -> tuple[list, list, list]: ...
    def final_values(self) -> list: ...


Changes = tuple[tuple[int, Any], ...]          # (column index, new value) against the cycle before


@dataclasses.dataclass(frozen=True)
class Recording:
    """One scenario's reference run: per cycle the changes of the static and the indexed columns' values (the
    indexed list grows by `grown` values when the reference first stores to new addresses), the new indexed
    columns, the missing operands and expectation failures, a fault (cycle, text) that ended it, and the values of
    the sweep read after the last cycle (when it went through)."""

    cycles: int                                 # cycles recorded without a fault
    static: tuple[Changes, ...]
    indexed: tuple[tuple[Changes, tuple], ...]  # (changes, values of the columns added this cycle)
    columns: dict[int, list]                    # cycle -> new indexed columns (NewColumn)
    missing: tuple[tuple[int, Any], ...]        # (cycle, MissingOperand)
    failures: tuple[Any, ...]                   # ExpectationFailure, each naming its cycle
    fault: tuple[int, str] | None
    final: list


def _changes(before: list, after: list) -> Changes:
    if before == after:
        return ()
    return tuple((i, b) for i, (a, b) in enumerate(zip(before, after)) if a != b)


def record(half: ReferenceHalf, total: int) -> Recording:
    """Run the reference half through `total` cycles (or to its fault) and keep what the comparison reads."""
    static: list[Changes] = []
    indexed: list[tuple[Changes, tuple]] = []
    columns: dict[int, list] = {}
    missing: list = []
    failures: list = []
    last_static: list = []
    last_indexed: list = []
    fault = None
    for cycle in range(total):
        text = half.step(cycle)
        if text is not None:
            fault = (cycle, text)
            break
        now_static, now_indexed = half.values()
        new_columns, new_missing, new_failures = half.take_news()
        if new_columns:
            columns[cycle] = new_columns
        missing += [(cycle, m) for m in new_missing]
        failures += new_failures
        static.append(tuple(enumerate(now_static)) if cycle == 0 else _changes(last_static, now_static))
        kept = len(last_indexed)
        indexed.append((_changes(last_indexed, now_indexed[:kept]), tuple(now_indexed[kept:])))
        last_static, last_indexed = list(now_static), list(now_indexed)
    final = half.final_values() if fault is None else []
    return Recording(len(static), tuple(static), tuple(indexed), columns, tuple(missing), tuple(failures), fault,
                     final)


class RecordedReference:
    """A Recording replayed as the reference half of cosimulate's cycle loop (the interface of _LocalReference)."""

    def __init__(self, recording: Recording):
        self.recording = recording
        self.missing = list(recording.missing)
        self.failures = list(recording.failures)
        self._static: list = []
        self._indexed: list = []
        self._values = (self._static, self._indexed)

    def fault(self, cycle: int) -> str | None:
        rec = self.recording
        if cycle >= rec.cycles:
            if rec.fault is not None and rec.fault[0] == cycle:
                return rec.fault[1]
            raise IndexError(f"the recording ends before cycle {cycle}")
        static, indexed = self._static, self._indexed
        if cycle == 0:
            static.extend(value for _, value in rec.static[0])
        else:
            for i, value in rec.static[cycle]:
                static[i] = value
        changes, grown = rec.indexed[cycle]
        for i, value in changes:
            indexed[i] = value
        if grown:
            indexed.extend(grown)
        return None

    def new_columns(self, cycle: int) -> list:
        return self.recording.columns.get(cycle, [])

    def agrees(self, cycle: int, values: tuple[list, list]) -> bool:
        return self._values == values

    def values(self, cycle: int) -> tuple[list, list]:
        return self._values

    def coverage(self) -> None:
        return None

    def final_values(self) -> list:
        return self.recording.final

    def close(self) -> None:
        pass
