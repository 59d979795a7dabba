"""The built-in ST executor's strict checker gives matiec's verdict on every recorded snippet.

tests/data/matiec_verdicts/*.st are small complete ST files; verdicts.json holds what strict iec2c (then gcc on
its C) said about each one, measured with `python -m tests.matiec_verdicts --measure`. The first test needs no
matiec and runs everywhere; the second re-measures with the real iec2c when it is found (`make test-matiec`).
"""

from __future__ import annotations

import pytest
from matiec_verdicts import DATA_DIR, VERDICTS_FILE, load_verdicts, measure_one, snippet_paths

from transpiler.backends.st.check import find_iec2c
from transpiler.exec.stexec import StError, load_st

# Fewer would mean the corpus was lost, not that matiec changed its mind.
MIN_SNIPPETS = 60


def _snippet_names() -> list[str]:
    return [path.stem for path in snippet_paths()]


def test_the_corpus_and_its_verdicts_are_complete():
    assert DATA_DIR.is_dir(), f"missing folder {DATA_DIR}"
    assert VERDICTS_FILE.is_file(), f"missing {VERDICTS_FILE} (measure it with python -m tests.matiec_verdicts --measure)"
    names = _snippet_names()
    assert len(names) >= MIN_SNIPPETS, f"only {len(names)} snippets in {DATA_DIR}"
    verdicts = load_verdicts()
    assert sorted(verdicts) == sorted(names), "every snippet needs exactly one recorded verdict"
    for name, verdict in verdicts.items():
        assert isinstance(verdict["accept"], bool), name
        assert verdict["accept"] == (verdict["message"] == ""), f"{name}: a rejection carries iec2c's message"
        assert "/" not in verdict["message"].split(": error")[0], f"{name}: message has a path"
        assert verdict["matiec_version"] and verdict["matiec_commit"], name
    accepted = sum(v["accept"] for v in verdicts.values())
    assert 0 < accepted < len(verdicts), "the corpus must hold both accepted and rejected files"


@pytest.mark.parametrize("name", _snippet_names())
def test_builtin_checker_agrees_with_matiec(name: str) -> None:
    verdict = load_verdicts().get(name)
    assert verdict is not None, f"no recorded verdict for {name}.st"
    text = (DATA_DIR / f"{name}.st").read_text(encoding="utf-8")
    try:
        load_st(text, f"{name}.st")
    except StError as exc:
        ours = [d.render() for d in exc.diagnostics]
        assert not verdict["accept"], f"matiec accepts {name}.st, the built-in checker rejects it: {ours}"
        return
    assert verdict["accept"], f"matiec rejects {name}.st ({verdict['message']}), the built-in checker accepts it"


@pytest.mark.skipif(find_iec2c() is None, reason="iec2c not found ($MATIEC_HOME/iec2c or PATH): "
                                                 "re-measuring matiec's verdicts needs it (make test-matiec)")
def test_recorded_verdicts_are_what_matiec_says_now() -> None:
    """One test for the whole corpus (it needs iec2c, so it is one skip, not one per snippet, where iec2c is absent);
    every snippet whose verdict or message changed is listed."""
    iec2c = find_iec2c()
    assert iec2c is not None
    verdicts = load_verdicts()
    changed = []
    for name in _snippet_names():
        measured = measure_one(iec2c, (DATA_DIR / f"{name}.st").read_text(encoding="utf-8"), f"{name}.st")
        recorded = verdicts[name]
        if (measured.accept, measured.message) != (recorded["accept"], recorded["message"]):
            changed.append(f"{name}: recorded {recorded['accept']} {recorded['message']!r}, "
                           f"now {measured.accept} {measured.message!r}")
    assert changed == []
