"""--target twincat writes a TwinCAT 3 PLC project folder: every .TcPOU/.TcGVL/.TcDUT parses with blark's own
TwinCAT file loader, the .plcproj lists exactly the files written (and blark's project loader finds each), the
objects declare what project.st declares, the task file calls the programs in order, and two runs are
byte-identical."""

from __future__ import annotations

import re
from pathlib import Path, PurePosixPath, PureWindowsPath

import pytest
from lxml import etree

from transpiler import api
from transpiler.backends.iec_model import Configuration, IecProject, IecVar, Pou, ProgramInstance, Task, VarSection
from transpiler.backends.plcopen.writer import REPLACEMENT
from transpiler.backends.st.dialect import for_target
from transpiler.backends.st.task_setup import task_setups
from transpiler.backends.st.writer import indent_body
from transpiler.backends.twincat.layout import guid, plan_project, project_name
from transpiler.backends.twincat.writer import BOM, render_project

ROOT = Path(__file__).resolve().parents[1]
SAMPLES = ROOT / "samples"
PROJECTS = {"basic_program": (SAMPLES / "basic_program" / "Main_PGM.src", SAMPLES / "basic_program" / "OEM.cfg"),
            "modules_demo": (SAMPLES / "modules_demo", None)}
PROJECTS.update({p.name: (p / "main.src", None) for p in sorted((SAMPLES / "constructs").iterdir())
                 if (p / "main.src").is_file()})
MSBUILD = "{http://schemas.microsoft.com/developer/msbuild/2003}"
OBJECT_SUFFIXES = (".TcPOU", ".TcGVL", ".TcDUT")
_POU = re.compile(r"^(PROGRAM|FUNCTION_BLOCK|FUNCTION) (\w+)", re.M)
_GVL = re.compile(r"^\(\* Global variable list (\w+) \*\)$", re.M)
_TYPE = re.compile(r"^TYPE\n    (\w+) :", re.M)


def _transpile(name: str) -> api.Transpilation:
    main, cfg = PROJECTS[name]
    return api.transpile(api.load_project(api.project_options(main, cfg=cfg)), target="twincat")


@pytest.fixture(scope="module")
def outputs():
    """The twincat translation of each sample, made once per name and kept for every test of this module."""
    cache: dict[str, api.Transpilation] = {}

    def get(name: str) -> api.Transpilation:
        if name not in cache:
            cache[name] = _transpile(name)
        return cache[name]
    return get


def _folder(files: dict[str, bytes]) -> str:
    (plcproj,) = [n for n in files if n.endswith(".plcproj")]
    return plcproj.rsplit("/", 1)[0]


def _blark_errors(path: Path) -> list[str]:
    """What blark's native TwinCAT loader and parser say about one object file: every part must parse and
    transform; an empty list means it did. Any exception is reported, not swallowed."""
    from blark.parse import parse
    problems = []
    results = list(parse(path))
    if not results:
        problems.append(f"{path.name}: blark found no code in the file")
    for result in results:
        if result.exception is not None:
            problems.append(f"{path.name}: {result.exception}")
        else:
            result.transform()
    return problems


@pytest.mark.parametrize("name", sorted(PROJECTS))
def test_every_object_file_parses_with_blark(outputs, name, tmp_path):
    pytest.importorskip("blark")
    out = outputs(name)
    out.write(tmp_path)
    folder = tmp_path / _folder(out.files)
    objects = sorted(p for p in folder.rglob("*") if p.suffix in OBJECT_SUFFIXES)
    assert objects, "no object files written"
    problems = [problem for path in objects for problem in _blark_errors(path)]
    assert problems == []


