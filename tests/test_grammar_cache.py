"""The parsers lark keeps in the per-user cache parse as freshly built ones do, and a cache folder or file that
cannot be used only costs the build."""

from __future__ import annotations

from pathlib import Path

import pytest
from lark import Lark
from lark.exceptions import UnexpectedInput

from transpiler.frontend.grammars import PARSER_CACHE_FOLDER, lalr_parser, load_grammar, parser_cache_file
from tests.test_grammar_coverage import CORPUS

BAD_LINES = {"src.lark": ["L K", "= [", "LBL"], "def.lark": ["#define", "I_x I I"], "pp.lark": ["DEFINE = 3", "#if"],
             "mp.lark": ["MP : 1", "MP4110.0 :"]}


@pytest.fixture
def own_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An empty per-user cache; the process's parsers are built again inside the test and after it."""
    monkeypatch.setenv("HH2IEC_CACHE", str(tmp_path / "cache"))
    lalr_parser.cache_clear()
    yield tmp_path / "cache"
    lalr_parser.cache_clear()


def _outcomes(parser: Lark, name: str) -> list[str]:
    """What the parser makes of the corpus and of bad lines: the tree, or where and what it expected."""
    found = []
    for line in CORPUS[name] + BAD_LINES[name]:
        try:
            found.append(parser.parse(line).pretty())
        except UnexpectedInput as exc:
            found.append(f"{type(exc).__name__} {exc.line}:{exc.column} {sorted(getattr(exc, 'expected', ()) or ())}")
    return found


def _fresh(name: str) -> Lark:
    return Lark(load_grammar(name), parser="lalr", lexer="contextual")


@pytest.mark.parametrize("name", sorted(CORPUS))
def test_a_cached_parser_parses_as_a_fresh_one(own_cache: Path, name: str) -> None:
    lalr_parser(name)
    cached = own_cache / PARSER_CACHE_FOLDER / f"{name}.cache"
    assert cached.is_file() and cached.stat().st_size > 0
    written = cached.stat().st_mtime_ns
    lalr_parser.cache_clear()
    loaded = lalr_parser(name)
    assert cached.stat().st_mtime_ns == written          # loaded, not built and written again
    assert _outcomes(loaded, name) == _outcomes(_fresh(name), name)


def test_a_damaged_cache_file_is_built_again(own_cache: Path) -> None:
    folder = own_cache / PARSER_CACHE_FOLDER
    folder.mkdir(parents=True)
    (folder / "src.lark.cache").write_bytes(b"not a lark cache\n\x80\x04garbage")
    assert _outcomes(lalr_parser("src.lark"), "src.lark") == _outcomes(_fresh("src.lark"), "src.lark")
    # ...and the file now holds the parser again.
    lalr_parser.cache_clear()
    assert _outcomes(lalr_parser("src.lark"), "src.lark") == _outcomes(_fresh("src.lark"), "src.lark")


def test_a_cache_that_cannot_be_made_or_written_is_done_without(tmp_path: Path,
                                                                monkeypatch: pytest.MonkeyPatch) -> None:
    blocker = tmp_path / "a-file"
    blocker.write_text("in the way of the cache folder")
    monkeypatch.setenv("HH2IEC_CACHE", str(blocker))
    assert parser_cache_file("def.lark") is False
    lalr_parser.cache_clear()
    try:
        assert _outcomes(lalr_parser("def.lark"), "def.lark") == _outcomes(_fresh("def.lark"), "def.lark")
        # A folder that exists but holds a folder where the file should be: lark can neither read nor write it.
        monkeypatch.setenv("HH2IEC_CACHE", str(tmp_path / "cache"))
        (tmp_path / "cache" / PARSER_CACHE_FOLDER / "pp.lark.cache").mkdir(parents=True)
        lalr_parser.cache_clear()
        assert _outcomes(lalr_parser("pp.lark"), "pp.lark") == _outcomes(_fresh("pp.lark"), "pp.lark")
    finally:
        lalr_parser.cache_clear()
