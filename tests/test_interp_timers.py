"""The timer and counter service touches only started and running timers and counters; over random start, release
and stray writes it must give what a pass over every timer and counter gives."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from transpiler.exec.interp.timers import TimerService
from transpiler.language.semantics import make_semantics


class EveryTimerService:
    """The service as a plain pass over every timer and counter each cycle (what TimerService must match)."""

    def __init__(self, service: TimerService):
        self.s = service
        self.rem = [0] * len(service.rem)
        self.cnt = [0] * len(service.cnt)
        self.prev_release = bytearray(len(service.cnt))

    def service(self, T: bytearray, C: bytearray) -> None:
        s = self.s
        first, n = s.t_first, len(self.rem)
        starts = T[first:first + n]
        for i in range(n):
            if starts[i] and (s.t_restart or self.rem[i] == 0):
                self.rem[i] = s.t_preset[i]
            elif self.rem[i] > 0:
                self.rem[i] -= 1
            if starts[i] and s.t_consumed:
                T[first + i] = 0
        T[first + s.t_run:first + s.t_run + n] = bytes(1 if r > 0 else 0 for r in self.rem)
        first, n = s.c_first, len(self.cnt)
        starts = C[first:first + n]
        release = C[first + s.c_rel:first + s.c_rel + n]
        for i in range(n):
            if starts[i]:
                self.cnt[i] = s.c_preset[i]
                if s.c_consumed:
                    C[first + i] = 0
            elif self.cnt[i] > 0 and release[i] and (not s.c_edges or not self.prev_release[i]):
                self.cnt[i] -= 1
        self.prev_release[:] = release
        C[first + s.c_run:first + s.c_run + n] = bytes(1 if c > 0 else 0 for c in self.cnt)


# One cycle: writes (space T or C, address, value) before the service. Addresses below 24 are the start operands
# of the timers and counters with presets (every third timer, every second counter up to 21), 96..119 counter
# release operands, any other address a stray write (of a running bit, say).
address = st.one_of(st.integers(0, 23), st.integers(96, 119), st.integers(0, 400))
writes = st.lists(st.tuples(st.sampled_from("TC"), address, st.integers(0, 3)), max_size=8)


@settings(max_examples=150, deadline=None)
@given(profile=st.sampled_from(["itnc530", "tv", "tnc426"]), consumed=st.booleans(), restart=st.booleans(),
       counter_consumed=st.booleans(), edges=st.booleans(), presets=st.lists(st.integers(-2, 6), min_size=8, max_size=8),
       cycles=st.lists(writes, max_size=40))
def test_the_active_sets_give_a_pass_over_every_timer_and_counter(profile, consumed, restart, counter_consumed, edges,
                                                                  presets, cycles) -> None:
    sem = make_semantics(profile, {"timer_start_consumed": consumed, "timer_restart_while_running": restart,
                                   "counter_start_consumed": counter_consumed,
                                   "counter_counts": "rising_edges" if edges else "cycles"})
    p = sem.profile
    # a few timers and counters with presets; the others have preset 0
    timer_presets = {p.timer_start[0] + i * 3: v for i, v in enumerate(presets)}
    counter_presets = {p.counter_start[0] + i * 2: v for i, v in enumerate(presets)}
    service = TimerService(sem, timer_presets, counter_presets)
    reference = EveryTimerService(service)
    size_t = max(p.timer_running[0] + len(service.rem), p.timer_start[1] + 1)
    size_c = max(p.counter_running[0], p.counter_release[0]) + len(service.cnt)
    spaces = {"T": (bytearray(size_t), bytearray(size_t)), "C": (bytearray(size_c), bytearray(size_c))}
    for cycle_writes in cycles:
        for kind, addr, value in cycle_writes:
            for space in spaces[kind]:
                # mostly start and release operands, sometimes any other bit (a running bit the program wrote)
                space[addr % len(space)] = value
        service.service(spaces["T"][0], spaces["C"][0])
        reference.service(spaces["T"][1], spaces["C"][1])
        assert spaces["T"][0] == spaces["T"][1]
        assert spaces["C"][0] == spaces["C"][1]
        assert service.rem == reference.rem and service.cnt == reference.cnt
