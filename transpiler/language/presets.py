"""Timer and counter presets from machine parameters: MP4110/MP4120 values to PLC cycles, exact decimals."""

from __future__ import annotations

from decimal import Decimal
from typing import Mapping

from transpiler.diagnostics import Diagnostics, Span
from transpiler.language.semantics import Semantics

MpKey = tuple[int, int]
TIMER_MP, COUNTER_MP = 4110, 4120


def preset_cycles(value: Decimal, unit: str, cycle_time_ms: int) -> int | None:
    """P = ceil(t / cycle time) for seconds, the value itself for cycles; None when the value is unusable."""
    if value < 0:
        return None
    if unit == "seconds":
        num, den = value.as_integer_ratio()
        return -(-(num * 1000) // (den * cycle_time_ms))
    if value != value.to_integral_value():
        return None
    return int(value)


def load_presets(mp: Mapping[MpKey, Decimal], semantics: Semantics, cycle_time_ms: int, diags: Diagnostics,
                 spans: Mapping[MpKey, Span] | None = None) -> tuple[dict[int, int], dict[int, int]]:
    """Timer presets (MP4110.n) and counter presets (MP4120.n, always cycles, A-36) in cycles; errors -> E-MP-VALUE."""
    profile = semantics.profile
    timers: dict[int, int] = {}
    counters: dict[int, int] = {}
    where = spans or {}
    for (number, index), value in mp.items():
        if number == TIMER_MP and profile.timer_start[0] <= index <= profile.timer_start[1]:
            unit, target = semantics["timer_unit"], timers
        elif number == COUNTER_MP and profile.counter_start[0] <= index <= profile.counter_start[1]:
            unit, target = "cycles", counters
        else:
            continue
        cycles = preset_cycles(value, unit, cycle_time_ms)
        if cycles is None:
            span = where.get((number, index), Span("<machine parameters>", 1, 1))
            need = "a whole number of PLC cycles" if unit == "cycles" else "a duration in seconds"
            diags.report("E-MP-VALUE", span, f"MP{number}.{index} = {value}: expected {need} ≥ 0 "
                        f"(profile {profile.name}, timer_unit {semantics['timer_unit']})")
            continue
        target[index] = cycles
    return timers, counters
