"""The module models against the catalogue: every module the catalogue documents in detail (confidence D) has
cases (parameters, calling context) -> (results, error status, W1022 code) taken from its row.

The data and machine modules run in the one C model both executors share: each case runs through the reference
interpreter's system context (SysContext.call_in) and through the translated program's HH_Sys FB body on the
built-in executor (SysBinding.externals on a clone of that context). The pure modules run through the
interpreter's pure_modules and through the generated ST library on the built-in executor.

The comments paraphrase the catalogue row each case comes from; where the row leaves a detail open, the case
pins the assumption named in the module table's row (module_table.py, `assumptions`).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Callable

import pytest

from tests.test_interp import cycles, machine, values
from tests.test_pure_lib import MEM_SIZE, N_STRINGS, POINT, STRING_LEN, _project
from transpiler.backends.st.hh_sys import FAULT, FAULT_CODE, IN_JOB, interface
from transpiler.backends.st.writer import render_st
from transpiler.exec.compiled.sysfb import SysBinding
from transpiler.exec.interp import pure_modules as pm
from transpiler.exec.interp.sysmodel import SysContext
from transpiler.language import module_table as mt

# The module numbers the catalogue marks D (call format and semantics read in a manual).
D_MODULES = frozenset({9019, 9035, 9036, 9038, 9040, 9042, 9048, 9049, 9050, 9052, 9053, 9080, 9081, 9093, 9094,
                       9095, 9097, 9102, 9105, 9124, 9127, 9144, 9150, 9159, 9161, 9162, 9169, 9190, 9191, 9192,
                       9194, 9195, 9231, 9244, 9260, 9261, 9262, 9263, 9429})
PURE_D = frozenset({9019, 9050, 9052, 9053})

# Signature and calling context as the catalogue gives them: (parameters, results, context, strobe-bound).
A, C, S = mt.ANY, mt.CYCLIC, mt.SUBMIT
CATALOGUE = {
    9019: (0, 1, A, False), 9035: (1, 1, S, False), 9036: (2, 1, A, False), 9038: (2, 1, A, False),
    9040: (2, 0, A, False), 9042: (1, 0, A, False), 9048: (2, 1, A, False), 9049: (2, 1, A, False),
    9050: (3, 0, A, False), 9052: (1, 2, A, False), 9053: (3, 0, A, False), 9080: (0, 0, A, False),
    9081: (0, 1, A, False), 9093: (3, 2, S, False), 9094: (4, 1, S, False), 9095: (1, 1, S, True),
    9097: (2, 1, S, True), 9102: (1, 1, A, False), 9105: (3, 0, S, False), 9124: (2, 1, A, False),
    9127: (2, 1, A, False), 9144: (3, 1, A, False), 9150: (2, 1, A, True), 9159: (0, 1, A, False),
    9161: (1, 0, C, False), 9162: (0, 1, A, False), 9169: (1, 0, C, False), 9190: (1, 0, A, False),
    9191: (1, 0, A, False), 9192: (1, 1, S, False), 9194: (3, 0, S, False), 9195: (0, 1, A, False),
    9231: (2, 0, C, False), 9244: (2, 1, S, False), 9260: (3, 1, S, False), 9261: (2, 0, A, False),
    9262: (0, 0, S, False), 9263: (1, 0, S, False), 9429: (3, 4, A, False),
}

# Modules whose catalogue row documents no error behaviour and no result a model could give: their cases pin
# the stub rule (results 0, no error).
NO_DOCUMENTED_BEHAVIOUR = frozenset({9080})

JOB, CYC = True, False
K80000000 = -(2**31)          # K$80000000, the submit queue's identifier, as a signed double word


@dataclasses.dataclass(frozen=True)
class Case:
    number: int
    params: tuple[int, ...]
    in_job: bool
    results: tuple[int, ...]
    status: int = 0                     # the module error marker (M4203 / M3171)
    code: int | None = None             # W1022 when the call failed
    setup: Callable[[SysContext], None] | None = None
    documented: bool = True             # an error code or a result the catalogue gives (False: happy path / stub)

    @property
    def id(self) -> str:
        ctx = "job" if self.in_job else "cyclic"
        return f"{self.number}-{','.join(map(str, self.params)) or 'none'}-{ctx}"


def ok(number: int, params: tuple, in_job: bool, results: tuple = (), *, documented: bool = False, setup=None) -> Case:
    return Case(number, params, in_job, results, 0, None, setup, documented)


def err(number: int, params: tuple, in_job: bool, results: tuple, code: int, setup=None) -> Case:
    return Case(number, params, in_job, results, 1, code, setup, True)


def _axes(*active: int, position: int = 0) -> Callable[[SysContext], None]:
    def setup(sys: SysContext) -> None:
        for a in active:
            sys.set_axis(a, True, position)
    return setup


def _ticks(n: int) -> Callable[[SysContext], None]:
    def setup(sys: SysContext) -> None:
        for _ in range(n):
            sys.tick()
    return setup


def _tool_table(sys: SysContext) -> None:
    sys.set_table(0, 5, 1, 40000)        # tool 5: R = 4.0000 mm


def _memory_1024(sys: SysContext) -> None:
    sys.set_memory_size(1024)


def _self_test_started(sys: SysContext) -> None:
    assert sys.call(9144, [0, 0, 0]) == ([0], 0, None)


def _drives(enable: int | None = None) -> Callable[[SysContext], None]:
    def setup(sys: SysContext) -> None:
        sys.set_drives(0b111, 0b100)
        if enable is not None:
            assert sys.call_in(9161, [enable], in_job=False)[1] == 0
    return setup


def _mp7641(value: str) -> Callable[[SysContext], None]:
    def setup(sys: SysContext) -> None:
        sys.set_mp(7641, 0, value)
    return setup


def _status(number: int, value: int) -> Callable[[SysContext], None]:
    def setup(sys: SysContext) -> None:
        sys.set_status(number, value)
    return setup


MODEL_CASES: tuple[Case, ...] = (
    # 9035 read status information: iTNC numbers 50..54 (tool change); 1 invalid number, 20 outside submit/spawn.
    ok(9035, (51,), JOB, (7,), setup=_status(51, 7), documented=True),
    err(9035, (256,), JOB, (0,), 1),
    err(9035, (-1,), JOB, (0,), 1),
    err(9035, (51,), CYC, (0,), 20),
    # 9036 write status information: 0-4 / 11-19 interpolation factors 0..10, 5 all axes, 10 jog limit (-1 and
    # -2 cancel); pulled error 1 wrong number / 2 out of range / 3 disabled; TNC 426 W1022 2 / 1 / 6; needs MP7641=1.
    ok(9036, (0, 10), CYC, (0,)),
    ok(9036, (19, 0), JOB, (0,)),
    ok(9036, (10, -2), CYC, (0,), documented=True),
    err(9036, (20, 1), CYC, (1,), 2),
    err(9036, (3, 11), CYC, (2,), 1),
    err(9036, (5, -1), CYC, (2,), 1),
    err(9036, (0, 1), CYC, (3,), 6, setup=_mp7641("0")),
    ok(9036, (0, 1), CYC, (0,), setup=_mp7641("1")),
    # 9038 axis information: axis or -1 = all (bit mask, bit 0 = first axis); info 0 axis active;
    # 1 info not available, 2 axis not found.
    ok(9038, (-1, 0), CYC, (0b101,), setup=_axes(0, 2), documented=True),
    ok(9038, (2, 0), JOB, (1,), setup=_axes(0, 2), documented=True),
    err(9038, (0, 10), CYC, (0,), 1),
    err(9038, (16, 0), CYC, (0,), 2),
    err(9038, (-2, 0), CYC, (0,), 2),
    # 9040 axis coordinates into double words: type 0 actual .. 4 distance-to-go; module error on failure.
    ok(9040, (100, 4), CYC, ()),
    err(9040, (100, 5), CYC, (), 1),
    err(9040, (100, -1), CYC, (), 1),
    err(9040, (102, 0), CYC, (), 1),
    err(9040, (1008, 0), CYC, (), 1, setup=_memory_1024),
    # 9042 spindle coordinates into 5 double words: error when the address is not DW-aligned or the block does
    # not fit.
    ok(9042, (1004,), CYC, (), setup=_memory_1024),
    err(9042, (6,), CYC, (), 1),
    err(9042, (1008,), CYC, (), 1, setup=_memory_1024),
    # 9048 axis operating state: axis (-1 = all), info 0 brake test, 1 free rotation; 1 invalid info, 2 invalid axis.
    ok(9048, (-1, 0), CYC, (0,), documented=True),
    ok(9048, (3, 1), JOB, (0,), documented=True),
    err(9048, (0, 2), CYC, (0,), 1),
    err(9048, (16, 0), CYC, (0,), 2),
    # 9049 position/speed of one axis: info 2 REF position [0.0001 mm], 3, 8..11; 2 invalid axis or info.
    ok(9049, (1, 2), CYC, (123456,), setup=_axes(1, position=123456), documented=True),
    ok(9049, (1, 10), CYC, (0,)),
    err(9049, (1, 4), CYC, (0,), 2),
    err(9049, (16, 2), CYC, (0,), 2),
    # 9080 clear the PLC window: the row names the error marker but no condition -- the catalogue gives no error
    # behaviour, so the stub rule is pinned.
    ok(9080, (), CYC, ()),
    # 9081 PLC window state: bit 0 window present, bit 1 foreground; the error marker is not affected.
    ok(9081, (), CYC, (0,), documented=True),
    # 9093 read a table element: file type 0 .T / 1 .D / 2 .TCH; error number 1 not in a submit job, 2 file type,
    # 3 no file, 4 line not in file, 5 bad element; submit or spawn job only.
    ok(9093, (0, 5, 1), JOB, (40000, 0), setup=_tool_table, documented=True),
    err(9093, (0, 5, 1), JOB, (0, 3), 3),
    err(9093, (3, 5, 1), JOB, (0, 2), 2, setup=_tool_table),
    err(9093, (0, 6, 1), JOB, (0, 4), 4, setup=_tool_table),
    err(9093, (0, 5, 64), JOB, (0, 5), 5, setup=_tool_table),
    err(9093, (0, 5, 1), CYC, (0, 1), 20, setup=_tool_table),
    # 9094 write a table element: errors as 9093 (6 value out of range); submit or spawn job only.
    ok(9094, (0, 5, 7, 1200), JOB, (0,), setup=_tool_table),
    err(9094, (0, 9, 7, 1), JOB, (4,), 4, setup=_tool_table),
    err(9094, (1, 5, 7, 1), JOB, (3,), 3, setup=_tool_table),
    err(9094, (0, 5, 7, 1), CYC, (1,), 20, setup=_tool_table),
    # 9095 activate a .CMA line: error 0 ok, 1 line missing, 7 not in a submit job; submit job only.
    ok(9095, (3,), JOB, (0,)),
    err(9095, (-1,), JOB, (1,), 1),
    err(9095, (3,), CYC, (7,), 20),
    # 9097 select kinematics: mode must be 0; pulled error 1 bad mode, 2 line missing, 6 not in spawn/submit;
    # W1022 2 for the configuration errors, 20 outside spawn/submit.
    ok(9097, (0, 0), JOB, (0,)),
    err(9097, (0, 1), JOB, (1,), 2),
    err(9097, (-1, 0), JOB, (2,), 2),
    err(9097, (0, 0), CYC, (6,), 20),
    # 9102 serial interface status: interface 0 RS-232 / 1 RS-422; -1 and error 1 for a wrong interface.
    ok(9102, (0,), CYC, (0,), documented=True),
    ok(9102, (1,), JOB, (0,), documented=True),
    err(9102, (2,), CYC, (-1,), 1),
    # 9105 send a block as hex: interface 0..1, address 0..1023, length 0..63, block past the end is an error;
    # submit job only.
    ok(9105, (0, 0, 63), JOB, ()),
    ok(9105, (1, 1000, 24), JOB, ()),
    err(9105, (1, 1000, 25), JOB, (), 1),
    err(9105, (0, 0, 64), JOB, (), 1),
    err(9105, (2, 0, 1), JOB, (), 1),
    err(9105, (0, 1024, 0), JOB, (), 1),
    err(9105, (0, 0, 1), CYC, (), 20),
    # 9124 PLC axis override: override 0..10000 (0.01 %); error 0 set, 1 no such axis, 3 bad override.
    ok(9124, (0, 10000), CYC, (0,)),
    err(9124, (16, 100), CYC, (1,), 1),
    err(9124, (0, 10001), CYC, (3,), 3),
    err(9124, (0, -1), JOB, (3,), 3),
    # 9127 axis coupling status: mode 0..3; W1022 1 bad axis, 2 bad mode.
    ok(9127, (0, 3), CYC, (0,), documented=True),
    err(9127, (-1, 0), CYC, (0,), 1),
    err(9127, (0, 4), CYC, (0,), 2),
    # 9144 functional safety: mode 0 self test (status 0 running), 10 FS mode (0..2), 11 axis test; 2 bad value,
    # 28 test already active.
    ok(9144, (0, 0, 0), CYC, (0,), documented=True),
    ok(9144, (10, 2, 0), CYC, (0,)),
    ok(9144, (11, 15, 0), JOB, (0,)),
    err(9144, (1, 0, 0), CYC, (0,), 2),
    err(9144, (10, 3, 0), CYC, (0,), 2),
    err(9144, (11, 16, 0), CYC, (0,), 2),
    err(9144, (0, 0, 0), CYC, (0,), 28, setup=_self_test_started),
    ok(9144, (0, 0, 0), CYC, (0,), setup=lambda s: (_self_test_started(s), s.tick())),
    # 9150 insert TOOL CALL: code 0 = TOOL CALL; result 0 inserted, 2 unknown code.
    ok(9150, (0, 100), CYC, (0,)),
    err(9150, (1, 100), CYC, (2,), 2),
    # 9159 drives switched off in about 200 ms: a bit mask, no errors.
    ok(9159, (), CYC, (0b100,), setup=_drives(), documented=True),
    # 9161 enable drive controllers: bit mask; error marker when called in a spawn/submit job.
    ok(9161, (0b101,), CYC, ()),
    err(9161, (0b101,), JOB, (), 24, setup=_drives()),
    # 9162 drive-ready status: bit mask (ready power stages the PLC enabled).
    ok(9162, (), CYC, (0b011,), setup=_drives(0b011), documented=True),
    ok(9162, (), JOB, (0,), setup=_drives(), documented=True),
    # 9169 axes for which I32 does not switch the drives off: error marker in a spawn/submit job.
    ok(9169, (0b1,), CYC, ()),
    err(9169, (0b1,), JOB, (), 24),
    # 9190 / 9191 start / stop the PLC operating-hours counters 1..8 (bits 0..7): error marker for a bad parameter.
    ok(9190, (0xFF,), CYC, ()),
    err(9190, (0x100,), CYC, (), 1),
    ok(9191, (0x01,), JOB, ()),
    err(9191, (0x100,), CYC, (), 1),
    # 9192 operating time in seconds: -3 control on, -2 machine on, -1 program run; -1 = error; submit or spawn.
    ok(9192, (-3,), JOB, (1,), setup=_ticks(50), documented=True),
    err(9192, (8,), JOB, (-1,), 1),
    err(9192, (-1,), CYC, (-1,), 20),
    # 9194 alarm marker for an operating time: number -3..-1 or a PLC time, threshold, marker; error marker for a
    # bad value or outside submit/spawn.
    ok(9194, (-1, 3600, 100), JOB, ()),
    ok(9194, (7, 0, 100), JOB, ()),
    err(9194, (-4, 3600, 100), JOB, (), 1),
    err(9194, (8, 3600, 100), JOB, (), 1),
    err(9194, (0, 3600, -1), JOB, (), 1),
    err(9194, (-1, 3600, 100), CYC, (), 20),
    # 9195 system time, UNIX seconds: no errors.
    ok(9195, (), CYC, (0,), documented=True),
    ok(9195, (), JOB, (1,), setup=_ticks(50), documented=True),
    # 9231 thermal compensation: axis 0..8, value -30000..+30000 [0.1 um]; 1 bad axis, 2 bad value, 24 in a job.
    ok(9231, (8, 30000), CYC, ()),
    ok(9231, (0, -30000), CYC, ()),
    err(9231, (9, 0), CYC, (), 1),
    err(9231, (-1, 0), CYC, (), 1),
    err(9231, (0, 30001), CYC, (), 2),
    err(9231, (0, -30001), CYC, (), 2),
    err(9231, (0, 0), JOB, (), 24),
    # 9244 write a line to a file: handle, string 0..7; bytes written, -1 on error; 2 bad handle, 3 bad string
    # number, 20 outside spawn/submit.
    ok(9244, (0, 7), JOB, (0,)),
    err(9244, (0, 8), JOB, (-1,), 3),
    err(9244, (-1, 0), JOB, (-1,), 2),
    err(9244, (0, 0), CYC, (-1,), 20),
    # 9260 read/wait for events: wait 0 or -1; 2 bad wait value, 20 outside spawn/submit.
    ok(9260, (0, 0, 0), JOB, (0,)),
    ok(9260, (-1, 1, 0xFF), JOB, (0,)),
    err(9260, (1, 0, 0), JOB, (0,), 2),
    err(9260, (0, 0, 0), CYC, (0,), 20),
    # 9261 send events: to a SPAWN identifier or the submit queue K$80000000, from anywhere; 30 bad identifier.
    ok(9261, (K80000000, 1), CYC, ()),
    ok(9261, (K80000000, 1), JOB, ()),
    err(9261, (5, 1), CYC, (), 30),
    err(9261, (-1, 1), JOB, (), 30),
    # 9262 context switch: 30 outside spawn/submit.
    ok(9262, (), JOB, ()),
    err(9262, (), CYC, (), 30),
    # 9263 sleep N ms: 30 outside spawn/submit.
    ok(9263, (100,), JOB, ()),
    err(9263, (100,), CYC, (), 30),
    # 9429 NC program status: channel, string, mode 0..3; status 0 running / 1 interrupted / 2 finished;
    # errors for an invalid channel, mode or string number.
    ok(9429, (0, 0, 0), CYC, (2, 0, 0, 0), documented=True),
    ok(9429, (0, 1, 3), JOB, (2, 0, 0, 0), documented=True),
    err(9429, (1, 0, 0), CYC, (0, 0, 0, 0), 1),
    err(9429, (0, 0, 4), CYC, (0, 0, 0, 0), 1),
    err(9429, (0, -1, 1), CYC, (0, 0, 0, 0), 1),
)


@dataclasses.dataclass(frozen=True)
class PureCase:
    number: int
    params: tuple[int, ...]             # string numbers: 0 valid, N_STRINGS invalid
    text: str = ""                      # contents of string 0 before the call
    mem: tuple[int, ...] = ()           # bytes from address 0
    results: tuple[int, ...] = ()
    out_text: str | None = None         # string 0 after a successful call (9050, 9053)
    code: int = 0                       # 0: no error, else the W1022 code

    @property
    def id(self) -> str:
        return f"{self.number}-{','.join(map(str, self.params))}-{self.text!r}"


BAD = N_STRINGS
PURE_CASES: tuple[PureCase, ...] = (
    # 9050 mantissa x 10^exponent to a left-aligned decimal string: only '-' as a sign, no leading or trailing
    # zeros, the decimal character of MP7280 (here a comma); 2 invalid string address or exponent.
    PureCase(9050, (-1234, -2, 0), out_text="-12,34"),
    PureCase(9050, (5, -3, 0), out_text="0,005"),
    PureCase(9050, (1200, -2, 0), out_text="12"),
    PureCase(9050, (7, 2, 0), out_text="700"),
    PureCase(9050, (1, 11, 0), code=2),
    PureCase(9050, (1, 0, BAD), code=2),
    # 9052 decimal string to mantissa and exponent: comma or point, no sign = positive, mantissa truncated to a
    # double word with the exponent adjusted; 2 invalid string address or no number.
    PureCase(9052, (0,), "12,5", results=(125, -1)),
    PureCase(9052, (0,), "-3.25", results=(-325, -2)),
    PureCase(9052, (0,), "7", results=(7, 0)),
    PureCase(9052, (0,), "99999999999", results=(999999999, 2)),
    PureCase(9052, (0,), "abc", results=(0, 0), code=2),
    PureCase(9052, (BAD,), "7", results=(0, 0), code=2),
    # 9053 bytes to hex, two characters per byte (B0 = 99 gives "63"); 1 too many bytes, 2 invalid string
    # address, 4 invalid word address.
    PureCase(9053, (0, 0, 1), mem=(99,), out_text="63"),
    PureCase(9053, (1, 0, 2), mem=(0, 0xAB, 0x0C), out_text="AB0C"),
    PureCase(9053, (0, 0, STRING_LEN // 2 + 1), code=1),
    PureCase(9053, (0, BAD, 1), code=2),
    PureCase(9053, (MEM_SIZE - 1, 0, 2), code=4),
    PureCase(9053, (-1, 0, 1), code=4),
)


# ---------------------------------------------------------------------------------------------
# the rows themselves


def test_every_d_module_matches_the_catalogue_signature_and_context() -> None:
    assert set(CATALOGUE) == D_MODULES
    for number, (nparams, nresults, context, strobe) in CATALOGUE.items():
        row = mt.MODULE_TABLE[number]
        assert (row.nparams, row.nresults, row.context, row.strobe) == (nparams, nresults, context, strobe), number
        assert row.confidence == "D", number
        assert (row.kind == mt.PURE) == (number in PURE_D), number


def test_every_d_module_has_a_case_with_documented_behaviour() -> None:
    cases: dict[int, list] = {}
    for case in (*MODEL_CASES, *PURE_CASES):
        cases.setdefault(case.number, []).append(case)
    cases.setdefault(9019, []).append("interpreter program below")
    assert set(cases) == D_MODULES
    for number in D_MODULES - {9019}:
        got = cases[number]
        if number in NO_DOCUMENTED_BEHAVIOUR:
            assert any(c.status == 0 and all(r == 0 for r in c.results) for c in got), number
            continue
        documented = [c for c in got if (c.code if isinstance(c, PureCase) else c.status) or getattr(c, "documented", True)]
        assert documented, f"{number}: only happy-path cases"
    # every D module whose row names error codes has at least one failing case, with a code the row names
    for number in D_MODULES:
        row = mt.MODULE_TABLE[number]
        codes = {c.code for c in cases[number] if isinstance(c, (Case, PureCase)) and c.code}
        if row.errors and number not in (9159, 9162, 9195):
            assert codes, f"{number}: no error case"
        known = set(row.errors) | {row.context_error(True), row.context_error(False)} | {1}
        assert codes <= known, f"{number}: codes {codes - known} not in the row"


# ---------------------------------------------------------------------------------------------
# data and machine modules: the C model, from both executors


class _Machine:
    """What SysBinding.attach reads of the interpreter's machine."""

    def __init__(self, sys: SysContext):
        self.sys = sys
        self.cycle_time_ms = 20
        self.semantics = {"module_context": "enforce"}


