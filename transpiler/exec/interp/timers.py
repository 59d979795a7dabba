"""Timer and counter service of cycle phase 3; presets come from transpiler.language.presets."""

from __future__ import annotations

from typing import Mapping

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

    def service(self, T: bytearray, C: bytearray) -> None:
        self._timers(T)
        self._counters(C)

    def _timers(self, T: bytearray) -> None:
        first, n = self.t_first, len(self.rem)
        starts = T[first:first + n]
        rem = self.rem
        # Only timers that are started or still running change; the rest stay at rem = 0.
        for i in (i for i in range(n) if starts[i] or rem[i]):
            started = starts[i]
            if started and (self.t_restart or rem[i] == 0):
                rem[i] = self.t_preset[i]
            elif rem[i] > 0:
                rem[i] -= 1
            if started and self.t_consumed:
                T[first + i] = 0
        run = first + self.t_run
        T[run:run + n] = bytes(1 if r > 0 else 0 for r in rem)

    def _counters(self, C: bytearray) -> None:
        first, n = self.c_first, len(self.cnt)
        starts = C[first:first + n]
        rel = first + self.c_rel
        release = C[rel:rel + n]
        cnt = self.cnt
        for i in (i for i in range(n) if starts[i] or cnt[i] or release[i] != self.prev_release[i]):
            if starts[i]:
                cnt[i] = self.c_preset[i]
                if self.c_consumed:
                    C[first + i] = 0
            elif cnt[i] > 0 and release[i] and (not self.c_edges or not self.prev_release[i]):
                cnt[i] -= 1
        self.prev_release[:] = release
        run = first + self.c_run
        C[run:run + n] = bytes(1 if c > 0 else 0 for c in cnt)
