"""HH_Lib: every helper FUNCTION and the timer/counter FUNCTION_BLOCKs as a library of their own (hh_lib.st,
hh_lib.xml), for users who keep the helpers in one place on their target (docs/hh_lib.md).

project.st stays self-contained: it declares the helpers its code calls (library.py), with the same bodies. The
library holds all of them, each with a doc comment (DOCS) that says which behaviour of the control it keeps;
HH_TIMER and HH_COUNTER are built for the project's semantics (the settings of A-34 and A-36). The printers
(writer.py, plcopen/writer.py) write it, as they write the HH_Sys library (sys_library.py).
"""

from __future__ import annotations

import dataclasses
import textwrap
from types import MappingProxyType

from transpiler.backends.iec_model import Configuration, IecProject, Pou
from transpiler.backends.st.library import counter_fb, helper_pous, timer_fb
from transpiler.language.semantics import Semantics

ST_FILE, XML_FILE = "hh_lib.st", "hh_lib.xml"
LIBRARY_NAME = "HH_Lib"

_SHIFT_COUNT = "The count K is taken modulo 32 (K = 33 acts as 1, K = -1 as 31), as the control does (A-14)."

# What each helper keeps of the control, for a PLC programmer reading the library (one entry per helper_pous()).
DOCS = MappingProxyType({
    "HH_ADD": "A + B as the control's + adds: the 32-bit sum wraps around (2147483647 + 1 = -2147483648) and sets "
              "no flag (A-09, docs/language.md#arithmetic).\nComputed in LINT, so no target traps on the overflow.",
    "HH_SUB": "A - B as the control's - subtracts: the 32-bit difference wraps around (-2147483648 - 1 = 2147483647) "
              "and sets no flag (A-09, docs/language.md#arithmetic).\nComputed in LINT, so no target traps on the "
              "overflow.",
    "HH_MUL": "A * B as the control's x multiplies: the low 32 bits of the full product, read as a signed DINT "
              "(65536 * 65536 = 0, 65536 * 32768 = -2147483648) (A-10, docs/language.md#arithmetic).\nWhether the "
              "product fitted is HH_MULOVF.",
    "HH_MULOVF": "TRUE when A * B does not fit a DINT (-2147483648..2147483647): the control's multiplication error "
                 "marker (M4200 on the iTNC 530) after x (A-10, docs/language.md#arithmetic).",
    "HH_DIV": "A / B as the control's / divides: the quotient is rounded toward zero (7 / -2 = -3).\nDividing by 0 "
              "returns A unchanged: the control leaves the accumulator as it is (the caller sets the division error "
              "marker). -2147483648 / -1 wraps to -2147483648 without a fault (A-11, A-12, "
              "docs/language.md#arithmetic).",
    "HH_MOD": "A MOD B as the control's MOD: the remainder takes the sign of the dividend A (-7 MOD 2 = -1, "
              "7 MOD -2 = 1).\nMOD 0 returns A unchanged, as the control leaves the accumulator (the caller sets the "
              "MOD error marker); -2147483648 MOD -1 = 0 without a fault (A-11, A-12, docs/language.md#arithmetic).",
    "HH_SEXT8": "The low 8 bits of V as a signed value -128..127 (bits 8..31 are ignored): the control compares a byte "
                "operand B signed over its own width (A-13, "
                "docs/language.md#comparisons-shifts-and-bit-commands).",
    "HH_SEXT16": "The low 16 bits of V as a signed value -32768..32767 (bits 16..31 are ignored): the control compares "
                 "a word operand W signed over its own width (A-13, "
                 "docs/language.md#comparisons-shifts-and-bit-commands).",
    "HH_WAND": "The control's A (and AN, with V inverted by the caller) with a word operand of W bits (8 for B, 16 for "
               "W, 32 for D): only the low W bits of A are ANDed with V, the bits above them are kept (A AND V would "
               "clear them). Any W other than 8 and 16 takes all 32 bits (docs/language.md#word-logic).",
    "HH_WOR": "The control's O (and ON) with a word operand of W bits (8 for B, 16 for W, 32 for D): only the low W "
              "bits of V are ORed into A, the bits above them are kept. Any W other than 8 and 16 takes all 32 bits "
              "(docs/language.md#word-logic).",
    "HH_WXOR": "The control's XO (and XON) with a word operand of W bits (8 for B, 16 for W, 32 for D): only the low "
               "W bits of V are XORed into A, the bits above them are kept. Any W other than 8 and 16 takes all 32 "
               "bits (docs/language.md#word-logic).",
    "HH_SHL": "A << K as the control shifts left: bits shifted out of bit 31 are lost without a flag "
              "(16#7FFFFFFF << 4 = -16). " + _SHIFT_COUNT,
    "HH_SHR": "A >> K as the control shifts right: arithmetically, the sign bit is copied in (-16 >> 2 = -4, "
              "-1 >> 31 = -1). " + _SHIFT_COUNT,
    "HH_BSET": "BS: A with bit K set (bit 0 is the lowest, bit 31 the sign bit). " + _SHIFT_COUNT,
    "HH_BCLR": "BC: A with bit K cleared (bit 0 is the lowest, bit 31 the sign bit). " + _SHIFT_COUNT,
    "HH_BTEST": "BT: TRUE when bit K of A is set (bit 0 is the lowest, bit 31 the sign bit). " + _SHIFT_COUNT,
    "HH_BIT": "Bit K of A, for K = 0..31 only (the translation passes constants in that range; unlike BT, K is not "
              "taken modulo 32): B=/W=/D= writing a word into bit operands, and a logic value on the data stack.",
    "HH_LOWORD": "The low 16 bits of V as an INT. The control's data stack holds 16-bit words (A-19): PS of a word "
                 "value pushes its low word, then its high word (HH_HIWORD).",
    "HH_HIWORD": "The high 16 bits of V as an INT: the second word PS pushes for a word value on the control's data "
                 "stack of 16-bit words (A-19).",
    "HH_FROMWORDS": "The 32-bit value of a high and a low 16-bit word: PL of a word value from the control's data "
                    "stack of 16-bit words (A-19). HH_FROMWORDS(HH_HIWORD(V), HH_LOWORD(V)) = V for every V.",
    "HH_MKINT": "A 16-bit word operand W read from the byte memory: B0 is its low byte, B1 its high byte (the caller "
                "picks the addresses by the control's byte order, A-42); the result is signed (16#FF, 16#FF = -1).",
    "HH_MKDINT": "A 32-bit double word operand D read from the byte memory: B0 is its lowest byte, B3 its highest "
                 "(the caller picks the addresses by the control's byte order, A-42).",
    "HH_BYTEOF": "Byte K of V (K = 0 the lowest, 3 the highest): storing a word or double word operand into the byte "
                 "memory byte by byte (the caller picks the addresses by the control's byte order, A-42).",
    "HH_PACK8": "LB: the 8 bit operands B0..B7 as the word accumulator loads them, B0 the lowest bit. Bit 7 is the "
                "sign: the value is sign-extended to 32 bits (all TRUE = -1, only B7 = -128) "
                "(docs/language.md#loads-and-assignments).",
    "HH_PACK16": "LW: the 16 bit operands B0..B15 as the word accumulator loads them, B0 the lowest bit. Bit 15 is "
                 "the sign: the value is sign-extended to 32 bits (all TRUE = -1, only B15 = -32768) "
                 "(docs/language.md#loads-and-assignments).",
    "HH_PACK32": "LD: the 32 bit operands B0..B31 as the word accumulator loads them, B0 the lowest bit and B31 the "
                 "sign bit (all TRUE = -1, only B31 = -2147483648) (docs/language.md#loads-and-assignments).",
})