def _fresh(case: Case) -> SysContext:
    sys = SysContext(20)
    if case.setup is not None:
        case.setup(sys)
    return sys


@pytest.mark.parametrize("case", MODEL_CASES, ids=lambda c: c.id)
def test_model_in_the_interpreter(case: Case) -> None:
    results, status, code = _fresh(case).call_in(case.number, list(case.params), case.in_job)
    assert (tuple(results), status, code) == (case.results, case.status, case.code)


@pytest.mark.parametrize("case", MODEL_CASES, ids=lambda c: c.id)
def test_model_in_the_translated_fb(case: Case) -> None:
    row = mt.MODULE_TABLE[case.number]
    binding = SysBinding(f"FUNCTION_BLOCK {row.st_name}\nEND_FUNCTION_BLOCK\n")
    binding.attach(_Machine(_fresh(case)))        # the translated side's own clone, as in the co-simulation
    itf = interface(case.number)
    state: dict = {n.lower(): v for n, v in zip(itf.inputs, case.params)}
    state[IN_JOB.lower()] = case.in_job
    binding.externals()[row.st_name](state)
    assert tuple(state[n.lower()] for n in itf.outputs) == case.results
    assert state[FAULT.lower()] is bool(case.status)
    assert state[FAULT_CODE.lower()] == (case.code or 0)


