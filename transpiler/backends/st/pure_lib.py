"""The pure PLC modules in portable ST: number/string conversion (9050, 9052, 9070) and hex dumps (9053, 9054).

Each is a FUNCTION_BLOCK with a real body, written here once and identical in behaviour to the reference
interpreter's transpiler/exec/interp/pure_modules.py (tests/test_pure_lib.py runs both over many inputs on the
built-in executor and on matiec). The blocks see no PLC memory of their own: the caller passes the string
contents and whether the string numbers are valid, and stores TEXT into the destination string when FAULT is
FALSE (modcalls.py); 9053/9054 take the byte memory as VAR_IN_OUT. Only IEC standard functions (LEN, LEFT,
RIGHT, MID, CONCAT of at most 3 inputs), integer arithmetic and WHILE loops (matiec's FOR skips short ranges) are used, so any IEC 61131-3 target compiles them unchanged.

Limit: an ST STRING holds at most 126 characters (matiec), the TNC's strings 128, so a 9053 dump of 64 bytes
loses its last two hex digits in the ST (named in docs/modules.md).
"""

from __future__ import annotations

from transpiler.backends.iec_model import IecVar, Pou, VarSection
from transpiler.backends.st.hh_sys import FAULT, FAULT_CODE

MAX_EXPONENT = 10
INT32_MAX = 2**31 - 1
MEM_TYPE = "T_HH_MEM"

PARSE_FB = "HH_PARSE_NUMBER"
FORMAT_FN = "HH_FORMAT_NUMBER"
DIGIT_FN = "HH_DIGIT_VALUE"


def _v(name: str, typ: str, comment: str | None = None, initial: str | None = None) -> IecVar:
    return IecVar(name, typ, initial=initial, comment=comment)


def _outputs(*extra: IecVar) -> VarSection:
    return VarSection("VAR_OUTPUT", extra + (_v(FAULT, "BOOL", "the module error marker after the call"),
                                             _v(FAULT_CODE, "DINT", "the error code when FAULT")))


def _fail(code: int) -> list[str]:
    return [f"    {FAULT} := TRUE;", f"    {FAULT_CODE} := {code};", "    RETURN;", "END_IF;"]


# Digit value of a one-character string, -1 for anything but 0-9 (base 10) or 0-9/a-f/A-F (base 16). A loop of
# MID comparisons rather than FIND or '<=' on strings: those differ between targets for non-ASCII characters.
_DIGIT = Pou(DIGIT_FN, "FUNCTION", (
    VarSection("VAR_INPUT", (_v("C", "STRING", "one character"), _v("BASE", "INT", "10 or 16"))),
    VarSection("VAR", (_v("K", "INT"),))), "\n".join([
        f"{DIGIT_FN} := -1;",
        "K := 0;",
        "WHILE K < BASE DO",
        "    IF C = MID('0123456789ABCDEF', 1, K + 1) OR C = MID('0123456789abcdef', 1, K + 1) THEN",
        f"        {DIGIT_FN} := K;",
        "    END_IF;",
        "    K := K + 1;",
        "END_WHILE;"]), return_type="INT",
    comment="Value of a decimal (BASE 10) or hexadecimal (BASE 16) digit character, -1 if it is none.")

