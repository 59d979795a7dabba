"""The pipelined co-simulation (the reference interpreter in a forked process, sending its values in batches) gives the same
result as the lockstep one: verdict, divergence, cycles run, coverage, indexed columns, missing operands, faults
and expectation failures, on equivalent runs and on runs that end early."""

from __future__ import annotations

import re

import pytest

from transpiler.diagnostics import Diagnostics
from transpiler.frontend.load import ProjectOptions
from transpiler.frontend.pipeline import compile_project
from transpiler.language.semantics import make_semantics
from transpiler.backends.report.report import io_map_of
from transpiler.backends.st.check import find_iec2c
from transpiler.backends.transpile import transpile_program
from transpiler.exec.interp import compile_program
from transpiler.verify import pipeline
from transpiler.verify.cosim import builtin_side_factory, cosimulate
from transpiler.verify.equiv import random_scenario
from transpiler.verify.scenario import load_scenario
from transpiler.verify.simulate import project_names

from test_st_backend import SAMPLE, transpile_sample

pytestmark = pytest.mark.skipif(not pipeline.fork_available(),
                                reason="no fork start method: co-simulation runs in lockstep")


def _both(program, factory, iomap, scenario, names, **kwargs):
    compiled = compile_program(program, coverage=True, exact=False)
    lockstep = cosimulate(program, factory, iomap, scenario, names, coverage=True, compiled=compiled, **kwargs)
    piped = cosimulate(program, factory, iomap, scenario, names, coverage=True, compiled=compiled, pipelined=True,
                       **kwargs)
    return lockstep, piped


def _assert_same(lockstep, piped):
    assert piped.cycles_run == lockstep.cycles_run
    assert piped.divergence == lockstep.divergence
    assert piped.error == lockstep.error and piped.error_side == lockstep.error_side
    assert piped.compared_indexed == lockstep.compared_indexed and piped.swept == lockstep.swept
    assert piped.missing == lockstep.missing
    assert piped.expectation_failures == lockstep.expectation_failures
    assert lockstep.coverage is not None and piped.coverage == lockstep.coverage


@pytest.fixture(scope="module")
def sample():
    program, out = transpile_sample()
    return program, out, io_map_of(out.result), project_names(program)


def test_equivalent_run_gives_the_same_result_and_coverage(sample):
    program, out, iomap, names = sample
    scenario = random_scenario(program, names, 1500, seed=5, machine_parameters=SAMPLE / "MP_data.mp")
    lockstep, piped = _both(program, builtin_side_factory(out.st_text), iomap, scenario, names)
    assert lockstep.equivalent and lockstep.cycles_run == 1500
    # a complete pipelined run keeps no machine of this process (its reference ran in the other one): proof that
    # the pipelined path ran, so the comparison below is not of lockstep with itself
    assert piped.machine is None and lockstep.machine is not None
    _assert_same(lockstep, piped)


def test_divergence_is_found_at_the_same_cycle_and_operand(sample):
    """A translation that ignores the door for the flood pump: found at the same cycle and operand."""
    program, out, iomap, names = sample
    broken, count = re.subn(r"O_coolant_flood := ML_sel\.flood AND MG_control_ok AND I_door_closed;",
                            "O_coolant_flood := ML_sel.flood AND MG_control_ok OR I_door_closed;", out.st_text)
    assert count == 1, "the mutation site moved: update the test"
    scenario = random_scenario(program, names, 3000, seed=2, machine_parameters=SAMPLE / "MP_data.mp")
    lockstep, piped = _both(program, builtin_side_factory(broken), iomap, scenario, names)
    assert lockstep.divergence is not None and lockstep.cycles_run < 3000
    _assert_same(lockstep, piped)
    assert piped.machine is not None            # coverage of the compared cycles, run again in this process


# The index comes from W10; from cycle 150 on X points at M200 + 30000: beyond the markers, a fault of the original.
INDEXED = """\
L     W10
=     X
L     I0
=     M200[X]
L     K77
=     W100[X]
EM
"""

INDEXED_SCENARIO = """\
name: indexed_far
cycles: {cycles}
initial: {{W10: 4, I0: 1}}
events:
  - {{cycle: 140, set: {{W10: 8, I0: 0}}}}{fault}
expect:
  - {{cycle: 145, values: {{M204: 0}}}}
"""


