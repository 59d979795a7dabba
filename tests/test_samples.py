"""The samples: the basic program checks clean in every configuration and meets its scenario expectations; every
construct sample checks clean, meets its expectations and is equivalent after translation."""

from __future__ import annotations

from pathlib import Path

import pytest

from transpiler.cli import main as hh2iec

ROOT = Path(__file__).resolve().parents[1]
BASIC = ROOT / "samples" / "basic_program"
CONSTRUCTS = sorted(p for p in (ROOT / "samples" / "constructs").iterdir() if (p / "main.src").is_file())
CONFIGS = sorted(BASIC.glob("OEM*.cfg"))


@pytest.mark.parametrize("cfg", CONFIGS, ids=lambda p: p.name)
def test_basic_program_checks_clean(cfg, capsys):
    assert hh2iec(["check", str(BASIC / "Main_PGM.src"), "--cfg", str(cfg), "--json"]) == 0
    out = capsys.readouterr()
    assert '"errors": 0' in out.out and '"warnings": 0' in out.out


def test_basic_program_is_large_and_uses_every_instruction_group():
    from transpiler.frontend.load import ProjectOptions
    from transpiler.frontend.pipeline import compile_project
    from transpiler.language.semantics import make_semantics
    lines = sum(len(p.read_text(encoding="latin-1").splitlines()) for p in BASIC.iterdir()
                if p.suffix.lower() in (".src", ".def", ".cfg", ".mp"))
    assert lines >= 2000
    result = compile_project(ProjectOptions(main=BASIC / "Main_PGM.src"), make_semantics("itnc530"))
    groups = {op.mnemonic for f in result.program.files for op in f.ops}
    for needed in ("L", "LN", "L-", "LB", "LW", "LD", "=", "B=", "W=", "D=", "S", "R", "SN", "RN", "A", "AN", "O",
                   "ON", "XO", "XON", "+", "-", "x", "/", "MOD", "==", "<", ">", "<=", ">=", "<>", "<<", ">>",
                   "BS", "BC", "BT", "PS", "PL", "PSW", "PLW", "PSL", "PLL", "PSX", "PLX", "JP", "JPT", "JPF",
                   "CM", "CMT", "CMF", "EM", "EMT", "EMF", "CASE", "IFT", "IFF", "ELSE", "ENDI", "WHILET", "ENDW",
                   "REPEAT", "UNTILT", "]"):
        assert needed in groups, needed
    assert any(op.operand is not None and op.operand.kind == "KF" for f in result.program.files for op in f.ops)
    assert any(op.operand is not None and op.operand.indexed for f in result.program.files for op in f.ops)
    assert any(op.code in ("SLD", "SCAT", "SST", "SCMP") for f in result.program.files for op in f.ops)


@pytest.mark.parametrize("scenario", sorted((BASIC / "scenarios").glob("*.yaml")), ids=lambda p: p.stem)
def test_basic_program_meets_scenario_expectations(scenario, capsys):
    assert hh2iec(["simulate", str(BASIC / "Main_PGM.src"), "--scenario", str(scenario)]) == 0, capsys.readouterr().err
    assert " 0 failed" in capsys.readouterr().out


@pytest.mark.parametrize("folder", CONSTRUCTS, ids=lambda p: p.name)
def test_construct_sample(folder, capsys):
    main, scenario = str(folder / "main.src"), str(folder / "scenario.yaml")
    assert hh2iec(["check", main]) == 0, capsys.readouterr().err
    assert hh2iec(["simulate", main, "--scenario", scenario]) == 0, capsys.readouterr().err
    capsys.readouterr()
    # `indexed` reads a KF table through an input-driven index: random inputs make the original fault (E-RT-INDEX).
    extra = [] if folder.name == "indexed" else ["--random-cycles", "200", "--seed", "5"]
    assert hh2iec(["equiv", main, "--scenario", scenario, *extra, "--backend", "builtin"]) == 0, capsys.readouterr()
    assert "EQUIVALENT" in capsys.readouterr().out


MODULES_DEMO = ROOT / "samples" / "modules_demo"


def test_modules_demo_uses_every_module_kind_and_submit_jobs_and_is_equivalent(capsys):
    # The acceptance project of PLC modules: pure, data and machine modules and SUBM/RPLY/CAN, nothing left
    # untranslated, every scenario's expectations met, equivalent over its scenarios and generated stimulus.
    from transpiler import api
    from transpiler.language.module_table import DATA, MACHINE, MODULE_TABLE, PURE
    project = api.load_project(api.project_options(MODULES_DEMO))
    ops = [op for f in project.program.files for op in f.ops]
    kinds = {MODULE_TABLE[op.call.module].kind for op in ops if op.call is not None and op.call.is_module}
    assert kinds == {PURE, DATA, MACHINE}
    assert {"SUBM", "RPLY", "CAN"} <= {op.code for op in ops}
    assert api.transpile(project).result.untranslated == ()
    scenarios = sorted((MODULES_DEMO / "scenarios").glob("*.yaml"))
    for scenario in scenarios:
        assert hh2iec(["simulate", str(MODULES_DEMO), "--scenario", str(scenario)]) == 0, capsys.readouterr().err
        assert " 0 failed" in capsys.readouterr().out
    args = [a for s in scenarios for a in ("--scenario", str(s))]
    assert hh2iec(["equiv", str(MODULES_DEMO), *args, "--random-cycles", "300", "--backend", "builtin"]) == 0, \
        capsys.readouterr()
    assert "EQUIVALENT" in capsys.readouterr().out
