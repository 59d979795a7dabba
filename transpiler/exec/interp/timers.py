"""Timer and counter service of cycle phase 3; presets come from transpiler.language.presets."""

from __future__ import annotations

from typing import Mapping

from transpiler.exec.interp.state import nonzero_positions
from transpiler.language.semantics import Semantics


class TimerService:
    """Hidden timer/counter state and the phase-3 update of the T and C bit spaces."""

    def __init__(self, semantics: Semantics, timer_presets: Mapping[int, int], counter_presets: Mapping[int, int]):
        profile = semantics.profile
        self.t_first, self.t_last = profile.timer_start
        self.t_run = profile.timer_running[0] - self.t_first
        self.c_first, self.c_last = profile.counter_start
        self.c_run = profile.counter_running[0] - self.c_first
        self.c_rel = profile.counter_release[0] - self.c_first
        self.t_consumed = bool(semantics["timer_start_consumed"])
        self.t_restart = bool(semantics["timer_restart_while_running"])
        self.c_consumed = bool(semantics["counter_start_consumed"])
        self.c_edges = semantics["counter_counts"] == "rising_edges"
        nt = self.t_last - self.t_first + 1
        nc = self.c_last - self.c_first + 1
        self.t_preset = [timer_presets.get(self.t_first + i, 0) for i in range(nt)]
        self.c_preset = [counter_presets.get(self.c_first + i, 0) for i in range(nc)]
        self.rem = [0] * nt
        self.cnt = [0] * nc
        self.prev_release = bytearray(nc)
        # Timers and counters with rem/cnt > 0, and the running bits they show: the service touches only these
        # and the started ones, so idle timers and counters cost nothing.
        self.t_active: set[int] = set()
        self.c_active: set[int] = set()
        self.t_running = bytearray(nt)
        self.c_running = bytearray(nc)

    def idle_running_bits(self) -> frozenset[int]:
        """The running bits (T addresses) of the timers whose preset is 0: a start loads 0 remaining cycles, so the
        service never sets them (the presets are fixed for the machine's life)."""
        run = self.t_first + self.t_run
        return frozenset(run + i for i, preset in enumerate(self.t_preset) if preset <= 0)

    def service(self, T: bytearray, C: bytearray) -> None:
        self._timers(T)
        self._counters(C)

    def _timers(self, T: bytearray) -> None:
        first, n = self.t_first, len(self.rem)
        starts = T[first:first + n]
        rem, preset = self.rem, self.t_preset
        # Only started timers and running ones (rem > 0) can change: an idle timer stays as it is, and one left
        # below 0 by a negative preset neither counts down nor (without restart) starts again.
        touched = set(self.t_active)
        if starts.count(0) != n:
            touched.update(nonzero_positions(starts))
        for i in touched:
            started = starts[i]
            if started and (self.t_restart or rem[i] == 0):
                rem[i] = preset[i]
            elif rem[i] > 0:
                rem[i] -= 1
            if started and self.t_consumed:
                T[first + i] = 0
        _track(touched, rem, self.t_active, self.t_running)
        run = first + self.t_run
        T[run:run + n] = self.t_running       # also undoes any write of the program to a running bit

    def _counters(self, C: bytearray) -> None:
        first, n = self.c_first, len(self.cnt)
        starts = C[first:first + n]
        rel = first + self.c_rel
        release = C[rel:rel + n]
        cnt, prev_release = self.cnt, self.prev_release
        # As with timers: only started counters and running ones (cnt > 0) can change.
        touched = set(self.c_active)
        if starts.count(0) != n:
            touched.update(nonzero_positions(starts))
        for i in touched:
            if starts[i]:
                cnt[i] = self.c_preset[i]
                if self.c_consumed:
                    C[first + i] = 0
            elif cnt[i] > 0 and release[i] and (not self.c_edges or not prev_release[i]):
                cnt[i] -= 1
        prev_release[:] = release
        _track(touched, cnt, self.c_active, self.c_running)
        run = first + self.c_run
        C[run:run + n] = self.c_running


def _track(touched: set[int], remaining: list[int], active: set[int], running: bytearray) -> None:
    """After an update of the `touched` entries: `active` holds the entries with remaining > 0, `running` is 1
    exactly there."""
    for i in touched:
        if remaining[i] > 0:
            active.add(i)
            running[i] = 1
        else:
            active.discard(i)
            running[i] = 0

