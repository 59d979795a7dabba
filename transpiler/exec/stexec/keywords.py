"""Reserved words of IEC 61131-3 (2nd edition) that strict matiec rejects as the name of a variable, POU or type.

Measured with iec2c (each word declared as an INT variable of a PROGRAM): all of these are rejected. IL operators,
SFC qualifiers and 3rd-edition words (LD, ST, S, R, N, Q, IN, PT, REF, THIS, METHOD, CLASS, VOID, CHAR,
PRIORITY, INTERVAL, SINGLE ...) are accepted in strict mode and are therefore not listed. EN and ENO, and the
names of standard functions and function blocks, are checked separately (stdlib.is_standard_name).
"""

from __future__ import annotations

RESERVED_WORDS: frozenset[str] = frozenset(word.lower() for word in """
    ON STEP END_STEP INITIAL_STEP TRANSITION END_TRANSITION FROM ACTION END_ACTION
    TASK RESOURCE END_RESOURCE CONFIGURATION END_CONFIGURATION TYPE END_TYPE
    PROGRAM END_PROGRAM FUNCTION END_FUNCTION FUNCTION_BLOCK END_FUNCTION_BLOCK
    VAR VAR_INPUT VAR_OUTPUT VAR_IN_OUT VAR_TEMP VAR_EXTERNAL VAR_GLOBAL VAR_ACCESS VAR_CONFIG END_VAR
    CONSTANT RETAIN NON_RETAIN READ_ONLY READ_WRITE WITH AT
    IF THEN ELSIF ELSE END_IF CASE OF END_CASE FOR TO BY DO END_FOR WHILE END_WHILE
    REPEAT UNTIL END_REPEAT EXIT CONTINUE RETURN
    AND OR XOR NOT MOD TRUE FALSE R_EDGE F_EDGE
    ARRAY STRUCT END_STRUCT STRING WSTRING
    BOOL BYTE WORD DWORD LWORD SINT INT DINT LINT USINT UINT UDINT ULINT REAL LREAL
    TIME DATE TOD DT TIME_OF_DAY DATE_AND_TIME
    ANY ANY_NUM ANY_INT ANY_REAL ANY_BIT ANY_DERIVED ANY_ELEMENTARY ANY_MAGNITUDE ANY_STRING ANY_DATE
""".split())


def is_reserved_word(key: str) -> bool:
    """True for a lower-case identifier that is an IEC 61131-3 keyword (or elementary type name)."""
    return key in RESERVED_WORDS
