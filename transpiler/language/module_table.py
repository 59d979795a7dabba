"""The PLC module table as data: every module hh2iec knows, one row each (see docs/modules.md).

One row per module number: parameters in push order and results in pull order (name and unit each),
the documented error codes, where it may be called (anywhere, cyclic program only, submit/spawn job
only; bound to a pending strobe while an NC program runs), the profiles that have it, its kind, how
sure the row is, and the assumptions its details rest on.

Kinds: *pure* modules are functions of their parameters and of PLC memory (number/string conversion,
stack depth) and are implemented exactly in portable ST; *data* modules read or write data the
transpiler generates from the project's files (machine parameters, status information, tables, axis
configuration); *machine* modules depend on the live control (coordinates, drives, clocks, files,
events) and become calls of the `HH_Sys` interface library that the integrator implements on the
target.

Confidence: "D" call format read in a manual, "P" partly documented (the parts not read are named
assumptions, listed in `assumptions`), "M" named in a manual without a usable signature (a stub:
no parameters, no results). The C runtime shim compiles the same rows: `c_table()` generates
runtime_shim/hh_module_table.h and tests/test_module_table.py checks both agree.
"""

from __future__ import annotations

import dataclasses
from types import MappingProxyType
from typing import Mapping

ANY, CYCLIC, SUBMIT = "any", "cyclic", "submit"
PURE, DATA, MACHINE = "pure", "data", "machine"

# W1022 codes of the calling context, shared by every module (the documented iTNC/TNC 426 convention).
ERR_NOT_IN_JOB = 20          # a submit/spawn-only module called in the cyclic program
ERR_NO_STROBE = 21           # called while an NC program runs and no strobe is pending
ERR_NOT_CYCLIC = 24          # a cyclic-only module called in a submit/spawn job

ALL_PROFILES = frozenset({"itnc530", "tnc426", "tv", "tnc407"})
NEW = frozenset({"itnc530", "tnc426", "tv"})          # M4203/W1022 generations
OLD = frozenset({"tnc407"})                           # M3171 generation


@dataclasses.dataclass(frozen=True)
class Value:
    """One parameter or result: an identifier (used as the ST argument name) and its unit ('' = a plain number)."""

    name: str
    unit: str = ""
    doc: str = ""


@dataclasses.dataclass(frozen=True)
class Module:
    number: int
    st_name: str                          # FUNCTION / FUNCTION_BLOCK name in the generated ST
    purpose: str
    params: tuple[Value, ...]
    results: tuple[Value, ...]
    errors: Mapping[int, str]             # W1022 code (or error result) -> meaning
    kind: str                             # PURE / DATA / MACHINE
    context: str = ANY                    # ANY / CYCLIC / SUBMIT
    strobe: bool = False                  # needs a pending strobe while an NC program runs
    profiles: frozenset[str] = ALL_PROFILES
    confidence: str = "D"                 # D / P / M
    assumptions: tuple[str, ...] = ()     # named inferences the row rests on (P rows)
    modelled: bool = False                # the simulation has an effect model (else: stub rule of A-46)
    error_result: int | None = None       # index of a result that carries the error code too
    context_code: int | None = None       # W1022 code of a call in the wrong context (None: 20 / 24)
    context_result: int | None = None     # the error result's value then (None: the W1022 code)
    # The values the error result can take where it carries nothing but the module's own result codes (the wrong
    # context's included); None: not stated (it may carry a value too, or W1022 codes differ from it).
    # tests/test_module_table.py calls the model with corner parameters in both contexts and checks them.
    error_values: frozenset[int] | None = None

    @property
    def nparams(self) -> int:
        return len(self.params)

    @property
    def nresults(self) -> int:
        return len(self.results)

    def context_error(self, in_job: bool) -> int:
        """W1022 code when the module is called in the wrong context, else 0."""
        if self.context == SUBMIT and not in_job:
            return self.context_code or ERR_NOT_IN_JOB
        if self.context == CYCLIC and in_job:
            return self.context_code or ERR_NOT_CYCLIC
        return 0

    def context_error_result(self, in_job: bool) -> int | None:
        """The error result's value when the module is called in the wrong context (None: no error result)."""
        code = self.context_error(in_job)
        if self.error_result is None or not code:
            return None
        return code if self.context_result is None else self.context_result


