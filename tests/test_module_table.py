"""The PLC module table: one set of rows for Python and the C shim, the calling-context rule, the pure modules."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.test_interp import cycles, machine, values
from transpiler.exec.compiled import shim
from transpiler.exec.interp.pure_modules import format_number, parse_number
from transpiler.exec.interp.sysmodel import module_meta
from transpiler.language import module_table as mt

ROOT = Path(__file__).resolve().parents[1]
KINDS = {mt.PURE: 0, mt.DATA: 1, mt.MACHINE: 2}
CONTEXTS = {mt.ANY: 0, mt.CYCLIC: 1, mt.SUBMIT: 2}

# Catalogue rows with call details (confidence D or P): 53 numbers, plus 9006 (the Basic Program's timer
# module) and 9221 (named beside 9222; its parameters are an assumption).
CATALOGUE_DP = {9019, 9031, 9032, 9035, 9036, 9038, 9040, 9041, 9042, 9048, 9049, 9050, 9051, 9052, 9053, 9054,
                9070, 9080, 9081, 9082, 9092, 9093, 9094, 9095, 9097, 9101, 9102, 9105, 9106, 9123, 9124, 9127,
                9144, 9150, 9159, 9161, 9162, 9169, 9190, 9191, 9192, 9194, 9195, 9222, 9227, 9231, 9244, 9260,
                9261, 9262, 9263, 9264, 9429}


def test_the_generated_c_header_is_the_python_table() -> None:
    text = (ROOT / "runtime_shim" / "hh_module_table.h").read_text(encoding="utf-8")
    assert text == mt.c_table(), "regenerate: python -m transpiler.language.module_table > runtime_shim/hh_module_table.h"


def test_the_loaded_shim_agrees_with_every_row() -> None:
    lib = shim.load_shim()
    c_rows = {info.number: info for info in shim.module_table(lib=lib)}
    assert set(c_rows) == set(mt.MODULE_TABLE)
    for m in mt.MODULE_ROWS:
        info = c_rows[m.number]
        assert (info.nparams, info.nresults, info.kind == "modelled") == (m.nparams, m.nresults, m.modelled), m.number
        assert module_meta(lib, m.number) == (KINDS[m.kind], CONTEXTS[m.context], int(m.strobe),
                                              mt.profile_mask(m.profiles), -1 if m.error_result is None
                                              else m.error_result)
    assert module_meta(lib, 9999) is None


def test_every_catalogue_row_with_call_details_has_an_entry() -> None:
    assert len(CATALOGUE_DP) == 53
    assert CATALOGUE_DP <= set(mt.MODULE_TABLE)
    for m in mt.MODULE_ROWS:
        assert m.confidence in "DPM"
        assert (m.confidence == "P") <= bool(m.assumptions), f"{m.number}: a P row names its assumptions"
        assert m.error_result is None or 0 <= m.error_result < m.nresults
        assert m.st_name.startswith("HH_") and m.st_name.isidentifier()
    assert len({m.st_name for m in mt.MODULE_ROWS}) == len(mt.MODULE_ROWS)


def test_nearest_known_numbers() -> None:
    assert mt.nearest(9033) == [9031, 9032, 9035]
    assert mt.nearest(9999) == [9263, 9264, 9429]


@pytest.mark.parametrize("mantissa, exponent, point, text", [
    (12345, -2, ".", "123.45"), (-5, -1, ",", "-0,5"), (100, -2, ".", "1"), (7, 2, ".", "700"), (0, 3, ".", "0"),
    (-120, -3, ".", "-0.12"),
])
def test_9050_format(mantissa: int, exponent: int, point: str, text: str) -> None:
    assert format_number(mantissa, exponent, point) == text


@pytest.mark.parametrize("text, found", [
    ("X=-12,5 mm", (-125, -1, 2, 7)), ("abc", None), ("+3", (3, 0, 0, 2)), ("99999999999", (999999999, 2, 0, 11)),
])
def test_9052_parse(text: str, found: tuple | None) -> None:
    assert parse_number(text) == found


def test_pure_modules_in_the_interpreter(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        PS  K-1234
        PS  K-2
        PS  K1
        CM  9050
        PS  K1
        CM  9052
        PL  D0
        PL  D4
        L   K99
        =   B20
        PS  K20
        PS  K2
        PS  K1
        CM  9053
        PS  K2
        PS  K24
        CM  9054
        CM  9019
        PL  D8
        PS  K1
        PS  K40
        PS  K1
        CM  9050
        L   M4203
        =   M1
        L   W1022
        =   W30
        EM
    """, profile="itnc530")
    cycles(m, 1)
    assert m.read("S", 1) == "-12.34"
    assert m.read("S", 2) == "63"
    assert values(m, "D0", "D4", "B24", "D8") == {"D0": -1234, "D4": -2, "B24": 99, "D8": 0}
    assert values(m, "M1", "W30") == {"M1": 1, "W30": 2}      # exponent 40: error 2 (A-46r)


CONTEXT_PROGRAM = """
    PS  K910
    PS  K0
    CM  9032
    PL  D0
    L   M4203
    =   M1
    L   W1022
    =   W10
    L   M4172
    SUBM JOB
    =   W12
    EM
    LBL JOB
    PS  K910
    PS  K0
    CM  9032
    PL  D4
    PS  K3
    CM  9161
    L   W1022
    =   W14
    EM
"""


def test_context_rule_codes_20_and_24(tmp_path: Path) -> None:
    m = machine(tmp_path, CONTEXT_PROGRAM, profile="itnc530", mp={"910.0": "100.1200"})
    cycles(m, 2)
    assert values(m, "D0", "M1", "W10", "D4", "W14") == {"D0": 0, "M1": 1, "W10": 20, "D4": 1001200, "W14": 24}


def test_context_rule_switched_off(tmp_path: Path) -> None:
    m = machine(tmp_path, CONTEXT_PROGRAM, profile="itnc530", overrides={"module_context": "ignore"},
                mp={"910.0": "100.1200"})
    cycles(m, 2)
    assert values(m, "D0", "M1") == {"D0": 1001200, "M1": 0}


def test_old_profile_sets_m3171(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        PS  K910
        PS  K0
        CM  9032
        PL  D0
        L   M3171
        =   M2
        EM
    """, profile="tnc407", mp={"910.0": "100.1200"})
    cycles(m, 1)
    assert values(m, "M2", "D0") == {"M2": 1, "D0": 0}      # submit-only in the cyclic program


def test_error_values_hold_every_error_result_the_model_gives() -> None:
    # A row's error_values let the boundary analysis claim that a word pulled from that result holds nothing else:
    # the model, called with corner parameters from the cyclic program and from a job, with tables present and not,
    # never gives another value there.
    from itertools import product

    from transpiler.exec.interp.sysmodel import SysContext
    corners = (-1, 0, 1, 2, 3, 5, 63, 64, 65, 1000)
    rows = [m for m in mt.MODULE_ROWS if m.error_values is not None]
    assert {m.number for m in rows} >= {9092, 9093, 9094}
    for filled in (False, True):
        sys = SysContext()
        if filled:
            for file_type, line, element in product((0, 1, 2), (0, 1, 5), (0, 1, 7)):
                sys.set_table(file_type, line, element, 1)
        for m in rows:
            seen = set()
            for params, in_job in product(product(corners, repeat=m.nparams), (False, True)):
                results, _, _ = sys.call_in(m.number, list(params), in_job)
                seen.add(results[m.error_result])
            assert seen <= m.error_values, (m.number, seen - m.error_values)
            assert len(seen) > 2, (m.number, seen)
