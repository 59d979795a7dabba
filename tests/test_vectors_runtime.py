"""Runs the language test vectors (tests/data/vectors, from spec section 20) on the reference interpreter, and proves each assumption switch is real."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from tests.vectors import Vector, load_vectors
from transpiler.frontend.load import ProjectOptions
from transpiler.exec.interp import Machine
from transpiler.frontend.pipeline import compile_project
from transpiler.verify.scenario import parse_operand, values_equal
from transpiler.language.semantics import ASSUMPTIONS, PROFILES, make_semantics

VECTORS = load_vectors()          # raises (a collection error, not a skip) when tests/data/vectors is missing
RUNTIME = [v for v in VECTORS if (v.expect_error or {}).get("phase") != "compile"]

# Integer settings have no listed alternative; these values are far enough from the default to matter.
INTEGER_FLIPS = {"data_stack_words": 2, "call_depth": 0, "cycle_time_ms": 40, "max_instructions_per_cycle": 3,
                 "first_cycle_marker": 4171, "index_register_width": 16, "psx_width": 16}

# Switches whose listed vectors cannot tell the alternative apart, and why; each one is proven real
# by its own program in tests/test_interp_switches.py (or belongs to the front end).
INSENSITIVE = {
    "while_retest": "TV-46 is written to give the same result for both settings (spec 6.15); front end",
    "symbol_case": "TV-65 spells every name exactly as defined; front end",
    "literal_range": "TV-19/TV-85 use literals inside the documented range; front end",
    "timer_start_consumed": "the timer vectors rewrite the start operand from a level every cycle "
                            "(test_interp_switches.py::test_timer_start_consumed)",
    "counter_start_consumed": "the counter vectors rewrite the start operand every cycle "
                              "(test_interp_switches.py::test_counter_start_consumed)",
    "index_scaling": "the indexed vectors use byte operands and KF, where both scalings agree "
                     "(test_interp_switches.py::test_index_scaling)",
    "index_read_check": "TV-62 faults on an indexed write, which is checked in both settings "
                        "(test_interp_switches.py::test_index_read_check)",
    "store_truncation": "TV-15/TV-18 store -1 and -4, which fit the signed byte/word range "
                        "(test_interp_switches.py::test_store_saturation)",
    "bracket_width": "TV-31 has only 32-bit operands inside its brackets; besides, make_semantics coerces this "
                     "key as an integer and rejects 'operand' (test_interp_switches.py::test_bracket_width)",
}


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    if "vector" in metafunc.fixturenames:
        metafunc.parametrize("vector", RUNTIME, ids=[v.id for v in RUNTIME])
    if "flip" in metafunc.fixturenames:
        flips = switch_flips()
        metafunc.parametrize("flip", flips, ids=[f"{k}={v}" for k, v, _ in flips])


# ---------------------------------------------------------------------------------------------
# the vector runner


@dataclasses.dataclass
class Outcome:
    mismatches: list[str]
    compile_errors: list[str]


def _ref(name: str) -> tuple[str, int]:
    if name in ("LA", "WA", "X"):
        return name, 0
    ref = parse_operand(name)
    assert ref is not None, f"vector names an unknown operand {name}"
    return ref.kind, ref.addr


def _equal(kind: str, expected: object, actual: object) -> bool:
    # LA/WA/X compare like a 32-bit operand (vectors compare modulo 2^width)
    return values_equal("D" if kind in ("LA", "WA", "X") else kind, expected, actual)


def run_vector(vector: Vector, folder: Path, overrides: dict | None = None) -> Outcome:
    """Compile and run one vector; the mismatches against its expect/trace/expect_error, as text."""
    main = vector.write(folder)
    semantics = make_semantics(vector.profile, overrides)
    result = compile_project(ProjectOptions(main=main, extra_global_defs=vector.extra_defs(folder)), semantics)
    if result.diagnostics.has_errors():
        return Outcome([], [d.render() for d in result.diagnostics.errors])
    data = vector.data
    machine = Machine(result.program, data.get("mp"), semantics["cycle_time_ms"])
    for name, value in (data.get("given") or {}).items():
        machine.write(*_ref(name), value)
    nc: dict[int, list[dict]] = {}
    for action in data.get("nc") or []:
        action = dict(action)
        nc.setdefault(action.pop("cycle"), []).append(action)
    expected_error = vector.expect_error
    mismatches: list[str] = []
    for cycle in range(data.get("cycles", 1)):
        writes = [(*_ref(name), values[cycle]) for name, values in (data.get("inputs") or {}).items()
                  if cycle < len(values)]
        report = machine.run_cycle(cycle, writes, nc.get(cycle, []))
        if report.faults:
            fault = report.faults[0]
            if expected_error is None:
                return Outcome([f"unexpected runtime fault {fault.render()}"], [])
            got = {"phase": "runtime", "code": fault.code, "line": fault.span.line if fault.span else None,
                   "cycle": fault.cycle}
            wrong = {k: (v, got.get(k)) for k, v in expected_error.items() if got.get(k) != v}
            return Outcome([f"runtime fault {fault.render()} differs from expect_error in {wrong}"] if wrong else [], [])
        for name, values in (data.get("trace") or {}).items():
            kind, addr = _ref(name)
            actual = machine.read(kind, addr)
            if not _equal(kind, values[cycle], actual):
                mismatches.append(f"{name} after cycle {cycle}: expected {values[cycle]!r}, got {actual!r}")
    if expected_error is not None:
        return Outcome([f"no runtime fault; expected {expected_error}"], [])
    for name, value in (data.get("expect") or {}).items():
        kind, addr = _ref(name)
        actual = machine.read(kind, addr)
        if not _equal(kind, value, actual):
            mismatches.append(f"{name}: expected {value!r}, got {actual!r}")
    return Outcome(mismatches, [])


# ---------------------------------------------------------------------------------------------
# every public vector passes


def test_vector(vector: Vector, tmp_path: Path) -> None:
    outcome = run_vector(vector, tmp_path)
    assert not outcome.compile_errors, "\n".join(outcome.compile_errors)
    assert not outcome.mismatches, f"{vector.id} {vector.data['title']}:\n" + "\n".join(outcome.mismatches)


def test_all_public_vectors_are_present() -> None:
    assert len(VECTORS) == 86
    assert len(RUNTIME) == 86 - sum(1 for v in VECTORS if (v.expect_error or {}).get("phase") == "compile")


# ---------------------------------------------------------------------------------------------
# every switch the vectors depend on is real


def _keys_of(assumption_id: str) -> list[str]:
    """Setting keys of an assumption id; A-34 covers A-34a and A-34b."""
    return [a.key for a in ASSUMPTIONS
            if a.id == assumption_id or (a.id.startswith(assumption_id) and a.id[len(assumption_id):].isalpha())]


def switch_flips() -> list[tuple[str, object, list[Vector]]]:
    by_key: dict[str, list[Vector]] = {}
    for vector in VECTORS:
        for assumption_id in vector.data.get("assumptions") or []:
            for key in _keys_of(assumption_id):
                by_key.setdefault(key, []).append(vector)
    flips = []
    for key, vectors in sorted(by_key.items()):
        assumption = next(a for a in ASSUMPTIONS if a.key == key)
        alternatives = [INTEGER_FLIPS[key]] if key in INTEGER_FLIPS else list(assumption.alternatives)
        flips += [(key, alt, vectors) for alt in alternatives]
    return flips


def test_flipping_a_switch_fails_a_vector_that_lists_it(flip: tuple, tmp_path: Path) -> None:
    key, alternative, vectors = flip
    if key in INSENSITIVE:
        pytest.skip(f"{key}: {INSENSITIVE[key]}")
    results = {}
    for vector in vectors:
        if PROFILES[vector.profile].defaults[key] == alternative:
            continue
        outcome = run_vector(vector, tmp_path / vector.id, {key: alternative})
        results[vector.id] = bool(outcome.mismatches or outcome.compile_errors)
    assert results, f"no vector listing {key} runs with a non-default value"
    assert any(results.values()), f"{key} = {alternative!r} changes none of {sorted(results)}: the switch has no effect"


def test_insensitive_list_names_only_switches_the_vectors_list() -> None:
    listed = {key for key, _, _ in switch_flips()}
    assert set(INSENSITIVE) <= listed
