"""What a reviewer needs to see of a divergence: the diverging operand on both sides over the cycles before it, the
inputs and NC actions of those cycles, and the source lines and ST lines that write the operand. A divergent run
is co-simulated once more (its shrunk stimulus where shrinking found one) with every cycle recorded."""

from __future__ import annotations

import dataclasses
import re
from typing import Callable, Mapping, Sequence

from transpiler.backends.report.iomap import IoMap
from transpiler.ir import Program
from transpiler.verify.cosim import StSide, comparison_for, cosimulate
from transpiler.verify.scenario import NameTable, Scenario
from transpiler.verify.simulate import operand_writers
from transpiler.verify.stimulus import build_stimulus

WINDOW = 40           # cycles shown before the divergence


@dataclasses.dataclass(frozen=True)
class DivergenceTrace:
    run: str                                   # the run as equiv reports it
    replayed: str                              # the stimulus replayed: the run's own, or its shrunk one
    cycle: int                                 # the divergence's cycle in the replayed stimulus
    name: str
    operand: str
    cycles: tuple[int, ...]
    original: tuple[int | str, ...]           # the operand on each side, cycle by cycle
    translated: tuple[int | str, ...]
    inputs: tuple[tuple[int, str, int | str], ...]    # (cycle, name, value) written before those cycles ran
    nc: tuple[tuple[int, str], ...]                   # (cycle, action) of the NC model
    source_lines: tuple[str, ...]              # file:line of the instructions that write the operand
    st_lines: tuple[tuple[int, str], ...]      # (line, text) of project.st statements that assign its variable


def trace_divergence(program: Program, make_side: Callable[[], StSide], iomap: IoMap, names: NameTable,
                     run: str, scenario: Scenario, st_text: str, base_mp: Mapping | None = None
                     ) -> DivergenceTrace | None:
    """Replay `scenario` recording every cycle; None when the replay does not diverge (the run diverged through
    something else, such as a fault)."""
    rows: list[tuple[int, Sequence, Sequence]] = []
    result = cosimulate(program, make_side, iomap, scenario, names, record=lambda c, a, b: rows.append((c, a, b)),
                        base_mp=base_mp)
    divergence = result.divergence
    if divergence is None:
        return None
    columns = list(comparison_for(program, names, iomap).columns)
    index = next((i for i, (name, _) in enumerate(columns) if name == divergence.name), None)
    first = max(0, divergence.cycle - WINDOW)
    shown = [row for row in rows if first <= row[0] <= divergence.cycle]
    if index is not None and shown:
        cycles = tuple(row[0] for row in shown)
        original = tuple(row[1][index] for row in shown)
        translated = tuple(row[2][index] for row in shown)
    else:
        # An address reached through the index register is no static column: only its diverging cycle is known.
        cycles, original, translated = (divergence.cycle,), (divergence.original,), (divergence.translated,)
    stimulus = build_stimulus(scenario, names)
    inputs = tuple((c, w.name, w.value) for c in range(first, divergence.cycle + 1) for w in stimulus.writes(c))
    nc = tuple((c, ", ".join(f"{k}: {v}" for k, v in action.items()))
               for c in range(first, divergence.cycle + 1) for action in stimulus.nc_actions(c))
    ref = columns[index][1] if index is not None else None
    sources = tuple(str(span) for span in operand_writers(program).get(ref, ())) if ref is not None else ()
    row = iomap.by_operand.get(divergence.operand)
    variable = row.iec if row is not None else divergence.name
    return DivergenceTrace(run, scenario.name, divergence.cycle, divergence.name, divergence.operand, cycles,
                           original, translated, inputs, nc, sources, _assignments(st_text, variable))


def _assignments(st_text: str, variable: str) -> tuple[tuple[int, str], ...]:
    """The lines of `st_text` that assign `variable` (a member or element of it included)."""
    target = re.compile(rf"(?<![\w.])(?:\w+\.)?{re.escape(variable)}(?:\[[^\]]*\]|\.\w+)*\s*:=", re.IGNORECASE)
    return tuple((number, line.strip()) for number, line in enumerate(st_text.splitlines(), start=1)
                 if target.search(line))