def test_the_stub_body_for_the_target_names_the_context_codes() -> None:
    from transpiler.backends.st.hh_sys import fb_pou
    assert "FAULT_CODE := 30;" in fb_pou(9262).body
    body = fb_pou(9244).body
    assert "FAULT_CODE := 20;" in body and "BYTES := -1;" in body
    assert "ERROR := 7;" in fb_pou(9095).body
    assert "FAULT_CODE := 24;" in fb_pou(9231).body


# ---------------------------------------------------------------------------------------------
# pure modules: the interpreter's functions and the generated ST library


class _State:
    def __init__(self, text: str, mem: tuple[int, ...]):
        self.S = [text] + [""] * (N_STRINGS - 1)
        self.mem = list(mem) + [0] * (MEM_SIZE - len(mem))
        self.mem_size = MEM_SIZE
        self.string_len = STRING_LEN


_PURE_FN = {9050: pm.m9050, 9052: pm.m9052, 9053: pm.m9053}


@pytest.mark.parametrize("case", PURE_CASES, ids=lambda c: c.id)
def test_pure_model_in_the_interpreter(case: PureCase) -> None:
    state = _State(case.text, case.mem)
    results, code = _PURE_FN[case.number](state, list(case.params), pm.PureEnv(lambda: 0, POINT))
    assert code == case.code
    if case.results:
        assert tuple(results) == case.results
    if case.out_text is not None:
        assert state.S[0] == case.out_text


