"""The templates jinja keeps compiled in the per-user cache print as freshly compiled ones do, and a cache file or
folder that cannot be used only costs the compile."""

from __future__ import annotations

from pathlib import Path

import jinja2
import pytest

from transpiler.backends import templating
from transpiler.backends.st.writer import StPrinter
from tests.test_st_writer import rich_project


@pytest.fixture
def own_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("HH2IEC_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


@pytest.fixture
def compiles(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """The names of the templates jinja compiles from their source from now on."""
    names: list[str] = []
    compile_source = jinja2.Environment.compile

    def counted(self, source, name=None, filename=None, raw=False, defer_init=False):
        names.append(name)
        return compile_source(self, source, name, filename, raw, defer_init)

    monkeypatch.setattr(jinja2.Environment, "compile", counted)
    return names


def _uncached_text() -> str:
    """The project printed by templates compiled without any cache."""
    printer = StPrinter()
    printer._env.bytecode_cache = None
    return printer.project(rich_project())


def _cache_files(cache: Path) -> list[Path]:
    return sorted((cache / templating.TEMPLATE_CACHE_FOLDER).rglob("*.cache"))


def test_a_second_process_loads_the_compiled_templates_and_prints_the_same(own_cache: Path,
                                                                           compiles: list[str]) -> None:
    expected = _uncached_text()
    compiles.clear()
    assert StPrinter().project(rich_project()) == expected
    assert compiles and _cache_files(own_cache)            # compiled once, and kept
    compiles.clear()
    assert StPrinter().project(rich_project()) == expected  # (a new environment, as in the next command)
    assert compiles == []


def test_a_changed_template_is_compiled_again(own_cache: Path, compiles: list[str], tmp_path: Path) -> None:
    folder = tmp_path / "tpl"
    folder.mkdir()
    (folder / "t.j2").write_text("one {{ x }}")
    env = lambda: jinja2.Environment(loader=jinja2.FileSystemLoader(str(folder)),  # noqa: E731
                                     bytecode_cache=templating.template_cache())
    assert env().get_template("t.j2").render(x=1) == "one 1"
    (folder / "t.j2").write_text("two {{ x }}")
    compiles.clear()
    assert env().get_template("t.j2").render(x=1) == "two 1"
    assert compiles == ["t.j2"]


# (jinja's own header followed by no checksum, or by bytes that are no pickle, or a checksum and no code)
_HEADER = jinja2.bccache.bc_magic


@pytest.mark.parametrize("damage", [b"", b"garbage", _HEADER, _HEADER + b"\x80\x05garbage",
                                    _HEADER + b"\x80\x04\x95\xff\xff\xff"])
def test_a_damaged_cache_file_only_costs_the_compile(own_cache: Path, compiles: list[str], damage: bytes) -> None:
    expected = _uncached_text()
    StPrinter().project(rich_project())
    files = _cache_files(own_cache)
    assert files
    for file in files:
        file.write_bytes(damage)
    compiles.clear()
    assert StPrinter().project(rich_project()) == expected
    assert compiles                                         # compiled again ...
    assert all(file.read_bytes() != damage for file in files if file.exists())   # ... and written again


def test_a_cache_folder_that_cannot_be_made_means_no_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    blocked = tmp_path / "a-file"
    blocked.write_text("not a folder")
    monkeypatch.setenv("HH2IEC_CACHE", str(blocked))
    assert templating.template_cache() is None
    assert StPrinter().project(rich_project()) == _uncached_text()


def test_a_cache_folder_that_cannot_be_written_only_costs_the_compile(own_cache: Path,
                                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    def refused(*args, **kwargs):
        raise PermissionError("read-only")

    monkeypatch.setattr(templating.jinja2.bccache.tempfile, "NamedTemporaryFile", refused)
    assert StPrinter().project(rich_project()) == _uncached_text()
    assert _cache_files(own_cache) == []


def test_templates_compiled_with_other_options_are_kept_apart(own_cache: Path) -> None:
    """jinja keys a cache file by the template's source and the Python version only, while options such as
    trim_blocks change the compiled code: another set of options (another hh2iec version, say) gets a folder of
    its own instead of loading code compiled for the current one."""
    other = {**templating._OPTIONS, "trim_blocks": False}
    ours, theirs = templating.template_cache(), templating.template_cache(other)
    assert ours is not None and theirs is not None
    assert ours.directory != theirs.directory
    assert templating.template_cache().directory == ours.directory     # the same options: the same folder
