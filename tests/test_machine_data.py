"""The scenario's `machine` data (axes, drives, tool/pocket tables) reaches the PLC module models of both the
reference interpreter and the translated program, at the start and in the cycle of each event."""

from __future__ import annotations

import textwrap
from pathlib import Path

from transpiler import api

PROGRAM = """\
PS    K0
PS    K2
CM    9049              ; actual position of axis 1 (X)
PL    D0
PS    K1
PS    K2
CM    9049              ; axis 2
PL    D4
PS    K-1
CM    9161              ; enable every drive
CM    9162              ; drives ready
PL    W8
EM
"""

SCENARIO = """\
name: machine
cycles: 6
machine:
  axes: {0: {position: 1250000}, 1: {position: -5000}}
  drives: {available: 5}
events:
  - {cycle: 3, machine: {axes: {0: {position: 1300000}}, drives: {available: 1}}}
expect:
  - {cycle: 0, values: {D0: 1250000, D4: -5000, W8: 5}}
  - {cycle: 2, values: {D0: 1250000, W8: 5}}
  - {cycle: 3, values: {D0: 1300000, D4: -5000, W8: 1}}
"""


def _project(tmp_path: Path):
    (tmp_path / "main.src").write_text(PROGRAM, encoding="utf-8")
    (tmp_path / "machine.yaml").write_text(textwrap.dedent(SCENARIO), encoding="utf-8")
    return api.load_project(api.project_options(tmp_path / "main.src")), tmp_path / "machine.yaml"


def test_machine_data_and_its_events_reach_the_interpreter(tmp_path):
    project, scenario = _project(tmp_path)
    run = api.simulate(project, scenario).run
    assert run.failures == [] and run.cycles_run == 6


def test_machine_events_reach_the_translated_program_too(tmp_path):
    # Catches: the event applied to the interpreter's context only (the translated side would keep reading
    # 1250000 from cycle 3 on: a divergence), or the initial data missing from the translated side's copy.
    project, scenario = _project(tmp_path)
    result = api.check_equivalence(project, scenarios=[scenario], backend="builtin")
    assert result.equivalent, result.result


STATUS_PROGRAM = """\
LN    M10
IFT
SUBM  Status_job
=     W20
L     K1
=     M10
ENDI
EM

LBL Status_job
PS    K1
CM    9035              ; NC status information 1
PL    W12
PS    K50
CM    9035
PL    W14
EM
"""

STATUS_SCENARIO = """\
name: status
cycles: 4
machine:
  status: {1: 42, 50: -3}
expect:
  - {cycle: 3, values: {W12: 42, W14: -3}}
"""


def test_nc_status_information_reaches_both_sides(tmp_path):
    # Catches: `status` not applied (9035 reads 0), or applied to one side only (a divergence).
    (tmp_path / "main.src").write_text(STATUS_PROGRAM, encoding="utf-8")
    (tmp_path / "status.yaml").write_text(STATUS_SCENARIO, encoding="utf-8")
    project = api.load_project(api.project_options(tmp_path / "main.src"))
    run = api.simulate(project, tmp_path / "status.yaml").run
    assert run.failures == [] and run.cycles_run == 4
    result = api.check_equivalence(project, scenarios=[tmp_path / "status.yaml"], backend="builtin")
    assert result.equivalent, result.result
