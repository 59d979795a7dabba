"""The mutation judge of a construct project (samples/constructs/NAME) under its scenario and a few generated
cycles, for the tests of mutant schemata and judging (test_mutate_speed, test_matiec_schema)."""

from __future__ import annotations

from pathlib import Path
from typing import Callable

from transpiler import api
from transpiler.api import _load_scenarios, _translate
from transpiler.backends.report.report import io_map_of
from transpiler.exec.interp import compile_program
from transpiler.verify.guided import generate
from transpiler.verify.mutate import NEVER_INFECTED, Judge
from transpiler.verify.simulate import project_names

CONSTRUCTS = Path(__file__).resolve().parents[1] / "samples" / "constructs"


def construct_parts(name: str, random_cycles: int = 300):
    """(project, translation, names, runs shortest first, base machine parameters) of construct `name`."""
    folder = CONSTRUCTS / name
    project = api.load_project(api.project_options(folder), api.semantics_for(scenario=folder / "scenario.yaml"))
    mp_path, mp, transpiled, diags = _translate(project, {"st"}, None, False)
    names = project_names(project.program)
    loaded = _load_scenarios(project, [folder / "scenario.yaml"], names, diags)
    loaded += generate(project.program, names, random_cycles, 1, loaded, machine_parameters=mp_path, base_mp=mp)
    # as `hh2iec mutate` gives them: None where the project has no machine-parameter file
    return project, transpiled, names, sorted(loaded, key=lambda s: s.cycles), mp if mp_path is not None else None


def construct_judge(name: str, side_factory: Callable, schema_factory: Callable | None = None,
                    random_cycles: int = 300) -> Judge:
    """The judge of construct `name`; `side_factory(translation)` and `schema_factory(translation)` give the
    backend's factories for that translation."""
    project, transpiled, names, scenarios, mp = construct_parts(name, random_cycles)
    return Judge(project.program, io_map_of(transpiled.result), names, scenarios, transpiled.st_text,
                 side_factory(transpiled), compile_program(project.program), mp,
                 schema_factory and schema_factory(transpiled))


def plain(verdict) -> tuple[str, str]:
    """What must not change: the outcome and, for every mutant that ran, its killer or message."""
    return verdict.outcome, "" if verdict.by == NEVER_INFECTED else verdict.by
