"""IEC names: keeps HEIDENHAIN spelling where legal, renames deterministically where not, and records every rename."""

from __future__ import annotations

import dataclasses
import re

# IEC keywords, standard functions/FBs, IL operators that matter, C macros matiec cannot survive (targets.md 1.2, 6).
RESERVED = frozenset(w.upper() for w in """
ACTION END_ACTION AND ANY ANY_BIT ANY_DATE ANY_DERIVED ANY_ELEMENTARY ANY_INT ANY_MAGNITUDE ANY_NUM ANY_REAL
ANY_STRING ARRAY AT BOOL BY BYTE CASE CONFIGURATION CONSTANT CONTINUE DATE DATE_AND_TIME DINT DO DT DWORD ELSE
ELSIF EN ENO END_CASE END_CONFIGURATION END_FOR END_FUNCTION END_FUNCTION_BLOCK END_IF END_PROGRAM END_REPEAT
END_RESOURCE END_STEP END_STRUCT END_TRANSITION END_TYPE END_VAR END_WHILE EXIT FALSE F_EDGE FOR FROM FUNCTION
FUNCTION_BLOCK IF INITIAL_STEP INT INTERVAL LINT LREAL LWORD MOD NON_RETAIN NOT OF ON OR PRIORITY PROGRAM
READ_ONLY READ_WRITE REAL REPEAT RESOURCE RETAIN RETURN R_EDGE SINGLE SINT STEP STRING STRUCT TASK THEN TIME
TIME_OF_DAY TO TOD TRANSITION TRUE TYPE UDINT UINT ULINT UNTIL USINT VAR VAR_ACCESS VAR_CONFIG VAR_EXTERNAL
VAR_GLOBAL VAR_INPUT VAR_IN_OUT VAR_OUTPUT VAR_TEMP WCHAR WHILE WITH WORD WSTRING XOR REF REF_TO DREF NULL
ABS ACOS ADD AND_ ASIN ATAN CONCAT COS CTD CTU CTUD DELETE DIV EQ EXP EXPT FIND F_TRIG GE GT INSERT LE LEFT LEN
LIMIT LN LOG LT MAX MID MIN MOVE MUL MUX NE REPLACE RIGHT ROL ROR RS R_TRIG SEL SHL SHR SIN SQRT SR SUB TAN TOF
TON TP TRUNC EOF BUFSIZ INT_MAX CHAR_BIT EXIT_SUCCESS EXIT_FAILURE INFINITY NAN M_PI STR_MAX_LEN RAND_MAX SIZE_MAX
CHAR VOID THIS SUPER METHOD CLASS INTERFACE SIZEOF ADR
""".split())
# Names the libraries iec2c always loads declare as variables (matiec's standard library; the extra libraries of the
# OpenPLC v3 runtime, its function blocks too). matiec takes every POU name of the program as a type name before it
# reads those libraries, so a POU of one of these names breaks the library that declares it (an FB `Init` fails
# OpenPLC's build in its own library file). Only POU names avoid them: a variable may be called so.
LIBRARY_VARIABLE_NAMES = frozenset(w.upper() for w in """
AUTO BUSY CD CDT CD_T CLAIM CLK CU CURRENT_TIME CU_T CV CYCLE DTERM EPS ERROR ET G IN IN0 IN1 IN2 ITERM K KP L LD M
MN MX N OFFSET P PDT PREV_IN PT PV Q Q1 QD QU Q_INTERNAL R R1 RELEASE RUN S S1 SP START_TIME STATE T TD TR X0 X1 X2
X3 XI XIN XIN1 XIN2 XOUT
AC_OPTO1 AC_OPTO2 AC_OPTO3 AC_OPTO4 ADC1 ADC2 ADC3 ADC4 ADC5 ADC6 ADC7 ADC8 BUTTON BYTES_RECEIVED BYTES_SENT
CH1_RANGE CH2_RANGE CH3_RANGE CH4_RANGE CLOSE CONNECT DRY_C1 DRY_C2 DRY_C3 DRY_C4 DRY_C5 DRY_C6 DRY_C7 DRY_C8 DUMMY
FREQ1 FREQ2 FREQ3 FREQ4 I0_10V1 I0_10V2 I0_10V3 I0_10V4 I1 I10 I11 I12 I13 I14 I15 I16 I2 I3 I4 I4_20MA1 I4_20MA2
I4_20MA3 I4_20MA4 I5 I6 I7 I8 I9 IN1_T IN2_T IN3_T IN4_T IN5_T IN6_T IN7_T IN8_T INIT IP_ADDRESS LED1 LED2 LED3 LED4
MOS1 MOS2 MOS3 MOS4 MOS5 MOS6 MOS7 MOS8 MSG O1 O10 O11 O12 O13 O14 O15 O16 O2 O3 O4 O5 O6 O7 O8 O9 OPTO1 OPTO2
OPTO3 OPTO4 OPTO5 OPTO6 OPTO7 OPTO8 OUT OWB_T1 OWB_T2 OWB_T3 OWB_T4 PORT PWM1 PWM2 PWM3 PWM4 Q0_10V1 Q0_10V2 Q0_10V3
Q0_10V4 Q4_20MA1 Q4_20MA2 Q4_20MA3 Q4_20MA4 QOD1 QOD2 QOD3 QOD4 READ RECEIVE RELAY1 RELAY2 RELAY3 RELAY4 RELAY5
RELAY6 RELAY7 RELAY8 SEND SLOT SOCKET_ID STACK SUCCESS TEMP1 TEMP2 TEMP3 TEMP4 TEMP5 TEMP6 TEMP7 TEMP8 TRIAC1 TRIAC2
TRIAC3 TRIAC4 UDP UNITS UNIV1 UNIV2 UNIV3 UNIV4 UNIV5 UNIV6 UNIV7 UNIV8
ROTARY_SWITCH SLM_04THM_CONFIG SLM_ANALOG_IN_4 SLM_ANALOG_IN_8 SLM_ANALOG_OUT_4 SLM_ANALOG_OUT_8 SLM_DISCRETE_IN_16
SLM_DISCRETE_IN_8 SLM_DISCRETE_OUT_15 SLM_DISCRETE_OUT_16 SLM_DISCRETE_OUT_8 SLM_INIT SLM_TEMPERATURE_4 SM_16DIN
SM_16RELAY SM_4REL4IN SM_8DIN SM_8MOSFET SM_8RELAY SM_BAS SM_HOME SM_INDUSTRIAL SM_RTD TCP_CLOSE TCP_CONNECT
TCP_RECEIVE TCP_SEND DERIVATIVE HYSTERESIS INTEGRAL PID RAMP RTC SEMA
""".split())
POU_KEY_PREFIX = "pou:"
MAX_LEN = 64
# Temporaries of a POU body are named tmp1, tmp2, ... They are declared per POU, after the globals the body uses may
# have been named, and IEC names are case-insensitive: so no other name may ever take this form (a symbol that
# wants it is renamed), or a temporary could shadow an operand such as T5.
TEMP_PREFIX = "tmp"
_TEMP_NAME = re.compile(TEMP_PREFIX + r"[0-9]+", re.IGNORECASE)
_ILLEGAL = re.compile(r"[^A-Za-z0-9_]")
_UNDERSCORES = re.compile(r"_+")