def _indexed(tmp_path, cycles: int, fault: int | None = None):
    (tmp_path / "main.src").write_text(INDEXED)
    far = f"\n  - {{cycle: {fault}, set: {{W10: 30000}}}}" if fault is not None else ""
    (tmp_path / "scenario.yaml").write_text(INDEXED_SCENARIO.format(cycles=cycles, fault=far))
    program = compile_project(ProjectOptions(main=tmp_path / "main.src"), make_semantics("itnc530", {})).program
    out = transpile_program(program, Diagnostics(), {}, {"st"})
    names = project_names(program)
    return program, out, names, load_scenario(tmp_path / "scenario.yaml", names)


def test_indexed_columns_and_expectations_match(tmp_path):
    program, out, names, scenario = _indexed(tmp_path, 400)
    lockstep, piped = _both(program, builtin_side_factory(out.st_text), io_map_of(out.result), scenario, names)
    assert lockstep.equivalent and lockstep.compared_indexed > 0
    assert [f.cycle for f in lockstep.expectation_failures] == [145]     # M204 keeps the 1 of cycles 0..139
    _assert_same(lockstep, piped)


def test_wrong_indexed_value_diverges_alike(tmp_path):
    program, out, names, scenario = _indexed(tmp_path, 400)
    broken, count = re.subn(r"\b77\b", "78", out.st_text)
    assert count >= 1
    lockstep, piped = _both(program, builtin_side_factory(broken), io_map_of(out.result), scenario, names)
    assert lockstep.divergence is not None
    _assert_same(lockstep, piped)


def test_fault_of_the_original_ends_both_alike(tmp_path):
    program, out, names, scenario = _indexed(tmp_path, 600, 300)
    lockstep, piped = _both(program, builtin_side_factory(out.st_text), io_map_of(out.result), scenario, names)
    assert lockstep.error_side == "original" and "cycle 300" in lockstep.error
    _assert_same(lockstep, piped)


def test_a_record_of_every_cycle_runs_in_lockstep(sample):
    program, out, iomap, names = sample
    scenario = random_scenario(program, names, 300, seed=1, machine_parameters=SAMPLE / "MP_data.mp")
    seen = []
    res = cosimulate(program, builtin_side_factory(out.st_text), iomap, scenario, names, pipelined=True,
                     record=lambda c, a, b: seen.append(c))
    assert res.equivalent and seen == list(range(300)) and res.machine is not None


@pytest.mark.skipif(find_iec2c() is None, reason="iec2c not found ($MATIEC_HOME/iec2c or PATH)")
def test_matiec_side_gives_the_same_result(sample):
    """The compiled side stays in this process; the forked reference never touches its library."""
    from transpiler.exec.compiled.matiec_side import matiec_side_factory
    program, out, iomap, names = sample
    factory = matiec_side_factory(out.st_text, out.result.project, find_iec2c())
    scenario = random_scenario(program, names, 1500, seed=8, machine_parameters=SAMPLE / "MP_data.mp")
    lockstep, piped = _both(program, factory, iomap, scenario, names)
    assert lockstep.equivalent
    _assert_same(lockstep, piped)


def test_a_store_where_the_original_never_stores_shows_after_the_last_cycle(tmp_path):
    """No column names byte 310 (the original stores to W104/W108 only): the sweep of the byte array after the
    last cycle finds the translation's stray store, in both modes."""
    program, out, names, scenario = _indexed(tmp_path, 400)
    line = re.search(r"^( *)HH_MEM\[101 \+ (\w+)\] := .*;$", out.st_text, re.M)
    assert line is not None, "the store of W100[X]'s high byte moved: update the test"
    indent, index = line.group(1), line.group(2)
    broken = out.st_text.replace(line.group(0), f"{line.group(0)}\n{indent}HH_MEM[302 + {index}] := 5;")
    lockstep, piped = _both(program, builtin_side_factory(broken), io_map_of(out.result), scenario, names)
    assert lockstep.divergence is not None
    assert (lockstep.divergence.cycle, lockstep.divergence.operand) == (399, "B306")
    assert (lockstep.divergence.original, lockstep.divergence.translated) == (0, 5)
    assert lockstep.swept > 1000
    _assert_same(lockstep, piped)
    correct = cosimulate(program, builtin_side_factory(out.st_text), io_map_of(out.result), scenario, names)
    assert correct.equivalent and correct.swept == lockstep.swept