# mantissa x 10^exponent as text: '-' only for negatives, no padding, no trailing zeros of the fraction.
_FORMAT = Pou(FORMAT_FN, "FUNCTION", (
    VarSection("VAR_INPUT", (_v("MANTISSA", "DINT"), _v("EXPONENT", "INT", "-10..10"),
                             _v("POINT", "STRING", "the decimal character"))),
    VarSection("VAR", (_v("M", "LINT"), _v("SIGN", "STRING"), _v("DIGITS", "STRING"), _v("FRAC", "STRING"),
                       _v("K", "INT")))), "\n".join([
        "M := DINT_TO_LINT(MANTISSA);",
        "SIGN := '';",
        "IF M < 0 THEN",
        "    SIGN := '-';",
        "    M := -M;",
        "END_IF;",
        "DIGITS := '';",
        "IF M = 0 THEN",
        "    DIGITS := '0';",
        "END_IF;",
        "WHILE M > 0 DO",
        "    DIGITS := CONCAT(MID('0123456789', 1, LINT_TO_INT(M MOD 10) + 1), DIGITS);",
        "    M := M / 10;",
        "END_WHILE;",
        "IF EXPONENT >= 0 THEN",
        "    IF MANTISSA <> 0 THEN",
        "        K := 0;",
        "        WHILE K < EXPONENT DO",
        "            DIGITS := CONCAT(DIGITS, '0');",
        "            K := K + 1;",
        "        END_WHILE;",
        "    END_IF;",
        f"    {FORMAT_FN} := CONCAT(SIGN, DIGITS);",
        "    RETURN;",
        "END_IF;",
        "WHILE LEN(DIGITS) < 1 - EXPONENT DO",
        "    DIGITS := CONCAT('0', DIGITS);",
        "END_WHILE;",
        "FRAC := RIGHT(DIGITS, -EXPONENT);",
        "DIGITS := LEFT(DIGITS, LEN(DIGITS) + EXPONENT);",
        "WHILE LEN(FRAC) > 0 AND RIGHT(FRAC, 1) = '0' DO",
        "    FRAC := LEFT(FRAC, LEN(FRAC) - 1);",
        "END_WHILE;",
        "IF LEN(FRAC) > 0 THEN",
        f"    {FORMAT_FN} := CONCAT(CONCAT(SIGN, DIGITS), CONCAT(POINT, FRAC));",
        "ELSE",
        f"    {FORMAT_FN} := CONCAT(SIGN, DIGITS);",
        "END_IF;"]), return_type="STRING",
    comment="MANTISSA x 10^EXPONENT as decimal text (PLC module 9050's format, see docs/modules.md).")

# The first number of a text: optional sign directly before a digit, digits with at most one '.' or ','; a
# mantissa beyond a double word keeps its leading digits and raises the exponent by the digits it drops.
_PARSE = Pou(PARSE_FB, "FUNCTION_BLOCK", (
    VarSection("VAR_INPUT", (_v("TEXT", "STRING"),)),
    VarSection("VAR_OUTPUT", (_v("FOUND", "BOOL"), _v("MANTISSA", "DINT"), _v("EXPONENT", "DINT"),
                              _v("START_POS", "INT", "offset of the first character (0 = first)"),
                              _v("END_POS", "INT", "offset after the last character"))),
    VarSection("VAR", (_v("N", "INT"), _v("I", "INT"), _v("D", "INT"), _v("C", "STRING"), _v("ACC", "LINT"),
                       _v("NEG", "BOOL"), _v("POINT_SEEN", "BOOL"), _v("OVER", "BOOL")))), "\n".join([
        "FOUND := FALSE;",
        "MANTISSA := 0;",
        "EXPONENT := 0;",
        "START_POS := 0;",
        "END_POS := 0;",
        "N := LEN(TEXT);",
        "I := 0;",
        "WHILE I < N DO",
        "    C := MID(TEXT, 1, I + 1);",
        f"    IF {DIGIT_FN}(C, 10) >= 0 THEN",
        "        EXIT;",
        "    END_IF;",
        "    IF (C = '+' OR C = '-') AND I + 1 < N THEN",
        f"        IF {DIGIT_FN}(MID(TEXT, 1, I + 2), 10) >= 0 THEN",
        "            EXIT;",
        "        END_IF;",
        "    END_IF;",
        "    I := I + 1;",
        "END_WHILE;",
        "IF I >= N THEN",
        "    RETURN;",
        "END_IF;",
        "START_POS := I;",
        "NEG := C = '-';",
        "IF C = '+' OR C = '-' THEN",
        "    I := I + 1;",
        "END_IF;",
        "ACC := 0;",
        "POINT_SEEN := FALSE;",
        "OVER := FALSE;",
        "WHILE I < N DO",
        "    C := MID(TEXT, 1, I + 1);",
        f"    D := {DIGIT_FN}(C, 10);",
        "    IF D >= 0 THEN",
        "        IF POINT_SEEN THEN",
        "            EXPONENT := EXPONENT - 1;",
        "        END_IF;",
        f"        IF NOT OVER AND ACC * 10 + INT_TO_LINT(D) <= {INT32_MAX} THEN",
        "            ACC := ACC * 10 + INT_TO_LINT(D);",
        "        ELSE",
        "            OVER := TRUE;",
        "            EXPONENT := EXPONENT + 1;",
        "        END_IF;",
        "    ELSIF (C = '.' OR C = ',') AND NOT POINT_SEEN THEN",
        "        POINT_SEEN := TRUE;",
        "    ELSE",
        "        EXIT;",
        "    END_IF;",
        "    I := I + 1;",
        "END_WHILE;",
        "END_POS := I;",
        "MANTISSA := LINT_TO_DINT(ACC);",
        "IF NEG THEN",
        "    MANTISSA := -MANTISSA;",
        "END_IF;",
        "FOUND := TRUE;"]),
    comment="The first number of TEXT (PLC modules 9052 and 9070, see docs/modules.md).")