def _timer_doc(semantics: Semantics) -> str:
    restart = ("a start while it runs starts it again" if semantics["timer_restart_while_running"]
               else "a start while it runs is ignored")
    consumed = ("START is reset by the block (the service consumes the start operand)"
                if semantics["timer_start_consumed"] else "START is left as it is")
    return ("The control's timer service for one timer (its start and its running operand), cycle by cycle: call it once per "
            "PLC cycle before the program logic (A-32). A start loads PRESET (PLC cycles); RUNNING is TRUE for "
            f"exactly PRESET cycles; {restart} (A-34b); {consumed} (A-34a). See docs/language.md#timers-and-counters.")


def _counter_doc(semantics: Semantics) -> str:
    counts = ("once per cycle in which RELEASE is TRUE" if semantics["counter_counts"] == "cycles"
              else "once per rising edge of RELEASE")
    consumed = ("START is reset by the block (the service consumes the start operand)"
                if semantics["counter_start_consumed"] else "START is left as it is")
    return ("The control's counter service for one counter (its start, running and release operands): call it once "
            "per PLC cycle before the program logic (A-32). A start loads PRESET; the counter then counts down "
            f"{counts} (A-36b) and RUNNING is TRUE while it is not zero; {consumed} (A-36a). "
            "See docs/language.md#timers-and-counters.")


def _wrapped(text: str) -> str:
    """A doc comment as lines of at most 100 characters (the writers print one comment per line)."""
    return "\n".join(textwrap.fill(part, 100, break_long_words=False, break_on_hyphens=False)
                     for part in text.split("\n"))


def library_pous(semantics: Semantics) -> tuple[Pou, ...]:
    """Every helper FUNCTION, then HH_TIMER and HH_COUNTER for `semantics`, each with its doc comment as comment.

    Raises KeyError for a helper without a doc: a new helper is documented before it ships."""
    helpers = [dataclasses.replace(p, comment=_wrapped(DOCS[name])) for name, p in helper_pous().items()]
    return tuple(helpers) + (dataclasses.replace(timer_fb(semantics), comment=_wrapped(_timer_doc(semantics))),
                             dataclasses.replace(counter_fb(semantics), comment=_wrapped(_counter_doc(semantics))))


def library_project(semantics: Semantics, project_name: str) -> IecProject:
    """HH_Lib as a project of its own (no tasks, no instances): every helper of the translation of `project_name`."""
    settings = ", ".join(f"{key} = {str(semantics[key]).lower()}" for key in (
        "timer_start_consumed", "timer_restart_while_running", "counter_start_consumed", "counter_counts"))
    header = _wrapped(
        "HH_Lib: every helper function and function block hh2iec's translations call, one POU each, with a "
        "comment saying which behaviour of the HEIDENHAIN PLC it keeps.\n"
        "project.st declares the ones it uses with the same bodies; to keep them in one place on the target, "
        "import this library and delete those declarations there (see docs/hh_lib.md).\n"
        f"Generated for project {project_name}: HH_TIMER and HH_COUNTER follow its settings {settings}.")
    config = Configuration(f"{LIBRARY_NAME}_CONFIG", f"{LIBRARY_NAME}_RES", (), (), ())
    return IecProject(LIBRARY_NAME, (), library_pous(semantics), config, header_comment=header)
