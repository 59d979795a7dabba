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
MAX_LEN = 64
# Temporaries of a POU body are named tmp1, tmp2, ... They are declared per POU, after the globals the body uses may
# have been named, and IEC names are case-insensitive: so no other name may ever take this form (a symbol that
# wants it is renamed), or a temporary could shadow an operand such as T5.
TEMP_PREFIX = "tmp"
_TEMP_NAME = re.compile(TEMP_PREFIX + r"[0-9]+", re.IGNORECASE)


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
        while candidate.upper() in self._taken or candidate.upper() in RESERVED or _TEMP_NAME.fullmatch(candidate):
            if _TEMP_NAME.fullmatch(candidate) and not reason:
                reason = "the form of the translator's temporaries"
            elif candidate.upper() in RESERVED and not reason:
                reason = "IEC keyword or standard name"
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
    reasons = []
    text = re.sub(r"[^A-Za-z0-9_]", "_", name)
    if text != name:
        reasons.append("illegal character")
    collapsed = re.sub(r"_+", "_", text)
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
