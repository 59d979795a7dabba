"""The lark grammars of the input languages (src, def, cfg/pp, mp), loaded by name."""

from __future__ import annotations

import functools
from importlib import resources

from lark import Lark


def load_grammar(name: str) -> str:
    return resources.files(__package__).joinpath(name).read_text(encoding="utf-8")


@functools.lru_cache(maxsize=None)
def lalr_parser(name: str) -> Lark:
    """The LALR parser of one grammar, built once per process.

    Building a parser takes ~50 ms, parsing a line ~50 us; a parser holds no per-parse state (lark creates
    the lexer and parser state afresh on every `parse`), so one instance serves every run.
    """
    return Lark(load_grammar(name), parser="lalr", lexer="contextual")