@pytest.fixture(scope="module")
def st_runtime():
    from transpiler.exec.stexec import load_st
    return load_st(render_st(_project())).instantiate()


def test_pure_model_in_the_st_library(st_runtime) -> None:
    rt = st_runtime
    for case in PURE_CASES:
        p = case.params
        string_no = {9050: p[2] if case.number == 9050 else 0, 9052: p[0], 9053: p[1] if case.number == 9053 else 0}
        rt.set("G_OK", string_no[case.number] == 0)
        rt.set("G_TXT", case.text)
        mem = list(case.mem) + [0] * (MEM_SIZE - len(case.mem))
        for i, b in enumerate(mem):
            rt.set(f"G_MEM[{i}]", b)
        if case.number == 9050:
            rt.set("G_M", p[0])
            rt.set("G_E", p[1])
            rt.run_cycle()
            got = (rt.get("R50_C"), rt.get("R50_TEXT") if not rt.get("R50_F") else None)
        elif case.number == 9052:
            rt.run_cycle()
            got = (rt.get("R52_C"), None)
            if case.results:
                assert (rt.get("R52_V"), rt.get("R52_E")) == case.results, case.id
        else:
            rt.set("G_ADDR", p[0])
            rt.set("G_CNT", p[2])
            rt.run_cycle()
            got = (rt.get("R53_C"), rt.get("R53_T") if not rt.get("R53_F") else None)
        assert got == (case.code, case.out_text), case.id