def _v(spec: str) -> tuple[Value, ...]:
    """'name[unit], name2' -> Values; keeps the rows below one line each."""
    out = []
    for part in filter(None, (p.strip() for p in spec.split(","))):
        name, _, unit = part.partition("[")
        out.append(Value(name.strip(), unit.rstrip("]").strip()))
    return tuple(out)


def _m(number: int, st_name: str, purpose: str, params: str, results: str, errors: Mapping[int, str], kind: str,
       **kw) -> Module:
    return Module(number, st_name, purpose, _v(params), _v(results), MappingProxyType(dict(errors)), kind, **kw)


_E_PARAM = {1: "invalid value or number", 2: "invalid parameter"}
_E_STR = {2: "invalid string address, exponent or characters"}
_E_CTX = {ERR_NOT_IN_JOB: "not called in a submit or spawn job"}
_E_CYC = {ERR_NOT_CYCLIC: "called in a submit or spawn job (cyclic program only)"}
_E_EVT = {30: "bad identifier / not in a spawn or submit job"}
_E_MPTAB = {0: "ok", 1: "not in a submit job", 2: "file type missing", 3: "no file with M status",
            4: "line not in file", 5: "bad element number"}

MODULE_ROWS: tuple[Module, ...] = (
    _m(9006, "HH_StartTimer", "start an additional timer T96-T999", "timer", "", {1: "timer not configured"},
       MACHINE, confidence="P", assumptions=("A-37: one parameter, the timer number",), modelled=True),
    _m(9019, "HH_StackDepth", "fill level of the PLC data stack", "", "depth[bytes]", {}, PURE, modelled=True),
    _m(9031, "HH_WriteMP", "overwrite a machine parameter (run-time value)", "number, index, value[scaled by the MP's decimals]",
       "error", {0: "ok", 1: "MP missing or not writable", 2: "value out of range", 3: "save error",
                 4: "not in a submit job", 5: "program running without strobe"}, DATA, context=SUBMIT, strobe=True,
       confidence="P", assumptions=("A-46a: push order number, index, value (call lines lost)",), modelled=True,
       error_result=0, context_result=4),
    _m(9032, "HH_ReadMP", "read a machine parameter", "number, index", "value[scaled by the MP's decimals]",
       {1: "no such MP", 2: "no separator", 3: "value out of range", 4: "MP not in file", 5: "no MP file",
        6: "not called from a submit job"}, DATA, context=SUBMIT, confidence="P",
       assumptions=("A-46a: push order number, index (call lines lost)",), modelled=True),
    _m(9035, "HH_ReadStatus", "read NC status information", "number", "value", {1: "invalid number", **_E_CTX}, DATA,
       context=SUBMIT, profiles=NEW, modelled=True,
       assumptions=("A-46b: one status table, all 0 at start, shared with 9036",)),
    _m(9036, "HH_WriteStatus", "write NC status information", "number, value", "error",
       {1: "value out of range (error result 2)", 2: "wrong number (error result 1)",
        6: "input disabled (error result 3)"}, DATA, modelled=True,
       assumptions=("A-46b: one status table, all 0 at start, shared with 9035",
                    "A-46s: numbers 0..19 are writable (0-4 and 11-19 interpolation factors 0..10, 5 all axes 0..10, "
                    "6 handwheel axis and 10 jog limit unchecked); the error result is the old generation's number "
                    "(1 wrong number, 2 out of range, 3 disabled), W1022 the TNC 426's (2, 1, 6); an interpolation "
                    "factor is disabled when MP7641 is given and is not 1",)),
    _m(9038, "HH_AxisInfo", "general axis information", "axis, info", "value",
       {1: "info not available", 2: "axis not found"}, DATA, profiles=NEW, modelled=True,
       assumptions=("A-46c: axis configuration from the scenario (axes_active bit mask, default 0)",)),
    _m(9040, "HH_AxisCoordinates", "axis coordinates into 5 double words (0.001 mm)", "address, type", "",
       {1: "bad type or address"}, MACHINE, modelled=True,
       assumptions=("A-46t: type 0..4; the address must be a D address (>= 0, divisible by 4) whose 5 double words "
                    "fit the memory (as 9041/9042); the coordinates depend on the machine: memory is not written",)),
    _m(9041, "HH_AxisCoordinatesFine", "axis coordinates into double words (0.0001 mm)", "address, type", "",
       {1: "bad type or address"}, MACHINE),
    _m(9042, "HH_SpindleCoordinates", "spindle coordinates into 5 double words (0.001 deg)", "address", "",
       {1: "address not DW-aligned or block does not fit"}, MACHINE, modelled=True,
       assumptions=("A-46t: the coordinates depend on the machine: memory is not written",)),
    _m(9048, "HH_AxisState", "operating state of an axis", "axis, info", "status", {1: "invalid info", 2: "invalid axis"},
       MACHINE, profiles=NEW, modelled=True,
       assumptions=("A-46u: no brake test and no free rotation runs in simulation: status 0 (mask 0 for axis -1); "
                    "axes 0..15; which axes are open-loop, slave or rotary is not configured, so info 1 is not "
                    "refused for them",)),
    _m(9049, "HH_AxisValue", "position or speed value of one axis", "axis, info", "value[0.0001 mm or mm/min]",
       {2: "invalid axis or info"}, MACHINE, profiles=NEW, modelled=True),
    _m(9050, "HH_NumToString", "binary (mantissa x 10^exponent) to a decimal string", "mantissa, exponent, string", "",
       _E_STR, PURE, profiles=NEW, modelled=True),
    _m(9051, "HH_NumToStringFormatted", "binary to a formatted decimal string", "value, mode, before, after, string", "",
       {1: "bad parameter"}, PURE, confidence="P",
       assumptions=("A-46d: push order value, mode, digits before, digits after, string (call lines lost)",)),
    _m(9052, "HH_StringToNum", "decimal string to mantissa and exponent", "string", "value, exponent", _E_STR, PURE,
       modelled=True),
    _m(9053, "HH_BytesToHex", "bytes of word memory to a hex string", "address, string, count", "",
       {1: "too many bytes", 2: "invalid string address", 4: "invalid word address"}, PURE, modelled=True),
    _m(9054, "HH_HexToBytes", "hex string to bytes of word memory", "string, address", "",
       {2: "invalid string address", 4: "invalid word address", 5: "odd length or not hex"}, PURE, confidence="P",
       assumptions=("A-46e: codes 4/5 for word address / odd length (garbled in the manual)",), modelled=True),
    _m(9070, "HH_FindNumber", "copy the first number inside a string", "source, destination", "offset[characters]",
       {1: "string number out of range", 2: "no number"}, PURE, confidence="P",
       assumptions=("A-46f: push order source, destination (labels lost)",), modelled=True),
    _m(9080, "HH_ClearPlcWindow", "clear the PLC status window", "", "", {}, MACHINE, profiles=OLD,
       assumptions=("A-46v: no PLC window in simulation; the manual names M3171 but no error condition: no error",)),
    _m(9081, "HH_PlcWindowState", "state of the PLC window", "", "state", {}, MACHINE, profiles=OLD,
       assumptions=("A-46v: no PLC window in simulation: state 0 (not present, not in the foreground); never an "
                    "error",)),
    _m(9082, "HH_ShowString", "show a string in the PLC window", "string, line, column, colour", "", {1: "bad parameter"},
       MACHINE, profiles=OLD, confidence="P", assumptions=("A-46g: push order string, line, column, colour",)),
    _m(9092, "HH_FindInTable", "search an entry in the tables selected for program run", "type, element, value",
       "line, error", {**_E_MPTAB, 6: "value not found"}, DATA, context=SUBMIT, confidence="P", error_result=1,
       context_result=1, error_values=frozenset(range(7)),
       assumptions=("A-46h: parameters file type, element, value; results line, error (call lines lost)",), modelled=True),
    _m(9093, "HH_ReadTable", "read one element of a tool/pocket/datum table", "type, line, element",
       "value[scaled by the field's decimals], error", _E_MPTAB, DATA, context=SUBMIT, error_result=1, modelled=True,
       context_result=1, error_values=frozenset(_E_MPTAB)),
    _m(9094, "HH_WriteTable", "write one element of a tool/pocket/datum table", "type, line, element, value",
       "error", {**_E_MPTAB, 6: "value out of range"}, DATA, context=SUBMIT, error_result=0, modelled=True,
       context_result=1, error_values=frozenset(range(7))),
    _m(9095, "HH_ActivateCompensation", "activate a line of the .CMA compensation table", "line", "error",
       {0: "ok", 1: "line missing", 2: ".COM table missing", 3: ".COM > 256 entries", 4: "too many points",
        5: "too many .COM tables / after program start without strobe", 6: "no .CMA", 7: "not in a submit job"},
       MACHINE, context=SUBMIT, strobe=True, error_result=0, context_result=7, modelled=True,
       assumptions=("A-46w: the compensation tables depend on the machine: a negative line is missing (1), every "
                    "other line activates (0); the strobe is not checked",)),
    _m(9097, "HH_SelectKinematics", "select a geometry description (kinematics)", "line, mode", "error",
       {2: "bad mode, line missing or configuration error (error result 1..5, 8)", 9: "MPFILE column",
        10: "MP7500 column", 11: "MP subfile error", 20: "not in a spawn/submit job (error result 6)",
        21: "running program without strobe (error result 7)"},
       MACHINE, context=SUBMIT, strobe=True, error_result=0, context_result=6, modelled=True,
       assumptions=("A-46w: mode must be 0 (else error result 1, W1022 2); a negative line is missing (error "
                    "result 2, W1022 2); the assignment table depends on the machine: every other line selects (0); "
                    "the strobe is not checked",)),
    _m(9101, "HH_ReleaseSerial", "release a serial interface", "interface", "", {1: "bad interface"}, MACHINE,
       confidence="P", assumptions=("A-46i: one parameter, the interface",)),
    _m(9102, "HH_SerialStatus", "serial interface status, bit-coded", "interface", "status", {1: "wrong interface"},
       MACHINE, modelled=True,
       assumptions=("A-46x: interfaces 0 and 1; no interface is assigned in simulation (9100 has no model): "
                    "status 0; another interface: status -1 and error 1",)),
    _m(9105, "HH_SerialSendHex", "send bytes of word memory as hex over the serial interface",
       "interface, address, length[bytes]", "", {1: "bad parameter or interface not ready"}, MACHINE, context=SUBMIT,
       modelled=True,
       assumptions=("A-46x: interface 0..1, address 0..1023, length 0..63 and the block inside bytes 0..1023, else "
                    "error 1; the interface is taken as assigned and the transmission as successful (nothing is "
                    "sent)",)),
    _m(9106, "HH_SerialReceiveHex", "receive hex into bytes of word memory", "interface, address", "length[bytes]",
       {1: "bad parameter or interface not ready"}, MACHINE, context=SUBMIT, confidence="P",
       assumptions=("A-46j: parameters interface, address",)),
    _m(9123, "HH_PlcAxisReference", "reference-mark traverse of a PLC axis", "axis, feed, direction", "error",
       {0: "started", 1: "axis missing", 2: "not a PLC axis", 3: "already positioning"}, MACHINE, confidence="P",
       error_result=0, assumptions=("A-46k: first two parameters axis and feed (labels lost)",)),
    _m(9124, "HH_PlcAxisOverride", "feed-rate override of a PLC axis", "axis, override[0.01 %]", "error",
       {0: "set", 1: "no such axis", 2: "not a PLC axis", 3: "bad override"}, MACHINE, error_result=0, modelled=True,
       assumptions=("A-46y: axes 0..15 exist (else 1); which axes are PLC axes is not configured, so 2 is never "
                    "given; override 0..10000 (else 3); W1022 is the error result",)),
    _m(9127, "HH_AxisCoupling", "status of an axis coupling", "axis, mode", "status", {1: "bad axis", 2: "bad mode"},
       MACHINE, profiles=NEW, modelled=True,
       assumptions=("A-46y: axes 0..15, modes 0..3; no axis is coupled in simulation: status 0",)),
    _m(9144, "HH_SafetyTest", "functional-safety self test / mode / axis test request", "mode, param1, param2", "status",
       {2: "bad value", 28: "test already active", 43: "not an HSCI/FS system"}, MACHINE, profiles=NEW, modelled=True,
       assumptions=("A-46z: modes 0, 10 (param1 0..2) and 11 (param1 an axis 0..15), else 2; the simulated control "
                    "is an HSCI/FS system; a self test (mode 0, status 0 running) stays active until the end of the "
                    "cycle that started it: a second start in that cycle gives 28",)),
    _m(9148, "HH_Module9148", "named in the sources without a signature", "", "", {}, MACHINE, confidence="M"),
    _m(9150, "HH_InsertToolCall", "insert an NC block (TOOL CALL)", "code, address", "error",
       {0: "inserted", 1: "program running without strobe", 2: "unknown code"}, MACHINE, strobe=True, error_result=0,
       modelled=True,
       assumptions=("A-46w: code 0 is inserted (no NC program runs, nothing is executed), any other code gives 2; "
                    "the parameter block is not read",)),
    _m(9159, "HH_DrivesSwitchingOff", "drives that will be switched off in about 200 ms", "", "mask", {}, MACHINE,
       modelled=True),
    _m(9161, "HH_EnableDrives", "enable/disable the drive controllers per axis", "mask", "",
       {1: "no current controller", **_E_CYC}, MACHINE, context=CYCLIC, modelled=True),
    _m(9162, "HH_DrivesReady", "drive-ready status, bit mask", "", "mask", {}, MACHINE, modelled=True),
    _m(9166, "HH_Module9166", "named in the sources without a signature", "", "", {}, MACHINE, confidence="M"),
    _m(9169, "HH_DrivesIgnoreI32", "axes for which input I32 does not switch off the drives", "mask", "",
       {1: "no current controller", **_E_CYC}, MACHINE, context=CYCLIC, modelled=True),
    _m(9190, "HH_StartHourCounters", "start PLC operating-hours counters", "mask", "", {1: "bad parameter"}, MACHINE,
       modelled=True),
    _m(9191, "HH_StopHourCounters", "stop PLC operating-hours counters", "mask", "", {1: "bad parameter"}, MACHINE,
       modelled=True),
    _m(9192, "HH_OperatingTime", "read an operating time", "number", "time[s]", {1: "bad value", **_E_CTX}, MACHINE,
       context=SUBMIT, modelled=True, error_result=0, context_result=-1,
       assumptions=("A-46l: -3/-2/-1 = simulated seconds since cycle 0; 0..7 = PLC counters of 9190/9191",)),
    _m(9194, "HH_TimeAlarm", "alarm marker when an operating time passes a threshold", "number, threshold[s], marker", "",
       {1: "bad value", **_E_CTX}, MACHINE, context=SUBMIT, modelled=True,
       assumptions=("A-46l2: numbers -3..-1 and the 8 PLC counters 0..7, marker >= 0, else 1; the alarm marker is "
                    "not set in simulation",)),
    _m(9195, "HH_SystemTime", "system time", "", "time[s since 1970]", {}, MACHINE, modelled=True,
       assumptions=("A-46m: the simulated clock starts at 0 (the epoch)",)),
    _m(9221, "HH_StartPositioning", "start PLC positioning of an NC axis", "axis, position[0.0001 mm], feed[mm/min]", "",
       {1: "invalid parameter"}, MACHINE, strobe=True, confidence="P", profiles=NEW,
       assumptions=("A-46n: parameters axis, position, feed (the manual names the module only)",)),
    _m(9222, "HH_PositioningState", "state of a PLC positioning", "axis", "state",
       {1: "invalid info", 2: "open-loop/auxiliary/slave axis"}, MACHINE, profiles=NEW),
    _m(9227, "HH_PositionAxes", "position axes with acceleration and jerk",
       "axis, position[0.0001 mm], feed[mm/min], acceleration, jerk, mode", "", {1: "invalid parameter"}, MACHINE,
       strobe=True, confidence="P", profiles=NEW, assumptions=("A-46o: parameters axis, position, feed, acceleration, "
                                                               "jerk, mode (call lines not visible)",)),
    _m(9231, "HH_ThermalCompensation", "thermal-expansion compensation of an axis", "axis, value[0.1 um]", "",
       {1: "bad axis", 2: "bad value", **_E_CYC}, MACHINE, context=CYCLIC, profiles=NEW, modelled=True,
       assumptions=("A-46y: the compensation has no effect in simulation (no positions move)",)),
    _m(9244, "HH_FileWriteLine", "write one line to an ASCII file", "handle, string", "bytes",
       {2: "bad handle", 3: "bad string number", 7: "file-system error", **_E_CTX}, MACHINE, context=SUBMIT,
       profiles=NEW, modelled=True, error_result=0, context_result=-1,
       assumptions=("A-46x: string numbers 0..7 (else 3), handles >= 0 (else 2), result -1 on every error; files "
                    "depend on the machine: nothing is written and the byte count reads 0",)),
    _m(9260, "HH_WaitEvents", "read / wait for events", "wait, combine, mask", "events", {2: "bad wait value", **_E_CTX},
       MACHINE, context=SUBMIT, profiles=NEW, modelled=True,
       assumptions=("A-46e2: wait 0 or -1 (else 2); no events are delivered in simulation: 0 events, no waiting",)),
    _m(9261, "HH_SendEvents", "send events to a spawn process or the submit queue", "identifier, events", "", _E_EVT,
       MACHINE, profiles=NEW, modelled=True,
       assumptions=("A-46e2: SPAWN has no model, so the submit queue (K$80000000) is the only valid identifier; the "
                    "events are not delivered",)),
    _m(9262, "HH_Yield", "voluntary context switch", "", "", _E_EVT, MACHINE, context=SUBMIT, profiles=NEW,
       context_code=30),
    _m(9263, "HH_Sleep", "sleep for at least N ms", "time[ms]", "", _E_EVT, MACHINE, context=SUBMIT, profiles=NEW,
       context_code=30),
    _m(9264, "HH_WaitCondition", "wait until a condition holds", "condition, mask", "", _E_EVT, MACHINE, context=SUBMIT,
       profiles=NEW, confidence="P", assumptions=("A-46p: parameters condition string number, event mask",)),
    _m(9429, "HH_ProgramStatus", "status of the NC program in a channel", "channel, string, mode",
       "status, substatus, block, help", {1: "invalid channel, mode or string number"}, MACHINE, profiles=NEW,
       modelled=True,
       assumptions=("A-46p2: one channel (0), modes 0..3, string numbers >= 0, else error 1 (the manual gives no "
                    "code numbers); no NC program runs in simulation: status 2 (finished), sub-status, block and "
                    "help number 0; the path string is not written",)),
)

