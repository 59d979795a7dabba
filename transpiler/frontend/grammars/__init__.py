"""The lark grammars of the input languages (src, def, cfg/pp, mp), loaded by name."""

from __future__ import annotations

import functools
from importlib import resources

from lark import Lark

from transpiler.resources import cache_dir

PARSER_CACHE_FOLDER = "grammars"
"""Folder of the per-user cache where lark keeps the built parsers."""


def load_grammar(name: str) -> str:
    return resources.files(__package__).joinpath(name).read_text(encoding="utf-8")


@functools.lru_cache(maxsize=None)
def lalr_parser(name: str) -> Lark:
    """The LALR parser of one grammar, built once per process.

    Building a parser takes ~50 ms, parsing a line ~50 us; a parser holds no per-parse state (lark creates
    the lexer and parser state afresh on every `parse`), so one instance serves every run. lark keeps the built
    parser in the per-user cache and loads it from there in a few ms; it builds it again (and rewrites the file)
    when the file's hash of the grammar, the options and lark's version is not the current one, and it carries
    on without a file it cannot read or write.
    """
    return Lark(load_grammar(name), parser="lalr", lexer="contextual", cache=parser_cache_file(name))


def parser_cache_file(name: str) -> str | bool:
    """Where lark caches the parser of grammar `name`; False (no cache) when the folder cannot be made."""
    try:
        folder = cache_dir() / PARSER_CACHE_FOLDER
        folder.mkdir(parents=True, exist_ok=True)
    except (OSError, RuntimeError):       # (RuntimeError: Path.home() without a home directory)
        return False
    return str(folder / f"{name}.cache")
