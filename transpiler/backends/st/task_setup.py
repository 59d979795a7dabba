"""The cyclic task a target must run, described for the user where the files cannot carry it.

A PLCopen import into CODESYS or TwinCAT creates no task, so the task (name, interval, priority and the programs it
calls, in order) is written out as plain sentences: in project.st's closing comment, in the README.md of the output
and in report.md. The sentences carry no markup so that each of those places can wrap them as it needs.
"""

from __future__ import annotations

import dataclasses

from transpiler.backends.iec_model import IecProject
from transpiler.backends.st.dialect import TargetProject


@dataclasses.dataclass(frozen=True)
class TaskSetup:
    """One cyclic task as the IDE's task configuration needs it."""

    name: str
    interval_ms: int
    priority: int
    programs: tuple[str, ...]       # the PROGRAM POUs it calls each cycle, in this order
    instances: tuple[str, ...] = () # their program instances, in the same order

    @property
    def interval(self) -> str:
        return f"T#{self.interval_ms}ms"


def task_setups(project: IecProject) -> tuple[TaskSetup, ...]:
    """The tasks of the project's configuration with the programs each calls (a library has none)."""
    conf = project.configuration
    def called(task: str) -> list:
        return [inst for inst in conf.instances if inst.task == task]
    return tuple(TaskSetup(task.name, task.interval_ms, task.priority,
                           tuple(inst.type_name for inst in called(task.name)),
                           tuple(inst.name for inst in called(task.name)))
                 for task in conf.tasks)


def task_lines(target: TargetProject) -> tuple[str, ...]:
    """Plain sentences (no markup) that say which task to create and what it calls, one task after the other."""
    lines: list[str] = []
    for setup in task_setups(target.project):
        lines.append(f"Task {setup.name}: cyclic, interval {setup.interval}, priority {setup.priority}.")
        lines += _call_lines(setup.programs)
    return tuple(lines)


def _call_lines(programs: tuple[str, ...]) -> list[str]:
    if not programs:
        return []
    if len(programs) == 1:
        return [f"It calls the program {programs[0]} once per cycle."]
    # The order carries meaning (the submit-job program works on what the main program queued in the same cycle),
    # so it is spelled out rather than left to the IDE's default order of calls.
    lines = [f"It calls these programs once per cycle, in this order: {', '.join(programs)}."]
    if len(programs) == 2:
        lines.append(f"{programs[1]} must run in this same task right after {programs[0]}; call neither from "
                     "another task.")
    else:
        lines.append("Each must run in this same task right after the one before it; call none of them from "
                     "another task.")
    return lines