MODULE_TABLE: Mapping[int, Module] = MappingProxyType({m.number: m for m in MODULE_ROWS})


def writes_anywhere(number: int) -> bool:
    """Whether a call of PLC module `number` may write memory the program does not name: one that writes to an
    address it is given, or one this table does not know (what it writes is unknown)."""
    row = MODULE_TABLE.get(number)
    return row is None or any("address" in p.name for p in row.params)


def nearest(number: int, count: int = 3) -> list[int]:
    """The `count` known module numbers closest to `number` (hint of E-MODULE-UNKNOWN)."""
    return sorted(sorted(MODULE_TABLE, key=lambda n: (abs(n - number), n))[:count])


PROFILE_BITS: Mapping[str, int] = MappingProxyType({"itnc530": 1, "tnc426": 2, "tv": 4, "tnc407": 8})


def profile_mask(profiles: frozenset[str]) -> int:
    return sum(PROFILE_BITS[p] for p in profiles)


_C_KIND = {PURE: "HH_KIND_PURE", DATA: "HH_KIND_DATA", MACHINE: "HH_KIND_MACHINE"}
_C_CTX = {ANY: "HH_CTX_ANY", CYCLIC: "HH_CTX_CYCLIC", SUBMIT: "HH_CTX_SUBMIT"}


