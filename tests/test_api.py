"""The public API (transpiler.api): typed results, one exception type carrying every diagnostic, and the
documented example in docs/api.md runs as written."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from transpiler import api
from transpiler.diagnostics import Severity

ROOT = Path(__file__).resolve().parents[1]
TIMERS = ROOT / "samples" / "constructs" / "timers"
MULTI = ROOT / "samples" / "constructs" / "multi_file_global_extern"


def _project(folder: Path, scenario: Path | None = None) -> api.Project:
    return api.load_project(api.project_options(folder / "main.src"), api.semantics_for(scenario=scenario))


def test_load_transpile_simulate_and_check_equivalence():
    scenario = TIMERS / "scenario.yaml"
    project = _project(TIMERS, scenario)
    assert project.program.instruction_count() > 0
    out = api.transpile(project)
    assert set(out.files) == {"project.st", "project.xml", "report.md", "io_map.csv", "hh_lib.st", "hh_lib.xml",
                              "plc_project/plc.xml", "plc_project/beremiz.xml"}
    assert out.files["project.st"].decode() == out.st_text and "PROGRAM" in out.st_text
    assert out.pou_count >= 1 and len(out.io_map.rows) > 0
    sim = api.simulate(project, scenario)
    assert sim.run.failures == [] and sim.run.cycles_run == sim.scenario.cycles
    check = api.check_equivalence(project, scenarios=[scenario], random_cycles=50, backend="builtin")
    assert check.equivalent and check.result.verdict == "EQUIVALENT"
    assert [o.result.scenario for o in check.result.outcomes] == ["timers", "random_seed1"]


def test_equivalence_of_a_wrong_translation_is_not_equivalent(tmp_path):
    """The API's verdict comes from the comparison: an ST file with one output inverted must diverge."""
    project = _project(TIMERS, TIMERS / "scenario.yaml")
    out = api.transpile(project)
    out.write(tmp_path)
    st = (tmp_path / "project.st").read_text()
    changed = st.replace("O1 := T48;", "O1 := NOT T48;", 1)
    assert changed != st
    (tmp_path / "project.st").write_text(changed)
    check = api.check_equivalence(project, scenarios=[TIMERS / "scenario.yaml"], st_file=tmp_path / "project.st",
                                  backend="builtin", shrink=False)
    assert not check.equivalent and check.result.divergent


def test_bad_input_raises_one_exception_type_with_every_diagnostic(tmp_path):
    (tmp_path / "main.src").write_text("L M1\n= UNDEFINED_ONE\nL NOT_THERE_EITHER\nEM\n", encoding="latin-1")
    with pytest.raises(api.HH2IECError) as caught:
        api.load_project(api.project_options(tmp_path / "main.src"))
    errors = [d for d in caught.value.diagnostics if d.severity is Severity.ERROR]
    assert len(errors) == 2 and {d.span.line for d in errors} == {2, 3}
    assert "main.src:2:" in str(caught.value)


@pytest.mark.parametrize("call", [
    lambda: api.project_options(Path("/nonexistent/main.src")),
    lambda: api.semantics_for("no_such_profile"),
    lambda: api.semantics_for(overrides={"no_such_setting": "1"}),
    lambda: api.simulate(_project(TIMERS), Path("/nonexistent/scenario.yaml")),
    lambda: api.check_equivalence(_project(TIMERS)),
])
def test_usage_problems_are_the_same_exception(call):
    with pytest.raises(api.HH2IECError) as caught:
        call()
    assert caught.value.diagnostics and all(d.severity is Severity.ERROR for d in caught.value.diagnostics)


def test_check_project_reports_instead_of_raising(tmp_path):
    (tmp_path / "main.src").write_text("L NOPE\nEM\n", encoding="latin-1")
    result = api.check_project(api.project_options(tmp_path / "main.src"))
    assert not result.ok and result.diagnostics.has_errors()


def test_the_cli_is_built_on_the_api():
    """cli/ holds no pipeline of its own: its modules call transpiler.api, never the stages' drivers directly."""
    offenders = []
    for path in sorted((ROOT / "transpiler" / "cli").glob("*.py")):
        text = path.read_text(encoding="utf-8")
        for forbidden in ("compile_project", "transpile_program", "cosimulate(", "run_scenario("):
            if forbidden in text:
                offenders.append(f"{path.name}: {forbidden}")
    assert offenders == []


def test_documented_example_runs(tmp_path):
    """docs/api.md's example, run as written on the sample's variants (output under tmp_path, fewer cycles)."""
    text = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    code = re.search(r"## Example.*?```python\n(.*?)```", text, re.S).group(1)
    code = code.replace('Path("samples/basic_program")', repr(str(ROOT / "samples" / "basic_program")).join(("Path(", ")")))
    code = code.replace('Path("out")', f"Path({str(tmp_path)!r})").replace("random_cycles=2000", "random_cycles=20")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=900, cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    verdicts = re.findall(r"^(OEM\S*\.cfg): (EQUIVALENT|NOT EQUIVALENT)$", proc.stdout, re.M)
    assert len(verdicts) == len(list((ROOT / "samples" / "basic_program").glob("OEM*.cfg")))
    assert all(v == "EQUIVALENT" for _, v in verdicts)
    assert (tmp_path / "OEM" / "project.st").is_file() and (tmp_path / "OEM_variant_B" / "project.xml").is_file()