@dataclasses.dataclass(frozen=True)
class Rename:
    original: str
    iec: str
    reason: str


class NameTable:
    """Hands out unique, legal, case-insensitively distinct IEC names; every forced change is recorded."""

    def __init__(self) -> None:
        self._taken: dict[str, str] = {}          # upper-case name -> owner key
        self._by_key: dict[str, str] = {}
        self.renames: list[Rename] = []

    def reserve(self, name: str, key: str) -> None:
        self._taken[name.upper()] = key
        self._by_key[key] = name

    def taken(self, name: str) -> bool:
        """Whether `name` is handed out (or reserved) already, in any case."""
        return name.upper() in self._taken

    def get(self, key: str) -> str | None:
        """The name handed out for `key`, or None when none was."""
        return self._by_key.get(key)

    def name(self, key: str, wanted: str) -> str:
        """The IEC name for `key` (stable: the same key always gets the same name)."""
        if key in self._by_key:
            return self._by_key[key]
        legal, reason = legalise(wanted)
        candidate = legal
        n = 2
        library = LIBRARY_VARIABLE_NAMES if key.startswith(POU_KEY_PREFIX) else frozenset()
        while candidate.upper() in self._taken or candidate.upper() in RESERVED or candidate.upper() in library \
                or _TEMP_NAME.fullmatch(candidate):
            if _TEMP_NAME.fullmatch(candidate) and not reason:
                reason = "the form of the translator's temporaries"
            elif candidate.upper() in RESERVED and not reason:
                reason = "IEC keyword or standard name"
            elif candidate.upper() in library and not reason:
                reason = "a name that the IEC libraries of matiec or OpenPLC declare; a POU may not take it"
            elif not reason:
                reason = "differs from another name only in case" if legal.upper() in self._taken else reason
            candidate = f"{legal}_{n}"
            n += 1
        if candidate != wanted:
            self.renames.append(Rename(wanted, candidate, reason or "renamed"))
        self._taken[candidate.upper()] = key
        self._by_key[key] = candidate
        return candidate


def legalise(name: str) -> tuple[str, str]:
    """A legal ST identifier close to `name` and the reason for any change ('' when unchanged)."""
    if name.isascii() and name.isidentifier() and name[0] != "_" and name[-1] != "_" and "__" not in name \
            and len(name) <= MAX_LEN:
        return name, ""         # (most names: legal as they are, the rules below would change nothing)
    reasons = []
    text = _ILLEGAL.sub("_", name)
    if text != name:
        reasons.append("illegal character")
    collapsed = _UNDERSCORES.sub("_", text)
    if collapsed != text:
        reasons.append("double underscore")
    text = collapsed
    if text.endswith("_"):
        text = text.rstrip("_") or "x"
        reasons.append("trailing underscore")
    if not text or text[0].isdigit() or text[0] == "_":
        text = "H" + (text if text.startswith("_") else "_" + text)
        reasons.append("must start with a letter")
    if len(text) > MAX_LEN:
        text = text[:MAX_LEN].rstrip("_")
        reasons.append(f"longer than {MAX_LEN} characters")
    return text, ", ".join(reasons)
