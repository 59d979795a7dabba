"""The reference half of a co-simulation in a process of its own, running ahead of the translated half.

The two halves of a co-simulation never feed each other: each runs its own program, environment model and
system context on the same stimulus. So the reference interpreter can run in a forked process while this process
runs the translated program, and the two meet only at the comparison. Per cycle the reference process sends a
digest of the values it compared (Python's hash of the value tuples); this process hashes the translated values
the same way. Equal values always give equal digests, so a cycle whose digests agree needs nothing more. Where
they differ, the values themselves are fetched from the reference process, which keeps every cycle not yet
acknowledged, and the divergence is located exactly as the lockstep run locates it. Two different value lists
with equal 64-bit digests would hide that cycle's difference: a chance of 2**-64 per cycle, and a difference that
persists shows again in the next cycle.

The reference process runs at most a few batches ahead, so what it keeps stays small, and it is killed when this
process has what it needs (a run that stops early needs nothing more from it)."""

from __future__ import annotations

import dataclasses
import multiprocessing
import os
import traceback
from array import array
from typing import Any, Protocol

BATCH = 128                 # cycles per message from the reference process
AHEAD = 4 * BATCH           # cycles the reference may run beyond the last one acknowledged


class ReferenceHalf(Protocol):
    """What the reference process runs: the original program with its stimulus, expectations and compared values."""

    def step(self, cycle: int) -> str | None: ...            # run one cycle; a fault's text, or None
    def values(self) -> tuple[list, list]: ...               # compared values now: static columns, indexed columns
    def take_news(self) -> tuple[list, list, list]: ...      # new indexed columns, missing operands, failures
    def coverage(self) -> Any: ...                           # the machine's coverage (None without)
    def final_values(self) -> list: ...                      # values read once after the last cycle


def fork_available() -> bool:
    """Whether this platform can fork the reference process (Linux and other Unix systems)."""
    return "fork" in multiprocessing.get_all_start_methods()


def worthwhile() -> bool:
    """Whether a reference process can run beside this one: fork is available and 2 or more CPUs are ours."""
    try:
        cpus = len(os.sched_getaffinity(0))
    except AttributeError:                       # no affinity call on this platform
        cpus = os.cpu_count() or 1
    return cpus >= 2 and fork_available()


@dataclasses.dataclass
class _Batch:
    """What one message of the reference process says about its cycles `first` .. `first + len(digests) - 1`."""

    first: int
    digests: array
    columns: list                   # (cycle, [new indexed column, ...]) in cycle order
    missing: list                   # (cycle, operand the translation has no place for)
    failures: list                  # expectation failures (each names its cycle)


def digest(values: tuple[list, list]) -> int:
    """The hash both halves compute of one cycle's compared values."""
    return hash((tuple(values[0]), tuple(values[1])))


def _serve(conn, half: ReferenceHalf, total: int) -> None:
    """The reference process: run every cycle, send digests in batches, answer requests for values."""
    kept: dict[int, tuple[list, list]] = {}
    acknowledged = 0
    end: tuple[int, str] | None = None

    def handle(message) -> None:
        nonlocal acknowledged
        kind, cycle = message
        if kind == "ack":
            for c in range(acknowledged, cycle):
                kept.pop(c, None)
            acknowledged = max(acknowledged, cycle)
        elif kind == "values":
            conn.send(("values", cycle, kept[cycle]))

    try:
        cycle = 0
        while cycle < total and end is None:
            first = cycle
            digests = array("q")
            columns: list = []
            missing: list = []
            failures: list = []
            while cycle < min(first + BATCH, total):
                fault = half.step(cycle)
                if fault is not None:
                    end = (cycle, fault)
                    break
                values = half.values()
                new_columns, new_missing, new_failures = half.take_news()
                if new_columns:
                    columns.append((cycle, new_columns))
                missing += [(cycle, m) for m in new_missing]
                failures += new_failures
                kept[cycle] = values
                digests.append(digest(values))
                cycle += 1
            conn.send(("batch", _Batch(first, digests, columns, missing, failures)))
            while conn.poll():
                handle(conn.recv())
            while cycle - acknowledged > AHEAD:
                handle(conn.recv())
        conn.send(("end", end, (half.coverage(), half.final_values()) if end is None else (None, [])))
        while True:
            handle(conn.recv())
    except EOFError:
        return
    except BaseException:  # noqa: BLE001 - whatever went wrong is told to the other side, which raises it
        try:
            conn.send(("crash", traceback.format_exc()))
        except OSError:
            pass


class ReferenceProcessFailed(RuntimeError):
    """The reference process ended without an answer (a bug in the interpreter, or it was killed)."""


class PipelinedReference:
    """The other end of _serve: per cycle, a fault or the digest to compare against, and values on request."""

    def __init__(self, half: ReferenceHalf, total: int):
        context = multiprocessing.get_context("fork")
        self._conn, child = context.Pipe()
        self._process = context.Process(target=_serve, args=(child, half, total), daemon=True)
        self._process.start()
        child.close()
        self._digests = array("q")
        self._columns: dict[int, list] = {}
        self.missing: list = []
        self.failures: list = []
        # (fault, (coverage, final values)) once the run ended
        self._end: tuple[tuple[int, str] | None, tuple[Any, list]] | None = None
        self._values: dict[int, tuple[list, list]] = {}
        self._acknowledged = 0

    def _receive(self) -> None:
        try:
            kind, *rest = self._conn.recv()
        except EOFError:
            raise ReferenceProcessFailed("the reference interpreter's process ended without an answer") from None
        if kind == "batch":
            batch: _Batch = rest[0]
            self._digests.extend(batch.digests)
            for cycle, columns in batch.columns:
                self._columns[cycle] = columns
            self.missing += batch.missing
            self.failures += batch.failures
        elif kind == "end":
            self._end = (rest[0], rest[1])
        elif kind == "values":
            self._values[rest[0]] = rest[1]
        else:
            raise ReferenceProcessFailed(f"the reference interpreter failed:\n{rest[0]}")

    def fault(self, cycle: int) -> str | None:
        """Wait until cycle `cycle` of the reference is known; the fault text if the reference faulted in it."""
        while len(self._digests) <= cycle:
            if self._end is not None:
                fault = self._end[0]
                if fault is not None and fault[0] == cycle:
                    return fault[1]
                raise ReferenceProcessFailed(f"the reference interpreter stopped before cycle {cycle}")
            self._receive()
        return None

    def new_columns(self, cycle: int) -> list:
        return self._columns.pop(cycle, [])

    def agrees(self, cycle: int, values: tuple[list, list]) -> bool:
        same = self._digests[cycle] == digest(values)
        if (cycle + 1) % BATCH == 0 and cycle + 1 > self._acknowledged:
            self._acknowledged = cycle + 1
            self._conn.send(("ack", cycle + 1))
        return same

    def values(self, cycle: int) -> tuple[list, list]:
        """The reference's compared values of `cycle` (not yet acknowledged), fetched from its process."""
        self._conn.send(("values", cycle))
        while cycle not in self._values:
            self._receive()
        return self._values.pop(cycle)

    def coverage(self) -> Any:
        """The coverage of a run that went through all its cycles (the reference process sends it at its end)."""
        while self._end is None:
            self._receive()
        return self._end[1][0]

    def final_values(self) -> list:
        """The values read after the last cycle of a run that went through all its cycles."""
        while self._end is None:
            self._receive()
        return self._end[1][1]

    def close(self) -> None:
        self._process.kill()
        self._process.join()
        self._conn.close()