def c_table() -> str:
    """The rows as a C initializer (runtime_shim/hh_module_table.h is this text; a test compares them)."""
    lines = ["/* hh_module_table.h - GENERATED from transpiler/language/module_table.py by",
             " * `python -m transpiler.language.module_table > runtime_shim/hh_module_table.h`; do not edit.",
             " * Rows: number, parameters, results, kind, calling context, strobe-bound, modelled,",
             " * profile bit mask (1 itnc530, 2 tnc426, 4 tv, 8 tnc407), error result index (-1 none),",
             " * W1022 code of a call in the wrong context (0: 20 / 24), the error result's value then",
             " * (context_result_set 0: the code), purpose. */",
             "static const module_entry MODULES[] = {"]
    for m in MODULE_ROWS:
        purpose = m.purpose.replace("\\", "\\\\").replace('"', '\\"')
        lines.append(f"    {{{m.number}, {m.nparams}, {m.nresults}, {_C_KIND[m.kind]}, {_C_CTX[m.context]}, "
                     f"{int(m.strobe)}, {int(m.modelled)}, {profile_mask(m.profiles)}, "
                     f"{-1 if m.error_result is None else m.error_result}, {m.context_code or 0}, "
                     f"{int(m.context_result is not None)}, {m.context_result or 0}, \"{purpose}\"}},")
    lines.append("};")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    print(c_table(), end="")
