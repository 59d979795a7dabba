"""`hh2iec check` and `hh2iec explain` as cli.md specifies them: summary, --json keys, diagnostics format, exit codes."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest
from test_frontend_support import write_project

from transpiler.cli import main
from transpiler.diagnostics import CODES

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "samples" / "basic_program" / "Main_PGM.src"
DIAGNOSTIC_LINE = re.compile(r"^(?P<file>[^:]+):(?P<line>\d+):(?P<col>\d+): (?P<sev>error|warning)\[(?P<code>[A-Z0-9-]+)\]: .+$")

PROJECT = {
    "Main.src": "#define /g Glb.def\nUSES Mod.src\nEXTERN Entry\nL   MG_first\nCMT Entry\nCM  Local\nEM\n"
                "LBL Local\nL   I_key\n=   O_lamp\nEM\n",
    "Mod.src": "GLOBAL Entry\nLBL Entry\n#if CFG = 1\nL   K1\n#else\nL   K2\n#endif\n=   WG_count\nEM\n",
    "Glb.def": "MG_first M 4172\nI_key I 3\nO_lamp O 4\nWG_count W\n",
    "OEM.cfg": "DEFINE CFG = 1\n",
}


def _run(argv, capsys) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_check_prints_the_summary_and_exits_0(tmp_path, capsys):
    write_project(tmp_path, PROJECT)
    code, out, err = _run(["check", tmp_path / "Main.src"], capsys)
    assert (code, err) == (0, "")
    rows = dict(re.findall(r"^  (\S+)\s+(\S+)$", out, re.M))
    assert {k: rows[k] for k in ("files", "modules", "labels", "symbols", "instructions", "lines", "errors", "warnings")} == {
        "files": "4", "modules": "2", "labels": "2", "symbols": "4", "instructions": "10", "lines": "25",
        "errors": "0", "warnings": "0"}


def test_check_json_keys_and_values(tmp_path, capsys):
    write_project(tmp_path, PROJECT)
    code, out, err = _run(["check", tmp_path / "Main.src", "--json"], capsys)
    data = json.loads(out)
    assert code == 0 and err == ""
    assert {"files", "modules", "labels", "symbols", "instructions", "errors", "warnings"} <= set(data)
    assert (data["files"], data["modules"], data["labels"], data["symbols"], data["instructions"], data["errors"],
            data["warnings"]) == (4, 2, 2, 4, 10, 0, 0)
    assert data["lines"] == 25
    assert data["auto_assigned"] == 1 and data["call_depth"] == 1 and data["profile"] == "itnc530"


def test_errors_go_to_stderr_in_the_contract_format_and_exit_2(tmp_path, capsys):
    write_project(tmp_path, {**PROJECT, "Mod.src": "GLOBAL Entry\nLBL Entry\nL   I_undefined\n=   W3\n"})
    code, out, err = _run(["check", tmp_path / "Main.src", "--json"], capsys)
    assert code == 2
    assert json.loads(out)["errors"] == 3
    lines = err.splitlines()
    assert [DIAGNOSTIC_LINE.match(line).group("file", "line", "col", "sev", "code") for line in lines] == [
        ("Mod.src", "3", "1", "error", "E-SYM-UNDEF"), ("Mod.src", "4", "1", "error", "E-ADDR-ALIGN"),
        ("Mod.src", "4", "1", "error", "E-FALL-OFF-END")]


def test_warnings_do_not_fail_the_check(tmp_path, capsys):
    write_project(tmp_path, {**PROJECT, "OEM.cfg": "DEFINE CFG = 1\nsome free text\n"})
    code, out, err = _run(["check", tmp_path / "Main.src", "--json"], capsys)
    assert code == 0 and json.loads(out)["warnings"] == 1
    assert DIAGNOSTIC_LINE.match(err.strip()).group("sev", "code") == ("warning", "E-CFG-IGNORED")


def test_options_reach_the_front_end(tmp_path, capsys):
    write_project(tmp_path, {**PROJECT, "other.cfg": "DEFINE CFG = 2\n", "lib/Extra.src": "GLOBAL X\nLBL X\nEM\n",
                             "extra.def": "I_more I 9\n"})
    main_src = tmp_path / "Main.src"
    main_src.write_text(PROJECT["Main.src"].replace("USES Mod.src", "USES Mod.src\nUSES Extra.src\nL I_more\n= O9"))
    assert _run(["check", main_src], capsys)[0] == 2                     # Extra.src not found, I_more undefined
    code, out, err = _run(["check", main_src, "-I", tmp_path / "lib", "--defs", tmp_path / "extra.def",
                           "--cfg", tmp_path / "other.cfg", "-D", "CFG=3", "--profile", "tnc426",
                           "-S", "star_comments=false", "--json"], capsys)
    assert (code, err) == (0, "")
    assert json.loads(out)["profile"] == "tnc426" and json.loads(out)["modules"] == 3


def test_unreadable_definition_files_from_the_command_line(tmp_path, capsys):
    write_project(tmp_path, {"main.src": "EM\n"})
    for defs, code in ((tmp_path / "none.def", "E-FILE-NOT-FOUND"), (Path("/dev/zero"), "E-FILE-READ"), (tmp_path, "E-FILE-READ")):
        status, out, err = _run(["check", tmp_path / "main.src", "--defs", defs], capsys)
        assert status == 2 and [DIAGNOSTIC_LINE.match(line).group("code") for line in err.splitlines()] == [code]


@pytest.mark.parametrize("argv, fragment", [
    (["frobnicate"], "invalid choice"),
    (["check"], "required"),
    (["check", "{tmp}/missing.src"], "does not exist"),
    (["check", "{tmp}/Main.src", "-D", "NOVALUE"], "NAME=VALUE"),
    (["check", "{tmp}/Main.src", "-S", "no_such_key=1"], "no_such_key"),
    (["check", "{tmp}/Main.src", "-S", "chain_model=sideways"], "chain_model"),
    (["check", "{tmp}/Main.src", "--profile", "tnc999"], "tnc999"),
    (["check", "{tmp}/Main.src", "--cfg", "{tmp}/none.cfg"], "none.cfg"),
    (["check", "{tmp}/Main.src", "-I", "{tmp}/nodir"], "nodir"),
    (["check", "{tmp}/Main.src", "--bogus"], "--bogus"),
    (["explain", "E-NO-SUCH-CODE"], "E-NO-SUCH-CODE"),
    ([], "required"),
])
def test_bad_usage_is_an_e_usage_diagnostic_with_exit_2(tmp_path, capsys, argv, fragment):
    write_project(tmp_path, PROJECT)
    code, out, err = _run([a.format(tmp=tmp_path) for a in argv], capsys)
    assert code == 2
    assert err.startswith("<command line>:1:1: error[E-USAGE]: ") and fragment in err
    assert "Traceback" not in err + out


def test_help_exits_0(capsys):
    assert main(["--help"]) == 0 and "check" in capsys.readouterr().out


@pytest.mark.parametrize("code", sorted(CODES))
def test_explain_every_registered_code(capsys, code):
    status, out, err = _run(["explain", code.lower()], capsys)
    info = CODES[code]
    assert (status, err) == (0, "")
    assert out.startswith(f"{code} ({info.severity.value}): {info.summary}")
    assert info.summary and info.example, f"{code} needs a summary and an example"
    assert "Example:" in out and all(line in out for line in info.example.splitlines())


# Examples of front-end codes are real: compiled as written they give the code they explain.
EXAMPLE_AS = {"E-SYM-RESERVED": "def", "E-SYM-DUP": "def", "E-SYM-CASE": "def", "E-DEF-DUP-ADDR": "def",
              "E-DEF-ALIAS": "def", "E-CFG-SYNTAX": "cfg", "E-PP-UNDEF": "src", "E-MOD-UNREACHABLE": "module",
              "E-SYM-GLOBAL-UNDEF": "module"}
RUNNABLE_EXAMPLES = ["E-PP-NEST", "E-PP-UNDEF", "E-PP-UNDEF-REF", "E-PP-SYNTAX", "E-DEF-REDEFINE", "E-CFG-SYNTAX",
                     "E-FILE-NOT-FOUND", "E-FILE-ESCAPE", "E-FILE-INCLUDE-CYCLE", "E-SYNTAX", "E-UNSUPPORTED",
                     "E-LIT-RANGE", "E-MOD-UNREACHABLE", "E-OPERAND-KIND", "E-ADDR-RANGE", "E-ADDR-ALIGN",
                     "E-SYM-UNDEF", "E-SYM-RESERVED", "E-SYM-DUP", "E-SYM-CASE", "E-SYM-DUP-LABEL",
                     "E-SYM-GLOBAL-UNDEF", "E-SYM-UNRESOLVED", "E-DEF-DUP-ADDR", "E-DEF-ALIAS", "E-BRACKET-BALANCE",
                     "E-BRACKET-MODE", "E-BRACKET-SPAN", "E-STRUCT-NEST", "E-CASE-BODY", "E-KF-PLACEMENT",
                     "E-JUMP-SCOPE", "E-FALL-OFF-END", "E-CALL-RECURSION", "E-MODULE-UNKNOWN"]


@pytest.mark.parametrize("code", RUNNABLE_EXAMPLES)
def test_explained_examples_trigger_their_code(tmp_path, capsys, code):
    example = CODES[code].example + "\n"
    where = EXAMPLE_AS.get(code, "src")
    files = {"main.src": example if where == "src" else "EM\n"}
    if where == "def":
        files.update({"main.src": "#define /g ex.def\nEM\n", "ex.def": example})
    elif where == "cfg":
        files["OEM.cfg"] = example
    if code == "E-PP-UNDEF":
        files["OEM.cfg"] = "DEFINE CFG_SET = 1\n"     # (without any configuration it is E-CFG-MISSING)
    elif where == "module":
        files.update({"main.src": "USES m.src\nEM\n", "m.src": example})
    if code == "E-FILE-INCLUDE-CYCLE":
        files["self.src"] = example
    write_project(tmp_path, files)
    _, _, err = _run(["check", tmp_path / "main.src"], capsys)
    assert f"[{code}]" in err, err


def test_console_script_never_shows_a_traceback(tmp_path):
    """The installed entry point, as a user runs it, on garbage input and on bad usage."""
    (tmp_path / "main.src").write_bytes(bytes(range(256)) * 4 + b"\nL I1 I2\n" + b"A[\n" * 50)
    runner = [sys.executable, "-c", "from transpiler.cli import entry; entry()"]
    for argv in (["check", tmp_path / "main.src"], ["check", tmp_path / "main.src", "--json"], ["nonsense"],
                 ["check", tmp_path / "none.src"]):
        proc = subprocess.run(runner + [str(a) for a in argv], capture_output=True, text=True, cwd=ROOT, timeout=60)
        assert proc.returncode == 2, proc.stderr
        assert "Traceback" not in proc.stderr + proc.stdout
        assert all(DIAGNOSTIC_LINE.match(line) for line in proc.stderr.splitlines()), proc.stderr


def test_console_script_ends_one_shot_commands_with_all_their_output(tmp_path, capsys, monkeypatch):
    """check and transpile end the hh2iec process themselves (without the interpreter's clean-up): what they print
    and write, and their exit code, are those of the same command run through main()."""
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "0")        # (the XML files' creation time; the subprocess inherits it)
    write_project(tmp_path, PROJECT)
    write_project(tmp_path / "bad", {"main.src": "L I1\nJP nowhere\nEM\n", "OEM.cfg": ""})
    monkeypatch.delenv("PYTHONUNBUFFERED", raising=False)   # (its output is buffered, as a user's usually is)
    runner = [sys.executable, "-c", "from transpiler.cli import entry; entry()"]
    for argv in (["check", tmp_path / "Main.src", "--json"], ["check", tmp_path / "bad" / "main.src"],
                 ["transpile", tmp_path / "Main.src", "--out", tmp_path / "out-process"]):
        proc = subprocess.run(runner + [str(a) for a in argv], capture_output=True, text=True, cwd=ROOT, timeout=60)
        in_process = [str(a).replace("out-process", "out-main") for a in argv]
        assert (proc.returncode, proc.stdout.replace("out-process", "out-main"), proc.stderr) == \
            _run(in_process, capsys), argv
    written = sorted(p.relative_to(tmp_path / "out-process") for p in (tmp_path / "out-process").rglob("*"))
    in_main = sorted(p.relative_to(tmp_path / "out-main") for p in (tmp_path / "out-main").rglob("*"))
    assert written and written == in_main
    for name in written:
        if (tmp_path / "out-main" / name).is_file():
            assert (tmp_path / "out-process" / name).read_bytes() == (tmp_path / "out-main" / name).read_bytes()


@pytest.mark.skipif(not SAMPLE.exists(), reason="the sample project is not there yet")
@pytest.mark.parametrize("cfg", ["OEM.cfg", "OEM_variant_B.cfg", "OEM_variant_C.cfg"])
def test_the_sample_project_checks_clean(capsys, cfg):
    if not (SAMPLE.parent / cfg).exists():
        pytest.skip(f"{cfg} is not in the sample project")
    code, out, err = _run(["check", SAMPLE, "--cfg", SAMPLE.parent / cfg, "--json"], capsys)
    data = json.loads(out)
    assert (code, data["errors"]) == (0, 0), err
    assert data["modules"] >= 2 and data["instructions"] > 100