def test_9019_stack_depth_in_the_interpreter(tmp_path: Path, capsys) -> None:
    # 9019: bytes on the data stack, 0 when empty; B/W/D/K entries take 4 bytes, M/I/O/T/C entries 2.
    assert pm.m9019(None, [], pm.PureEnv(lambda: 0, POINT)) == ([0], 0)
    assert pm.m9019(None, [], pm.PureEnv(lambda: 3, POINT)) == ([6], 0)
    m = machine(tmp_path, """
        CM  9019
        PL  D0
        PS  K1
        PS  M0
        CM  9019
        PL  D4
        PL  M1
        PL  D8
        EM
    """, profile="itnc530")
    cycles(m, 1)
    assert values(m, "D0", "D4") == {"D0": 0, "D4": 6}
    # The translation reads the emulated stack's pointer (the program keeps its whole stack there): the same
    # depths, also inside a subprogram whose caller pushed its parameter.
    from transpiler.cli import main
    src = tmp_path / "main.src"
    src.write_text("CM 9019\nPL D0\nPS K1\nPS M0\nCM 9019\nPL D4\nPL M1\nPL D8\nPS W20\nCM Sub\nPL D12\nEM\n"
                   "LBL Sub\nCM 9019\nPL D16\nPL D24\nCM 9019\nEM\n", encoding="latin-1")
    assert main(["transpile", str(src), "--out", str(tmp_path / "out")]) == 0
    st = (tmp_path / "out" / "project.st").read_text()
    assert "INT_TO_DINT(HH_SP) * 2;" in st
    capsys.readouterr()
    assert main(["equiv", str(src), "--random-cycles", "20", "--backend", "builtin"]) == 0
    assert "hh2iec equiv: EQUIVALENT" in capsys.readouterr().out
