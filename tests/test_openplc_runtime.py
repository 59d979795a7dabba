"""`--target openplc` builds and runs on the OpenPLC v3 runtime (docs/import.md).

In CI (no OpenPLC here): the built-in rules of transpiler/verify/openplc_rules.py agree with the runtime build's
recorded verdicts on the corpus tests/data/openplc_verdicts/*.st, every sample project's openplc translation passes
those rules, and the recorded verdicts of the sample projects say they built, ran and matched the reference.

With OPENPLC_HOME (an OpenPLC_v3 checkout with its iec2c, libmodbus and snap7 built in place; `make test-openplc`):
the verdicts are measured again, every sample project and a few random projects of the differential tester are built
with the runtime's own steps, linked, started, and their coils read over Modbus TCP are compared with the reference
(tests/openplc_runtime.py says how), and an ST whose outputs are deliberately wired wrong is caught.
"""

from __future__ import annotations

import json
import re
import tempfile
from pathlib import Path

import pytest
from openplc_runtime import (DATA_DIR, PROJECT_VERDICTS, SNIPPET_VERDICTS, UNSAFE_PREFIX, build_program,
                             check_project, find_home, measure_snippet, project_key, random_projects, reference,
                             run_and_read, sample_projects)

from transpiler import api
from transpiler.cli import main as hh2iec
from transpiler.verify import openplc_rules
from transpiler.verify.openplc_rules import location_problem, openplc_problems

HOME, WHY = find_home()
NEEDS_OPENPLC = pytest.mark.skipif(HOME is None, reason=f"OpenPLC runtime build not checked: {WHY}; "
                                                        "`make test-openplc OPENPLC_HOME=<checkout>` runs it")
MIN_SNIPPETS = 12
RANDOM_PROJECTS, RANDOM_SEED = 6, 2


def _snippets() -> list[Path]:
    return sorted(DATA_DIR.glob("*.st"))


def test_the_recorded_verdicts_are_complete():
    verdicts = json.loads(SNIPPET_VERDICTS.read_text(encoding="utf-8"))
    names = [p.stem for p in _snippets()]
    assert len(names) >= MIN_SNIPPETS and sorted(verdicts) == sorted(names)
    assert {v["accept"] for v in verdicts.values()} == {True, False}, "the corpus needs accepted and rejected files"
    for name, verdict in verdicts.items():
        assert verdict["openplc_commit"] != "unknown", name
        assert verdict["accept"] == (verdict["failed_step"] == ""), name
        assert "/" not in verdict["message"].split(":")[0] or verdict["message"].startswith("./st_files"), name
    projects = json.loads(PROJECT_VERDICTS.read_text(encoding="utf-8"))
    assert sorted(projects) == sorted(project_key(p) for p in sample_projects()), \
        "every sample project needs a recorded runtime verdict (python -m tests.openplc_runtime --measure)"


@pytest.mark.parametrize("name", [p.stem for p in _snippets()])
def test_builtin_rules_agree_with_the_runtime_build(name):
    verdict = json.loads(SNIPPET_VERDICTS.read_text(encoding="utf-8"))[name]
    problems = openplc_problems((DATA_DIR / f"{name}.st").read_text(encoding="utf-8"), f"{name}.st")
    if name.startswith(UNSAFE_PREFIX):
        # The build takes these; the program does not fit the runtime's I/O image, so the rules refuse them.
        assert verdict["accept"], f"{name}: an unsafe_ snippet is one the build accepts"
        assert problems, f"{name}: the rules accept an address the runtime does not map"
    elif verdict["accept"]:
        assert not problems, f"the runtime builds {name}.st, the rules reject it: {[p.render() for p in problems]}"
    else:
        assert problems, f"the runtime rejects {name}.st ({verdict['failed_step']}: {verdict['message']}), " \
                         "the rules accept it"


@pytest.mark.parametrize("address, fits", [
    ("%IX0.0", True), ("%QX1023.7", True), ("%IW0", True), ("%QD12", True), ("%MW1023", True), ("%ML10", True),
    ("%QX1024.0", False), ("%QX0.8", False), ("%MX0.0", False), ("%MB3", False), ("%QL0", False), ("%ML1024", False),
    ("%IX0", False), ("%IW3.1", False), ("%IX0.0.1", False)])
def test_location_rule(address, fits):
    assert (location_problem(address) is None) == fits