def _pou_9050() -> Pou:
    return Pou("HH_NumToString", "FUNCTION_BLOCK", (
        VarSection("VAR_INPUT", (_v("MANTISSA", "DINT"), _v("EXPONENT", "DINT"),
                                 _v("STRING_OK", "BOOL", "the string number is valid"),
                                 _v("POINT", "STRING", "decimal character (MP7280)"))),
        _outputs(_v("TEXT", "STRING", "the new string contents when not FAULT"))), "\n".join([
            f"{FAULT} := FALSE;", f"{FAULT_CODE} := 0;", "TEXT := '';",
            f"IF NOT STRING_OK OR EXPONENT > {MAX_EXPONENT} OR EXPONENT < -{MAX_EXPONENT} THEN", *_fail(2),
            f"TEXT := {FORMAT_FN}(MANTISSA, DINT_TO_INT(EXPONENT), POINT);"]),
        comment="PLC module 9050 (pure): a number (mantissa, exponent) as decimal text. Error 2: invalid string "
                f"number or exponent outside -{MAX_EXPONENT}..{MAX_EXPONENT}. See docs/modules.md.")


def _pou_9052() -> Pou:
    return Pou("HH_StringToNum", "FUNCTION_BLOCK", (
        VarSection("VAR_INPUT", (_v("TEXT", "STRING", "contents of the string"),
                                 _v("STRING_OK", "BOOL", "the string number is valid"))),
        _outputs(_v("VALUE", "DINT", "mantissa"), _v("EXPONENT", "DINT")),
        VarSection("VAR", (_v("P", PARSE_FB),))), "\n".join([
            f"{FAULT} := FALSE;", f"{FAULT_CODE} := 0;", "VALUE := 0;", "EXPONENT := 0;",
            "IF NOT STRING_OK THEN", *_fail(2),
            "P(TEXT := TEXT);",
            "IF NOT P.FOUND THEN", *_fail(2),
            "VALUE := P.MANTISSA;", "EXPONENT := P.EXPONENT;"]),
        comment="PLC module 9052 (pure): the first number of a string as mantissa and exponent. Error 2: invalid "
                "string number or no number. See docs/modules.md.")


def _pou_9070() -> Pou:
    return Pou("HH_FindNumber", "FUNCTION_BLOCK", (
        VarSection("VAR_INPUT", (_v("TEXT", "STRING", "contents of the source string"),
                                 _v("STRINGS_OK", "BOOL", "both string numbers are valid"))),
        _outputs(_v("OFFSET", "DINT", "offset after the number, -1 on error"),
                 _v("NUMBER_TEXT", "STRING", "the number's characters, for the destination string")),
        VarSection("VAR", (_v("P", PARSE_FB),))), "\n".join([
            f"{FAULT} := FALSE;", f"{FAULT_CODE} := 0;", "OFFSET := -1;", "NUMBER_TEXT := '';",
            "IF NOT STRINGS_OK THEN", *_fail(1),
            "P(TEXT := TEXT);",
            "IF NOT P.FOUND THEN", *_fail(2),
            "NUMBER_TEXT := MID(TEXT, P.END_POS - P.START_POS, P.START_POS + 1);",
            "OFFSET := INT_TO_DINT(P.END_POS);"]),
        comment="PLC module 9070 (pure): copies the first number of a string into another. Error 1: a string "
                "number out of range; 2: no number. See docs/modules.md.")