def test_the_blark_check_fails_on_a_broken_object(outputs, tmp_path):
    # Catches: a check that passes whatever the file holds (blark reports, it does not raise, on a syntax error).
    pytest.importorskip("blark")
    files = outputs("timers").files
    name = next(n for n in files if n.endswith(".TcPOU") and "/POUs/main." in n)
    broken = tmp_path / "main.TcPOU"
    broken.write_bytes(files[name].replace(b"<ST><![CDATA[", b"<ST><![CDATA[x := ;\n"))
    assert _blark_errors(broken) and "main.TcPOU" in _blark_errors(broken)[0]


@pytest.mark.parametrize("name", ["basic_program", "submit_jobs", "modules_demo"])
def test_the_plcproj_lists_exactly_the_files_written_and_blark_loads_each(outputs, name, tmp_path):
    out = outputs(name)
    folder = _folder(out.files)
    written = {PurePosixPath(n).relative_to(folder) for n in out.files if n.startswith(folder + "/")}
    plcproj = next(p for p in written if p.suffix == ".plcproj")
    root = etree.fromstring(out.files[f"{folder}/{plcproj}"])
    listed = [PurePosixPath(*PureWindowsPath(c.get("Include")).parts) for c in root.iter(f"{MSBUILD}Compile")]
    assert len(listed) == len(set(listed))
    assert set(listed) == written - {plcproj}
    assert {f.get("Include") for f in root.iter(f"{MSBUILD}Folder")} == {str(p.parent) for p in listed} - {"."}
    assert root.findtext(f"{MSBUILD}PropertyGroup/{MSBUILD}Name") == plcproj.stem
    pytest.importorskip("blark")
    from blark.solution import TwincatPlcProject
    out.write(tmp_path)
    loaded = TwincatPlcProject.from_filename(tmp_path / folder / plcproj)
    assert len(loaded.sources) == len(listed)
    assert all(s.local_path is not None and s.contents is not None for s in loaded.sources)


@pytest.mark.parametrize("name", ["basic_program", "submit_jobs", "strings", "modules_demo"])
def test_the_objects_declare_what_project_st_declares(outputs, name):
    # Catches: an object missing or extra, or its declaration or body differing from project.st's text.
    files = outputs(name).files
    st = files["project.st"].decode()
    texts = {n: etree.fromstring(data) for n, data in files.items() if n.endswith(OBJECT_SUFFIXES)}
    names = {kind: {root[0].get("Name") for n, root in texts.items() if n.endswith(kind)} for kind in OBJECT_SUFFIXES}
    assert names[".TcPOU"] == {m.group(2) for m in _POU.finditer(st)}
    assert names[".TcGVL"] == set(_GVL.findall(st))
    assert names[".TcDUT"] == set(_TYPE.findall(st))
    for n, root in texts.items():
        declaration = root.findtext("*/Declaration")
        if n.endswith(".TcPOU"):
            kind = _POU.search(declaration).group(1)
            body = root.findtext("*/Implementation/ST")
            assert declaration + indent_body(body) + f"\nEND_{kind}\n" in st, n
        elif n.endswith(".TcGVL"):
            assert f"*)\n{declaration}" in st, n
        else:
            assert declaration in st, n


def test_the_task_file_calls_the_programs_in_order(outputs):
    out = outputs("basic_program")
    (name,) = [n for n in out.files if n.endswith(".TcTTO")]
    task = etree.fromstring(out.files[name]).find("Task")
    (setup,) = task_setups(for_target(out.result.project, "twincat").project)
    assert [c.findtext("Name") for c in task.iter("PouCall")] == ["Main_PGM", "HH_SubmitJobs"] == list(setup.programs)
    assert (task.get("Name"), task.findtext("CycleTime"), task.findtext("Priority")) == ("HH_Cycle", "20000", "20")
    # the same task is the one README.md and project.st describe
    assert "It calls these programs once per cycle, in this order: Main_PGM, HH_SubmitJobs." in \
        out.files["README.md"].decode()
    assert "(* Task HH_Cycle: cyclic, interval T#20ms, priority 20. *)" in out.files["project.st"].decode()


