"""The language test vectors (tests/data/vectors, from spec section 20) through the front end: compile errors
exactly as expected, else clean."""

from __future__ import annotations

import pytest
from test_frontend_support import errors
from vectors import Vector, VectorDataMissing, load_vectors

from transpiler.frontend.load import ProjectOptions
from transpiler.frontend.pipeline import compile_project
from transpiler.language.semantics import make_semantics

VECTORS = load_vectors()          # raises (a collection error, not a skip) when tests/data/vectors is missing


def _params():
    return [pytest.param(v, id=v.id) for v in VECTORS]


def _compile(vector: Vector, tmp_path):
    main = vector.write(tmp_path)
    options = ProjectOptions(main=main, extra_global_defs=vector.extra_defs(tmp_path))
    return compile_project(options, make_semantics(vector.profile))


def test_the_spec_has_vectors_of_both_kinds():
    compile_errors = [v for v in VECTORS if (v.expect_error or {}).get("phase") == "compile"]
    assert len(VECTORS) >= 80
    assert compile_errors, "the spec should contain vectors with an expected compile-time error"


@pytest.mark.parametrize("vector", _params())
def test_vector_compiles_as_expected(vector: Vector, tmp_path):
    result = _compile(vector, tmp_path)
    expected = vector.expect_error or {}
    got = errors(result)
    if expected.get("phase") == "compile":
        assert [e.code for e in got] == [expected["code"]], [d.render() for d in result.diagnostics.items]
        if "line" in expected:
            assert got[0].line == expected["line"], got[0]
            assert got[0].file == "main.src"
    else:
        assert got == [], [d.render() for d in result.diagnostics.items]
        assert result.program is not None and result.program.files[0].ops


def test_every_vector_compiles_the_same_twice(tmp_path):
    """Determinism: two runs over the same files give the same diagnostics, ops, symbols and auto-assigned addresses."""
    for vector in VECTORS:
        folder = tmp_path / vector.id
        first = _compile(vector, folder)
        second = _compile(vector, folder)
        assert [d.render() for d in first.diagnostics.items] == [d.render() for d in second.diagnostics.items]
        if first.program is not None:
            assert first.program.files == second.program.files, vector.id
            assert first.program.symbols == second.program.symbols, vector.id
            assert first.program.auto_assigned == second.program.auto_assigned, vector.id


def test_missing_or_empty_vector_folder_is_an_error_not_a_skip(tmp_path):
    """A checkout without tests/data/vectors must fail loudly, never run zero vector tests."""
    with pytest.raises(VectorDataMissing, match="restore them"):
        load_vectors(tmp_path / "absent")
    (tmp_path / "empty").mkdir()
    with pytest.raises(VectorDataMissing):
        load_vectors(tmp_path / "empty")