def _pou_9053(string_len: int) -> Pou:
    return Pou("HH_BytesToHex", "FUNCTION_BLOCK", (
        VarSection("VAR_INPUT", (_v("ADDRESS", "DINT"), _v("COUNT", "DINT"),
                                 _v("STRING_OK", "BOOL", "the string number is valid"),
                                 _v("MEM_SIZE", "DINT", "bytes of PLC memory"))),
        VarSection("VAR_IN_OUT", (_v("MEM", MEM_TYPE, "the PLC byte memory"),)),
        _outputs(_v("TEXT", "STRING", "the new string contents when not FAULT")),
        VarSection("VAR", (_v("A", "DINT"), _v("B", "INT")))), "\n".join([
            f"{FAULT} := FALSE;", f"{FAULT_CODE} := 0;", "TEXT := '';",
            f"IF COUNT < 0 OR 2 * COUNT > {string_len} THEN", *_fail(1),
            "IF NOT STRING_OK THEN", *_fail(2),
            "IF ADDRESS < 0 OR ADDRESS + COUNT > MEM_SIZE THEN", *_fail(4),
            "A := ADDRESS;",
            "WHILE A < ADDRESS + COUNT DO",
            "    B := BYTE_TO_INT(MEM[A]);",
            "    TEXT := CONCAT(TEXT, MID('0123456789ABCDEF', 1, B / 16 + 1), MID('0123456789ABCDEF', 1, B MOD 16 + 1));",
            "    A := A + 1;",
            "END_WHILE;"]),
        comment="PLC module 9053 (pure): COUNT bytes from ADDRESS as upper-case hex text. Error 1: too many bytes; "
                "2: invalid string number; 4: invalid address. See docs/modules.md.")


def _pou_9054() -> Pou:
    return Pou("HH_HexToBytes", "FUNCTION_BLOCK", (
        VarSection("VAR_INPUT", (_v("TEXT", "STRING", "contents of the string"),
                                 _v("STRING_OK", "BOOL", "the string number is valid"), _v("ADDRESS", "DINT"),
                                 _v("MEM_SIZE", "DINT", "bytes of PLC memory"))),
        VarSection("VAR_IN_OUT", (_v("MEM", MEM_TYPE, "the PLC byte memory"),)),
        _outputs(),
        VarSection("VAR", (_v("K", "INT"), _v("N", "INT"), _v("HI", "INT"), _v("LO", "INT")))), "\n".join([
            f"{FAULT} := FALSE;", f"{FAULT_CODE} := 0;",
            "IF NOT STRING_OK THEN", *_fail(2),
            "N := LEN(TEXT);",
            "IF N MOD 2 <> 0 THEN", *_fail(5),
            "K := 1;",
            "WHILE K <= N DO",
            f"    IF {DIGIT_FN}(MID(TEXT, 1, K), 16) < 0 THEN",
            f"        {FAULT} := TRUE;", f"        {FAULT_CODE} := 5;", "        RETURN;", "    END_IF;",
            "    K := K + 1;",
            "END_WHILE;",
            "IF ADDRESS < 0 OR ADDRESS + INT_TO_DINT(N / 2) > MEM_SIZE THEN", *_fail(4),
            "K := 0;",
            "WHILE K < N / 2 DO",
            f"    HI := {DIGIT_FN}(MID(TEXT, 1, 2 * K + 1), 16);",
            f"    LO := {DIGIT_FN}(MID(TEXT, 1, 2 * K + 2), 16);",
            "    MEM[ADDRESS + INT_TO_DINT(K)] := INT_TO_BYTE(HI * 16 + LO);",
            "    K := K + 1;",
            "END_WHILE;"]),
        comment="PLC module 9054 (pure): hex text (either case, even length) into bytes from ADDRESS. Error 2: "
                "invalid string number; 4: invalid address; 5: odd length or not hex. See docs/modules.md.")


PURE_TRANSLATED = (9050, 9052, 9053, 9054, 9070)
NEEDS_MEMORY = (9053, 9054)


def pure_pous(numbers: set[int], string_len: int) -> list[Pou]:
    """The library POUs the pure modules `numbers` need, callees first."""
    wanted = set(numbers) & set(PURE_TRANSLATED)
    if not wanted:
        return []
    pous = [_DIGIT]
    if wanted - {9052, 9070, 9053, 9054}:
        pous.append(_FORMAT)
    if wanted & {9052, 9070}:
        pous.append(_PARSE)
    makers = {9050: _pou_9050, 9052: _pou_9052, 9070: _pou_9070, 9053: lambda: _pou_9053(string_len),
              9054: _pou_9054}
    return pous + [makers[n]() for n in sorted(wanted)]


def fb_name(number: int) -> str:
    return {9050: "HH_NumToString", 9052: "HH_StringToNum", 9053: "HH_BytesToHex", 9054: "HH_HexToBytes",
            9070: "HH_FindNumber"}[number]
