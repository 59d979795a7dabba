"""Equivalence by co-simulation: the sample and the vectors are equivalent; a broken translation is caught and shrunk."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from transpiler.diagnostics import Diagnostics
from transpiler.frontend.mpfile import read_mp_file
from transpiler.verify.cosim import builtin_side_factory, cosimulate
from transpiler.verify.equiv import random_scenario, shrink
from transpiler.verify.scenario import load_scenario
from transpiler.verify.simulate import project_names
from transpiler.backends.report.report import io_map_of

from test_st_backend import SAMPLE, transpile_sample, transpile_vector
from vectors import load_vectors, vector_scenario_yaml

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = sorted((SAMPLE / "scenarios").glob("*.yaml"))


@pytest.fixture(scope="module")
def sample():
    program, out = transpile_sample()
    return program, out, builtin_side_factory(out.st_text), io_map_of(out.result), project_names(program)


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.stem)
def test_sample_scenario_is_equivalent(sample, path):
    program, out, factory, iomap, names = sample
    # the project's machine parameters: a scenario's own are written into the ST as run-time data
    result = cosimulate(program, factory, iomap, load_scenario(path, names), names,
                        base_mp=read_mp_file(SAMPLE / "MP_data.mp", Diagnostics()))
    assert result.error is None
    assert result.divergence is None
    assert result.compared > 100 and result.cycles_run > 0


def test_sample_random_cycles_are_equivalent(sample):
    program, out, factory, iomap, names = sample
    # The ST holds the presets of MP_data.mp: the random run uses the same machine parameters.
    scenario = random_scenario(program, names, 2000, seed=11, machine_parameters=SAMPLE / "MP_data.mp")
    result = cosimulate(program, factory, iomap, scenario, names)
    assert result.equivalent, (result.divergence, result.error)
    assert result.cycles_run == 2000


def _runtime_vectors():
    return [v for v in load_vectors() if not v.expect_error and v.id != "TV-73"]


@pytest.mark.parametrize("vector", _runtime_vectors(), ids=lambda v: v.id)
def test_vector_is_equivalent(vector, tmp_path):
    program, out = transpile_vector(vector, tmp_path)
    names = project_names(program)
    path = tmp_path / "scenario.yaml"
    path.write_text(vector_scenario_yaml(vector))
    result = cosimulate(program, builtin_side_factory(out.st_text), io_map_of(out.result), load_scenario(path, names), names)
    assert result.equivalent, (result.divergence, result.error)


def _break(st: str) -> str:
    """A deliberately wrong translation: the coolant flood pump ignores the door (AND -> OR)."""
    broken, count = re.subn(r"O_coolant_flood := ML_sel\.flood AND MG_control_ok AND I_door_closed;",
                            "O_coolant_flood := ML_sel.flood AND MG_control_ok OR I_door_closed;", st)
    assert count == 1, "the mutation site moved: update the test"
    return broken


def test_broken_translation_diverges_and_is_shrunk(sample):
    program, out, _, iomap, names = sample
    factory = builtin_side_factory(_break(out.st_text))
    scenario = load_scenario(SAMPLE / "scenarios" / "coolant_m8_m9.yaml", names)
    first = cosimulate(program, factory, iomap, scenario, names)
    assert first.divergence is not None and first.divergence.operand == "O" + str(
        next(s.addr for s in program.symbols.values() if s.name == "O_coolant_flood"))
    shrunk, runs = shrink(program, factory, iomap, scenario, names, first)
    assert shrunk.cycles <= first.divergence.cycle + 1
    assert len(shrunk.events) <= len(scenario.events)
    again = cosimulate(program, factory, iomap, shrunk, names)
    assert again.divergence is not None


def test_cli_equiv_reports_divergence_with_exit_1(tmp_path, sample):
    program, out, *_ = sample
    st = tmp_path / "broken.st"
    st.write_text(_break(out.st_text))
    (tmp_path / "io_map.csv").write_bytes(out.files["io_map.csv"])
    proc = subprocess.run([sys.executable, "-m", "transpiler.cli", "equiv", str(SAMPLE / "Main_PGM.src"),
                           "--scenario", str(SAMPLE / "scenarios" / "coolant_m8_m9.yaml"), "--st", str(st),
                           "--backend", "builtin", "--report", str(tmp_path / "r.json"), "--junit", str(tmp_path / "j.xml")],
                          capture_output=True, text=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert proc.returncode == 1, proc.stderr
    assert "DIVERGENCE" in proc.stdout and "O_coolant_flood" in proc.stdout
    shrunk_yaml = proc.stdout.split("rerun it with --scenario:\n", 1)[1].split("coverage:")[0]
    data = yaml.safe_load(shrunk_yaml)
    assert 1 <= data["cycles"] <= load_scenario(SAMPLE / "scenarios" / "coolant_m8_m9.yaml", sample[4]).cycles
    # The printed reproducer is a scenario the user can rerun, and it still diverges.
    rerun = tmp_path / "shrunk.yaml"
    rerun.write_text(shrunk_yaml)
    again = subprocess.run([sys.executable, "-m", "transpiler.cli", "equiv", str(SAMPLE / "Main_PGM.src"),
                            "--scenario", str(rerun), "--st", str(st), "--backend", "builtin", "--no-shrink"],
                           capture_output=True, text=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert again.returncode == 1, again.stderr
    assert (tmp_path / "r.json").is_file() and 'failures="1"' in (tmp_path / "j.xml").read_text()


def test_cli_equiv_sample_is_equivalent(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "transpiler.cli", "equiv", str(SAMPLE / "Main_PGM.src"),
                           "--scenario", str(SAMPLE / "scenarios" / "spindle_m3_m5.yaml"), "--backend", "builtin"],
                          capture_output=True, text=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert proc.returncode == 0, proc.stderr
    assert "EQUIVALENT" in proc.stdout and "backend builtin" in proc.stdout and "coverage:" in proc.stdout


@pytest.mark.skipif(__import__("transpiler.backends.st.check", fromlist=["find_iec2c"]).find_iec2c() is None,
                    reason="iec2c not found ($MATIEC_HOME/iec2c or PATH): the matiec co-simulation backend is skipped")
def test_sample_is_equivalent_on_matiec(sample):
    from transpiler.exec.compiled.matiec_side import matiec_side_factory
    from transpiler.backends.st.check import find_iec2c
    program, out, _, iomap, names = sample
    factory = matiec_side_factory(out.st_text, out.result.project, find_iec2c())
    for name in ("spindle_m3_m5", "tool_call_magazine"):
        result = cosimulate(program, factory, iomap, load_scenario(SAMPLE / "scenarios" / f"{name}.yaml", names), names)
        assert result.equivalent, (name, result.divergence, result.error)
    broken = matiec_side_factory(_break(out.st_text), out.result.project, find_iec2c())
    result = cosimulate(program, broken, iomap, load_scenario(SAMPLE / "scenarios" / "coolant_m8_m9.yaml", names), names)
    assert result.divergence is not None


@pytest.mark.skipif(__import__("transpiler.backends.st.check", fromlist=["find_iec2c"]).find_iec2c() is None,
                    reason="iec2c not found ($MATIEC_HOME/iec2c or PATH): the matiec co-simulation backend is skipped")
@pytest.mark.parametrize("project", ["samples/constructs/byte_overlap/main.src", "samples/constructs/indexed/main.src",
                                     "samples/constructs/strings/main.src"])
def test_matiec_bulk_read_agrees_with_single_reads(project):
    """The one-call reader of the matiec side returns what each accessor reads, byte-array words included."""
    import random
    from transpiler.verify.cosim import comparison_for
    from transpiler.diagnostics import Diagnostics
    from transpiler.frontend.load import ProjectOptions
    from transpiler.exec.compiled.matiec_side import matiec_side_factory
    from transpiler.frontend.pipeline import compile_project
    from transpiler.language.semantics import make_semantics
    from transpiler.backends.st.check import find_iec2c
    from transpiler.backends.transpile import transpile_program
    program = compile_project(ProjectOptions(main=ROOT / project), make_semantics("itnc530", {})).program
    out = transpile_program(program, Diagnostics(), {}, {"st"})
    iomap = io_map_of(out.result)
    columns = comparison_for(program, project_names(program), iomap).columns
    accessors = [iomap.accessor(str(ref)) for _, ref in columns]
    side = matiec_side_factory(out.st_text, out.result.project, find_iec2c())()
    rng = random.Random(5)
    byte_sized = any(acc.place.width for acc in accessors)
    for acc, (_, ref) in zip(accessors, columns):
        if ref.kind in "BWD":
            bits = {"B": 8, "W": 16, "D": 32}[ref.kind]
            acc.write(side, rng.randrange(-(1 << (bits - 1)), 1 << (bits - 1)))
        elif ref.kind == "S":
            acc.write(side, "text%d" % rng.randrange(100))
        else:
            acc.write(side, rng.randrange(2))
    singles = [acc.read(side) for acc in accessors]
    assert side.bulk_reader([acc.place for acc in accessors])() == singles
    assert len(singles) > 3
    assert byte_sized == ("strings" not in project)   # overlapping or indexed B/W/D live in one byte array