def test_two_runs_are_byte_identical(monkeypatch):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")
    first, second = _transpile("submit_jobs").files, _transpile("submit_jobs").files
    assert sorted(first) == sorted(second)
    assert [n for n in first if first[n] != second[n]] == []


def test_files_are_utf8_with_a_byte_order_mark_and_guids_are_unique(outputs):
    files = {n: d for n, d in outputs("basic_program").files.items() if n.startswith("twincat/")}
    assert all(d.startswith(BOM.encode("utf-8") + b'<?xml version="1.0" encoding="utf-8"?>') for d in files.values())
    ids = re.findall(rb"\{[0-9a-f]{8}-[0-9a-f]{4}-5[0-9a-f]{3}-[89ab][0-9a-f]{3}-[0-9a-f]{12}\}", b"".join(files.values()))
    assert len(ids) > 130 and len(ids) == len(set(ids))


def _tiny(body: str, extra_pous: tuple[Pou, ...] = (), name: str = "Tiny") -> IecProject:
    main = Pou("Main", "PROGRAM", (VarSection("VAR", (IecVar("x", "INT"),)),), body)
    conf = Configuration("C", "R", (Task("T", 10, 0),), (ProgramInstance("I", "T", "Main"),),
                         (VarSection("VAR_GLOBAL", (IecVar("g", "INT"),), comment="Markers"),))
    return IecProject(name, (), extra_pous + (main,), conf)


def test_a_guid_depends_only_on_the_project_and_the_object():
    # Catches: GUIDs numbered by position (one new POU would change every later file), or random ones.
    plain = plan_project(for_target(_tiny("x := 1;"), "twincat"))
    helper = Pou("Helper", "FUNCTION_BLOCK", (), "x := 2;")
    grown = plan_project(for_target(_tiny("x := 1;", (helper,)), "twincat"))
    by_name = {o.name: o.guid for o in grown.objects}
    assert all(by_name[o.name] == o.guid for o in plain.objects)
    assert by_name["Main"] == guid("Tiny", "POU", "Main") != guid("Other", "POU", "Main")
    assert plan_project(for_target(_tiny("x := 1;", name="Other"), "twincat")).objects[-1].guid != by_name["Main"]


def test_text_xml_cannot_carry_survives_as_cdata():
    # Catches: ']]>' closing the CDATA section early, or a control character making the file unreadable XML.
    body = "x := 1; (* a[b[1]]>c \x01 *)"
    files = render_project(plan_project(for_target(_tiny(body), "twincat")))
    main = etree.fromstring(files["twincat/Tiny/POUs/Main.TcPOU"])
    assert main.findtext("POU/Implementation/ST") == body.replace("\x01", REPLACEMENT)


def test_a_project_name_cannot_leave_the_output_folder(tmp_path):
    assert project_name("../evil name") == "_evil_name" and project_name("...") == "Project"
    files = render_project(plan_project(for_target(_tiny("x := 1;", name="../x y"), "twincat")))
    assert all(n.startswith("twincat/_x_y/") for n in files)
    for bad in ("../x", "/abs", "a/../../b", "a\\b", "a//b", ""):
        with pytest.raises(ValueError):
            api.inside(tmp_path, bad)
    assert api.inside(tmp_path, "twincat/P/POUs/M.TcPOU") == tmp_path / "twincat" / "P" / "POUs" / "M.TcPOU"


def test_readme_only_for_targets_whose_import_creates_no_task(outputs):
    out = outputs("submit_jobs")
    readme = out.files["README.md"].decode()
    assert f"`{_folder(out.files)}/main.plcproj`" in readme
    assert "- HH_SubmitJobs must run in this same task right after main; call neither from another task." in readme
    for target in ("codesys", "matiec"):
        main, _ = PROJECTS["submit_jobs"]
        files = api.transpile(api.load_project(api.project_options(main)), target=target).files
        assert ("README.md" in files) == (target == "codesys")
        assert not any("/" in n and not n.startswith("plc_project/") for n in files)
