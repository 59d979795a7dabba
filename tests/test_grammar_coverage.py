"""Every rule, alias and terminal of each .lark grammar is exercised by a test line, and every rule has a transformer handler."""

from __future__ import annotations

import inspect

import pytest
from lark import Lark, Token, Transformer, Tree

from transpiler.frontend import parse, preprocess
from transpiler.frontend.grammars import lalr_parser, load_grammar

# Lines (comments already split off, as the parsers receive them) that together use every rule and terminal.
CORPUS = {
    "src.lark": [
        "LBL Step_1", "KFIELD Speeds", "ENDK", "K$7D0", "K%1010", "k -5", "USES Spindle.src", "GLOBAL Entry",
        "EXTERN Entry", "#define /g Machine_IO.def", "#define Local.def", "EM", "A [", "]", "L  M12", "L I 212",
        "L W262", "L d4[X]", "L K+25", "L S3", "L S#E12", "L S\"a;b\"", "L KF Speeds[X]", "L X", "CM 9032",
        "L MG_step", "= MG_tab [ X ]", "x K3", "L- W2", "B= M8",
    ],
    "def.lark": [
        "#type Markers", "#TYPE", "#TYPEDEF ApiSpin", "#define /g Other.def", "#define Local.def", "I_door I 17",
        "O_lamp O4", "KL_retries K 3", "KG_mask K $00FF", "MG_step M", "/c I_air M &MG_one",
    ],
    "pp.lark": [
        'DEFINE A = "belt"', "DEFINE B = -3", "DEFINE C = %0101", "DEFINE D = $1F", "DEFINE E = &A", "#if A = 1",
        "#if A <> &B", "#ifdef A", "#ifndef A", "#else", "#endif",
    ],
    "mp.lark": ["MP4110.0 : 0.125", "MP 4120 : 3"],
}

TRANSFORMERS = {"src.lark": parse._SrcTransformer, "def.lark": parse._DefTransformer, "pp.lark": preprocess._PPTransformer}


def _grammar(name: str) -> tuple[Lark, Lark]:
    """The production parser and a twin that keeps every token (anonymous ones such as '=' included)."""
    return lalr_parser(name), Lark(load_grammar(name), parser="lalr", lexer="contextual", keep_all_tokens=True)


def _tree_names(parser: Lark) -> set[str]:
    """Names that can head a parse tree: named rules and aliases (inlined '?' rules without alias excluded)."""
    return {str(r.alias or r.origin.name) for r in parser.rules
            if not str(r.origin.name).startswith("_") and (r.alias or not r.options.expand1)}


def _walk(tree: Tree, rules: set[str], terminals: set[str]) -> None:
    rules.add(str(tree.data))
    for child in tree.children:
        if isinstance(child, Tree):
            _walk(child, rules, terminals)
        elif isinstance(child, Token):
            terminals.add(child.type)


@pytest.mark.parametrize("name", sorted(CORPUS))
def test_every_rule_and_terminal_is_exercised(name):
    production, keep_all = _grammar(name)
    rules: set[str] = set()
    terminals: set[str] = set()
    for line in CORPUS[name]:
        _walk(keep_all.parse(line), rules, terminals)
        production.parse(line)                 # the production parser accepts the same line
    assert _tree_names(production) - rules == set()
    # (lexer_conf.ignore: a parser loaded from the cache has no ignore_tokens attribute)
    all_terminals = {t.name for t in production.terminals} - set(production.lexer_conf.ignore)
    assert all_terminals - terminals == set()


@pytest.mark.parametrize("name", sorted(TRANSFORMERS))
def test_every_rule_has_a_transformer_handler_and_no_handler_is_stale(name):
    names = _tree_names(lalr_parser(name))
    transformer = TRANSFORMERS[name]
    handlers = {n for n, f in inspect.getmembers(transformer, inspect.isfunction)
                if f.__qualname__.startswith(transformer.__name__ + ".") and not n.startswith("_")}
    assert names - handlers == set(), "rules without a handler"
    assert handlers - names == set(), "handlers without a rule"
    assert issubclass(transformer, Transformer)


def test_the_mp_grammar_is_read_without_a_transformer():
    """MpParser reads the tokens of `start` directly; the grammar must stay a single flat rule for that."""
    assert _tree_names(lalr_parser("mp.lark")) == {"start"}


def test_every_grammar_file_is_covered():
    from importlib import resources
    files = {p.name for p in resources.files("transpiler.frontend.grammars").iterdir() if p.name.endswith(".lark")}
    assert files == set(CORPUS)


def test_the_transformers_turn_the_corpus_into_values():
    """The handlers run on every corpus line without error (the corpus is also the handler test)."""
    src = parse.SrcParser()
    for line in CORPUS["src.lark"]:
        assert src.parse_line(line)[0] == "ok", line
    pp = preprocess.PPParser()
    for line in CORPUS["pp.lark"]:
        assert pp.parse(line) is not None, line
    defs = parse._DefTransformer()
    for line in CORPUS["def.lark"]:
        assert isinstance(defs.transform(lalr_parser("def.lark").parse(line)), tuple), line