@pytest.mark.parametrize("folder", sample_projects(), ids=project_key)
def test_every_sample_translates_for_the_runtime(folder):
    """transpile --target openplc runs the rules itself: it raises on any problem, so this passing means none."""
    project = api.load_project(api.project_options(folder))
    text = api.transpile(project, target="openplc", validate_xml=False, formats=("st",)).files["project.st"].decode()
    assert re.search(r"^CONFIGURATION Config0$", text, re.M) and re.search(r"^\s+RESOURCE Res0 ON PLC$", text, re.M)
    recorded = json.loads(PROJECT_VERDICTS.read_text(encoding="utf-8"))[project_key(folder)]
    assert recorded["build"] and recorded["mismatches"] == [], recorded


def test_recorded_sample_run_compared_outputs():
    """The recorded run of the Basic-Program-style sample compared real outputs, not an empty set."""
    recorded = json.loads(PROJECT_VERDICTS.read_text(encoding="utf-8"))["samples/basic_program"]
    assert recorded["compared"] >= 10 and recorded["reads"] >= 3 and recorded["mismatches"] == []


def test_a_translation_the_rules_reject_is_not_written(tmp_path, monkeypatch, capsys):
    (tmp_path / "main.src").write_text("L I0\n= O0\nEM\n")
    out = tmp_path / "out"
    bad = openplc_problems((DATA_DIR / "names_other_configuration.st").read_text(encoding="utf-8"), "project.st")
    assert bad and all(d.code == "E-TARGET" for d in bad)
    monkeypatch.setattr(openplc_rules, "openplc_problems", lambda text, filename="project.st": bad)
    assert hh2iec(["transpile", str(tmp_path / "main.src"), "--target", "openplc", "--out", str(out)]) == 2
    assert re.search(r"^project\.st:\d+:\d+: error\[E-TARGET\]: the CONFIGURATION must be named Config0",
                     capsys.readouterr().err, re.M)
    assert not out.exists()
    # The other targets are not the runtime's: the rules are not asked there.
    assert hh2iec(["transpile", str(tmp_path / "main.src"), "--target", "matiec", "--out", str(out)]) == 0


@NEEDS_OPENPLC
def test_recorded_verdicts_are_what_the_runtime_build_says_now():
    recorded = json.loads(SNIPPET_VERDICTS.read_text(encoding="utf-8"))
    changed = []
    with tempfile.TemporaryDirectory(prefix="openplc_verdicts_") as tmp:
        for path in _snippets():
            now = measure_snippet(HOME, path.read_text(encoding="utf-8"), Path(tmp) / path.stem, Path(tmp))
            if now["accept"] != recorded[path.stem]["accept"]:
                changed.append(f"{path.stem}: recorded {recorded[path.stem]['accept']}, now {now}")
    assert not changed


@NEEDS_OPENPLC
def test_every_sample_builds_runs_and_matches_on_the_runtime():
    failures = []
    with tempfile.TemporaryDirectory(prefix="openplc_projects_") as tmp:
        for folder in sample_projects():
            key = project_key(folder)
            verdict = check_project(HOME, folder, Path(tmp) / key.replace("/", "_"), Path(tmp))
            if not verdict["build"] or verdict["mismatches"]:
                failures.append(f"{key}: {verdict}")
        # Programs nobody wrote for this check: random projects of the differential tester.
        for key, main, cfg in random_projects(RANDOM_PROJECTS, RANDOM_SEED, Path(tmp) / "random"):
            verdict = check_project(HOME, main, Path(tmp) / key.replace(":", "_"), Path(tmp), cfg)
            if not verdict["build"] or verdict["mismatches"]:
                failures.append(f"{key}: {verdict}")
        # The comparison can fail: the sample with two steady outputs of different values wired to each other's
        # addresses must show a mismatch.
        ref = reference(sample_projects()[0])
        ones = [c for c, v in ref.st_steady.items() if v == 1]
        zeros = [c for c, v in ref.st_steady.items() if v == 0]
        assert ones and zeros, "the sample needs steady outputs of both values for the self-check"

        def address(coil: int) -> str:
            return f"%QX{coil // 8}.{coil % 8}"
        a, b = address(ones[0]), address(zeros[0])
        swapped = ref.st_text.replace(f"AT {a} ", "AT @@ ").replace(f"AT {b} ", f"AT {a} ").replace("AT @@ ", f"AT {b} ")
        assert swapped != ref.st_text
        build = build_program(HOME, swapped, Path(tmp) / "swapped", Path(tmp))
        assert build.ok, build
        reads = run_and_read(HOME, build.folder, max(ref.coils) + 1)
        assert all(values[ones[0]] == 0 and values[zeros[0]] == 1 for _, values in reads), reads
    assert not failures
