"""The submit-job queue of the simulation model (ASSUMPTION A-45): identifiers, RPLY states, CAN, scheduling."""

from __future__ import annotations

import dataclasses
from typing import Callable

MAX_QUEUED = 8
MAX_ID = 255
REPLY_STATES = (0, 1, 2)        # what RPLY gives: finished or unknown, running, waiting


@dataclasses.dataclass(frozen=True)
class Job:
    ident: int
    func: Callable[[int], None]      # generated file function
    block: int                       # block id of the job's label inside that function
    label: str
    cycle: int                       # cycle in which SUBM queued it


class SubmitQueue:
    """FIFO of queued jobs; `same_cycle` runs them in phase 5 of the submitting cycle, `next_cycle` one cycle later."""

    def __init__(self, model: str):
        self.model = model
        self.queued: list[Job] = []
        self.running: Job | None = None
        self.next_id = 1

    def submit(self, func: Callable[[int], None], block: int, label: str, cycle: int) -> int:
        """SUBM: the new identifier 1..255, or 0 when the queue is full or SUBM runs inside a job."""
        if self.running is not None or len(self.queued) >= MAX_QUEUED:
            return 0
        in_use = {j.ident for j in self.queued}
        ident = self.next_id
        while ident in in_use:       # at most MAX_QUEUED identifiers are in use, so this ends
            ident = ident % MAX_ID + 1
        self.next_id = ident % MAX_ID + 1
        self.queued.append(Job(ident, func, block, label, cycle))
        return ident

    def reply(self, ident: int) -> int:
        """RPLY: 0 finished or unknown, 1 running, 2 waiting in the queue."""
        finished, running, waiting = REPLY_STATES
        if self.running is not None and self.running.ident == ident:
            return running
        return waiting if any(j.ident == ident for j in self.queued) else finished

    def cancel(self, ident: int) -> bool:
        """CAN: drop a queued job; True when `ident` is the running job (the caller unwinds it)."""
        self.queued = [j for j in self.queued if j.ident != ident]
        return self.running is not None and self.running.ident == ident

    def take(self, cycle: int) -> Job | None:
        """The next job to run in phase 5 of `cycle` (FIFO), or None."""
        for i, job in enumerate(self.queued):
            if self.model == "same_cycle" or job.cycle < cycle:
                return self.queued.pop(i)
        return None

    def state(self) -> tuple:
        return (tuple(self.queued), self.running, self.next_id)

    def restore(self, state: tuple) -> None:
        queued, self.running, self.next_id = state
        self.queued = list(queued)
