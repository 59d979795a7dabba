"""hh2iec installs like any Python tool: a wheel built from the repository, installed into a new venv outside the
checkout, transpiles and proves the sample from a folder of its own, building the runtime shim into a fresh
per-user cache from the sources it carries. Also the locating of the data folders and the shim cache."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import venv
from pathlib import Path

import pytest

from transpiler import __version__, resources
from transpiler.exec.compiled import shim

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "samples" / "basic_program"
# What `pip wheel .` reads from the repository; copied so the build's own build/ and egg-info stay out of the
# working tree other processes are using.
BUILD_INPUTS = ("pyproject.toml", "setup.py", "MANIFEST.in", "README.md", "transpiler", "templates", "runtime_shim")


def _run(argv: list[str], cwd: Path, env: dict[str, str], timeout: int = 300) -> subprocess.CompletedProcess:
    proc = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)
    assert proc.returncode == 0, f"{' '.join(map(str, argv))} -> {proc.returncode}\n{proc.stdout}\n{proc.stderr}"
    return proc


def _clean_env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "VIRTUAL_ENV", "HH2IEC_CACHE", "XDG_CACHE_HOME", "MATIEC_HOME", "PYTHONHOME")}
    return env


def test_wheel_installs_into_a_new_venv_and_runs_the_sample_outside_the_checkout(tmp_path: Path) -> None:
    src = tmp_path / "src"
    src.mkdir()
    for name in BUILD_INPUTS:
        path = ROOT / name
        if path.is_dir():
            shutil.copytree(path, src / name, ignore=shutil.ignore_patterns("build", "__pycache__", "*.egg-info"))
        else:
            shutil.copy2(path, src / name)
    env = _clean_env()
    dist = tmp_path / "dist"
    # Build isolation fetches setuptools as a user's pip would; the registry downloads come from the pip cache.
    _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--quiet", "-w", str(dist), str(src)], tmp_path, env)
    (wheel,) = dist.glob("hh2iec-*.whl")
    target = tmp_path / "venv"
    venv.create(target, with_pip=True)
    python, hh2iec = target / "bin" / "python", target / "bin" / "hh2iec"
    _run([str(python), "-m", "pip", "install", "--quiet", str(wheel)], tmp_path, env)

    installed = Path(_run([str(python), "-c", "import transpiler, sys; print(transpiler.__file__)"], tmp_path,
                          env).stdout.strip()).parent
    assert installed.is_relative_to(target), installed
    # Every template folder of the checkout is packaged whole (a folder setup.py does not name would be missing).
    assert sorted(p.relative_to(installed / "_data" / "templates") for p in
                  (installed / "_data" / "templates").glob("*/*.j2")) == sorted(
        p.relative_to(ROOT / "templates") for p in (ROOT / "templates").glob("*/*.j2"))
    assert {p.name for p in (installed / "_data" / "runtime_shim").iterdir()} == {
        p.name for p in (ROOT / "runtime_shim").glob("*.[ch]")}

    work = tmp_path / "work"
    work.mkdir()
    # pip above kept its own cache; hh2iec gets an empty one, so the shim is built from the packaged sources.
    run_env = dict(env, XDG_CACHE_HOME=str(tmp_path / "xdg"))
    assert _run([str(hh2iec), "--version"], work, run_env).stdout == f"hh2iec {__version__}\n"
    _run([str(hh2iec), "transpile", str(SAMPLE / "Main_PGM.src"), "--out", "out"], work, run_env)
    for name in ("project.st", "project.xml", "report.md", "io_map.csv"):
        assert (work / "out" / name).stat().st_size > 0, name
    # The TwinCAT project folder and the README come from the packaged templates too.
    _run([str(hh2iec), "transpile", str(SAMPLE / "Main_PGM.src"), "--target", "twincat", "--out", "tc"], work, run_env)
    assert (work / "tc" / "README.md").stat().st_size > 0
    assert len(list((work / "tc" / "twincat").rglob("*.TcPOU"))) > 50
    scenarios = sorted(SAMPLE.glob("scenarios/*.yaml"))[:3]
    proc = _run([str(hh2iec), "equiv", str(SAMPLE / "Main_PGM.src"), "--backend", "builtin",
                 *[a for s in scenarios for a in ("--scenario", str(s))], "--random-cycles", "200",
                 "--report", "equiv.json", "--junit", "equiv.xml"], work, run_env)
    assert "EQUIVALENT" in proc.stdout and "NOT EQUIVALENT" not in proc.stdout, proc.stdout
    assert (work / "equiv.json").stat().st_size > 0 and (work / "equiv.xml").stat().st_size > 0
    (built,) = (tmp_path / "xdg" / "hh2iec").glob(f"shim-{__version__}-*/{shim.LIB_NAME}")
    assert not list(installed.rglob("*.so")), "the shim must never be built into the installed package"


def test_data_folders_come_from_the_checkout_when_the_package_carries_none() -> None:
    assert resources.data_dir("templates") == ROOT / "templates"
    assert resources.data_dir("runtime_shim") == ROOT / "runtime_shim"
    with pytest.raises(ValueError, match="unknown data folder"):
        resources.data_dir("samples")


def test_an_installed_copy_wins_over_the_checkout(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    package = tmp_path / "transpiler"
    (package / resources.PACKAGED_DATA / "templates").mkdir(parents=True)
    monkeypatch.setattr(resources.resources, "files", lambda name: package)
    assert resources.data_dir("templates") == package / resources.PACKAGED_DATA / "templates"


def test_cache_dir_follows_hh2iec_cache_then_xdg(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("HH2IEC_CACHE", str(tmp_path / "own"))
    assert resources.cache_dir() == tmp_path / "own"
    monkeypatch.delenv("HH2IEC_CACHE")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert resources.cache_dir() == tmp_path / "xdg" / "hh2iec"
    monkeypatch.setenv("XDG_CACHE_HOME", "relative/is/ignored")
    assert resources.cache_dir() == Path.home() / ".cache" / "hh2iec"


def test_default_shim_build_goes_to_a_versioned_cache_folder(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("HH2IEC_CACHE", str(tmp_path))
    lib = shim.ensure_built()
    assert lib.parent.parent == tmp_path and lib.parent.name.startswith(f"shim-{__version__}-")
    assert lib.parent.name == f"shim-{shim.cache_key(ROOT / 'runtime_shim')}"
    assert shim.load_shim().hh_module_count() > 0
    # Already built: no compiler is needed any more.
    monkeypatch.setenv("PATH", str(tmp_path / "no-such-dir"))
    monkeypatch.delenv("CC", raising=False)
    assert shim.ensure_built() == lib


def test_changed_sources_get_a_new_cache_key(tmp_path: Path) -> None:
    root = tmp_path / "shim"
    shutil.copytree(ROOT / "runtime_shim", root, ignore=shutil.ignore_patterns("build", "tests"))
    before = shim.cache_key(root)
    with open(root / "hh_nc.c", "a", encoding="utf-8") as f:
        f.write("\n/* changed */\n")
    assert shim.cache_key(root) != before


def test_cc_naming_a_missing_compiler_is_reported_by_name(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CC", "no-such-cc-hh2iec --flag")
    with pytest.raises(shim.ShimUnavailable, match=r"named by CC \('no-such-cc-hh2iec --flag'\) was not found"):
        shim.find_compiler()


def test_cli_without_a_compiler_says_e_tool_naming_it(monkeypatch: pytest.MonkeyPatch, tmp_path: Path,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    from transpiler.cli.app import main
    monkeypatch.setenv("HH2IEC_CACHE", str(tmp_path / "empty-cache"))
    monkeypatch.setenv("PATH", str(tmp_path / "no-such-dir"))
    monkeypatch.delenv("CC", raising=False)
    scenario = sorted(SAMPLE.glob("scenarios/*.yaml"))[0]
    assert main(["simulate", str(SAMPLE / "Main_PGM.src"), "--scenario", str(scenario)]) == 2
    err = capsys.readouterr().err
    assert "error[E-TOOL]" in err and "no C compiler found" in err and "'gcc'" in err, err
    assert "Traceback" not in err
