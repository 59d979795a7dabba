"""The reference half of a co-simulation in a process of its own, running ahead of the translated half.

The two halves of a co-simulation never feed each other: each runs its own program, environment model and
system context on the same stimulus. So the reference interpreter can run in a forked process while this process
runs the translated program, and the two meet only at the comparison: the reference process sends, batch by
batch, the values it read after each cycle (with the indexed columns, missing operands and expectation failures
found on the way), and this process compares them with the translated side's values exactly as the lockstep run
does. The pipe between them bounds how far the reference runs ahead: a send blocks while a few batches wait
unread. The reference process is killed when this process has what it needs (a run that stops early needs
nothing more from it)."""

from __future__ import annotations

import collections
import marshal
import multiprocessing
import os
import pickle
import traceback
from typing import Any, Protocol

BATCH = 128                 # cycles per message from the reference process


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


def _serve(conn, half: ReferenceHalf, total: int) -> None:
    """The reference process: run every cycle and send what it compares, batch by batch, then the run's end."""
    end: tuple[int, str] | None = None
    try:
        cycle = 0
        while cycle < total and end is None:
            values: list = []           # per cycle: (static column values, indexed column values)
            columns: list = []          # (cycle, [new indexed column, ...]) in cycle order
            missing: list = []          # (cycle, operand the translation has no place for)
            failures: list = []         # expectation failures (each names its cycle)
            last = min(cycle + BATCH, total)
            while cycle < last:
                fault = half.step(cycle)
                if fault is not None:
                    end = (cycle, fault)
                    break
                values.append(half.values())
                new_columns, new_missing, new_failures = half.take_news()
                if new_columns:
                    columns.append((cycle, new_columns))
                missing += [(cycle, m) for m in new_missing]
                failures += new_failures
                cycle += 1
            # The values (ints and texts) travel as marshal data, which is quicker both ways than pickle; the
            # rarer findings, which are objects, are pickled. Batches come in cycle order.
            news = (columns, missing, failures)
            conn.send_bytes(marshal.dumps(("batch", values, pickle.dumps(news) if any(news) else None)))
        final = (half.coverage(), half.final_values()) if end is None else (None, [])
        conn.send_bytes(marshal.dumps(("end", pickle.dumps((end, final)))))
    except (BrokenPipeError, EOFError):
        return
    except BaseException:  # noqa: BLE001 - whatever went wrong is told to the other side, which raises it
        try:
            conn.send_bytes(marshal.dumps(("crash", traceback.format_exc())))
        except OSError:
            pass


class ReferenceProcessFailed(RuntimeError):
    """The reference process ended without an answer (a bug in the interpreter, or it was killed)."""


class PipelinedReference:
    """The other end of _serve: per cycle, in order, a fault or the values to compare against."""

    def __init__(self, half: ReferenceHalf, total: int):
        context = multiprocessing.get_context("fork")
        self._conn, child = context.Pipe()
        self._process = context.Process(target=_serve, args=(child, half, total), daemon=True)
        self._process.start()
        child.close()
        self._values: collections.deque = collections.deque()      # values of cycles `_first` .. received
        self._first = 0
        self._columns: dict[int, list] = {}
        self.missing: list = []
        self.failures: list = []
        self._end: tuple[tuple[int, str] | None, tuple[Any, list]] | None = None     # (fault, (coverage, final))

    def _receive(self) -> None:
        try:
            kind, *rest = marshal.loads(self._conn.recv_bytes())
        except EOFError:
            raise ReferenceProcessFailed("the reference interpreter's process ended without an answer") from None
        if kind == "batch":
            values, news = rest
            self._values.extend(values)
            if news is not None:
                columns, missing, failures = pickle.loads(news)
                for cycle, new in columns:
                    self._columns[cycle] = new
                self.missing += missing
                self.failures += failures
        elif kind == "end":
            self._end = pickle.loads(rest[0])
        else:
            raise ReferenceProcessFailed(f"the reference interpreter failed:\n{rest[0]}")

    def fault(self, cycle: int) -> str | None:
        """Wait until cycle `cycle` of the reference is known (cycles come in order; the earlier ones are dropped);
        the fault text if the reference faulted in it."""
        while self._first + len(self._values) <= cycle:
            if self._end is not None:
                fault = self._end[0]
                if fault is not None and fault[0] == cycle:
                    return fault[1]
                raise ReferenceProcessFailed(f"the reference interpreter stopped before cycle {cycle}")
            self._receive()
        while self._first < cycle:
            self._values.popleft()
            self._first += 1
        return None

    def new_columns(self, cycle: int) -> list:
        return self._columns.pop(cycle, [])

    def agrees(self, cycle: int, values: tuple[list, list]) -> bool:
        return self._values[0] == values

    def values(self, cycle: int) -> tuple[list, list]:
        return self._values[0]

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
