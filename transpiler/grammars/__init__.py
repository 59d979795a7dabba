"""The lark grammars of the input languages (src, def, cfg/pp, mp), loaded by name."""

from __future__ import annotations

from importlib import resources


def load_grammar(name: str) -> str:
    return resources.files(__package__).joinpath(name).read_text(encoding="utf-8")
